//! The inverse-dynamics document (`egt dynamics --format json`): driving
//! torques, accelerations, per-mesh multipliers and forces (eq. 7-11), the
//! equivalent inertia and the conditions of the systems solved.

use egt_core::{DynamicsRequest, InverseDynamics, LinkId, Train};
use serde::Serialize;

#[derive(Debug, Serialize)]
pub struct LinkRow {
    pub name: String,
    pub acceleration: f64,
    pub torque: f64,
    pub role: String,
}

#[derive(Debug, Serialize)]
pub struct MeshRow {
    pub pair: String,
    pub gear_i: String,
    pub gear_j: String,
    pub carrier: String,
    pub multiplier: f64,
    pub torque_i: f64,
    pub torque_j: f64,
    pub torque_carrier: f64,
    /// F_im and F_jm of eq. (11), summed over identical copies.
    pub force: Option<[f64; 2]>,
    /// The same per copy (per planet).
    pub force_per_copy: Option<[f64; 2]>,
    pub copies: u32,
}

#[derive(Debug, Serialize)]
pub struct Report {
    pub source: String,
    pub name: Option<String>,
    pub dof: usize,
    pub static_analysis: bool,
    pub links: Vec<LinkRow>,
    pub driving_torques: Vec<(String, f64)>,
    pub housing_torque: f64,
    pub meshes: Vec<MeshRow>,
    pub equivalent_inertia: Option<(String, f64)>,
    pub reduced_mass_matrix: Option<(Vec<String>, Vec<Vec<f64>>)>,
    pub conditions: [f64; 2],
    pub warnings: Vec<String>,
}

pub fn build(
    train: &Train,
    source: &str,
    req: &DynamicsRequest,
    r: &InverseDynamics,
    reduce_to: Option<LinkId>,
) -> Report {
    let name = |l: LinkId| train.link_name(l).to_string();
    let links = train
        .links_with_ids()
        .map(|(id, l)| {
            let role = if id == train.frame() {
                "frame (housing)"
            } else if req.driving.contains(&id) {
                "driving"
            } else if req.torques.iter().any(|t| t.0 == id) {
                "loaded"
            } else {
                ""
            };
            LinkRow {
                name: l.name.clone(),
                acceleration: r.acceleration[id.index()],
                torque: r.torque[id.index()],
                role: role.into(),
            }
        })
        .collect();
    let meshes = train
        .circuits()
        .iter()
        .zip(train.gears())
        .zip(&r.meshes)
        .map(|((c, g), m)| {
            let copies = train.link(c.gear_i).copies.max(train.link(c.gear_j).copies);
            MeshRow {
                pair: g.name.clone(),
                gear_i: name(c.gear_i),
                gear_j: name(c.gear_j),
                carrier: name(c.carrier),
                multiplier: m.multiplier,
                torque_i: m.torque_i,
                torque_j: m.torque_j,
                torque_carrier: m.torque_carrier,
                force: m.force,
                force_per_copy: m
                    .force
                    .map(|[a, b]| [a / f64::from(copies), b / f64::from(copies)]),
                copies,
            }
        })
        .collect();
    // Equivalent inertia / reduced mass matrix, when inertia data exists.
    let has_inertia = train
        .links()
        .iter()
        .any(|l| l.inertia.is_some() || l.mass.is_some());
    let (mut equivalent_inertia, mut reduced_mass_matrix) = (None, None);
    let mut warnings = r.warnings.clone();
    if has_inertia {
        if train.dof() == 1 {
            let to = reduce_to.unwrap_or(req.driving[0]);
            match train.equivalent_inertia(to) {
                Ok(j) => equivalent_inertia = Some((name(to), j)),
                Err(e) => warnings.push(format!("no equivalent inertia: {e}")),
            }
        } else {
            match train.reduced_mass_matrix(&req.driving, &[]) {
                Ok(m) => {
                    reduced_mass_matrix = Some((
                        req.driving.iter().map(|&l| name(l)).collect(),
                        (0..m.nrows())
                            .map(|i| (0..m.ncols()).map(|j| m[(i, j)]).collect())
                            .collect(),
                    ));
                }
                Err(e) => warnings.push(format!("no reduced mass matrix: {e}")),
            }
        }
    }
    Report {
        source: source.to_string(),
        name: train.name().map(str::to_string),
        dof: train.dof(),
        static_analysis: req.accelerations.iter().all(|a| a.1 == 0.0),
        links,
        driving_torques: r
            .driving_torques
            .iter()
            .map(|&(l, t)| (name(l), t))
            .collect(),
        housing_torque: r.torque[train.frame().index()],
        meshes,
        equivalent_inertia,
        reduced_mass_matrix,
        conditions: r.conditions,
        warnings,
    }
}

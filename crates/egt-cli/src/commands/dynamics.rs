//! `egt dynamics SPEC`: inverse dynamics (eq. 6-11) for any DOF: link
//! accelerations, solved driving torques, Lagrange multipliers, the torques
//! each gear pair carries and its tangential meshing forces (eq. 11), the
//! housing reaction, and the equivalent inertia (1 DOF) or reduced mass
//! matrix (several DOF). Without accelerations it is the static-force analysis.

use std::io::Write;

use anyhow::Context;
use egt_core::{DynamicsRequest, InverseDynamics, LinkId, Train};
use serde::Serialize;

use crate::args::{LoadArgs, load_request, mass_if_needed};
use crate::cli::{OutputFormat, SpecArgs};
use crate::input;
use crate::report::{self, Table};

/// Arguments of `egt dynamics`.
#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub spec: SpecArgs,
    #[command(flatten)]
    pub loads: LoadArgs,
    /// Require tangential meshing forces for every gear pair (needs pitch radii).
    #[arg(long)]
    pub forces: bool,
    /// Link to reduce the equivalent inertia to (1 DOF). Default: `[analysis]
    /// reduce_to`, else the first driving link.
    #[arg(long, value_name = "LINK")]
    pub reduce_to: Option<String>,
}

#[derive(Debug, Serialize)]
struct LinkRow {
    name: String,
    acceleration: f64,
    torque: f64,
    role: String,
}

#[derive(Debug, Serialize)]
struct MeshRow {
    pair: String,
    gear_i: String,
    gear_j: String,
    carrier: String,
    multiplier: f64,
    torque_i: f64,
    torque_j: f64,
    torque_carrier: f64,
    /// F_im and F_jm of eq. (11), summed over identical copies.
    force: Option<[f64; 2]>,
    /// The same per copy (per planet).
    force_per_copy: Option<[f64; 2]>,
    copies: u32,
}

#[derive(Debug, Serialize)]
pub(crate) struct Report {
    source: String,
    name: Option<String>,
    dof: usize,
    static_analysis: bool,
    links: Vec<LinkRow>,
    driving_torques: Vec<(String, f64)>,
    housing_torque: f64,
    meshes: Vec<MeshRow>,
    equivalent_inertia: Option<(String, f64)>,
    reduced_mass_matrix: Option<(Vec<String>, Vec<Vec<f64>>)>,
    conditions: [f64; 2],
    warnings: Vec<String>,
}

/// Run `egt dynamics`.
///
/// # Errors
/// Spec errors (exit 2); missing data, singular or ill-conditioned systems (exit 1).
pub fn run(args: &Args, out: &mut dyn Write) -> anyhow::Result<()> {
    let loaded = input::load(&args.spec)?;
    let train = &loaded.train;
    let req = load_request(train, &args.loads)?;
    let mass = mass_if_needed(train, &req)?;
    let r = train
        .inverse_dynamics(&req, mass.as_ref())
        .with_context(|| format!("{}: inverse dynamics", loaded.source))?;
    if args.forces
        && let Some(g) = train.gears().iter().find(|g| g.radii.is_none())
    {
        let e = egt_core::AnalysisError::MissingData {
            what: format!("the pitch radii of gear pair `{}`", g.name),
            analysis: "meshing forces (eq. 11)".into(),
            hint: format!("give `radii`, or `module` with `teeth`, at {}", g.path),
        };
        return Err(egt_core::Error::from(e).into());
    }
    let reduce_to = match &args.reduce_to {
        Some(n) => Some(train.resolve(n, &format!("--reduce-to {n}"))?),
        None => train.analysis().reduce_to,
    };
    let report = build(train, &loaded.source, &req, &r, reduce_to);
    match args.spec.format {
        OutputFormat::Json => report::json(out, &report),
        OutputFormat::Table => write_table(out, train, &loaded.source, &report),
    }
}

pub(crate) fn build(
    train: &Train,
    source: &str,
    req: &DynamicsRequest,
    r: &InverseDynamics,
    reduce_to: Option<LinkId>,
) -> Report {
    let name = |l: LinkId| train.link_name(l).to_string();
    let links = train
        .links()
        .iter()
        .enumerate()
        .map(|(i, l)| {
            let id = LinkId::from_index(i);
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
                acceleration: r.acceleration[i],
                torque: r.torque[i],
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

fn write_table(out: &mut dyn Write, train: &Train, source: &str, r: &Report) -> anyhow::Result<()> {
    let kind = if r.static_analysis {
        "static-force analysis"
    } else {
        "inverse dynamics"
    };
    writeln!(
        out,
        "{}: {kind} ({} DOF)",
        report::title(train, source),
        r.dof
    )?;
    let f = report::float;
    let mut t = Table::new(&["link", "role", "acceleration", "applied torque"]).right(&[2, 3]);
    for l in &r.links {
        t.row(vec![
            l.name.clone(),
            l.role.clone(),
            f(l.acceleration),
            f(l.torque),
        ]);
    }
    writeln!(
        out,
        "links (applied torque: known loads, solved driving torques, and the housing reaction):"
    )?;
    t.write(out, 2)?;
    let with_forces = r.meshes.iter().any(|m| m.force.is_some());
    let mut headers = vec![
        "pair",
        "i",
        "j",
        "carrier",
        "lambda",
        "T_i",
        "T_j",
        "T_carrier",
    ];
    if with_forces {
        headers.extend(["F_i", "F_j", "copies", "F per copy"]);
    }
    let mut t = Table::new(&headers).right(&[4, 5, 6, 7, 8, 9, 10, 11]);
    let dash = || "-".to_string();
    for m in &r.meshes {
        let mut row = vec![
            m.pair.clone(),
            m.gear_i.clone(),
            m.gear_j.clone(),
            m.carrier.clone(),
            f(m.multiplier),
            f(m.torque_i),
            f(m.torque_j),
            f(m.torque_carrier),
        ];
        if with_forces {
            row.push(m.force.map_or_else(dash, |x| f(x[0])));
            row.push(m.force.map_or_else(dash, |x| f(x[1])));
            row.push(m.copies.to_string());
            row.push(m.force_per_copy.map_or_else(dash, |x| f(x[0])));
        }
        t.row(row);
    }
    writeln!(
        out,
        "gear pairs (torques each member spends on the mesh, lambda psi_w; forces by eq. 11):"
    )?;
    t.write(out, 2)?;
    if let Some((l, j)) = &r.equivalent_inertia {
        writeln!(out, "equivalent inertia reduced to `{l}`: {}", f(*j))?;
    }
    if let Some((names, m)) = &r.reduced_mass_matrix {
        writeln!(out, "reduced mass matrix over [{}]:", names.join(", "))?;
        for row in m {
            writeln!(
                out,
                "  [{}]",
                row.iter().map(|x| f(*x)).collect::<Vec<_>>().join(", ")
            )?;
        }
    }
    writeln!(
        out,
        "condition numbers: [Psi_w] {}, force system {}",
        f(r.conditions[0]),
        f(r.conditions[1])
    )?;
    for w in &r.warnings {
        writeln!(out, "warning: {w}")?;
    }
    Ok(())
}

//! `egt modes`: natural frequencies and mass-normalised mode shapes of the
//! lumped torsional model of a train (docs/vibration.md), bare or in a gear
//! state: the rigid-body modes (as many as the DOF the springs leave, each a
//! solution of the kinematics), the elastic modes with their frequencies,
//! multiplicities, and the shares of strain energy per spring and of kinetic
//! energy per coordinate; the damped modes' complex eigenvalues when damping
//! is given (`damped`); and the static deflection under a steady load,
//! mesh by mesh beside the rigid model's eq. (11) (`statics`).

mod damped;
mod eigen;
mod meshing;
mod model;
mod statics;

use nalgebra::DMatrix;
use serde::Serialize;

pub use damped::DampedMode;
pub use eigen::NULL_TOLERANCE;
pub use meshing::{Crossing, MeshOrder, Meshing};
pub use model::{ElasticElement, ElasticKind, ModeCoordinate, TorsionalModel};
pub use statics::{BALANCE_TOLERANCE, MeshCheck, SpringLoad, StaticCheck, StaticDeflection};

use crate::error::Result;
use crate::model::train::Train;

/// Elastic frequencies closer than this fraction of the larger are one
/// degenerate frequency (e.g. the planet modes, N - 1 of them).
pub const DEGENERATE_REL: f64 = 1e-6;

/// What `egt modes` asks for.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ModesRequest {
    /// The gear state whose engaged elements hold (None: the bare train).
    pub state: Option<String>,
    /// The input speed range \[rpm\] of the Campbell diagram's crossings
    /// (None: no crossings; the mesh orders are given when they can be).
    pub campbell: Option<[f64; 2]>,
}

/// One mode of the undamped model.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NaturalMode {
    /// A rigid-body mode (frequency 0): a motion of the kinematics.
    pub rigid: bool,
    /// Natural frequency \[rad/s\].
    pub omega: f64,
    /// Natural frequency \[Hz\].
    pub hertz: f64,
    /// How many modes share this frequency (1: simple); rigid modes count
    /// the DOF.
    pub multiplicity: usize,
    /// Index of the first mode of its group of equal frequencies.
    pub group: usize,
    /// The shape over the model's coordinates, phi^T M phi = 1 \[rad
    /// sqrt(kg) m\]^-1; the largest component is positive.
    pub shape: Vec<f64>,
    /// Share of the mode's strain energy in each spring (zeros for a rigid mode).
    pub strain_energy: Vec<f64>,
    /// Share of its kinetic energy in each coordinate.
    pub kinetic_energy: Vec<f64>,
    /// Modal damping ratio phi^T C phi / (2 omega) when some damping is
    /// given (the damping matrix's coupling between modes neglected).
    pub damping_ratio: Option<f64>,
}

/// The natural modes of a train.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct NaturalModes {
    /// The gear state, if one was asked for.
    pub state: Option<String>,
    /// The model the modes are of.
    pub model: TorsionalModel,
    /// The rigid-body modes' count: the model's DOF.
    pub dof: usize,
    /// The modes: rigid-body modes first, then by rising frequency.
    pub modes: Vec<NaturalMode>,
    /// Mesh orders per unit input speed and the Campbell crossings, with one
    /// rigid-body mode, an input link and tooth counts (else None, unless
    /// the crossings were asked for: then an error says what is missing).
    pub meshing: Option<Meshing>,
    /// The damped modes (complex eigenvalues of the model with its damping),
    /// by rising |lambda|; empty when no damping is given.
    pub damped: Vec<DampedMode>,
}

impl Train {
    /// The natural frequencies and modes of the lumped torsional model.
    ///
    /// ```
    /// use egt_core::{Format, ModesRequest, Train};
    ///
    /// // Two inertias on one shaft: f = sqrt(k (1/J1 + 1/J2)) / 2 pi.
    /// let spec = r#"
    ///     frame = "0"
    ///     adjacency = "0-1:a 0-2:b 1-2:G=-1"
    ///     links = [{ name = "1", inertia = 0.5 }, { name = "2", inertia = 2.0 }]
    ///     [compliance]
    ///     meshes = [{ gear = "G1", stiffness = 1.0e6, base_radii = [0.01, 0.01] }]
    /// "#;
    /// let train = Train::from_str(spec, Format::Toml, "doc").unwrap();
    /// let modes = train.modes(&ModesRequest::default()).unwrap();
    /// assert_eq!(modes.dof, 1);
    /// let k: f64 = 1.0e6 * 0.01 * 0.01;
    /// let omega = (k * (1.0 / 0.5 + 1.0 / 2.0)).sqrt();
    /// assert!((modes.modes[1].omega - omega).abs() < 1e-9 * omega);
    /// ```
    ///
    /// # Errors
    /// As [`Train::torsional_model`]; [`crate::AnalysisError::IndefiniteMass`]
    /// when the reduced mass matrix is not positive definite.
    pub fn modes(&self, req: &ModesRequest) -> Result<NaturalModes> {
        let model = self.torsional_model(req.state.as_deref())?;
        let n = model.coordinates.len();
        let (t, _) = if model.constraints.nrows() == 0 {
            (DMatrix::identity(n, n), DMatrix::zeros(n, 0))
        } else {
            eigen::null_space(&model.constraints, n)?
        };
        let springs = DMatrix::from_fn(model.elastic.len(), n, |r, c| model.elastic[r].row[c]);
        let k = model.stiffness();
        let m = DMatrix::from_diagonal(&nalgebra::DVector::from_column_slice(&model.mass));
        let e = eigen::solve(&t, &springs, &k, &m)?;
        let damped = model.elastic.iter().any(|s| s.damping > 0.0);
        let dof = e.rigid.ncols();
        let mut modes = Vec::with_capacity(dof + e.lambda.len());
        for c in 0..dof {
            let shape = normalised(e.rigid.column(c).iter().copied().collect());
            modes.push(NaturalMode {
                rigid: true,
                omega: 0.0,
                hertz: 0.0,
                multiplicity: dof,
                group: 0,
                strain_energy: vec![0.0; model.elastic.len()],
                kinetic_energy: kinetic(&model.mass, &shape),
                damping_ratio: None,
                shape,
            });
        }
        // Every spring's deflection in every elastic mode, over each row's
        // two or three non-zeros (the sign a shape takes below does not
        // matter: energies are squares).
        let mut deflections = DMatrix::zeros(model.elastic.len(), e.lambda.len());
        for (s, spring) in model.elastic.iter().enumerate() {
            for (c, &v) in spring.row.iter().enumerate().filter(|x| *x.1 != 0.0) {
                for j in 0..e.lambda.len() {
                    deflections[(s, j)] += v * e.elastic[(c, j)];
                }
            }
        }
        let damped_modes = damped::damped_modes(&model, &deflections, &e.lambda)?;
        for (c, &lambda) in e.lambda.iter().enumerate() {
            let shape = normalised(e.elastic.column(c).iter().copied().collect());
            let omega = lambda.sqrt();
            let deflection = deflections.column(c);
            let strain: Vec<f64> = model
                .elastic
                .iter()
                .zip(deflection.iter())
                .map(|(s, d)| s.stiffness * d * d)
                .collect();
            let total: f64 = strain.iter().sum();
            let damping = model
                .elastic
                .iter()
                .zip(deflection.iter())
                .map(|(s, d)| s.damping * d * d)
                .sum::<f64>();
            modes.push(NaturalMode {
                rigid: false,
                omega,
                hertz: omega / std::f64::consts::TAU,
                multiplicity: 1,
                group: dof + c,
                strain_energy: strain.iter().map(|s| s / total).collect(),
                kinetic_energy: kinetic(&model.mass, &shape),
                damping_ratio: (damped && omega > 0.0).then(|| damping / (2.0 * omega)),
                shape,
            });
        }
        group_degenerate(&mut modes[dof..], dof);
        let speed_of = |l: crate::LinkId| {
            model
                .coordinates
                .iter()
                .position(|c| c.link == l)
                .map_or(0.0, |k| modes[0].shape[k])
        };
        let meshing = match self.meshing(&speed_of, dof, &modes, req.campbell) {
            Ok(m) => Some(m),
            Err(e) if req.campbell.is_some() => return Err(e),
            Err(_) => None,
        };
        Ok(NaturalModes {
            state: req.state.clone(),
            model,
            dof,
            modes,
            meshing,
            damped: damped_modes,
        })
    }
}

/// Shares of kinetic energy M_cc phi_c^2 (M is diagonal).
fn kinetic(mass: &[f64], shape: &[f64]) -> Vec<f64> {
    let e: Vec<f64> = mass.iter().zip(shape).map(|(m, p)| m * p * p).collect();
    let total: f64 = e.iter().sum();
    e.iter().map(|v| v / total).collect()
}

/// The shape with its largest component positive.
fn normalised(mut shape: Vec<f64>) -> Vec<f64> {
    let big = shape
        .iter()
        .copied()
        .fold(0.0_f64, |a, v| if v.abs() > a.abs() { v } else { a });
    if big < 0.0 {
        shape.iter_mut().for_each(|v| *v = -*v);
    }
    shape
}

/// Mark runs of equal frequencies (relative gap below [`DEGENERATE_REL`]).
fn group_degenerate(modes: &mut [NaturalMode], first: usize) {
    let mut start = 0;
    for i in 1..=modes.len() {
        let ends = i == modes.len()
            || modes[i].omega - modes[i - 1].omega > DEGENERATE_REL * modes[i].omega;
        if ends {
            for m in &mut modes[start..i] {
                m.multiplicity = i - start;
                m.group = first + start;
            }
            start = i;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mode(omega: f64) -> NaturalMode {
        NaturalMode {
            rigid: false,
            omega,
            hertz: omega / std::f64::consts::TAU,
            multiplicity: 0,
            group: 0,
            shape: vec![],
            strain_energy: vec![],
            kinetic_energy: vec![],
            damping_ratio: None,
        }
    }

    #[test]
    fn equal_frequencies_form_one_group() {
        let mut m: Vec<NaturalMode> = [1.0, 2.0, 2.0 * (1.0 + 1e-9), 3.0].map(mode).into();
        group_degenerate(&mut m, 1);
        let got: Vec<(usize, usize)> = m.iter().map(|x| (x.multiplicity, x.group)).collect();
        assert_eq!(got, [(1, 1), (2, 2), (2, 2), (1, 4)]);
    }

    #[test]
    fn a_shape_is_signed_by_its_largest_component() {
        assert_eq!(normalised(vec![0.5, -2.0, 1.0]), [-0.5, 2.0, -1.0]);
        assert_eq!(normalised(vec![0.5, 2.0]), [0.5, 2.0]);
    }
}

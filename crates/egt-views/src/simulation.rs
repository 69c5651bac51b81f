//! The forward-dynamics document (`egt simulate --format json`): the time
//! series, the integrator's diagnostics, the curves' equilibrium and the
//! observed growth rate about it.

use egt_core::model::train::Curve;
use egt_core::{LinkId, Method, Simulation, Train};
use serde::Serialize;

#[derive(Debug, Serialize)]
pub struct SampleOut {
    pub t: f64,
    pub speeds: Vec<f64>,
    pub drift: f64,
    pub energy: f64,
    pub work: f64,
    pub power: f64,
}

#[derive(Debug, Serialize)]
pub struct MeshOut {
    pub gear: String,
    pub multiplier: f64,
    pub torque_i: f64,
    pub torque_j: f64,
    pub torque_carrier: f64,
}

#[derive(Debug, Serialize)]
pub struct Report {
    pub source: String,
    pub name: Option<String>,
    pub dof: usize,
    pub method: Method,
    pub dt: f64,
    pub t_end: f64,
    pub steps: usize,
    pub eigenvalues: Vec<f64>,
    pub rk4_step_limit: Option<f64>,
    pub max_drift: f64,
    pub energy_error: f64,
    pub newton_iterations: usize,
    pub diverged: Option<egt_core::motion::simulate::Divergence>,
    /// The equilibrium of the curves (link speeds), when it is unique.
    pub equilibrium: Option<Vec<f64>>,
    /// Growth rate of the deviation from the equilibrium over the second half.
    pub observed_rate: Option<f64>,
    /// Link names, in the order of every `speeds` array.
    pub links: Vec<String>,
    pub reactions: Option<Vec<MeshOut>>,
    pub warnings: Vec<String>,
    pub samples: Vec<SampleOut>,
}

impl Report {
    /// Indices of the links to plot (every link but the frame).
    pub fn links_plotted(&self, train: &Train) -> Vec<LinkId> {
        (0..self.links.len())
            .map(LinkId::from_index)
            .filter(|&l| l != train.frame())
            .collect()
    }
}

/// The equilibrium of the curves (link speeds, when unique), to plot and to
/// measure the deviation against, and the observed growth rate of that
/// deviation over the second half of the run.
pub fn equilibrium(
    train: &Train,
    curves: &[Curve],
    sim: &Simulation,
) -> (Option<Vec<f64>>, Option<f64>) {
    if curves.is_empty() {
        return (None, None);
    }
    let equilibrium = train
        .automatic_coordinates()
        .and_then(|coords| train.reduced_model(&coords, curves))
        .ok()
        .and_then(|m| m.equilibrium().ok())
        .map(|(e, _)| e);
    let observed_rate = equilibrium.as_ref().and_then(|e| {
        let mass = train.mass_matrix().ok()?;
        let half = sim.samples.last()?.t / 2.0;
        sim.growth_rate(train, &mass, e, half)
    });
    (equilibrium, observed_rate)
}

pub fn build(
    train: &Train,
    source: &str,
    sim: &Simulation,
    t_end: f64,
    equilibrium: Option<Vec<f64>>,
    observed_rate: Option<f64>,
    reactions: Option<Vec<MeshOut>>,
) -> Report {
    Report {
        source: source.to_string(),
        name: train.name().map(str::to_string),
        dof: train.dof(),
        method: sim.method,
        dt: sim.dt,
        t_end,
        steps: sim.steps,
        eigenvalues: sim.eigenvalues.clone(),
        rk4_step_limit: sim.rk4_step_limit,
        max_drift: sim.max_drift,
        energy_error: sim.energy_error,
        newton_iterations: sim.newton_iterations,
        diverged: sim.diverged.clone(),
        equilibrium,
        observed_rate,
        links: train.links().iter().map(|l| l.name.clone()).collect(),
        reactions,
        warnings: sim.warnings.clone(),
        samples: sim
            .samples
            .iter()
            .map(|s| SampleOut {
                t: s.t,
                speeds: s.speed.clone(),
                drift: s.drift,
                energy: s.energy,
                work: s.work,
                power: s.power,
            })
            .collect(),
    }
}

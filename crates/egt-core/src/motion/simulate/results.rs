//! A simulation's results: the samples, the divergence, the energy and drift
//! diagnostics.

use super::*;

/// One stored instant.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Sample {
    /// Time \[s\].
    pub t: f64,
    /// Every link's speed (by link index).
    pub speed: Vec<f64>,
    /// Willis drift: max |psi_m(w)| / max |w| (eq. 2).
    pub drift: f64,
    /// Kinetic energy w^T M w / 2.
    pub energy: f64,
    /// Work of the applied torques since t = 0.
    pub work: f64,
    /// Power of the applied torques, w . T.
    pub power: f64,
}

/// Why a simulation stopped early.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Divergence {
    /// Time of the last finite state.
    pub t: f64,
    /// In words.
    pub reason: String,
}

/// A simulated time series and its checks.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Simulation {
    /// The integrator.
    pub method: Method,
    /// The step.
    pub dt: f64,
    /// Steps taken.
    pub steps: usize,
    /// Stored samples (t = 0 first).
    pub samples: Vec<Sample>,
    /// Largest Willis drift over the samples.
    pub max_drift: f64,
    /// max |E - E0 - W| relative to the largest energy or work: the integration error.
    pub energy_error: f64,
    /// Set when the solution blew up; `samples` end at the last finite state.
    pub diverged: Option<Divergence>,
    /// RK4's stable step on the linearisation at the initial state, when it has a decaying mode.
    pub rk4_step_limit: Option<f64>,
    /// Eigenvalues of the linearisation at the initial state (largest first).
    pub eigenvalues: Vec<f64>,
    /// Newton iterations (implicit) or algebraic re-solves (massless directions).
    pub newton_iterations: usize,
    /// Implicit steps that were halved because Newton failed.
    pub halvings: usize,
    /// Warnings.
    pub warnings: Vec<String>,
}

impl Simulation {
    /// Growth rate of the deviation from `reference` (link speeds), in the
    /// energy norm sqrt(dw^T M dw): ln(d(t_end) / d(t_from)) / (t_end - t_from),
    /// with `t_from` the first sample at or after `from`. None when the
    /// deviation vanishes or there is no such interval.
    pub fn growth_rate(
        &self,
        train: &Train,
        mass: &MassMatrix,
        reference: &[f64],
        from: f64,
    ) -> Option<f64> {
        // sqrt(2 K(dw)), with dw scaled to unit size first: K is quadratic, and
        // squaring a deviation of 1e-200 would underflow to a zero norm.
        let norm = |s: &Sample| {
            let dw: Vec<f64> = s.speed.iter().zip(reference).map(|(a, b)| a - b).collect();
            let size = dw.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
            if size == 0.0 || !size.is_finite() {
                return size;
            }
            let unit: Vec<f64> = dw.iter().map(|v| v / size).collect();
            size * (2.0 * train.kinetic_energy(mass, &unit)).max(0.0).sqrt()
        };
        let last = self.samples.last()?;
        let first = self.samples.iter().find(|s| s.t >= from)?;
        let (a, b) = (norm(first), norm(last));
        (last.t > first.t && a > 0.0 && b > 0.0).then(|| (b / a).ln() / (last.t - first.t))
    }
}

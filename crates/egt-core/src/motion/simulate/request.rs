//! What to simulate: the method and step options, the request resolved from
//! the spec and overrides, and the [`Train`] entry points.

use super::*;

/// The integrator.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// Classical explicit Runge-Kutta, order 4, fixed step.
    #[default]
    Rk4,
    /// Two-stage L-stable SDIRK (Alexander), order 2, fixed step, Newton on the analytic Jacobian.
    Implicit,
}

impl FromStr for Method {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s.trim().to_ascii_lowercase().as_str() {
            "rk4" | "explicit" => Ok(Method::Rk4),
            "implicit" | "sdirk" | "sdirk2" => Ok(Method::Implicit),
            other => Err(format!(
                "unknown integrator `{other}` (expected `rk4` or `implicit`)"
            )),
        }
    }
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Method::Rk4 => "rk4",
            Method::Implicit => "implicit",
        })
    }
}

/// Step control of a simulation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimulationOptions {
    /// End time \[s\].
    pub t_end: f64,
    /// Fixed step \[s\] (the last step is shortened to end at `t_end`).
    pub dt: f64,
    /// Integrator.
    pub method: Method,
    /// Store every `every`-th step (0: about [`DEFAULT_SAMPLES`] samples). The last step is always stored.
    pub every: usize,
}

/// Where a simulation starts and how long it runs, with the spec's defaults.
#[derive(Debug, Clone, PartialEq)]
pub struct SimulationRequest {
    /// F initial link speeds; empty: the spec's `simulate.initial`, else its `speeds`.
    pub initial: Vec<(LinkId, f64)>,
    /// Step control.
    pub options: SimulationOptions,
}

/// What a caller sets over the spec's `[analysis.simulate]` settings (the
/// CLI's flags, Python's keywords); `None` keeps the spec's value.
#[derive(Debug, Clone, Default)]
pub struct SimulationOverrides {
    /// End time \[s\].
    pub t_end: Option<f64>,
    /// Step \[s\].
    pub dt: Option<f64>,
    /// Integrator.
    pub method: Option<Method>,
    /// Keep every n-th step (0 or 1: every step).
    pub every: Option<usize>,
    /// F initial link speeds.
    pub initial: Option<Vec<(LinkId, f64)>>,
}

impl SimulationRequest {
    /// The spec's `[analysis.simulate]` settings: t_end (required), dt
    /// (default t_end / 1000), method (default rk4), initial speeds.
    ///
    /// # Errors
    /// No `t_end`; an unknown method name.
    pub fn from_spec(train: &Train) -> Result<Self> {
        Self::resolve(train, &SimulationOverrides::default())
    }

    /// The request a caller's overrides and the spec's settings resolve to:
    /// each setting from the override, else the spec, else its default
    /// (dt = t_end / 1000, rk4, every step, the spec's initial speeds). The
    /// one place those defaults are decided, for the CLI and Python alike.
    ///
    /// # Errors
    /// No end time anywhere; an unknown method name in the spec.
    pub fn resolve(train: &Train, over: &SimulationOverrides) -> Result<Self> {
        let sim = train.analysis().simulate.clone().unwrap_or_default();
        let t_end = over.t_end.or(sim.t_end).ok_or_else(|| {
            Error::spec(
                "analysis.simulate.t_end",
                SpecErrorKind::Missing {
                    what: "the end time of the simulation (`t_end`)".into(),
                },
            )
        })?;
        let method = match (over.method, &sim.method) {
            (Some(m), _) => m,
            (None, Some(m)) => m
                .parse()
                .map_err(|e: String| Error::invalid("analysis.simulate.method", e))?,
            (None, None) => Method::default(),
        };
        Ok(SimulationRequest {
            initial: over.initial.clone().unwrap_or_else(|| sim.initial.clone()),
            options: SimulationOptions {
                t_end,
                dt: over.dt.or(sim.dt).unwrap_or(t_end / 1000.0),
                method,
                every: over.every.unwrap_or(0),
            },
        })
    }
}

impl Train {
    /// Simulate under the spec's curves from the request's initial speeds,
    /// else the spec's `simulate.initial`, else its `speeds`.
    ///
    /// # Errors
    /// No curves; as [`ReducedDynamics::new`] and [`ReducedDynamics::simulate`].
    pub fn simulate(&self, req: &SimulationRequest) -> Result<Simulation> {
        let curves = &self.analysis().curves;
        let torque = LinearCurves::new(self, curves)?;
        self.simulate_with(req, &torque)
    }

    /// As [`Train::simulate`] with any torque model.
    ///
    /// # Errors
    /// As [`Train::simulate`].
    pub fn simulate_with(
        &self,
        req: &SimulationRequest,
        torque: &dyn TorqueModel,
    ) -> Result<Simulation> {
        let initial = self.initial_speeds(req)?;
        let mut dynamics = ReducedDynamics::new(self, torque)?;
        dynamics.simulate(&initial, &req.options)
    }

    /// The initial speeds a request resolves to.
    ///
    /// # Errors
    /// None given anywhere.
    pub fn initial_speeds(&self, req: &SimulationRequest) -> Result<Vec<(LinkId, f64)>> {
        if !req.initial.is_empty() {
            return Ok(req.initial.clone());
        }
        if let Some(s) = self
            .analysis()
            .simulate
            .as_ref()
            .filter(|s| !s.initial.is_empty())
        {
            return Ok(s.initial.clone());
        }
        if !self.analysis().speeds.is_empty() {
            return Ok(self.analysis().speeds.iter().map(|s| (s.0, s.1)).collect());
        }
        Err(AnalysisError::MissingData {
            what: "initial speeds".into(),
            analysis: "the simulation".into(),
            hint: "give `[analysis.simulate] initial` or `[analysis] speeds`, one per degree of freedom".into(),
        }
        .into())
    }
}

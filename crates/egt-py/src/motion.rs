//! Stability (paper section 5, any DOF) and forward simulation (eq. 12) for
//! `egt.Train.stability` and `egt.Train.simulate`: names to ids, the core
//! analysis, plain Python values back. A Python callable can be the torque
//! law of a simulation; an exception it raises is re-raised after the run.

use std::cell::RefCell;

use egt_core::Train;
use egt_core::analysis::stability::StabilityRequest;
use egt_core::model::train::Curve;
use egt_core::motion::simulate::{
    LinearCurves, SimulationOverrides, SimulationRequest, TorqueModel,
};
use numpy::{PyArray1, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;

use crate::convert::{self, to_py};
use crate::errors::{Error, Result, guard, value_error};
use crate::train::TrainCore;

/// A curve as the Python side passes it: (link, torque, slope, speed).
type CurveArg = (String, f64, f64, f64);

fn curves(train: &Train, cs: &[CurveArg]) -> Result<Vec<Curve>> {
    cs.iter()
        .enumerate()
        .map(|(k, (name, torque, slope, speed))| {
            Ok(Curve {
                link: convert::link(train, name, &format!("curves[{k}].link"))?,
                torque: *torque,
                slope: *slope,
                speed: *speed,
            })
        })
        .collect()
}

/// The stability of the train about an operating point (eq. 12-27, corrected).
#[pyfunction]
#[pyo3(signature = (core, coordinates = None, curves = None, speeds = None))]
pub fn stability<'py>(
    py: Python<'py>,
    core: &TrainCore,
    coordinates: Option<Vec<String>>,
    curves: Option<Vec<CurveArg>>,
    speeds: Option<Vec<(String, f64)>>,
) -> Result<Bound<'py, PyAny>> {
    guard(|| {
        let t = &core.train;
        let req = StabilityRequest {
            coordinates: coordinates
                .map(|c| convert::links(t, &c, "coordinates"))
                .transpose()?,
            curves: curves.map(|c| self::curves(t, &c)).transpose()?,
            speeds: speeds
                .map(|s| convert::valued(t, &s, "speeds"))
                .transpose()?,
        };
        let rep = t.stability(&req)?;
        let doc = egt_views::stability(t, &core.source, &rep);
        convert::documented(py, &rep, doc)
    })
}

/// A Python callable `torque(t, speeds) -> torques` (per-link arrays) as a torque law.
struct PyTorque<'py> {
    f: Bound<'py, PyAny>,
    n: usize,
    error: RefCell<Option<PyErr>>,
}

impl PyTorque<'_> {
    fn call(&self, t: f64, speed: &[f64], torque: &mut [f64]) -> PyResult<()> {
        let py = self.f.py();
        let w = PyArray1::from_slice(py, speed);
        let out = self.f.call1((t, w))?;
        let arr = out.cast_into::<PyArray1<f64>>().map_err(|_| {
            pyo3::exceptions::PyTypeError::new_err(
                "the torque function must return a 1-D float64 NumPy array (one torque per link)",
            )
        })?;
        if arr.len() != self.n {
            return Err(pyo3::exceptions::PyValueError::new_err(format!(
                "the torque function returned {} torques for {} links",
                arr.len(),
                self.n
            )));
        }
        let ro = arr.readonly();
        let s = ro.as_slice().map_err(|_| {
            pyo3::exceptions::PyValueError::new_err("the torque array must be contiguous")
        })?;
        torque.copy_from_slice(s);
        Ok(())
    }
}

impl TorqueModel for PyTorque<'_> {
    fn torques(&self, t: f64, speed: &[f64], torque: &mut [f64]) {
        if self.error.borrow().is_some() {
            torque.iter_mut().for_each(|v| *v = f64::NAN);
            return;
        }
        if let Err(e) = self.call(t, speed, torque) {
            // Poison the run (NaN stops the integrator) and re-raise afterwards.
            torque.iter_mut().for_each(|v| *v = f64::NAN);
            *self.error.borrow_mut() = Some(e);
        }
    }
}

/// Simulate the train forward in time (eq. 12 in reduced coordinates).
#[pyfunction]
#[pyo3(signature = (core, t_end = None, dt = None, method = None, initial = None, curves = None, torque = None, every = 0))]
#[allow(clippy::too_many_arguments)]
pub fn simulate<'py>(
    py: Python<'py>,
    core: &TrainCore,
    t_end: Option<f64>,
    dt: Option<f64>,
    method: Option<String>,
    initial: Option<Vec<(String, f64)>>,
    curves: Option<Vec<CurveArg>>,
    torque: Option<Bound<'py, PyAny>>,
    every: usize,
) -> Result<Bound<'py, PyAny>> {
    guard(|| {
        let t = &core.train;
        // Keyword arguments are checked as arguments (ValueError); the spec's
        // values are checked by the core, naming their field.
        for (v, what) in [(t_end, "t_end"), (dt, "dt")] {
            if let Some(v) = v
                && !(v.is_finite() && v > 0.0)
            {
                return Err(value_error(format!(
                    "{what} must be a positive number, got {v}"
                )));
            }
        }
        let over = SimulationOverrides {
            t_end,
            dt,
            method: method
                .as_deref()
                .map(str::parse)
                .transpose()
                .map_err(value_error)?,
            every: Some(every),
            initial: initial
                .as_ref()
                .map(|i| convert::valued(t, i, "initial"))
                .transpose()?,
        };
        let req = SimulationRequest::resolve(t, &over)?;
        // The curves the run used (None: a Python torque function), for the
        // document's equilibrium.
        let (sim, used) = match (&torque, &curves) {
            (Some(_), Some(_)) => {
                return Err(value_error("give either `curves` or `torque`, not both"));
            }
            (Some(f), None) => {
                if !f.is_callable() {
                    return Err(Error::Py(pyo3::exceptions::PyTypeError::new_err(
                        "`torque` must be callable as torque(t, speeds) -> torques",
                    )));
                }
                let model = PyTorque {
                    f: f.clone(),
                    n: t.links().len(),
                    error: RefCell::new(None),
                };
                let result = t.simulate_with(&req, &model);
                if let Some(e) = model.error.into_inner() {
                    return Err(Error::Py(e));
                }
                (result?, None)
            }
            (None, Some(c)) => {
                let c = self::curves(t, c)?;
                (t.simulate_with(&req, &LinearCurves::new(t, &c)?)?, Some(c))
            }
            (None, None) => (t.simulate(&req)?, Some(t.analysis().curves.clone())),
        };
        let doc = egt_views::simulation(t, &core.source, &sim, req.options.t_end, used.as_deref());
        convert::documented(py, &sim, doc)
    })
}

/// A capacity as the Python side passes it: `[C]` or `[t0, t1, from, to]`.
fn capacity(v: &[f64], field: &str) -> Result<egt_core::shift_dynamics::Capacity> {
    use egt_core::shift_dynamics::Capacity;
    match *v {
        [c] => Ok(Capacity::Constant(c)),
        [t0, t1, from, to] => Ok(Capacity::Ramp { t0, t1, from, to }),
        _ => Err(value_error(format!(
            "{field}: a capacity is a number or (t0, t1, from, to), got {} numbers",
            v.len()
        ))),
    }
}

/// `method` of a shift run by name.
fn shift_method(method: &str) -> Result<egt_core::shift_dynamics::ShiftMethod> {
    use egt_core::shift_dynamics::ShiftMethod;
    match method {
        "auto" => Ok(ShiftMethod::Auto),
        "explicit" => Ok(ShiftMethod::Explicit),
        "implicit" => Ok(ShiftMethod::Implicit),
        other => Err(value_error(format!(
            "method: expected \"auto\", \"explicit\" or \"implicit\", got {other:?}"
        ))),
    }
}

/// The names of the spec's `[[shift]]` entries, in spec order.
#[pyfunction]
pub fn shift_names(core: &TrainCore) -> Vec<String> {
    core.train
        .transmission()
        .map(|t| t.shifts.iter().map(|s| s.name.clone()).collect())
        .unwrap_or_default()
}

/// The spec's shift `name` in time (`ShiftSim::named`), with the given
/// integration settings, as its serde form.
#[pyfunction]
#[pyo3(signature = (core, name, rtol, atol, method, max_steps))]
pub fn shift_named<'py>(
    py: Python<'py>,
    core: &TrainCore,
    name: &str,
    rtol: f64,
    atol: f64,
    method: &str,
    max_steps: Option<usize>,
) -> Result<Bound<'py, PyAny>> {
    use egt_core::shift_dynamics::{DEFAULT_MAX_STEPS, ShiftSim};
    let method = shift_method(method)?;
    guard(|| {
        let sim = ShiftSim {
            rtol,
            atol,
            method,
            max_steps: max_steps.unwrap_or(DEFAULT_MAX_STEPS),
            ..ShiftSim::named(&core.train, name)?
        };
        let doc = egt_views::shift_simulation(&sim.run(&core.train)?)
            .map_err(|e| value_error(e.to_string()))?;
        to_py(py, &doc)
    })
}

/// A gear change in time (egt_core::shift_dynamics::ShiftSim), as its serde form.
#[pyfunction]
#[pyo3(signature = (core, from_, to, input_speed, input_torque, torque_table, road_load, vehicle_inertia, mu, mu_decay, off_going, on_coming, ramps, t_end, rtol, atol, method, max_steps, output_shaft, losses))]
#[allow(clippy::too_many_arguments)]
pub fn shift_sim<'py>(
    py: Python<'py>,
    core: &TrainCore,
    from_: String,
    to: String,
    input_speed: f64,
    input_torque: Option<f64>,
    torque_table: Option<Vec<(f64, f64)>>,
    road_load: (f64, f64, f64),
    vehicle_inertia: f64,
    mu: (f64, f64),
    mu_decay: Option<f64>,
    off_going: Option<Vec<f64>>,
    on_coming: Option<Vec<f64>>,
    ramps: Vec<(String, Vec<f64>)>,
    t_end: f64,
    rtol: f64,
    atol: f64,
    method: &str,
    max_steps: Option<usize>,
    output_shaft: Option<(f64, f64)>,
    losses: bool,
) -> Result<Bound<'py, PyAny>> {
    use egt_core::shift_dynamics::{FrictionLaw, InputTorque, OutputShaft, ShiftSim};
    let method = shift_method(method)?;
    let input_torque = match (input_torque, torque_table) {
        (Some(t), None) => InputTorque::Constant(t),
        (None, Some(table)) => InputTorque::Table(table),
        _ => {
            return Err(value_error(
                "give exactly one of input_torque (a number) and torque_table ((speed, torque) pairs)",
            ));
        }
    };
    let sim = ShiftSim {
        from: from_,
        to,
        input_speed,
        input_torque,
        road_load: [road_load.0, road_load.1, road_load.2],
        vehicle_inertia,
        law: FrictionLaw {
            mu_static: mu.0,
            mu_kinetic: mu.1,
            decay: mu_decay,
        },
        off_going: off_going.map(|c| capacity(&c, "off_going")).transpose()?,
        on_coming: on_coming.map(|c| capacity(&c, "on_coming")).transpose()?,
        ramps: ramps
            .into_iter()
            .map(|(name, c)| {
                let cap = capacity(&c, &format!("ramps[{name:?}]"))?;
                Ok((name, cap))
            })
            .collect::<Result<_>>()?,
        t_end,
        rtol,
        atol,
        method,
        max_steps: max_steps.unwrap_or(egt_core::shift_dynamics::DEFAULT_MAX_STEPS),
        output_shaft: output_shaft.map(|(stiffness, damping)| OutputShaft { stiffness, damping }),
        losses,
    };
    // The document is the run's serde form (and the version): one payload.
    guard(|| {
        let doc = egt_views::shift_simulation(&sim.run(&core.train)?)
            .map_err(|e| value_error(e.to_string()))?;
        to_py(py, &doc)
    })
}

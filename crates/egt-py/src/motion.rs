//! Stability (paper section 5, any DOF) and forward simulation (eq. 12) for
//! `egt.Train.stability` and `egt.Train.simulate`: names to ids, the core
//! analysis, plain Python values back. A Python callable can be the torque
//! law of a simulation; an exception it raises is re-raised after the run.

use std::cell::RefCell;

use egt_core::analysis::stability::{CoordinateSource, OperatingSource, StabilityRequest, Verdict};
use egt_core::model::train::Curve;
use egt_core::motion::simulate::{
    LinearCurves, SimulationOverrides, SimulationRequest, TorqueModel,
};
use egt_core::{LinkId, Train};
use numpy::{PyArray1, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::convert::{self, dmatrix, mat2, vec1};
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

fn names(train: &Train, ls: &[LinkId]) -> Vec<String> {
    ls.iter().map(|&l| train.link_name(l).to_string()).collect()
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
) -> Result<Bound<'py, PyDict>> {
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
        let r = t.stability(&req)?;
        let d = PyDict::new(py);
        let m = &r.model;
        d.set_item("coordinates", names(t, &m.coordinates))?;
        d.set_item(
            "source",
            match m.source {
                CoordinateSource::Given => "given",
                CoordinateSource::SpecSpeeds => "spec_speeds",
                CoordinateSource::Automatic => "automatic",
            },
        )?;
        d.set_item("velocity", dmatrix(py, &m.velocity)?)?;
        d.set_item("gamma_condition", m.gamma_condition)?;
        d.set_item("orthogonality", m.orthogonality)?;
        d.set_item("mass", dmatrix(py, &m.mass)?)?;
        d.set_item("slope", dmatrix(py, &m.slope)?)?;
        d.set_item("link_slope", vec1(py, m.link_slope.clone()))?;
        let o = &r.operating;
        let od = PyDict::new(py);
        od.set_item(
            "source",
            match o.source {
                OperatingSource::Speeds => "speeds",
                OperatingSource::Equilibrium => "equilibrium",
            },
        )?;
        od.set_item("speed", vec1(py, o.speed.clone()))?;
        od.set_item("torque", vec1(py, o.torque.clone()))?;
        od.set_item("reduced_torque", vec1(py, o.reduced_torque.clone()))?;
        od.set_item("residual", o.residual)?;
        od.set_item("steady", o.steady)?;
        od.set_item("equilibrium", o.equilibrium.clone().map(|e| vec1(py, e)))?;
        od.set_item("equilibrium_condition", o.equilibrium_condition)?;
        d.set_item("operating", od)?;
        let s = &r.stability;
        d.set_item("eigenvalues", vec1(py, s.eigenvalues.clone()))?;
        let modes = PyList::empty(py);
        for mode in &s.modes {
            modes.append((
                mode.eigenvalue,
                mode.time_constant,
                vec1(py, mode.coordinates.clone()),
                vec1(py, mode.speeds.clone()),
            ))?;
        }
        d.set_item("modes", modes)?;
        d.set_item(
            "verdict",
            match s.verdict {
                Verdict::Stable => "stable",
                Verdict::Unstable => "unstable",
                Verdict::Marginal => "marginal",
            },
        )?;
        d.set_item("reason", s.reason.as_str())?;
        d.set_item("margin", s.margin)?;
        d.set_item("tolerance", s.tolerance)?;
        let massless = PyList::empty(py);
        for x in &s.massless {
            massless.append((
                vec1(py, x.coordinates.clone()),
                vec1(py, x.speeds.clone()),
                names(t, &x.links),
                x.slope,
            ))?;
        }
        d.set_item("massless", massless)?;
        d.set_item("rk4_step_limit", s.rk4_step_limit)?;
        d.set_item("stiffness", s.stiffness)?;
        d.set_item("residual", s.residual)?;
        d.set_item("warnings", r.warnings.clone())?;
        Ok(d)
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
) -> Result<Bound<'py, PyDict>> {
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
        let sim = match (&torque, &curves) {
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
                result?
            }
            (None, Some(c)) => {
                t.simulate_with(&req, &LinearCurves::new(t, &self::curves(t, c)?)?)?
            }
            (None, None) => t.simulate(&req)?,
        };
        let d = PyDict::new(py);
        let n = t.links().len();
        let k = sim.samples.len();
        d.set_item("method", sim.method.to_string())?;
        d.set_item("dt", sim.dt)?;
        d.set_item("steps", sim.steps)?;
        d.set_item(
            "t",
            vec1(py, sim.samples.iter().map(|s| s.t).collect::<Vec<_>>()),
        )?;
        d.set_item(
            "speeds",
            mat2(
                py,
                k,
                n,
                sim.samples
                    .iter()
                    .flat_map(|s| s.speed.iter().copied())
                    .collect(),
            )?,
        )?;
        for (name, f) in [
            (
                "drift",
                (|s: &egt_core::Sample| s.drift) as fn(&egt_core::Sample) -> f64,
            ),
            ("energy", |s| s.energy),
            ("work", |s| s.work),
            ("power", |s| s.power),
        ] {
            d.set_item(
                name,
                vec1(py, sim.samples.iter().map(f).collect::<Vec<_>>()),
            )?;
        }
        d.set_item("max_drift", sim.max_drift)?;
        d.set_item("energy_error", sim.energy_error)?;
        d.set_item(
            "diverged",
            sim.diverged.as_ref().map(|x| (x.t, x.reason.clone())),
        )?;
        d.set_item("rk4_step_limit", sim.rk4_step_limit)?;
        d.set_item("eigenvalues", vec1(py, sim.eigenvalues.clone()))?;
        d.set_item("newton_iterations", sim.newton_iterations)?;
        d.set_item("halvings", sim.halvings)?;
        d.set_item("warnings", sim.warnings.clone())?;
        Ok(d)
    })
}

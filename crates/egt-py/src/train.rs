//! `TrainCore`: the validated train behind `egt.Train`. Every method converts
//! names to ids, calls egt-core, and returns plain Python values (dicts, lists,
//! NumPy arrays); the Python package wraps them in result classes.

use egt_core::analysis::power::PowerRequest;
use egt_core::model::mass::MassMatrix;
use egt_core::{DynamicsRequest, Extra, LoadOverrides};
use egt_core::{Format, SpeedInput, Train};
use nalgebra::DMatrix;
use numpy::PyArray2;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use egt_views as document;

use crate::convert::{self, dmatrix, to_py};
use crate::errors::{Result, guard, value_error};

/// A validated gear train (see `egt.Train` for the documented API).
#[pyclass(frozen, module = "egt._egt", name = "TrainCore")]
#[derive(Debug)]
pub struct TrainCore {
    pub(crate) train: Train,
    /// The name the spec was read under: the `source` of every document.
    pub(crate) source: String,
}

/// One prescribed input speed as the Python side passes it: link, float, exact text.
type InputArg = (String, f64, Option<String>);

pub(crate) fn format_of(format: &str) -> Result<Format> {
    match format.to_ascii_lowercase().as_str() {
        "toml" => Ok(Format::Toml),
        "json" => Ok(Format::Json),
        other => Err(value_error(format!(
            "format must be \"toml\" or \"json\", got {other:?}"
        ))),
    }
}

/// A matrix of a train for given independent inputs and engaged elements.
type InputMatrix = fn(&Train, &[egt_core::LinkId], &[Extra]) -> egt_core::Result<DMatrix<f64>>;

impl TrainCore {
    fn speed_inputs(&self, inputs: &[InputArg]) -> Result<Vec<SpeedInput>> {
        inputs
            .iter()
            .map(|(name, v, exact)| {
                let link = convert::link(&self.train, name, &format!("inputs.{name}"))?;
                // Exact text wins: its value is the speed (the float is a placeholder then).
                let (speed, exact) = match exact {
                    Some(t) => {
                        let q = convert::rational(t, &format!("inputs.{name}"))?;
                        (egt_core::numerics::exact::to_f64(&q), Some(q))
                    }
                    None => (*v, egt_core::numerics::exact::from_f64(*v)),
                };
                Ok(SpeedInput { link, speed, exact })
            })
            .collect()
    }

    /// The request from Python's keywords (`None`: the spec's `[analysis]`).
    fn request(
        &self,
        torques: Option<&[(String, f64)]>,
        accelerations: Option<&[(String, f64)]>,
        driving: Option<&[String]>,
        engaged: &[String],
    ) -> Result<DynamicsRequest> {
        let t = &self.train;
        let over = LoadOverrides {
            torques: torques
                .map(|v| convert::valued(t, v, "torques"))
                .transpose()?,
            accelerations: accelerations
                .map(|v| convert::valued(t, v, "accelerations"))
                .transpose()?,
            driving: driving
                .map(|v| convert::links(t, v, "driving"))
                .transpose()?,
            extras: convert::engaged(t, engaged)?,
        };
        DynamicsRequest::resolve(t, &over).map_err(|e| {
            e.with_hint("pass `driving=[...]` or give `[analysis] driving`")
                .into()
        })
    }

    /// The mass matrix when the request needs it, unless `inertia` is off.
    fn mass_for(&self, req: &DynamicsRequest, inertia: bool) -> Result<Option<MassMatrix>> {
        if !inertia {
            return Ok(None);
        }
        Ok(self.train.mass_for(req)?)
    }

    /// A matrix of the train for the independent `inputs` with the
    /// `engaged` elements (as [`Train::velocity_matrix`]), as a NumPy array.
    fn input_matrix<'py>(
        &self,
        py: Python<'py>,
        inputs: &[String],
        engaged: &[String],
        matrix: InputMatrix,
    ) -> Result<Bound<'py, PyArray2<f64>>> {
        guard(|| {
            let ids = convert::links(&self.train, inputs, "inputs")?;
            let extras: Vec<Extra> = convert::engaged(&self.train, engaged)?;
            dmatrix(py, &matrix(&self.train, &ids, &extras)?)
        })
    }

    fn link_name(&self, l: egt_core::LinkId) -> &str {
        self.train.link_name(l)
    }

    fn names(&self, ls: impl IntoIterator<Item = egt_core::LinkId>) -> Vec<String> {
        ls.into_iter()
            .map(|l| self.link_name(l).to_string())
            .collect()
    }
}

#[pymethods]
impl TrainCore {
    /// Parse and validate a spec from text.
    #[staticmethod]
    #[pyo3(signature = (text, format = "toml", source = "<string>"))]
    fn from_text(py: Python<'_>, text: &str, format: &str, source: &str) -> Result<Self> {
        let format = format_of(format)?;
        guard(|| {
            let train = py.detach(|| Train::from_str(text, format, source))?;
            Ok(TrainCore {
                train,
                source: source.to_string(),
            })
        })
    }

    /// Title from the spec.
    #[getter]
    fn name(&self) -> Option<String> {
        self.train.name().map(str::to_string)
    }

    /// The frame's name.
    #[getter]
    fn frame(&self) -> String {
        self.link_name(self.train.frame()).to_string()
    }

    /// Degree of freedom.
    #[getter]
    fn dof(&self) -> usize {
        self.train.dof()
    }

    /// Link names in link order (the order of every per-link array).
    #[getter]
    fn link_names(&self) -> Vec<String> {
        self.train.links().iter().map(|l| l.name.clone()).collect()
    }

    /// Coordinate names: every link but the frame (rows/columns of [M], columns of [psi_w]).
    #[getter]
    fn coordinates(&self) -> Vec<String> {
        self.names(self.train.coordinates().iter().copied())
    }

    /// Axis level names.
    #[getter]
    fn levels(&self) -> Vec<String> {
        self.train.levels().to_vec()
    }

    /// The topology checks that passed, in words.
    fn checks(&self) -> Vec<String> {
        self.train.checks().to_vec()
    }

    /// Links with their data, as dicts.
    fn links<'py>(&self, py: Python<'py>) -> Result<Bound<'py, PyList>> {
        let out = PyList::empty(py);
        for (i, l) in self.train.links().iter().enumerate() {
            let d = PyDict::new(py);
            d.set_item("name", l.name.as_str())?;
            d.set_item("inertia", l.inertia)?;
            d.set_item("mass", l.mass)?;
            d.set_item("copies", l.copies)?;
            d.set_item("wheels", l.wheels)?;
            d.set_item("sized", l.sized)?;
            d.set_item("frame", i == self.train.frame().index())?;
            out.append(d)?;
        }
        Ok(out)
    }

    /// Gear pairs with their data, as dicts.
    fn gears<'py>(&self, py: Python<'py>) -> Result<Bound<'py, PyList>> {
        let out = PyList::empty(py);
        for g in self.train.gears() {
            let d = PyDict::new(py);
            d.set_item("name", g.name.as_str())?;
            d.set_item("gear_i", self.link_name(g.gear_i))?;
            d.set_item("gear_j", self.link_name(g.gear_j))?;
            convert::set_ratio(&d, g.ratio.as_ref())?;
            d.set_item("teeth", g.teeth.map(|t| (t[0], t[1])))?;
            d.set_item(
                "mesh",
                g.mesh.map(|m| match m {
                    egt_core::spec::MeshKind::External => "external",
                    egt_core::spec::MeshKind::Internal => "internal",
                }),
            )?;
            d.set_item("radii", g.radii.map(|r| (r[0], r[1])))?;
            d.set_item("efficiency", g.efficiency)?;
            d.set_item("path", g.path.as_str())?;
            out.append(d)?;
        }
        Ok(out)
    }

    /// The fundamental-circuit table (Table 1), as dicts.
    fn circuits<'py>(&self, py: Python<'py>) -> Result<Bound<'py, PyList>> {
        let out = PyList::empty(py);
        for c in self.train.circuits() {
            let g = &self.train.gears()[c.gear.index()];
            let d = PyDict::new(py);
            d.set_item("gear", g.name.as_str())?;
            d.set_item("gear_i", self.link_name(c.gear_i))?;
            d.set_item("gear_j", self.link_name(c.gear_j))?;
            d.set_item("carrier", self.link_name(c.carrier))?;
            d.set_item("level_i", self.train.level_name(c.level_i))?;
            d.set_item("level_j", self.train.level_name(c.level_j))?;
            d.set_item("path", self.names(c.path.iter().copied()))?;
            out.append(d)?;
        }
        Ok(out)
    }

    /// Shift elements as (name, kind, links).
    fn elements(&self) -> Vec<(String, String, Vec<String>)> {
        self.train
            .elements()
            .iter()
            .map(|e| {
                let kind = match e.kind {
                    egt_core::spec::ElementKind::Brake => "brake",
                    egt_core::spec::ElementKind::Clutch => "clutch",
                    egt_core::spec::ElementKind::OneWayBrake => "one_way_brake",
                    egt_core::spec::ElementKind::OneWayClutch => "one_way_clutch",
                };
                (
                    e.name.clone(),
                    kind.to_string(),
                    self.names(e.links.iter().copied()),
                )
            })
            .collect()
    }

    /// The spec's `[analysis]` data (defaults for the analyses), as a dict.
    fn analysis<'py>(&self, py: Python<'py>) -> Result<Bound<'py, PyDict>> {
        let a = self.train.analysis();
        let d = PyDict::new(py);
        d.set_item(
            "speeds",
            a.speeds
                .iter()
                .map(|(l, v, q)| {
                    (
                        self.link_name(*l).to_string(),
                        *v,
                        q.as_ref().map(convert::q_text),
                    )
                })
                .collect::<Vec<_>>(),
        )?;
        let pairs = |v: &[(egt_core::LinkId, f64)]| -> Vec<(String, f64)> {
            v.iter()
                .map(|(l, x)| (self.link_name(*l).to_string(), *x))
                .collect()
        };
        d.set_item("torques", pairs(&a.torques))?;
        d.set_item("accelerations", pairs(&a.accelerations))?;
        d.set_item("driving", self.names(a.driving.iter().copied()))?;
        d.set_item(
            "reduce_to",
            a.reduce_to.map(|l| self.link_name(l).to_string()),
        )?;
        d.set_item(
            "curves",
            a.curves
                .iter()
                .map(|c| {
                    (
                        self.link_name(c.link).to_string(),
                        c.torque,
                        c.slope,
                        c.speed,
                    )
                })
                .collect::<Vec<_>>(),
        )?;
        Ok(d)
    }

    /// Speeds of every link for the inputs `[(link, speed, exact text or None)]`.
    fn kinematics<'py>(&self, py: Python<'py>, inputs: Vec<InputArg>) -> Result<Bound<'py, PyAny>> {
        guard(|| {
            let inputs = self.speed_inputs(&inputs)?;
            let speeds = self.train.kinematics(&inputs)?;
            let doc = document::kinematics(&self.train, &self.source, &inputs, &speeds);
            convert::documented(py, &speeds, doc)
        })
    }

    /// The Willis Jacobian [psi_w] (circuits x coordinates).
    fn willis_jacobian<'py>(&self, py: Python<'py>) -> Result<Bound<'py, PyArray2<f64>>> {
        guard(|| dmatrix(py, &self.train.willis_jacobian()?))
    }

    /// The mass matrix with the offsets used and notes (dense rows: refused
    /// past the dense limit, as the other dense matrices).
    fn mass_matrix<'py>(&self, py: Python<'py>) -> Result<Bound<'py, PyAny>> {
        guard(|| {
            let m = self.train.mass_matrix()?;
            m.require_dense()?;
            to_py(py, &m)
        })
    }

    /// Inverse dynamics (eq. 6-11).
    #[pyo3(signature = (torques, accelerations, driving, engaged, inertia = true))]
    fn dynamics<'py>(
        &self,
        py: Python<'py>,
        torques: Option<Vec<(String, f64)>>,
        accelerations: Option<Vec<(String, f64)>>,
        driving: Option<Vec<String>>,
        engaged: Vec<String>,
        inertia: bool,
    ) -> Result<Bound<'py, PyAny>> {
        guard(|| {
            let req = self.request(
                torques.as_deref(),
                accelerations.as_deref(),
                driving.as_deref(),
                &engaged,
            )?;
            let mass = self.mass_for(&req, inertia)?;
            let r = self.train.inverse_dynamics(&req, mass.as_ref())?;
            let doc = document::dynamics(&self.train, &self.source, &req, &r, None);
            convert::documented(py, &r, doc)
        })
    }

    /// Power flow, ideal or with mesh losses.
    #[pyo3(signature = (speeds, torques, accelerations, driving, engaged, losses = true, inertia = true))]
    #[allow(clippy::too_many_arguments)]
    fn power<'py>(
        &self,
        py: Python<'py>,
        speeds: Vec<InputArg>,
        torques: Option<Vec<(String, f64)>>,
        accelerations: Option<Vec<(String, f64)>>,
        driving: Option<Vec<String>>,
        engaged: Vec<String>,
        losses: bool,
        inertia: bool,
    ) -> Result<Bound<'py, PyAny>> {
        guard(|| {
            let dynamics = self.request(
                torques.as_deref(),
                accelerations.as_deref(),
                driving.as_deref(),
                &engaged,
            )?;
            let mass = self.mass_for(&dynamics, inertia)?;
            let req = PowerRequest {
                speeds: self.speed_inputs(&speeds)?,
                dynamics,
                losses,
            };
            let pf = self.train.power_flow(&req, mass.as_ref())?;
            // The power document, and those of its speeds and dynamics (the
            // documents `egt kinematics` and `egt dynamics` print for them).
            let t = &self.train;
            let doc = (|| {
                Ok(serde_json::json!({
                    "power": document::power(t, &self.source, &pf, losses)?,
                    "speeds": document::kinematics(t, &self.source, &req.speeds, &pf.speeds)?,
                    "dynamics": document::dynamics(t, &self.source, &req.dynamics, &pf.dynamics, None)?,
                }))
            })();
            convert::documented(py, &pf, doc)
        })
    }

    /// [V] of eq. (23) for the independent inputs.
    #[pyo3(signature = (inputs, engaged = Vec::new()))]
    fn velocity_matrix<'py>(
        &self,
        py: Python<'py>,
        inputs: Vec<String>,
        engaged: Vec<String>,
    ) -> Result<Bound<'py, PyArray2<f64>>> {
        self.input_matrix(py, &inputs, &engaged, Train::velocity_matrix)
    }

    /// V^T M V (eq. 25).
    #[pyo3(signature = (inputs, engaged = Vec::new()))]
    fn reduced_mass_matrix<'py>(
        &self,
        py: Python<'py>,
        inputs: Vec<String>,
        engaged: Vec<String>,
    ) -> Result<Bound<'py, PyArray2<f64>>> {
        self.input_matrix(py, &inputs, &engaged, Train::reduced_mass_matrix)
    }

    /// Equivalent inertia of a 1-DOF train reduced to `link`.
    fn equivalent_inertia(&self, link: &str) -> Result<f64> {
        guard(|| {
            let l = convert::link(&self.train, link, "link")?;
            Ok(self.train.equivalent_inertia(l)?)
        })
    }

    /// Willis residual max|psi_m| / max|w| of per-link speeds under the train's ratios.
    fn willis_residual(&self, speeds: numpy::PyReadonlyArray1<'_, f64>) -> Result<f64> {
        guard(|| {
            let s = speeds.as_slice().map_err(|e| value_error(e.to_string()))?;
            if s.len() != self.train.links().len() {
                return Err(value_error(format!(
                    "speeds has {} entries, the train has {} links",
                    s.len(),
                    self.train.links().len()
                )));
            }
            let ratios = self.train.ratios()?;
            Ok(egt_core::solve::kinematics::willis_residual(
                &self.train,
                &ratios,
                s,
            ))
        })
    }

    /// A deliberate panic, to test that panics reach Python as `egt.InternalError`.
    fn _panic(&self) -> Result<()> {
        guard(|| panic!("deliberate panic from TrainCore._panic"))
    }

    fn __repr__(&self) -> String {
        format!(
            "TrainCore({:?}, links={}, gears={}, dof={})",
            self.train.name().unwrap_or(""),
            self.train.links().len(),
            self.train.gears().len(),
            self.train.dof()
        )
    }
}

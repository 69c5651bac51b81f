//! Every mapping from Rust errors to Python exceptions lives here, and only here.
//!
//! The exception tree mirrors `egt_core::Error`:
//!
//! ```text
//! EgtError                    kind, names
//! ├── SpecError               path, value, suggestion
//! │   └── SpecSyntaxError     source, line, column
//! ├── TopologyError           links, pairs, levels, dof
//! ├── TransmissionError       state, elements, gears, free, dof, input, output
//! ├── AnalysisError
//! │   ├── InputError          dof, given, what, link
//! │   ├── UnderdeterminedError  free
//! │   ├── InconsistentError   conflicting
//! │   ├── SingularError       what, detail
//! │   ├── IllConditionedError what, condition, threshold
//! │   ├── MissingDataError    what, analysis, hint
//! │   ├── SelfLockingError    (no consistent direction of power: the train self-locks)
//! │   └── NonFiniteError      what, detail (an overflow, never an inf or NaN result)
//! └── InternalError           (a Rust panic, caught before it reaches Python)
//! ```
//!
//! An analysis that fails inside a gear state (`TransmissionError::InState`)
//! raises the exception of its cause, with the state named in the message and
//! in the `state` attribute.
//!
//! Every exception carries `kind` (the variant, in snake case) and `names`
//! (the offending links, pairs, fields or levels), plus the attributes above.
//! Attributes an exception does not use are `None` (class-level defaults).

use std::any::Any;
use std::panic::{AssertUnwindSafe, catch_unwind};

use egt_core::TransmissionError as CoreTransmission;
use egt_core::error::{AnalysisError as CoreAnalysis, SpecErrorKind, TopologyError as CoreTopo};
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use pyo3::types::{PyTuple, PyType};
use pyo3::{IntoPyObjectExt, PyTypeInfo};

pyo3::create_exception!(egt, EgtError, PyException, "Base class of every egt error.");
pyo3::create_exception!(
    egt,
    SpecError,
    EgtError,
    "The spec is invalid: `path` names the field, `kind` what is wrong."
);
pyo3::create_exception!(
    egt,
    SpecSyntaxError,
    SpecError,
    "The spec text is not valid TOML/JSON or has a wrongly typed value; located by `source`, `line`, `column`."
);
pyo3::create_exception!(
    egt,
    TopologyError,
    EgtError,
    "The graph is not a valid geared kinematic chain (paper section 2)."
);
pyo3::create_exception!(
    egt,
    TransmissionError,
    EgtError,
    "A gear state of a transmission cannot be analysed as written (`state` names it)."
);
pyo3::create_exception!(
    egt,
    AnalysisError,
    EgtError,
    "An analysis was asked something the train cannot answer as posed."
);
pyo3::create_exception!(
    egt,
    InputError,
    AnalysisError,
    "Wrong inputs: a count that does not match the DOF, the frame as an input, a repeated link."
);
pyo3::create_exception!(
    egt,
    UnderdeterminedError,
    AnalysisError,
    "The inputs leave links free (`free` names them)."
);
pyo3::create_exception!(
    egt,
    InconsistentError,
    AnalysisError,
    "The inputs conflict (`conflicting` names the equations)."
);
pyo3::create_exception!(
    egt,
    SingularError,
    AnalysisError,
    "A system is exactly singular."
);
pyo3::create_exception!(
    egt,
    IllConditionedError,
    AnalysisError,
    "A system is too ill-conditioned for a trustworthy answer."
);
pyo3::create_exception!(
    egt,
    MissingDataError,
    AnalysisError,
    "A datum the analysis needs is absent (`what`, `analysis`, `hint`)."
);
pyo3::create_exception!(
    egt,
    SelfLockingError,
    AnalysisError,
    "No consistent direction of power flow exists through the lossy meshes: the train self-locks under these loads."
);
pyo3::create_exception!(
    egt,
    NonFiniteError,
    AnalysisError,
    "A quantity or result is not finite: the inputs overflow double precision (`what`, `detail`)."
);
pyo3::create_exception!(
    egt,
    InternalError,
    EgtError,
    "A bug in egt (a Rust panic), reported instead of crashing the interpreter."
);

/// The binding's error: a core error, an error already in Python form, or a panic.
#[derive(Debug)]
pub enum Error {
    /// From egt-core.
    Core(egt_core::Error),
    /// Already a Python exception (argument conversion, ...).
    Py(PyErr),
    /// A caught panic, with its message.
    Panic(String),
    /// egt-fmu's shared library cannot be read (`Train.export_fmu`):
    /// `EgtError` of kind `io`, as the CLI's code for a file it cannot read.
    Library(String),
    /// egt-fmu's packager refused after the core's checks passed (two unit
    /// variables with one name, the archive writer): `EgtError` of kind `fmu`.
    Unit(String),
}

impl From<egt_core::Error> for Error {
    fn from(e: egt_core::Error) -> Self {
        Error::Core(e)
    }
}

impl From<PyErr> for Error {
    fn from(e: PyErr) -> Self {
        Error::Py(e)
    }
}

impl From<Error> for PyErr {
    fn from(e: Error) -> PyErr {
        match e {
            Error::Py(e) => e,
            Error::Core(e) => Python::attach(|py| core_to_py(py, &e)),
            Error::Panic(msg) => Python::attach(|py| {
                build::<InternalError>(
                    py,
                    format!("internal error (please report): {msg}"),
                    "panic",
                    &[],
                    &[],
                )
            }),
            Error::Library(msg) => Python::attach(|py| build::<EgtError>(py, msg, "io", &[], &[])),
            Error::Unit(msg) => Python::attach(|py| build::<EgtError>(py, msg, "fmu", &[], &[])),
        }
    }
}

/// Result alias for binding functions.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Run `f`, turning a panic into [`Error::Panic`] so it reaches Python as
/// `egt.InternalError` instead of pyo3's `PanicException` (a `BaseException`).
pub fn guard<T>(f: impl FnOnce() -> Result<T>) -> Result<T> {
    catch_unwind(AssertUnwindSafe(f)).unwrap_or_else(|p| Err(Error::Panic(panic_message(&*p))))
}

/// The text of a panic payload.
pub fn panic_message(p: &(dyn Any + Send)) -> String {
    if let Some(s) = p.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = p.downcast_ref::<String>() {
        s.clone()
    } else {
        "panic".to_string()
    }
}

/// A short, stable code for a core error (the `kind` attribute), used also for
/// per-row error codes in batches: the core's [`egt_core::Error::code`].
pub fn kind(e: &egt_core::Error) -> &'static str {
    e.code()
}

type Attr<'py> = (&'static str, Bound<'py, PyAny>);

/// Instantiate exception type `T` with `msg`, set `kind`, `names` and `attrs`.
fn build<T: PyTypeInfo>(
    py: Python<'_>,
    msg: String,
    kind: &str,
    names: &[String],
    attrs: &[Attr<'_>],
) -> PyErr {
    let made = (|| -> PyResult<Bound<'_, PyAny>> {
        let inst = py.get_type::<T>().call1((msg.clone(),))?;
        inst.setattr("kind", kind)?;
        inst.setattr("names", PyTuple::new(py, names)?)?;
        for (k, v) in attrs {
            inst.setattr(*k, v)?;
        }
        Ok(inst)
    })();
    match made {
        Ok(inst) => PyErr::from_value(inst),
        Err(e) => e,
    }
}

fn obj<'py, T>(py: Python<'py>, v: T) -> Bound<'py, PyAny>
where
    T: IntoPyObject<'py>,
{
    v.into_bound_py_any(py)
        .unwrap_or_else(|_| py.None().into_bound(py))
}

fn tuple<'py>(py: Python<'py>, items: &[String]) -> Bound<'py, PyAny> {
    match PyTuple::new(py, items) {
        Ok(t) => t.into_any(),
        Err(_) => py.None().into_bound(py),
    }
}

/// Map a core error to the Python exception of its family, with its attributes.
pub fn core_to_py(py: Python<'_>, e: &egt_core::Error) -> PyErr {
    map(py, e, e.to_string())
}

/// Map `e` to its exception with the message `msg`.
fn map(py: Python<'_>, e: &egt_core::Error, msg: String) -> PyErr {
    let k = kind(e);
    match e {
        egt_core::Error::Syntax(s) => {
            // serde_path_to_error writes `?` where it knows no field path.
            let path = s.path.as_deref().filter(|p| *p != "?");
            build::<SpecSyntaxError>(
                py,
                msg,
                k,
                &path.iter().map(|p| (*p).to_string()).collect::<Vec<_>>(),
                &[
                    ("source", obj(py, s.source_name.as_str())),
                    ("line", obj(py, s.line)),
                    ("column", obj(py, s.column)),
                    ("path", obj(py, path)),
                    ("message", obj(py, s.message.as_str())),
                ],
            )
        }
        egt_core::Error::Spec { path, kind: sk } => {
            let (names, value, suggestion): (Vec<String>, Option<f64>, Option<String>) = match sk {
                SpecErrorKind::UnknownLink { name, suggestion } => {
                    (vec![name.clone()], None, suggestion.clone())
                }
                SpecErrorKind::DuplicateLink { name } => (vec![name.clone()], None, None),
                SpecErrorKind::SelfLoop { link } => (vec![link.clone()], None, None),
                SpecErrorKind::Duplicate { first, .. } => (vec![first.clone()], None, None),
                #[allow(clippy::cast_precision_loss)]
                SpecErrorKind::InvalidTeeth { value } => (Vec::new(), Some(*value as f64), None),
                SpecErrorKind::NonFinite { value } | SpecErrorKind::OutOfRange { value, .. } => {
                    (Vec::new(), Some(*value), None)
                }
                _ => (Vec::new(), None, None),
            };
            build::<SpecError>(
                py,
                msg,
                k,
                &names,
                &[
                    ("path", obj(py, path.as_str())),
                    ("value", obj(py, value)),
                    ("suggestion", obj(py, suggestion)),
                ],
            )
        }
        egt_core::Error::Topology(t) => {
            let none = Vec::new();
            let (links, pairs, levels, dof): (&[String], &[String], &[String], Option<i64>) =
                match t {
                    CoreTopo::Disconnected { links }
                    | CoreTopo::NoTurningPath { links }
                    | CoreTopo::RevoluteCycle { links }
                    | CoreTopo::Locked { links }
                    | CoreTopo::NonPlanar { links }
                    | CoreTopo::FreeLinks { links } => (links, &none, &none, None),
                    CoreTopo::AmbiguousTransferVertex { pair, candidates } => {
                        (candidates, std::slice::from_ref(pair), &none, None)
                    }
                    CoreTopo::NoTransferVertex { pair, levels } => {
                        (&none, std::slice::from_ref(pair), levels, None)
                    }
                    CoreTopo::Redundant { pairs } => (&none, pairs, &none, None),
                    CoreTopo::NoMobility { dof } => (&none, &none, &none, Some(*dof)),
                    CoreTopo::Fractionated { link, .. } => {
                        (std::slice::from_ref(link), &none, &none, None)
                    }
                    _ => (&none, &none, &none, None),
                };
            let mut names: Vec<String> = links.to_vec();
            names.extend(pairs.iter().cloned());
            let parts: Vec<Vec<String>> = match t {
                CoreTopo::Fractionated { parts, .. } => parts.clone(),
                _ => Vec::new(),
            };
            build::<TopologyError>(
                py,
                msg,
                k,
                &names,
                &[
                    ("links", tuple(py, links)),
                    ("pairs", tuple(py, pairs)),
                    ("levels", tuple(py, levels)),
                    ("dof", obj(py, dof)),
                    ("parts", obj(py, parts)),
                ],
            )
        }
        egt_core::Error::Analysis(a) => analysis_to_py(py, a, msg, k),
        egt_core::Error::Transmission(t) => transmission_to_py(py, t, msg, k),
        _ => build::<EgtError>(py, msg, k, &[], &[]),
    }
}

/// state, elements, gear pairs, free links, DOF, input, output.
type StateFields<'a> = (
    Option<&'a String>,
    &'a [String],
    &'a [String],
    &'a [String],
    Option<usize>,
    Option<&'a String>,
    Option<&'a String>,
);

fn transmission_to_py(py: Python<'_>, t: &CoreTransmission, msg: String, k: &str) -> PyErr {
    let none: Vec<String> = Vec::new();
    let (state, elements, gears, free, dof, input, output): StateFields<'_> = match t {
        CoreTransmission::InState { state, cause } => {
            let err = map(py, cause, msg);
            let _ = err.value(py).setattr("state", state.as_str());
            return err;
        }
        CoreTransmission::UnknownState { state, .. } => {
            (Some(state), &none, &none, &none, None, None, None)
        }
        CoreTransmission::Underconstrained { state, dof, free } => {
            (Some(state), &none, &none, free, Some(*dof), None, None)
        }
        CoreTransmission::Locked { state, elements } => {
            (Some(state), elements, &none, &none, Some(0), None, None)
        }
        CoreTransmission::Redundant {
            state,
            elements,
            gears,
            dof,
        } => (Some(state), elements, gears, &none, Some(*dof), None, None),
        CoreTransmission::InputHeld {
            state,
            input,
            moving,
        } => (Some(state), &none, &none, moving, None, Some(input), None),
        CoreTransmission::OutputHeld { state, output } => {
            (Some(state), &none, &none, &none, None, None, Some(output))
        }
        _ => (None, &none, &none, &none, None, None, None),
    };
    let suggestion = match t {
        CoreTransmission::UnknownState { suggestion, .. } => suggestion.clone(),
        _ => None,
    };
    let mut names: Vec<String> = state.into_iter().cloned().collect();
    names.extend(elements.iter().cloned());
    names.extend(gears.iter().cloned());
    names.extend(free.iter().cloned());
    names.extend(input.into_iter().cloned());
    names.extend(output.into_iter().cloned());
    build::<TransmissionError>(
        py,
        msg,
        k,
        &names,
        &[
            ("state", obj(py, state.map(String::as_str))),
            ("elements", tuple(py, elements)),
            ("gears", tuple(py, gears)),
            ("free", tuple(py, free)),
            ("dof", obj(py, dof)),
            ("input", obj(py, input.map(String::as_str))),
            ("output", obj(py, output.map(String::as_str))),
            ("suggestion", obj(py, suggestion)),
        ],
    )
}

fn analysis_to_py(py: Python<'_>, a: &CoreAnalysis, msg: String, k: &str) -> PyErr {
    match a {
        CoreAnalysis::WrongInputCount { dof, given, what } => build::<InputError>(
            py,
            msg,
            k,
            &[],
            &[
                ("dof", obj(py, *dof)),
                ("given", obj(py, *given)),
                ("what", obj(py, what.as_str())),
            ],
        ),
        CoreAnalysis::FrameInput { link } => build::<InputError>(
            py,
            msg,
            k,
            std::slice::from_ref(link),
            &[("link", obj(py, link.as_str()))],
        ),
        CoreAnalysis::Underdetermined { free } => {
            build::<UnderdeterminedError>(py, msg, k, free, &[("free", tuple(py, free))])
        }
        CoreAnalysis::Inconsistent { conflicting } => build::<InconsistentError>(
            py,
            msg,
            k,
            conflicting,
            &[("conflicting", tuple(py, conflicting))],
        ),
        CoreAnalysis::Singular { what, detail } => build::<SingularError>(
            py,
            msg,
            k,
            std::slice::from_ref(what),
            &[
                ("what", obj(py, what.as_str())),
                ("detail", obj(py, detail.as_str())),
            ],
        ),
        CoreAnalysis::IllConditioned {
            what,
            condition,
            threshold,
        } => build::<IllConditionedError>(
            py,
            msg,
            k,
            std::slice::from_ref(what),
            &[
                ("what", obj(py, what.as_str())),
                ("condition", obj(py, *condition)),
                ("threshold", obj(py, *threshold)),
            ],
        ),
        CoreAnalysis::MissingData {
            what,
            analysis,
            hint,
        } => build::<MissingDataError>(
            py,
            msg,
            k,
            std::slice::from_ref(what),
            &[
                ("what", obj(py, what.as_str())),
                ("analysis", obj(py, analysis.as_str())),
                ("hint", obj(py, hint.as_str())),
            ],
        ),
        CoreAnalysis::SelfLocking => build::<SelfLockingError>(py, msg, k, &[], &[]),
        CoreAnalysis::NonFinite { what, detail } => build::<NonFiniteError>(
            py,
            msg,
            k,
            std::slice::from_ref(what),
            &[
                ("what", obj(py, what.as_str())),
                ("detail", obj(py, detail.as_str())),
            ],
        ),
        CoreAnalysis::RepeatedLink { link, .. } => build::<InputError>(
            py,
            msg,
            k,
            std::slice::from_ref(link),
            &[("link", obj(py, link.as_str()))],
        ),
        CoreAnalysis::OverConstrained { .. } => build::<InputError>(py, msg, k, &[], &[]),
        CoreAnalysis::ConfigurationDependent { links, .. } => {
            build::<AnalysisError>(py, msg, k, links, &[])
        }
        // The rest (iterations that did not converge, an indefinite [M], directions undecided, words).
        _ => build::<AnalysisError>(py, msg, k, &[], &[]),
    }
}

/// A malformed argument (shapes, unknown keywords): `egt.ArgumentError`, an
/// `EgtError` that is also a `ValueError` (defined in `egt._args`), so that
/// no bad input escapes the egt hierarchy; a plain `ValueError` only if that
/// module cannot be imported.
pub fn value_error(msg: impl Into<String>) -> Error {
    let msg = msg.into();
    Error::Py(Python::attach(|py| {
        py.import("egt._args")
            .and_then(|m| m.getattr("ArgumentError"))
            .and_then(|cls| cls.call1((msg.clone(),)))
            .map_or_else(
                |_| pyo3::exceptions::PyValueError::new_err(msg.clone()),
                PyErr::from_value,
            )
    }))
}

/// Register the exception classes on the module, with class-level `None`
/// defaults for every attribute so that each attribute exists on each class.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    let classes: [(&str, Bound<'_, PyType>, &[&str]); 15] = [
        (
            "EgtError",
            py.get_type::<EgtError>(),
            &["kind", "names", "state"],
        ),
        (
            "SpecError",
            py.get_type::<SpecError>(),
            &["path", "value", "suggestion"],
        ),
        (
            "SpecSyntaxError",
            py.get_type::<SpecSyntaxError>(),
            &["source", "line", "column", "message"],
        ),
        (
            "TopologyError",
            py.get_type::<TopologyError>(),
            &["links", "pairs", "levels", "dof", "parts"],
        ),
        (
            "TransmissionError",
            py.get_type::<TransmissionError>(),
            &[
                "elements",
                "gears",
                "free",
                "dof",
                "input",
                "output",
                "suggestion",
            ],
        ),
        ("AnalysisError", py.get_type::<AnalysisError>(), &[]),
        (
            "InputError",
            py.get_type::<InputError>(),
            &["dof", "given", "what", "link"],
        ),
        (
            "UnderdeterminedError",
            py.get_type::<UnderdeterminedError>(),
            &["free"],
        ),
        (
            "InconsistentError",
            py.get_type::<InconsistentError>(),
            &["conflicting"],
        ),
        (
            "SingularError",
            py.get_type::<SingularError>(),
            &["what", "detail"],
        ),
        (
            "IllConditionedError",
            py.get_type::<IllConditionedError>(),
            &["what", "condition", "threshold"],
        ),
        (
            "MissingDataError",
            py.get_type::<MissingDataError>(),
            &["what", "analysis", "hint"],
        ),
        ("SelfLockingError", py.get_type::<SelfLockingError>(), &[]),
        (
            "NonFiniteError",
            py.get_type::<NonFiniteError>(),
            &["what", "detail"],
        ),
        ("InternalError", py.get_type::<InternalError>(), &[]),
    ];
    for (name, ty, attrs) in classes {
        for a in attrs {
            ty.setattr(*a, py.None())?;
        }
        m.add(name, ty)?;
    }
    Ok(())
}

//! `egt.Train.export_fmu`: egt-fmu's packager over a train and its spec text,
//! with egt-fmu's shared library read from `EGT_FMU_LIBRARY`, else the file
//! the wheel carries (docs/fmu.md). Python writes the unit it returns.

use std::path::PathBuf;

use egt_core::Format;
use pyo3::prelude::*;
use pyo3::types::PyBytes;

use crate::errors::{Error, Result, guard, value_error};
use crate::train::{TrainCore, format_of};

/// The environment variable that names egt-fmu's shared library (as for `egt fmu`).
const LIBRARY_VARIABLE: &str = "EGT_FMU_LIBRARY";

/// The `.fmu` of `core` (read from `text` in `format`) as bytes. Its model
/// identifier is
/// `model_identifier`, else `stem` (the output file's) made a C identifier;
/// the library is `EGT_FMU_LIBRARY`, else `bundled`.
#[pyfunction]
#[pyo3(signature = (core, text, format, stem, model_identifier, bundled))]
pub fn fmu_package<'py>(
    py: Python<'py>,
    core: &TrainCore,
    text: &str,
    format: &str,
    stem: &str,
    model_identifier: Option<&str>,
    bundled: Option<PathBuf>,
) -> Result<Bound<'py, PyBytes>> {
    let json = format_of(format)? == Format::Json;
    let id = match model_identifier {
        Some(id) if id != egt_fmu::model_identifier(id) => {
            return Err(value_error(format!(
                "model_identifier `{id}` is not a C identifier (letters, digits and `_`, not starting with a digit)"
            )));
        }
        Some(id) => id.to_string(),
        None => egt_fmu::model_identifier(stem),
    };
    let env = std::env::var_os(LIBRARY_VARIABLE).map(PathBuf::from);
    let from_env = env.is_some();
    let Some(library) = env.or(bundled) else {
        return Err(Error::Library(format!(
            "this egt module carries no {}: set {LIBRARY_VARIABLE} to one (`cargo build --release -p egt-fmu` builds it)",
            egt_fmu::LIBRARY_FILE
        )));
    };
    let bytes = std::fs::read(&library).map_err(|e| {
        let origin = if from_env {
            format!("{LIBRARY_VARIABLE}={}", library.display())
        } else {
            format!(
                "{} (the wheel's; set {LIBRARY_VARIABLE} to use another)",
                library.display()
            )
        };
        Error::Library(format!("egt-fmu's shared library {origin}: {e}"))
    })?;
    let unit = guard(|| {
        py.detach(|| {
            // Shift elements make a transmission unit, which needs gear
            // states (the core's own error); a train without elements is a
            // unit of its links.
            if !core.train.elements().is_empty() {
                core.train.checked_transmission()?;
            }
            egt_fmu::package(&core.train, text, json, &id, &bytes).map_err(|e| Error::Unit(e.0))
        })
    })?;
    Ok(PyBytes::new(py, &unit))
}

//! `egt.Train.modes`: the natural frequencies and modes of the lumped
//! torsional model (docs/vibration.md), bare or in a gear state, with the
//! Campbell crossings when a speed range is given.

use egt_core::ModesRequest;
use pyo3::prelude::*;

use crate::convert;
use crate::errors::{Result, guard};
use crate::train::TrainCore;

/// The torsional modes of the train (`egt modes`).
#[pyfunction]
#[pyo3(signature = (core, state = None, campbell = None))]
pub fn modes<'py>(
    py: Python<'py>,
    core: &TrainCore,
    state: Option<String>,
    campbell: Option<(f64, f64)>,
) -> Result<Bound<'py, PyAny>> {
    guard(|| {
        let t = &core.train;
        let req = ModesRequest {
            state,
            campbell: campbell.map(|(lo, hi)| [lo, hi]),
        };
        let m = t.modes(&req)?;
        let doc = egt_views::modes(t, &core.source, &m);
        convert::documented(py, &m, doc)
    })
}

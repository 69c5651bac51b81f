//! `egt.Train.modes`: the natural frequencies and modes of the lumped
//! torsional model (docs/vibration.md), bare or in a gear state, with the
//! Campbell crossings when a speed range is given, and the static deflection
//! under a steady input torque in a gear state.

use egt_core::ModesRequest;
use pyo3::prelude::*;

use crate::convert;
use crate::errors::{Result, guard};
use crate::train::TrainCore;

/// The torsional modes of the train (`egt modes`).
#[pyfunction]
#[pyo3(signature = (core, state = None, campbell = None, static_torque = None))]
pub fn modes<'py>(
    py: Python<'py>,
    core: &TrainCore,
    state: Option<String>,
    campbell: Option<(f64, f64)>,
    static_torque: Option<f64>,
) -> Result<Bound<'py, PyAny>> {
    guard(|| {
        let t = &core.train;
        let req = ModesRequest {
            state,
            campbell: campbell.map(|(lo, hi)| [lo, hi]),
        };
        let m = t.modes(&req)?;
        let mut doc = egt_views::modes(t, &core.source, &m);
        if let (Some(torque), Some(state), Ok(doc)) = (static_torque, &req.state, doc.as_mut()) {
            let check = t.static_check_in_gear(state, torque)?;
            let part = egt_views::modes::statics(t, &m, &check, torque);
            doc["static_load"] = serde_json::to_value(part).unwrap_or_default();
        }
        convert::documented(py, &m, doc)
    })
}

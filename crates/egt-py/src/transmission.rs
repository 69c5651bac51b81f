//! Gear states of an automatic transmission for `egt.Train.gear` and
//! `egt.Train.shift_table`: the core's results through the one conversion
//! (`convert::to_py`; ids are indices, exact values `"p/q"` text).

use pyo3::prelude::*;

use crate::convert;
use crate::errors::{Result, guard};
use crate::train::TrainCore;

/// One gear state, per unit input speed and torque.
#[pyfunction]
pub fn gear<'py>(py: Python<'py>, core: &TrainCore, state: &str) -> Result<Bound<'py, PyAny>> {
    guard(|| {
        let g = core.train.analyse_gear(state)?;
        // Forward or reverse is decided across the states (the sign most
        // ratios share); when another state cannot be analysed, by the sign.
        let forward = core
            .train
            .shift_table()
            .map_or(g.ratio > 0.0, |t| t.forward[g.index]);
        convert::documented(py, &g, egt_views::gear(&core.train, &g, forward))
    })
}

/// Every gear state and the table across them (ratios, steps, spread, shifts).
#[pyfunction]
pub fn shift_table<'py>(py: Python<'py>, core: &TrainCore) -> Result<Bound<'py, PyAny>> {
    guard(|| {
        let table = core.train.shift_table()?;
        let doc = egt_views::shift(&core.train, &core.source, &table);
        convert::documented(py, &table, doc)
    })
}

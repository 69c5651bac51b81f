//! Gear states of an automatic transmission for `egt.Train.gear` and
//! `egt.Train.shift_table`: the core's results through the one conversion
//! (`convert::to_py`; ids are indices, exact values `"p/q"` text).

use pyo3::prelude::*;

use crate::convert::to_py;
use crate::errors::{Result, guard};
use crate::train::TrainCore;

/// One gear state, per unit input speed and torque.
#[pyfunction]
pub fn gear<'py>(py: Python<'py>, core: &TrainCore, state: &str) -> Result<Bound<'py, PyAny>> {
    guard(|| to_py(py, &core.train.analyse_gear(state)?))
}

/// Every gear state and the table across them (ratios, steps, spread, shifts).
#[pyfunction]
pub fn shift_table<'py>(py: Python<'py>, core: &TrainCore) -> Result<Bound<'py, PyAny>> {
    guard(|| to_py(py, &core.train.shift_table()?))
}

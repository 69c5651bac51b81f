//! The native module `egt._egt`: thin pyo3 bindings over egt-core.
//!
//! Every binding converts names to ids, calls the core and converts back; the
//! Pythonic surface (result classes, NumPy argument handling, SymPy export)
//! lives in the `egt` package (`python/egt`). Errors map to Python exceptions
//! in exactly one place, [`errors`].

mod atlas;
mod batch;
mod convert;
mod design;
mod errors;
mod fmu;
mod motion;
mod structure;
mod train;
mod transmission;
mod vibration;

use pyo3::prelude::*;

/// Run the `egt` command line with `args` (without the program name) and
/// return its exit code; output goes to the process's stdout and stderr.
/// The GIL is released while it runs.
#[cfg(feature = "command")]
#[pyfunction]
fn cli(py: Python<'_>, args: Vec<String>) -> u8 {
    py.detach(|| egt_cli::run(std::iter::once("egt".to_string()).chain(args)))
}

/// The native part of the `egt` package.
#[pymodule]
fn _egt(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<train::TrainCore>()?;
    m.add_function(wrap_pyfunction!(structure::structure, m)?)?;
    m.add_class::<batch::BatchPlanCore>()?;
    m.add_function(wrap_pyfunction!(batch::batch_plan, m)?)?;
    m.add_function(wrap_pyfunction!(batch::ratios_from_teeth, m)?)?;
    m.add_function(wrap_pyfunction!(motion::stability, m)?)?;
    m.add_function(wrap_pyfunction!(motion::simulate, m)?)?;
    m.add_function(wrap_pyfunction!(motion::shift_sim, m)?)?;
    m.add_function(wrap_pyfunction!(motion::shift_named, m)?)?;
    m.add_function(wrap_pyfunction!(motion::shift_names, m)?)?;
    m.add_function(wrap_pyfunction!(vibration::modes, m)?)?;
    m.add_function(wrap_pyfunction!(transmission::gear, m)?)?;
    m.add_function(wrap_pyfunction!(transmission::shift_table, m)?)?;
    #[cfg(feature = "command")]
    m.add_function(wrap_pyfunction!(cli, m)?)?;
    m.add_function(wrap_pyfunction!(fmu::fmu_package, m)?)?;
    m.add_function(wrap_pyfunction!(atlas::atlas, m)?)?;
    m.add_function(wrap_pyfunction!(atlas::atlas_member, m)?)?;
    m.add_class::<design::SearchCore>()?;
    m.add_function(wrap_pyfunction!(design::search_inputs, m)?)?;
    errors::register(m)?;
    // The module is private: the package's `__all__` lists the public names,
    // once. pyo3 keeps a list as it adds each name; the stub would repeat it.
    m.delattr("__all__")?;
    Ok(())
}

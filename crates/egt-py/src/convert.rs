//! Conversions between Python values and egt-core types: link names to ids,
//! exact rationals to `"p/q"` text (the Python side makes `fractions.Fraction`s),
//! vectors and matrices to NumPy arrays.

use egt_core::Extra;
use egt_core::numerics::exact::{self, Q};
use egt_core::spec::ElementKind;
use egt_core::{LinkId, Ratio, Train};
use nalgebra::DMatrix;
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::{Error, Result, value_error};

/// Resolve a link name; an unknown name is a spec error at `where_` with a suggestion.
pub fn link(train: &Train, name: &str, where_: &str) -> Result<LinkId> {
    Ok(train.resolve(name, where_)?)
}

/// Resolve a list of link names.
pub fn links(train: &Train, names: &[String], where_: &str) -> Result<Vec<LinkId>> {
    names
        .iter()
        .enumerate()
        .map(|(k, n)| link(train, n, &format!("{where_}[{k}]")))
        .collect()
}

/// Resolve `(name, value)` pairs.
pub fn valued(train: &Train, pairs: &[(String, f64)], where_: &str) -> Result<Vec<(LinkId, f64)>> {
    pairs
        .iter()
        .map(|(n, v)| Ok((link(train, n, &format!("{where_}.{n}"))?, *v)))
        .collect()
}

/// The constraint rows of engaged shift elements (brakes hold, clutches join;
/// an engaged one-way element acts as its locked counterpart).
pub fn engaged(train: &Train, names: &[String]) -> Result<Vec<Extra>> {
    names
        .iter()
        .enumerate()
        .map(|(k, n)| {
            let e = train
                .elements()
                .iter()
                .find(|e| &e.name == n)
                .ok_or_else(|| {
                    egt_core::Error::invalid(
                        format!("engaged[{k}]"),
                        format!(
                            "unknown shift element `{n}`{}",
                            egt_core::error::suggest(
                                n,
                                train.elements().iter().map(|e| e.name.as_str())
                            )
                            .map(|s| format!(" (did you mean `{s}`?)"))
                            .unwrap_or_default()
                        ),
                    )
                })?;
            Ok(match e.kind {
                ElementKind::Brake | ElementKind::OneWayBrake => Extra::Hold(e.links[0]),
                ElementKind::Clutch | ElementKind::OneWayClutch => {
                    Extra::Join(e.links[0], e.links[1])
                }
            })
        })
        .collect()
}

/// Parse an exact value written as text (`"p/q"`, `"-3"`, `"2.5"`).
pub fn rational(text: &str, where_: &str) -> Result<Q> {
    exact::parse_finite(text)
        .map(|(q, _)| q)
        .map_err(|e| Error::Core(egt_core::Error::invalid(where_, format!("`{text}`: {e}"))))
}

/// `p/q` text of an exact value.
pub fn q_text(x: &Q) -> String {
    exact::display(x)
}

/// Set a gear pair's Willis ratio on `d`: `ratio` (float) and `ratio_exact`
/// (`p/q` text), each `None` when not known.
pub fn set_ratio(d: &Bound<'_, PyDict>, ratio: Option<&Ratio>) -> Result<()> {
    d.set_item("ratio", ratio.map(|r| r.value))?;
    d.set_item(
        "ratio_exact",
        ratio.and_then(|r| r.exact.as_ref()).map(q_text),
    )?;
    Ok(())
}

/// A vector as a 1-D NumPy array.
pub fn vec1<'py, T: numpy::Element>(py: Python<'py>, v: Vec<T>) -> Bound<'py, PyArray1<T>> {
    PyArray1::from_vec(py, v)
}

/// A row-major buffer as a 2-D NumPy array.
pub fn mat2<'py>(
    py: Python<'py>,
    rows: usize,
    cols: usize,
    data: Vec<f64>,
) -> Result<Bound<'py, PyArray2<f64>>> {
    mat2_ordered(py, rows, cols, data, false)
}

/// A buffer as a 2-D NumPy array: row-major, or column-major (`fortran`)
/// into a Fortran-ordered array (no copy: each column is contiguous).
pub fn mat2_ordered<'py>(
    py: Python<'py>,
    rows: usize,
    cols: usize,
    data: Vec<f64>,
    fortran: bool,
) -> Result<Bound<'py, PyArray2<f64>>> {
    use numpy::ndarray::ShapeBuilder;
    let a = Array2::from_shape_vec((rows, cols).set_f(fortran), data)
        .map_err(|e| crate::errors::value_error(e.to_string()))?;
    Ok(a.into_pyarray(py))
}

/// A nalgebra matrix (column-major) as a 2-D NumPy array.
pub fn dmatrix<'py>(py: Python<'py>, m: &DMatrix<f64>) -> Result<Bound<'py, PyArray2<f64>>> {
    let mut out = Vec::with_capacity(m.nrows() * m.ncols());
    for r in 0..m.nrows() {
        for c in 0..m.ncols() {
            out.push(m[(r, c)]);
        }
    }
    mat2(py, m.nrows(), m.ncols(), out)
}

/// A core result as Python objects (dicts, lists, numbers, strings, None):
/// the one conversion of every result, through its `Serialize` form, so that
/// no field is listed by hand here. Ids are indices; exact values are text.
///
/// # Errors
/// A result that does not serialize (a non-finite number becomes None).
pub fn to_py<'py>(py: Python<'py>, value: &impl serde::Serialize) -> Result<Bound<'py, PyAny>> {
    let text = serde_json::to_string(value).map_err(|e| value_error(e.to_string()))?;
    Ok(py.import("json")?.call_method1("loads", (text,))?)
}

/// A core result with the CLI's JSON document of it (`egt_views`),
/// as the pair `[result, document]`: the Python result classes read the
/// first and return the second from `to_dict()`, so that the CLI and Python
/// give one shape.
///
/// # Errors
/// A result or document that does not serialize.
pub fn documented<'py>(
    py: Python<'py>,
    value: &impl serde::Serialize,
    document: serde_json::Result<serde_json::Value>,
) -> Result<Bound<'py, PyAny>> {
    let document = document.map_err(|e| value_error(e.to_string()))?;
    to_py(py, &(value, document))
}

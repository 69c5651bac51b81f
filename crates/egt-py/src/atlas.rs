//! `egt.atlas(links, dof, level, part, fractionation, search)`: the atlas of non-isomorphic gear-train
//! graphs (egt_core::synthesis) as a list of dicts, one per member; and
//! `atlas_member(train, level)`, the member a train is.

use egt_core::synthesis::hypertree::enumerate_by_levels;
use egt_core::synthesis::{
    AtlasMember, AtlasRequest, Fractionation, GraphLevel, enumerate, member,
};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::{Result, guard};
use crate::train::TrainCore;

fn level_of(level: &str) -> Result<GraphLevel> {
    match level {
        "rotation" => Ok(GraphLevel::Rotation),
        "displacement" => Ok(GraphLevel::Displacement),
        other => Err(egt_core::Error::invalid(
            "level",
            format!("`{other}`: expected `rotation` or `displacement`"),
        )
        .into()),
    }
}

fn to_dict<'py>(py: Python<'py>, m: AtlasMember) -> Result<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("adjacency", m.adjacency)?;
    d.set_item("links", m.links)?;
    d.set_item("dof", m.dof)?;
    d.set_item("gears", m.gears)?;
    d.set_item("carriers", m.carriers)?;
    d.set_item("axes", m.axes)?;
    d.set_item("coaxial", m.coaxial)?;
    d.set_item("coaxial_triples", m.coaxial_triples)?;
    d.set_item("displacement_graphs", m.displacement_graphs)?;
    d.set_item("code", m.code)?;
    Ok(d)
}

/// Every member with `links` links and `dof` DOF, at level `rotation` or
/// `displacement`. Its defaults are `egt.atlas`'s, which checks the numbers.
#[pyfunction]
#[pyo3(signature = (links, dof, level, part, fractionation, search = "trees"))]
pub fn atlas<'py>(
    py: Python<'py>,
    links: usize,
    dof: usize,
    level: &str,
    part: Option<(usize, usize)>,
    fractionation: &str,
    search: &str,
) -> Result<Vec<Bound<'py, PyDict>>> {
    let by_levels = match search {
        "trees" => false,
        "levels" => true,
        other => {
            return Err(egt_core::Error::invalid(
                "search",
                format!("`{other}`: expected `trees` or `levels`"),
            )
            .into());
        }
    };
    let level = level_of(level)?;
    let fractionation = match fractionation {
        "layout" => Fractionation::Layout,
        "kinematic" => Fractionation::Kinematic,
        other => {
            return Err(egt_core::Error::invalid(
                "fractionation",
                format!("`{other}`: expected `layout` or `kinematic`"),
            )
            .into());
        }
    };
    let req = AtlasRequest {
        links,
        dof,
        level,
        part,
        fractionation,
    };
    let members = guard(|| {
        Ok(if by_levels {
            enumerate_by_levels(&req)?
        } else {
            enumerate(&req)?
        })
    })?;
    members.into_iter().map(|m| to_dict(py, m)).collect()
}

/// The member `core`'s train is, at level `rotation` or `displacement`.
#[pyfunction]
#[pyo3(signature = (core, level = "rotation"))]
pub fn atlas_member<'py>(
    py: Python<'py>,
    core: &TrainCore,
    level: &str,
) -> Result<Bound<'py, PyDict>> {
    let level = level_of(level)?;
    let m = guard(|| Ok(member(&core.train, level)?))?;
    to_dict(py, m)
}

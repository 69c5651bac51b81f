//! `egt.atlas(links, dof, level, part)`: the atlas of non-isomorphic gear-train
//! graphs (egt_core::synthesis) as a list of dicts, one per member.

use egt_core::synthesis::{AtlasRequest, GraphLevel, enumerate};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::{Result, guard};

/// Every member with `links` links and `dof` DOF, at level `rotation` or `displacement`.
#[pyfunction]
#[pyo3(signature = (links, dof = 1, level = "rotation", part = None))]
pub fn atlas<'py>(
    py: Python<'py>,
    links: usize,
    dof: usize,
    level: &str,
    part: Option<(usize, usize)>,
) -> Result<Vec<Bound<'py, PyDict>>> {
    let level = match level {
        "rotation" => GraphLevel::Rotation,
        "displacement" => GraphLevel::Displacement,
        other => {
            return Err(egt_core::Error::invalid(
                "level",
                format!("`{other}`: expected `rotation` or `displacement`"),
            )
            .into());
        }
    };
    let members = guard(|| {
        Ok(enumerate(&AtlasRequest {
            links,
            dof,
            level,
            part,
        })?)
    })?;
    let mut out = Vec::with_capacity(members.len());
    for m in members {
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
        out.push(d);
    }
    Ok(out)
}

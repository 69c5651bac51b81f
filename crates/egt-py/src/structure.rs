//! The train's structure for computer algebra (`egt.Train.to_sympy`): which
//! links each Willis equation relates (eq. 2), each link's chain of carriers
//! and axis offsets along its tree path (eq. 4), copies and data. The SymPy
//! objects are built from this in `python/egt/sympy_export.py`.

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::convert;
use crate::errors::{Result, guard};
use crate::train::TrainCore;

/// The structure of a train as plain Python values.
#[pyfunction]
pub fn structure<'py>(py: Python<'py>, core: &TrainCore) -> Result<Bound<'py, PyDict>> {
    guard(|| {
        let t = &core.train;
        let name = |l: egt_core::LinkId| t.link_name(l).to_string();
        let level = |l: egt_core::LevelId| t.level_name(l).to_string();
        let d = PyDict::new(py);
        d.set_item("frame", name(t.frame()))?;
        d.set_item("levels", t.levels().to_vec())?;
        d.set_item(
            "coordinates",
            t.coordinates().iter().map(|&l| name(l)).collect::<Vec<_>>(),
        )?;
        let links = PyList::empty(py);
        for (id, l) in t.links_with_ids() {
            let ld = PyDict::new(py);
            ld.set_item("name", l.name.as_str())?;
            ld.set_item("coordinate", t.coordinate(id))?;
            ld.set_item("copies", l.copies)?;
            ld.set_item("inertia", l.inertia)?;
            ld.set_item("mass", l.mass)?;
            ld.set_item("sized", l.sized)?;
            ld.set_item(
                "parent",
                t.tree()
                    .parent(id)
                    .map(|(p, r)| (name(p), level(t.revolutes()[r.index()].level))),
            )?;
            // eq. (4): the carriers along the tree path where the level changes.
            ld.set_item(
                "chain",
                t.offset_chain(id)
                    .into_iter()
                    .map(|(c, lv)| (name(c), level(lv[0]), level(lv[1])))
                    .collect::<Vec<_>>(),
            )?;
            links.append(ld)?;
        }
        d.set_item("links", links)?;
        let circuits = PyList::empty(py);
        for (c, g) in t.circuits().iter().zip(t.gears()) {
            let cd = PyDict::new(py);
            cd.set_item("gear", g.name.as_str())?;
            cd.set_item("gear_i", name(c.gear_i))?;
            cd.set_item("gear_j", name(c.gear_j))?;
            cd.set_item("carrier", name(c.carrier))?;
            cd.set_item("level_i", level(c.level_i))?;
            cd.set_item("level_j", level(c.level_j))?;
            convert::set_ratio(&cd, g.ratio.as_ref())?;
            cd.set_item("radii", g.radii.map(|r| (r[0], r[1])))?;
            circuits.append(cd)?;
        }
        d.set_item("circuits", circuits)?;
        let (offsets, _) = t.axis_offsets();
        d.set_item(
            "offsets",
            offsets
                .iter()
                .map(|o| (level(o.levels[0]), level(o.levels[1]), o.distance))
                .collect::<Vec<_>>(),
        )?;
        Ok(d)
    })
}

//! Gear states of an automatic transmission for `egt.Train.gear` and
//! `egt.Train.shift_table`: every result with element, gear-pair and link
//! names in place of ids, exact values as `"p/q"` text.

use egt_core::analysis::transmission::{Freewheel, GearAnalysis, ShiftKind};
use egt_core::{ElementId, Train};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::convert;
use crate::errors::{Result, guard};
use crate::train::TrainCore;

fn element(t: &Train, e: ElementId) -> String {
    t.elements()[e.index()].name.clone()
}

fn elements(t: &Train, es: &[ElementId]) -> Vec<String> {
    es.iter().map(|&e| element(t, e)).collect()
}

fn gear_dict<'py>(py: Python<'py>, t: &Train, g: &GearAnalysis) -> Result<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("state", g.state.as_str())?;
    d.set_item("index", g.index)?;
    d.set_item("engaged", elements(t, &g.engaged))?;
    d.set_item("ratio", g.ratio)?;
    d.set_item("ratio_exact", g.ratio_exact.as_ref().map(convert::q_text))?;
    d.set_item(
        "speeds",
        t.links()
            .iter()
            .zip(&g.speed)
            .map(|(l, s)| (l.name.clone(), *s))
            .collect::<Vec<_>>(),
    )?;
    d.set_item(
        "speeds_exact",
        g.speed_exact.as_ref().map(|v| {
            t.links()
                .iter()
                .zip(v)
                .map(|(l, s)| (l.name.clone(), s.as_ref().map(convert::q_text)))
                .collect::<Vec<_>>()
        }),
    )?;
    d.set_item(
        "relative",
        g.relative
            .iter()
            .map(|r| {
                (
                    t.link_name(r.link).to_string(),
                    t.link_name(r.carrier).to_string(),
                    r.speed,
                )
            })
            .collect::<Vec<_>>(),
    )?;
    let slips = PyList::empty(py);
    for s in &g.slips {
        slips.append((
            element(t, s.element),
            s.speed,
            s.exact.as_ref().map(convert::q_text),
            s.freewheel.map(|f| match f {
                Freewheel::Overruns => "overruns",
                Freewheel::Idle => "idle",
                Freewheel::Locks => "locks",
            }),
        ))?;
    }
    d.set_item("slips", slips)?;
    d.set_item("output_torque", g.output_torque)?;
    d.set_item("housing_torque", g.housing_torque)?;
    d.set_item(
        "elements",
        g.elements
            .iter()
            .map(|e| (element(t, e.element), e.torque, e.holds, e.parallel))
            .collect::<Vec<_>>(),
    )?;
    d.set_item(
        "meshes",
        g.meshes
            .iter()
            .map(|m| {
                (
                    t.gears()[m.gear.index()].name.clone(),
                    m.multiplier,
                    m.force.map(|f| (f[0], f[1])),
                )
            })
            .collect::<Vec<_>>(),
    )?;
    let power = match &g.power {
        Some(p) => {
            let pd = PyDict::new(py);
            pd.set_item("efficiency", p.efficiency)?;
            pd.set_item("output_torque", p.output_torque)?;
            pd.set_item("loss", p.loss)?;
            pd.set_item("circulation_ratio", p.circulation_ratio)?;
            pd.set_item(
                "circulating",
                p.circulating.as_ref().map(|(gs, ls)| {
                    (
                        gs.iter()
                            .map(|g| t.gears()[g.index()].name.clone())
                            .collect::<Vec<_>>(),
                        ls.iter()
                            .map(|&l| t.link_name(l).to_string())
                            .collect::<Vec<_>>(),
                    )
                }),
            )?;
            Some(pd)
        }
        None => None,
    };
    d.set_item("power", power)?;
    d.set_item("power_balance", g.power_balance)?;
    d.set_item("torque_balance", g.torque_balance)?;
    d.set_item("warnings", g.warnings.clone())?;
    d.set_item("notes", g.notes.clone())?;
    Ok(d)
}

/// One gear state, per unit input speed and torque.
#[pyfunction]
pub fn gear<'py>(py: Python<'py>, core: &TrainCore, state: &str) -> Result<Bound<'py, PyDict>> {
    guard(|| gear_dict(py, &core.train, &core.train.analyse_gear(state)?))
}

/// Every gear state and the table across them (ratios, steps, spread, shifts).
#[pyfunction]
pub fn shift_table<'py>(py: Python<'py>, core: &TrainCore) -> Result<Bound<'py, PyDict>> {
    guard(|| {
        let t = &core.train;
        let s = t.shift_table()?;
        let d = PyDict::new(py);
        d.set_item("input", t.link_name(s.input))?;
        d.set_item("output", t.link_name(s.output))?;
        let gears = PyList::empty(py);
        for g in &s.gears {
            gears.append(gear_dict(py, t, g)?)?;
        }
        d.set_item("gears", gears)?;
        d.set_item("forward", s.forward.clone())?;
        d.set_item(
            "steps",
            s.steps
                .iter()
                .map(|x| (x.from, x.to, x.value, x.exact.as_ref().map(convert::q_text)))
                .collect::<Vec<_>>(),
        )?;
        d.set_item(
            "spread",
            s.spread.as_ref().map(|x| {
                (
                    x.lowest,
                    x.highest,
                    x.value,
                    x.exact.as_ref().map(convert::q_text),
                )
            }),
        )?;
        d.set_item(
            "shifts",
            s.shifts
                .iter()
                .map(|x| {
                    (
                        x.from,
                        x.to,
                        match x.kind {
                            ShiftKind::Sequential => "sequential",
                            ShiftKind::Garage => "garage",
                        },
                        elements(t, &x.off),
                        elements(t, &x.on),
                        elements(t, &x.kept),
                        x.single_swap,
                    )
                })
                .collect::<Vec<_>>(),
        )?;
        d.set_item("warnings", s.warnings.clone())?;
        Ok(d)
    })
}

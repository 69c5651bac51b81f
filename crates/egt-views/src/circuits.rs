//! The fundamental-circuit table (the paper's Table 1) by names: for each
//! gear pair m, gear i, gear j, transfer vertex k, the Willis ratio (exact
//! when known, symbolic for a planet without teeth) and the levels i/j.

use egt_core::Train;
use serde::Serialize;

use crate::format;

/// One row of Table 1, by names.
#[derive(Debug, Clone, Serialize)]
pub struct CircuitRow {
    /// Circuit number m (from 1; circuit m is gear pair m).
    pub m: usize,
    /// Name of the gear pair.
    pub gear_pair: String,
    /// Gear i.
    pub gear_i: String,
    /// Gear j.
    pub gear_j: String,
    /// Transfer vertex k (the carrier).
    pub carrier: String,
    /// Willis ratio tau_m, when known.
    pub ratio: Option<f64>,
    /// Exact ratio as `p/q`, when known.
    pub ratio_exact: Option<String>,
    /// For a mesh with a planet given without teeth: the ratio in terms of
    /// its unknown tooth count, e.g. `-z(P.planet)/30` (`ratio` is then null).
    pub ratio_symbolic: Option<String>,
    /// Level of the turning pairs on gear i's side of the carrier.
    pub level_i: String,
    /// Level of the turning pairs on gear j's side.
    pub level_j: String,
}

/// The circuit table of a train, by names, in the core's canonical order.
pub fn rows(train: &Train) -> Vec<CircuitRow> {
    train
        .circuits()
        .iter()
        .enumerate()
        .map(|(m, c)| {
            let g = &train.gears()[c.gear.index()];
            let symbolic = unsized_ratio(train, g);
            CircuitRow {
                m: m + 1,
                gear_pair: g.name.clone(),
                gear_i: train.link_name(c.gear_i).to_string(),
                gear_j: train.link_name(c.gear_j).to_string(),
                carrier: train.link_name(c.carrier).to_string(),
                ratio: g
                    .ratio
                    .as_ref()
                    .map(|r| r.value)
                    .filter(|_| symbolic.is_none()),
                ratio_exact: g
                    .ratio
                    .as_ref()
                    .and_then(|r| r.exact.as_ref())
                    .map(format::exact)
                    .filter(|_| symbolic.is_none()),
                ratio_symbolic: symbolic,
                level_i: train.level_name(c.level_i).to_string(),
                level_j: train.level_name(c.level_j).to_string(),
            }
        })
        .collect()
}

/// A mesh of a planet created without a tooth count carries one virtual tooth
/// on that side; show the true ratio in terms of the unknown count instead.
fn unsized_ratio(train: &Train, g: &egt_core::GearPair) -> Option<String> {
    let (si, sj) = (train.link(g.gear_i).sized, train.link(g.gear_j).sized);
    if si && sj {
        return None;
    }
    let [zi, zj] = g.teeth?;
    let z = |sized: bool, l: egt_core::LinkId, z: u32| {
        if sized {
            z.to_string()
        } else {
            format!("z({})", train.link_name(l))
        }
    };
    let sign = if g.mesh == Some(egt_core::spec::MeshKind::External) {
        "-"
    } else {
        ""
    };
    Some(format!(
        "{sign}{}/{}",
        z(sj, g.gear_j, zj),
        z(si, g.gear_i, zi)
    ))
}

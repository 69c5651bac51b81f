//! Across the gear table: step ratios between adjacent forward gears, the
//! overall spread, and which shift elements change at each shift (a shift that
//! is not one element off and one on needs more than one element controlled at
//! once, and is flagged).
//!
//! Forward gears are those whose ratio has the sign most states share (ties:
//! positive); the others are reverse gears. A transaxle whose final drive
//! turns the output opposite to the input has negative forward ratios, and
//! its reverse gear the positive one.

use serde::Serialize;

use crate::model::train::{ElementId, Train, Transmission};
use crate::numerics::exact::{self, Q};

use super::GearAnalysis;

/// The ratio step between two adjacent forward gears.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Step {
    /// Lower gear (index into the gear list).
    pub from: usize,
    /// Next gear up.
    pub to: usize,
    /// ratio(from) / ratio(to).
    pub value: f64,
    /// Exact step, when the ratios are exact.
    #[serde(serialize_with = "exact::text::option")]
    pub exact: Option<Q>,
}

/// The overall spread: largest forward ratio over smallest forward ratio.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Spread {
    /// The gear with the largest forward ratio.
    pub lowest: usize,
    /// The gear with the smallest forward ratio.
    pub highest: usize,
    /// ratio(lowest) / ratio(highest).
    pub value: f64,
    /// Exact spread, when the ratios are exact.
    #[serde(serialize_with = "exact::text::option")]
    pub exact: Option<Q>,
}

/// Which shifts are listed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ShiftKind {
    /// Between forward gears adjacent in the state list.
    Sequential,
    /// From the first forward gear to a reverse gear (a garage shift).
    Garage,
}

/// The elements that change between two gear states.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Shift {
    /// Gear shifted from (index into the gear list).
    pub from: usize,
    /// Gear shifted to.
    pub to: usize,
    /// Which kind of shift.
    pub kind: ShiftKind,
    /// Elements released.
    pub off: Vec<ElementId>,
    /// Elements applied.
    pub on: Vec<ElementId>,
    /// Elements engaged in both.
    pub kept: Vec<ElementId>,
    /// True when exactly one element is released and one applied.
    pub single_swap: bool,
}

/// The whole gear table.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ShiftTable {
    /// Input link.
    pub input: crate::LinkId,
    /// Output link.
    pub output: crate::LinkId,
    /// Every gear state, in the spec's order.
    pub gears: Vec<GearAnalysis>,
    /// Whether each gear is a forward gear (its ratio has the majority sign).
    pub forward: Vec<bool>,
    /// Steps between forward gears adjacent in the list.
    pub steps: Vec<Step>,
    /// The overall spread (None with fewer than two forward gears).
    pub spread: Option<Spread>,
    /// Sequential and garage shifts.
    pub shifts: Vec<Shift>,
    /// Table-level notes (e.g. forward gears listed out of ratio order).
    pub warnings: Vec<String>,
}

fn ratio_q(g: &GearAnalysis) -> Option<&Q> {
    g.ratio_exact.as_ref()
}

fn shift(gears: &[GearAnalysis], from: usize, to: usize, kind: ShiftKind) -> Shift {
    let (a, b) = (&gears[from].engaged, &gears[to].engaged);
    let off: Vec<ElementId> = a.iter().copied().filter(|e| !b.contains(e)).collect();
    let on: Vec<ElementId> = b.iter().copied().filter(|e| !a.contains(e)).collect();
    let kept: Vec<ElementId> = a.iter().copied().filter(|e| b.contains(e)).collect();
    Shift {
        from,
        to,
        kind,
        single_swap: off.len() == 1 && on.len() == 1,
        off,
        on,
        kept,
    }
}

pub(super) fn build(train: &Train, t: &Transmission, gears: Vec<GearAnalysis>) -> ShiftTable {
    let positive = gears.iter().filter(|g| g.ratio > 0.0).count();
    let sign = if 2 * positive >= gears.len() {
        1.0
    } else {
        -1.0
    };
    let is_forward: Vec<bool> = gears.iter().map(|g| g.ratio * sign > 0.0).collect();
    let forward: Vec<usize> = (0..gears.len()).filter(|&k| is_forward[k]).collect();
    let mut warnings = Vec::new();
    let steps: Vec<Step> = forward
        .windows(2)
        .map(|w| {
            let (a, b) = (&gears[w[0]], &gears[w[1]]);
            let exact = match (ratio_q(a), ratio_q(b)) {
                (Some(x), Some(y)) => Some(x / y),
                _ => None,
            };
            if a.ratio.abs() <= b.ratio.abs() {
                warnings.push(format!(
                    "forward gear `{}` (ratio {:.4}) is listed before `{}` (ratio {:.4}), which has a larger or equal ratio: the step is not an upshift",
                    a.state, a.ratio, b.state, b.ratio
                ));
            }
            Step {
                from: w[0],
                to: w[1],
                value: exact.as_ref().map_or(a.ratio / b.ratio, exact::to_f64),
                exact,
            }
        })
        .collect();
    let by_ratio = |pick_max: bool| {
        forward.iter().copied().reduce(|x, y| {
            let (rx, ry) = (gears[x].ratio.abs(), gears[y].ratio.abs());
            if (ry > rx) == pick_max && ry != rx {
                y
            } else {
                x
            }
        })
    };
    let spread = match (by_ratio(true), by_ratio(false)) {
        (Some(lo), Some(hi)) if forward.len() >= 2 => {
            let exact = match (ratio_q(&gears[lo]), ratio_q(&gears[hi])) {
                (Some(x), Some(y)) => Some(x / y),
                _ => None,
            };
            Some(Spread {
                lowest: lo,
                highest: hi,
                value: exact
                    .as_ref()
                    .map_or(gears[lo].ratio / gears[hi].ratio, exact::to_f64),
                exact,
            })
        }
        _ => None,
    };
    let mut shifts: Vec<Shift> = forward
        .windows(2)
        .map(|w| shift(&gears, w[0], w[1], ShiftKind::Sequential))
        .collect();
    if let Some(&first) = forward.first() {
        for k in (0..gears.len()).filter(|&k| !is_forward[k]) {
            shifts.push(shift(&gears, first, k, ShiftKind::Garage));
        }
    }
    for s in &shifts {
        if s.kind == ShiftKind::Sequential && !s.single_swap {
            let names = |es: &[ElementId]| {
                es.iter()
                    .map(|e| train.elements()[e.index()].name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            };
            warnings.push(format!(
                "shift {} -> {} is not a single swap: off [{}], on [{}]",
                gears[s.from].state,
                gears[s.to].state,
                names(&s.off),
                names(&s.on)
            ));
        }
    }
    debug_assert!(spread.as_ref().is_none_or(|s| s.value >= 1.0));
    ShiftTable {
        input: t.input,
        output: t.output,
        gears,
        forward: is_forward,
        steps,
        spread,
        shifts,
        warnings,
    }
}

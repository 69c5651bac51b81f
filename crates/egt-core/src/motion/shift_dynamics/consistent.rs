//! The mode a shift is in at one instant: at `t = 0` and after every mode
//! change, every locked element is checked against its capacity (a one-way
//! element against the sign it can hold) and released, slipping the way its
//! torque cannot be held; an element at zero slip locks where it can hold.
//!
//! With a few changing elements this is a small complementarity problem. Each
//! element at zero slip (locked, or the one whose event fired) may be locked
//! or slip either way; an element slipping at a speed keeps slipping. The
//! candidates are tried in order of preference (fewest changes to elements
//! that did not fire; locked before slipping; the way the torque pushes
//! first), and the first *consistent* one is taken:
//! - a locked clutch or brake carries `|T| <= mu_s C(t)`, a locked one-way
//!   element `T >= 0` (its holding sign, as `egt shift`);
//! - an element that starts slipping at zero slip has its slip speed growing
//!   the way it slips (`dir * d(slip)/dt >= 0`), so that the kinetic friction
//!   it is given opposes its motion.
//!
//! A candidate whose locked rows tie the train up (zero DOF) is skipped. When
//! no candidate is consistent the run is refused, naming the elements.

use super::train_mode::{Mode, Phase, Setup, refuse};
use crate::error::Result;
use crate::solve::losses::Driver;

/// A consistent mode at one instant, and how it was reached.
pub(super) struct Settled {
    /// The mode (the changing elements' phases).
    pub(super) mode: Mode,
    /// The state in it (speeds projected onto the mode where an element locked).
    pub(super) y: Vec<f64>,
    /// Kinetic energy removed by that projection (J).
    pub(super) lost: f64,
    /// The elements whose phase changed (or whose event fired), in index order.
    pub(super) changed: Vec<usize>,
}

/// What located the instant a mode is settled at.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Cause {
    /// `t = 0`.
    Start,
    /// A changing element's event: its current phase has ended and is not
    /// a candidate.
    Element(usize),
    /// A lossy mesh's event; the mesh whose driver flipped (unchecked), if
    /// it had one.
    Mesh(Option<usize>),
    /// The parked vehicle's static torque reached the road load's `c0`: it
    /// may not stay parked.
    Unpark,
}

/// Relative slack on the slip acceleration of an element that starts to slip
/// (a rate of rounding size, against the largest acceleration, is no sign).
const RATE_SLACK: f64 = 1e-9;

/// The consistent mode at time `t` and state `y`, starting from `phases`,
/// at an instant located by `cause`. With mesh losses, every candidate gets
/// its meshes' directions (`mesh_loss.rs`): `prior` first where they hold,
/// else the direction search. At rest with a road load `c0 > 0`, each
/// candidate is tried parked first (`rest.rs`): the output held by the
/// road load while its static torque is within `c0`.
///
/// # Errors
/// A tie-up (every candidate locks the train), a singular mode, or no
/// consistent candidate (the elements named).
pub(super) fn settle(
    setup: &Setup<'_>,
    phases: &[Phase],
    t: f64,
    y: &[f64],
    cause: Cause,
    prior: Option<&[Driver]>,
) -> Result<Settled> {
    let n = setup.n;
    let fired = match cause {
        Cause::Element(i) => Some(i),
        _ => None,
    };
    let flipped = match cause {
        Cause::Mesh(m) => m,
        _ => None,
    };
    let parks: &[bool] =
        if cause != Cause::Unpark && setup.stopping() > 0.0 && setup.at_rest(&y[..n]) {
            &[true, false]
        } else {
            &[false]
        };
    // The way each locked element's torque pushes: it slips that way if released.
    let k = phases.len();
    let now = setup.directed(setup.mode_or_rest(phases, &y[..n])?, t, y, prior, flipped)?;
    let dy = setup.rhs(&now, t, y);
    let (lam, _) = setup.locked_torques(&now, t, y, &dy);
    let options: Vec<Vec<Phase>> = (0..k)
        .map(|i| {
            let release = if setup.one_way[i] {
                vec![Phase::Slipping(1.0)]
            } else {
                // The torque on the first link is `-dir mu C`: it slips against its torque.
                let dir = if lam[i] > 0.0 { -1.0 } else { 1.0 };
                vec![Phase::Slipping(dir), Phase::Slipping(-dir)]
            };
            match (phases[i], fired == Some(i)) {
                (Phase::Locked, true) => release,
                (Phase::Locked, false) => [vec![Phase::Locked], release].concat(),
                (Phase::Slipping(d), true) => {
                    let back = if setup.one_way[i] { 1.0 } else { -d };
                    vec![Phase::Locked, Phase::Slipping(back)]
                }
                (p @ Phase::Slipping(_), false) => vec![p],
            }
        })
        .collect();
    // Every combination of the options, the last element's varying fastest.
    let mut candidates: Vec<(Vec<Phase>, (usize, usize))> = Vec::new();
    let mut pick = vec![0usize; k];
    loop {
        let c: Vec<Phase> = (0..k).map(|i| options[i][pick[i]]).collect();
        let moved = (0..k)
            .filter(|&i| fired != Some(i) && c[i] != phases[i])
            .count();
        candidates.push((c, (moved, pick.iter().sum())));
        // the next combination (an odometer over the options)
        let Some(i) = (0..k).rev().find(|&i| pick[i] + 1 < options[i].len()) else {
            break;
        };
        pick[i] += 1;
        pick[i + 1..].iter_mut().for_each(|p| *p = 0);
    }
    candidates.sort_by_key(|(_, key)| *key);
    let mut tie_up = None;
    for (c, park) in (candidates.iter()).flat_map(|(c, _)| parks.iter().map(move |&p| (c, p))) {
        let mode = if park {
            match setup.parked_mode(c) {
                Some(m) => m,
                None => continue,
            }
        } else {
            match setup.mode_or_rest(c, &y[..n]) {
                Ok(m) => m,
                Err(e) => {
                    tie_up.get_or_insert(e);
                    continue;
                }
            }
        };
        let locks = (0..k).any(|i| c[i] == Phase::Locked && phases[i] != Phase::Locked);
        let mut yc = y.to_vec();
        let mut lost = 0.0;
        // A lock, or a rest (no DOF: the speeds of rounding size go to 0).
        if locks || mode.basis.ncols() == 0 {
            let (speed, l) = setup.project(&mode, &y[..n]);
            yc[..n].copy_from_slice(speed.as_slice());
            lost = l;
        }
        let mode = match setup.directed(mode, t, &yc, prior, flipped) {
            Ok(m) => m,
            Err(e) => {
                tie_up.get_or_insert(e);
                continue;
            }
        };
        let d = setup.rhs(&mode, t, &yc);
        let (torque, _) = setup.locked_torques(&mode, t, &yc, &d);
        let slack = RATE_SLACK * d[..n].iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let entered = |i: usize| fired == Some(i) || c[i] != phases[i];
        let holds = (0..k).all(|i| match c[i] {
            Phase::Locked if setup.one_way[i] => torque[i] >= 0.0,
            Phase::Locked => torque[i].abs() <= setup.sim.law.static_limit(setup.capacity[i].at(t)),
            Phase::Slipping(dir) if entered(i) => {
                let rate: f64 = setup.rows[i].iter().zip(&d[..n]).map(|(a, b)| a * b).sum();
                dir * rate >= -slack
            }
            Phase::Slipping(_) => true,
        });
        let parked = mode
            .park_row
            .is_none_or(|r| setup.multipliers(&mode, t, &yc, &d)[r].abs() <= setup.stopping());
        if holds && parked {
            let changed = (0..k).filter(|&i| entered(i)).collect();
            return Ok(Settled {
                mode,
                y: yc,
                lost,
                changed,
            });
        }
    }
    let names: Vec<String> = (0..k)
        .filter(|&i| options[i].len() > 1)
        .map(|i| format!("`{}`", setup.name(i)))
        .collect();
    Err(tie_up.unwrap_or_else(|| {
        refuse(format!(
            "no consistent mode at t = {t}: {} can neither hold their torques within their capacities nor slip the way those torques push (the stick-slip problem has no solution)",
            names.join(" and ")
        ))
    }))
}

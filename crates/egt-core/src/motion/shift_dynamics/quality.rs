//! Shift quality: a finished shift's torque and inertia phases, and the
//! measures a shift-calibration engineer reads from them, taken from the
//! result's samples alone (no new integration).
//!
//! The samples hold both sides of every mode change (two samples at the
//! change's time, the left limit first), so the measures below see the value
//! just before a release or a lock as well as just after. The output torque's
//! turning points between samples, where `extremes.rs` searched the step's
//! dense output for them (those that could be an extreme of the run), are
//! candidates for the dip and the overshoot too.
//!
//! - **Torque phase** `[shift_start, t_release]`: from the time an on-coming
//!   element first carries capacity to the time the last off-going element
//!   stops holding (its first change to slipping or overrunning; the latest
//!   of those over the off-going elements). Torque passes from the old path
//!   to the new one while the speeds still follow the old gear.
//! - **Inertia phase** `[t_release, lock_time]`: from that release to the
//!   time the on-coming elements are all locked. The speeds move from the
//!   old ratio to the new one.
//!
//! A phase is `None` when it is empty or cannot be placed: no on-coming
//! capacity, an off-going element that never lets go, no lock, or an end not
//! after its start (an off-going element released at `t = 0` by the
//! consistent mode, before any on-coming capacity, leaves no torque phase;
//! a power-on downshift releases first and so has its inertia phase before
//! the on-coming element takes torque).

use serde::Serialize;

use super::shift::ShiftResult;

/// A value and the time it occurs.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct AtTime {
    /// Time (s).
    pub t: f64,
    /// The value (its unit is the measure's).
    pub value: f64,
}

/// One changing element's thermal measures.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ElementQuality {
    /// The element's name.
    pub element: String,
    /// Energy it dissipated over the run (J): [`ShiftResult::dissipated`].
    pub energy: f64,
    /// Its largest friction power `|T_e slip_e|` over the samples (W), and
    /// when (the first sample that reaches it). Between samples the power is
    /// not searched: a value at most one step's change below the true peak.
    pub peak_power: Option<AtTime>,
}

/// The phases and quality measures of a shift (docs/shift_dynamics.md,
/// "Phases and shift quality"). Torques are the output torque of
/// [`super::ShiftSample::output_torque`] (N m); a measure that cannot be
/// defined (no phase, no lock, no vehicle inertia, no samples) is `None`.
#[derive(Debug, Clone, PartialEq, Serialize, Default)]
pub struct ShiftQuality {
    /// `[start, end]` of the torque phase (s): `shift_start` to the release
    /// of the last off-going element. `None` if empty or not placed.
    pub torque_phase: Option<[f64; 2]>,
    /// `[start, end]` of the inertia phase (s): the release of the last
    /// off-going element to `lock_time`. `None` if empty or not placed.
    pub inertia_phase: Option<[f64; 2]>,
    /// Output torque of the first sample, at `t = 0` (N m): the reference of
    /// the dip. (After a change at `t = 0`, the new mode's.)
    pub output_torque_start: Option<f64>,
    /// Output torque of the last sample (N m): the steady value the
    /// overshoot is measured from.
    pub output_torque_end: Option<f64>,
    /// The lowest output torque in the torque phase (every sample with `t`
    /// in the closed phase, both sides of its events, and turning points
    /// inside) minus `output_torque_start` (N m): negative is a dip. `t` is
    /// where the lowest value is.
    pub dip: Option<AtTime>,
    /// The highest output torque from the start of the inertia phase to the
    /// lock, both sides of the lock included, minus `output_torque_end`
    /// (N m): positive is an overshoot of the final torque.
    pub overshoot: Option<AtTime>,
    /// Largest minus smallest output torque from the lock (its right limit,
    /// the locked mode) to the end of the run (N m). `None` without a lock.
    pub oscillation_after_lock: Option<f64>,
    /// The largest `|dT_out/dt| / J_vehicle` (rad/s^3: the output shaft's
    /// jerk, with `T_out = J_vehicle a_out + road load`), each rate the finite
    /// difference `(T_out[i+1] - T_out[i]) / (t[i+1] - t[i])` of two
    /// consecutive samples at distinct times. The jumps at mode changes (two
    /// samples at one time) are not in it: they are `largest_step`. `t` is
    /// the middle of the pair's interval. `None` without vehicle inertia.
    /// A secant over one step, so it is at most the true peak and tends to
    /// it as the steps shrink.
    pub jerk: Option<AtTime>,
    /// The largest jump of the output torque at a mode change, right limit
    /// minus left limit (N m, signed), and its time. `None` if no change
    /// after `t = 0`.
    pub largest_step: Option<AtTime>,
    /// Per changing element, in the order of [`ShiftResult::elements`].
    pub elements: Vec<ElementQuality>,
}

impl ShiftQuality {
    /// The phases and measures of `run`, whose vehicle inertia at the output
    /// is `vehicle_inertia` (kg m^2). `turns` are the output torque's turning
    /// points between samples, `(t, T_out)`, as `extremes.rs` found them (may
    /// be empty).
    pub fn of(run: &ShiftResult, vehicle_inertia: f64, turns: &[(f64, f64)]) -> Self {
        let s = &run.samples;
        let (Some(first), Some(last)) = (s.first(), s.last()) else {
            return Self::default();
        };
        let release = release_time(run);
        let torque_phase = match (run.shift_start, release) {
            (Some(a), Some(b)) if a < b => Some([a, b]),
            _ => None,
        };
        let inertia_phase = match (release, run.lock_time) {
            (Some(a), Some(b)) if a < b => Some([a, b]),
            _ => None,
        };
        // Every output-torque value in the closed window [a, b]: samples
        // (both sides of its events) and turning points.
        let window = |a: f64, b: f64| {
            s.iter()
                .map(|x| (x.t, x.output_torque))
                .chain(turns.iter().copied())
                .filter(move |&(t, _)| t >= a && t <= b)
        };
        let (start, end) = (first.output_torque, last.output_torque);
        let dip = torque_phase.and_then(|[a, b]| {
            lowest(window(a, b)).map(|(t, v)| AtTime {
                t,
                value: v - start,
            })
        });
        let overshoot = inertia_phase.and_then(|[a, b]| {
            lowest(window(a, b).map(|(t, v)| (t, -v))).map(|(t, v)| AtTime { t, value: -v - end })
        });
        let oscillation_after_lock = run.lock_time.and_then(|l| {
            // from the lock's right limit: the last sample at its time
            let from = s.iter().rposition(|x| x.t <= l)?;
            let values = s[from..]
                .iter()
                .map(|x| x.output_torque)
                .chain(turns.iter().filter(|x| x.0 > l).map(|x| x.1));
            let (hi, lo) = values.fold((f64::NEG_INFINITY, f64::INFINITY), |(h, m), v| {
                (h.max(v), m.min(v))
            });
            Some(hi - lo)
        });
        let (mut jerk, mut largest_step): (Option<AtTime>, Option<AtTime>) = (None, None);
        for p in s.windows(2) {
            let (dt, dv) = (p[1].t - p[0].t, p[1].output_torque - p[0].output_torque);
            if dt > 0.0 {
                if vehicle_inertia > 0.0 {
                    let rate = (dv / dt).abs() / vehicle_inertia;
                    if jerk.is_none_or(|j| rate > j.value) {
                        jerk = Some(AtTime {
                            t: 0.5 * (p[0].t + p[1].t),
                            value: rate,
                        });
                    }
                }
            } else if largest_step.is_none_or(|j| dv.abs() > j.value.abs()) {
                largest_step = Some(AtTime {
                    t: p[1].t,
                    value: dv,
                });
            }
        }
        let elements = run
            .elements
            .iter()
            .enumerate()
            .map(|(e, name)| ElementQuality {
                element: name.clone(),
                energy: run.dissipated[e],
                peak_power: lowest(
                    s.iter()
                        .map(|x| (x.t, -(x.element_torque[e] * x.slip[e]).abs())),
                )
                .map(|(t, v)| AtTime { t, value: -v }),
            })
            .collect();
        Self {
            torque_phase,
            inertia_phase,
            output_torque_start: Some(start),
            output_torque_end: Some(end),
            dip,
            overshoot,
            oscillation_after_lock,
            jerk,
            largest_step,
            elements,
        }
    }
}

/// When the last off-going element stops holding: the latest, over the
/// off-going elements, of each one's first change to slipping or
/// overrunning. `None` if one of them never lets go.
fn release_time(run: &ShiftResult) -> Option<f64> {
    run.off_going
        .iter()
        .map(|e| {
            run.changes
                .iter()
                .find(|c| &c.element == e && c.now != "locked")
                .map(|c| c.t)
        })
        .try_fold(f64::NEG_INFINITY, |m, t| t.map(|t| m.max(t)))
        .filter(|t| t.is_finite())
}

/// The first `(t, v)` with the lowest finite `v`.
fn lowest(values: impl Iterator<Item = (f64, f64)>) -> Option<(f64, f64)> {
    values
        .filter(|p| p.1.is_finite())
        .fold(None, |best: Option<(f64, f64)>, p| match best {
            Some(b) if b.1 <= p.1 => Some(b),
            _ => Some(p),
        })
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::super::shift::tests::{
        APPLY, RELEASE, rel, two_speed, two_speed_upshift, zf, zf_2_3, zf_change,
    };
    use super::super::{Capacity, FrictionLaw, InputTorque, ShiftSample, ShiftSim};
    use super::*;

    /// The trapezoid integral of `f` over the times `t` (intervals of zero
    /// length, the two sides of an event, add nothing), and an estimate of its
    /// error: `h^3 / 12 |f''|` summed over the intervals, with `f''` the
    /// second divided difference of the interval and a neighbour at a
    /// distinct time (the trapezoid rule's error term).
    fn trapezoid(t: &[f64], f: &[f64]) -> (f64, f64) {
        let (mut sum, mut err) = (0.0, 0.0);
        let second = |a: usize, b: usize, c: usize| {
            2.0 * ((f[c] - f[b]) / (t[c] - t[b]) - (f[b] - f[a]) / (t[b] - t[a])) / (t[c] - t[a])
        };
        for i in 0..t.len() - 1 {
            let h = t[i + 1] - t[i];
            if h <= 0.0 {
                continue;
            }
            sum += 0.5 * h * (f[i] + f[i + 1]);
            let d2 = if i > 0 && t[i - 1] < t[i] {
                second(i - 1, i, i + 1)
            } else if i + 2 < t.len() && t[i + 2] > t[i + 1] {
                second(i, i + 1, i + 2)
            } else {
                0.0
            };
            err += h.powi(3) / 12.0 * d2.abs();
        }
        (sum, err)
    }

    fn series(r: &ShiftResult, f: impl Fn(&ShiftSample) -> f64) -> Vec<f64> {
        r.samples.iter().map(f).collect()
    }

    #[test]
    fn the_dissipated_energies_and_the_energy_balance_are_rebuilt_from_the_time_series() {
        // Each element's energy is its friction power |T_e slip_e| integrated
        // over the samples (trapezoid), and the whole balance
        //   W_in - W_road - (KE_end - KE_0) - E_lock = sum of E_e
        // holds with every term rebuilt from the samples' speeds and
        // torques, not from the integrator's running energy states. The
        // trapezoid's own error bound sets the tolerance; at rtol 1e-10 the
        // integrator's error is far below it.
        for (train, sim) in [(zf(), zf_2_3()), (two_speed(), two_speed_upshift())] {
            let sim = ShiftSim {
                rtol: 1e-10,
                atol: 1e-10,
                ..sim
            };
            let r = sim.run(&train).unwrap();
            let t = series(&r, |s| s.t);
            let total: f64 = r.dissipated.iter().sum();
            for e in 0..r.elements.len() {
                let power = series(&r, |s| (s.element_torque[e] * s.slip[e]).abs());
                let (energy, bound) = trapezoid(&t, &power);
                let off = (energy - r.dissipated[e]).abs();
                println!(
                    "{} -> {} `{}`: trapezoid {energy} J, integrated {} J, off {off:e}, bound {bound:e}",
                    sim.from, sim.to, r.elements[e], r.dissipated[e]
                );
                assert!(
                    off <= 2.0 * bound + 1e-9 * total,
                    "`{}`: {energy} vs {} (bound {bound:e})",
                    r.elements[e],
                    r.dissipated[e]
                );
                assert_eq!(r.quality.elements[e].energy, r.dissipated[e]);
            }
            // The balance from the samples.
            let tr = train.checked_transmission().unwrap();
            let (input, output) = (tr.input.index(), tr.output.index());
            let mut m = train.mass_matrix().unwrap().matrix().unwrap();
            let out_k = train.coordinate(tr.output).unwrap();
            m[(out_k, out_k)] += sim.vehicle_inertia;
            let kinetic = |s: &ShiftSample| {
                let v = nalgebra::DVector::from_iterator(
                    train.coordinates().len(),
                    train.coordinates().iter().map(|l| s.speed[l.index()]),
                );
                0.5 * v.dot(&(&m * &v))
            };
            let [c0, c1, c2] = sim.road_load;
            let road = |w: f64| c0 * w.signum() + c1 * w + c2 * w * w.abs();
            let (w_in, b_in) = trapezoid(
                &t,
                &series(&r, |s| sim.input_torque.at(s.speed[input]) * s.speed[input]),
            );
            let (w_road, b_road) =
                trapezoid(&t, &series(&r, |s| road(s.speed[output]) * s.speed[output]));
            let dke = kinetic(r.samples.last().unwrap()) - kinetic(&r.samples[0]);
            let rebuilt = w_in - w_road - dke - r.lock_loss;
            println!(
                "{} -> {}: rebuilt {rebuilt} J against {total} J (off {:e}, bounds {b_in:e} + {b_road:e}, W_in {w_in})",
                sim.from,
                sim.to,
                rebuilt - total
            );
            assert!(
                (rebuilt - total).abs() <= 2.0 * (b_in + b_road) + 1e-9 * w_in.abs(),
                "{rebuilt} vs {total}"
            );
        }
    }

    /// The two-speed train with no brake capacity and a constant clutch
    /// capacity: the brake releases at t = 0, and sun and carrier are two
    /// free inertias joined by the clutch (as in `shift.rs`).
    fn constant_engagement() -> (ShiftSim, [f64; 5]) {
        let (j1, j2, mu, cap, w) = (0.01, 0.05, 0.12, 1000.0, 200.0);
        let sim = ShiftSim {
            input_speed: w,
            input_torque: InputTorque::Constant(0.0),
            road_load: [0.0; 3],
            vehicle_inertia: 0.0,
            law: FrictionLaw {
                mu_static: 0.15,
                mu_kinetic: mu,
                decay: None,
            },
            off_going: Some(Capacity::Constant(0.0)),
            on_coming: Some(Capacity::Constant(cap)),
            t_end: 0.1,
            ..two_speed_upshift()
        };
        (sim, [j1, j2, mu, cap, w])
    }

    #[test]
    fn the_constant_capacity_engagement_has_its_closed_form_peak_power_and_inertia_phase() {
        let (sim, [j1, j2, mu, cap, w]) = constant_engagement();
        let r = sim.run(&two_speed()).unwrap();
        let q = &r.quality;
        let s0 = w - w / 3.4; // sun minus carrier in first
        let t_lock = s0 / (mu * cap * (1.0 / j1 + 1.0 / j2));
        // The slip falls linearly from s0, so the power mu C s is largest at t = 0+.
        let peak = q.elements[1].peak_power.unwrap();
        println!(
            "peak power {} W at {} s; mu C s0 = {} W",
            peak.value,
            peak.t,
            mu * cap * s0
        );
        assert_eq!(peak.t, 0.0);
        assert!(rel(peak.value, mu * cap * s0) < 1e-12, "{peak:?}");
        // The brake let go at t = 0, when the clutch already had capacity:
        // no torque phase; the inertia phase is the slip time.
        assert_eq!(q.torque_phase, None);
        let [a, b] = q.inertia_phase.unwrap();
        assert_eq!(a, 0.0);
        assert!(rel(b, t_lock) < 1e-9, "{b} vs {t_lock}");
        assert_eq!(q.dip, None);
        // No vehicle inertia: no jerk; the brake never slipped with torque.
        assert_eq!(q.jerk, None);
        assert_eq!(q.elements[0].peak_power.unwrap().value, 0.0);
    }

    #[test]
    fn the_dip_and_the_overshoot_do_not_move_with_the_tolerance() {
        for (train, sim) in [(zf(), zf_2_3()), (two_speed(), two_speed_upshift())] {
            let runs: Vec<ShiftResult> = [1e-6, 1e-8, 1e-10]
                .into_iter()
                .map(|tol| {
                    ShiftSim {
                        rtol: tol,
                        atol: tol,
                        ..sim.clone()
                    }
                    .run(&train)
                    .unwrap()
                })
                .collect();
            let fine = &runs[2];
            let range = fine.output_torque_range[0] - fine.output_torque_range[1];
            let measures = |r: &ShiftResult| {
                [
                    r.quality.dip.unwrap().value,
                    r.quality.overshoot.unwrap().value,
                ]
            };
            for r in &runs {
                println!(
                    "{} -> {}: dip {:?}, overshoot {:?}, phases {:?} {:?}",
                    sim.from,
                    sim.to,
                    r.quality.dip,
                    r.quality.overshoot,
                    r.quality.torque_phase,
                    r.quality.inertia_phase
                );
            }
            for r in &runs[..2] {
                for (a, b) in measures(r).iter().zip(measures(fine)) {
                    assert!(
                        (a - b).abs() <= 1e-6 * range,
                        "{} -> {}: {a} against {b} (range {range})",
                        sim.from,
                        sim.to
                    );
                }
            }
        }
    }

    #[test]
    fn a_power_on_upshift_dips_in_its_torque_phase_and_its_phases_are_in_order() {
        for (train, sim) in [(two_speed(), two_speed_upshift()), (zf(), zf_2_3())] {
            let r = sim.run(&train).unwrap();
            let q = &r.quality;
            let [start, release] = q.torque_phase.unwrap();
            let [from, lock] = q.inertia_phase.unwrap();
            assert_eq!(Some(start), r.shift_start);
            assert_eq!(Some(lock), r.lock_time);
            assert_eq!(release, from);
            assert!(start <= release && release <= lock, "{q:?}");
            // the off-going element lets go at the end of the torque phase
            assert!(
                r.changes
                    .iter()
                    .any(|c| c.element == r.off_going[0] && c.now == "slipping" && c.t == release)
            );
            let dip = q.dip.unwrap();
            assert!(dip.value < 0.0, "{dip:?}");
            assert!(dip.t >= start && dip.t <= release);
            // the dip is a value the output torque takes, below the start
            assert!(dip.value + q.output_torque_start.unwrap() >= r.output_torque_range[1] - 1e-9);
            let over = q.overshoot.unwrap();
            assert!(over.t >= release && over.t <= lock);
            assert!(q.oscillation_after_lock.unwrap() >= 0.0);
            let jerk = q.jerk.unwrap();
            assert!(jerk.value.is_finite() && jerk.value > 0.0);
            println!("{} -> {} {:?}: {q:?}", sim.from, sim.to, train.name());
        }
    }

    #[test]
    fn a_double_swaps_torque_phase_ends_when_the_last_off_going_element_lets_go() {
        // The 8HP 1-4: A and C off (the same ramp), D and E on.
        let r = zf_change(
            "1",
            "4",
            &[("A", RELEASE), ("C", RELEASE), ("D", APPLY), ("E", APPLY)],
        )
        .run(&zf())
        .unwrap();
        let released = |e: &str| {
            r.changes
                .iter()
                .find(|c| c.element == e && c.now != "locked")
                .unwrap()
                .t
        };
        let last = released("A").max(released("C"));
        let q = &r.quality;
        assert_eq!(q.torque_phase, Some([r.shift_start.unwrap(), last]));
        assert_eq!(q.inertia_phase, Some([last, r.lock_time.unwrap()]));
        assert_eq!(q.elements.len(), 4);
        for (e, m) in q.elements.iter().enumerate() {
            assert_eq!(m.element, r.elements[e]);
            assert!(m.peak_power.unwrap().value >= 0.0);
        }
        println!(
            "1 -> 4: A lets go at {}, C at {}: {q:?}",
            released("A"),
            released("C")
        );
    }

    /// A result with the output torques `torques` at the times `times`, one
    /// changing element each way, and nothing else.
    fn by_hand(times: &[f64], torques: &[f64]) -> ShiftResult {
        let samples = times
            .iter()
            .zip(torques)
            .map(|(&t, &q)| ShiftSample {
                t,
                speed: vec![0.0; 2],
                slip: vec![0.0, t],
                element_torque: vec![0.0, 2.0],
                output_torque: q,
                dissipated: vec![0.0; 2],
                energy_residual: 0.0,
                mesh_loss: None,
                dof: 1,
                kept_torque: Vec::new(),
            })
            .collect();
        ShiftResult {
            elements: vec!["off".into(), "on".into()],
            off_going: vec!["off".into()],
            on_coming: vec!["on".into()],
            kept: Vec::new(),
            held: Vec::new(),
            samples,
            changes: Vec::new(),
            shift_start: None,
            lock_time: None,
            shift_time: None,
            output_torque_range: [0.0; 2],
            element_torque_range: vec![[0.0; 2]; 2],
            slip_range: vec![[0.0; 2]; 2],
            kept_torque_range: Vec::new(),
            dissipated: vec![0.0; 2],
            lock_loss: 0.0,
            rest_time: None,
            mesh_loss: None,
            max_energy_residual: 0.0,
            steps: 0,
            method: "explicit".into(),
            stiff: None,
            quality: ShiftQuality::default(),
        }
    }

    #[test]
    fn jerk_is_the_steepest_secant_between_distinct_times_and_a_step_is_apart() {
        // 10 -> 8 over 1 s, a jump to 12 at t = 1 (two samples), 12 -> 15 over 2 s.
        let r = by_hand(&[0.0, 1.0, 1.0, 3.0], &[10.0, 8.0, 12.0, 15.0]);
        let q = ShiftQuality::of(&r, 4.0, &[]);
        assert_eq!(
            q.jerk,
            Some(AtTime {
                t: 0.5,
                value: 2.0 / 4.0
            })
        );
        assert_eq!(q.largest_step, Some(AtTime { t: 1.0, value: 4.0 }));
        // no phases without a release, a shift start or a lock: no measures of them
        assert_eq!((q.torque_phase, q.inertia_phase), (None, None));
        assert_eq!(
            (q.dip, q.overshoot, q.oscillation_after_lock),
            (None, None, None)
        );
        assert_eq!(q.output_torque_start, Some(10.0));
        assert_eq!(q.output_torque_end, Some(15.0));
        // the power of `on` is 2 t, largest at the last sample
        assert_eq!(
            q.elements[1].peak_power,
            Some(AtTime { t: 3.0, value: 6.0 })
        );
        // no vehicle inertia: no jerk, and no samples: nothing at all
        assert_eq!(ShiftQuality::of(&r, 0.0, &[]).jerk, None);
        let empty = by_hand(&[], &[]);
        assert_eq!(ShiftQuality::of(&empty, 1.0, &[]), ShiftQuality::default());
    }
}

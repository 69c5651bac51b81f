//! Issue 11, class 4: round-off must never decide the direction of power.
//!
//! Thousands of gear states of production-style layouts (the ZF 8HP70's four
//! simple sets, the Ford C4 Simpson set, the Ford AOD Ravigneaux set) with
//! random tooth counts and lossy meshes (and the ZF 6HP26 Lepelletier). The reference is independent of
//! egt's float direction search: the statics are solved in exact rational
//! arithmetic, a mesh is idle when its exact multiplier is zero, the
//! direction of every loaded mesh is read from the exact ideal solution, the
//! lossy system is solved exactly once with those directions, and the answer
//! is accepted only if it is consistent (every loaded mesh keeps its
//! direction). egt must then report an efficiency, never self-locking, and
//! it must equal the exact one.

// A failed unwrap is a failed test, with its location.
#![allow(clippy::unwrap_used)]

use egt_core::numerics::exact::{self, Q};
use egt_core::{Driver, Format, GearState, Train};
use num_traits::{Signed, Zero};

/// A small deterministic generator (xorshift64*), so the draws never change.
struct Rng(u64);

impl Rng {
    fn int(&mut self, lo: u32, hi: u32) -> u32 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let r = self.0.wrapping_mul(0x2545_F491_4F6C_DD1D);
        lo + u32::try_from(r % u64::from(hi - lo + 1)).unwrap()
    }
}

/// The example with every planetary set's teeth redrawn and a basic
/// efficiency of 0.98 on every mesh.
fn redraw(example: &str, rng: &mut Rng) -> String {
    let text = std::fs::read_to_string(crate::util::example_path(example)).unwrap();
    let mut out = String::new();
    for line in text.lines() {
        let t = line.trim_start();
        if t.starts_with("efficiency") {
            continue;
        }
        if t.starts_with("teeth = { sun =") && t.contains("sun2") {
            let s = rng.int(20, 40);
            let s2 = s + rng.int(2, 12);
            let r = s2 + 2 * rng.int(14, 30);
            out.push_str(&format!(
                "teeth = {{ sun = {s}, sun2 = {s2}, ring = {r} }}\n"
            ));
        } else if t.starts_with("teeth = { sun =") {
            let s = rng.int(20, 60);
            let r = s + 2 * rng.int(12, 40);
            let p = (r - s) / 2;
            out.push_str(&format!(
                "teeth = {{ sun = {s}, ring = {r}, planet = {p} }}\n"
            ));
        } else {
            out.push_str(line);
            out.push('\n');
        }
        if t == "[[planetary]]" {
            out.push_str("efficiency = 0.98\n");
        }
    }
    out
}

/// The exact efficiency of `state` (unit input torque and speed, the output
/// absorbing) and the meshes that roll but are idle (zero exact multiplier),
/// or `None` when the one-shot directions are not consistent.
fn exact_efficiency(train: &Train, state: &GearState) -> Option<(Q, Vec<usize>)> {
    let t = train.transmission().unwrap();
    let n = train.coordinates().len();
    let col = |l| train.coordinate(l);
    let taus: Vec<Q> = train
        .gears()
        .iter()
        .map(|g| g.ratio.as_ref().unwrap().exact.clone().unwrap())
        .collect();
    let etas: Vec<Q> = train
        .gears()
        .iter()
        .map(|g| exact::from_f64(g.efficiency).unwrap())
        .collect();
    // Constraint rows: Willis (eq. 2) with the given ratios, then the engaged elements.
    let rows = |ratios: &[Q]| -> Vec<Vec<Q>> {
        let mut rows = Vec::new();
        for (c, tau) in train.circuits().iter().zip(ratios) {
            let mut row = vec![Q::zero(); n];
            for (l, v) in [
                (c.gear_i, exact::q(1)),
                (c.gear_j, -tau.clone()),
                (c.carrier, tau - exact::q(1)),
            ] {
                if let Some(k) = col(l) {
                    row[k] += v;
                }
            }
            rows.push(row);
        }
        for e in &state.engaged {
            let mut row = vec![Q::zero(); n];
            let links = &train.elements()[e.index()].links;
            row[col(links[0]).unwrap()] += exact::q(1);
            if let Some(&b) = links.get(1) {
                row[col(b).unwrap()] -= exact::q(1);
            }
            rows.push(row);
        }
        rows
    };
    // Speeds: the constraints and a unit input speed.
    let mut a = rows(&taus);
    let mut unit = vec![Q::zero(); n];
    unit[col(t.input).unwrap()] = exact::q(1);
    a.push(unit);
    let mut b = vec![Q::zero(); n];
    b[n - 1] = exact::q(1);
    let w = exact::solve(&a, &b).ok()?;
    let speed = |l| col(l).map_or(Q::zero(), |k| w[k].clone());
    // Statics (eq. 6 without inertia): psi~^T lambda - e_out T_out = e_in.
    let statics = |ratios: &[Q]| -> Vec<Q> {
        let r = rows(ratios);
        let mut a = vec![vec![Q::zero(); n]; n];
        for (j, row) in r.iter().enumerate() {
            for k in 0..n {
                a[k][j] = row[k].clone();
            }
        }
        a[col(t.output).unwrap()][n - 1] = exact::q(-1);
        let mut q = vec![Q::zero(); n];
        q[col(t.input).unwrap()] = exact::q(1);
        exact::solve(&a, &q).unwrap()
    };
    let ideal = statics(&taus);
    // Directions from the exact ideal solution: gear i drives when lambda tau (w_j - w_k) > 0.
    let drive_i: Vec<Option<bool>> = train
        .circuits()
        .iter()
        .enumerate()
        .map(|(m, c)| {
            let p = &ideal[m] * &taus[m] * (speed(c.gear_j) - speed(c.carrier));
            (!p.is_zero()).then(|| p.is_positive())
        })
        .collect();
    let force: Vec<Q> = (0..taus.len())
        .map(|m| match drive_i[m] {
            Some(true) => &taus[m] * &etas[m],
            Some(false) => &taus[m] / &etas[m],
            None => taus[m].clone(),
        })
        .collect();
    let lossy = statics(&force);
    let consistent = train.circuits().iter().enumerate().all(|(m, c)| {
        let p = &lossy[m] * &taus[m] * (speed(c.gear_j) - speed(c.carrier));
        drive_i[m].is_none_or(|i| !p.is_zero() && p.is_positive() == i)
    });
    let idle = train
        .circuits()
        .iter()
        .enumerate()
        .filter(|(m, c)| ideal[*m].is_zero() && speed(c.gear_j) != speed(c.carrier))
        .map(|(m, _)| m)
        .collect();
    // Output power over the unit input power.
    consistent.then(|| (-(&lossy[n - 1]) * speed(t.output), idle))
}

/// Random tooth counts on one layout: every gear state's efficiency exists and is exact.
fn check_layout(example: &str, draws: usize, seed: u64) {
    let mut rng = Rng(seed);
    let (mut states, mut idle_states, mut skipped) = (0, 0, 0);
    for _ in 0..draws {
        let text = redraw(example, &mut rng);
        let train = Train::from_str(&text, Format::Toml, example).unwrap();
        let table = train.shift_table().unwrap();
        for (gear, state) in table
            .gears
            .iter()
            .zip(&train.transmission().unwrap().states)
        {
            let Some((reference, idle)) = exact_efficiency(&train, state) else {
                skipped += 1;
                continue;
            };
            states += 1;
            let power = gear.power.as_ref().unwrap_or_else(|| {
                panic!(
                    "{example}, gear {}: no power flow ({:?})\n{text}",
                    gear.state, gear.warnings
                )
            });
            let expected = exact::to_f64(&reference);
            // A direct gear (nothing rolls) is exactly lossless, not 1 + round-off.
            if expected == 1.0 {
                assert_eq!(power.efficiency, 1.0, "{example}, gear {}", gear.state);
            }
            assert!(
                (power.efficiency - expected).abs() <= 1e-12 * expected.abs(),
                "{example}, gear {}: efficiency {} against the exact {expected}\n{text}",
                gear.state,
                power.efficiency
            );
            // A mesh that rolls unloaded has no loss and no direction.
            for &m in &idle {
                let mesh = &power.meshes[m];
                assert!(
                    mesh.driver == Driver::None && mesh.loss == 0.0,
                    "{example}, gear {}: idle mesh {m} given {:?}, loss {}",
                    gear.state,
                    mesh.driver,
                    mesh.loss
                );
            }
            idle_states += usize::from(!idle.is_empty());
        }
    }
    // The exact one-shot reference decides nearly every state, and idle sets occur.
    assert!(
        skipped * 50 <= states,
        "{example}: {skipped} undecided of {states}"
    );
    assert!(
        states > 0 && idle_states > 0,
        "{example}: {states} states, {idle_states} idle"
    );
}

#[test]
fn zf_8hp70_efficiency_with_random_teeth() {
    check_layout("zf_8hp70.toml", 60, 0x8e5f_2a11);
}

#[test]
fn ford_c4_simpson_efficiency_with_random_teeth() {
    check_layout("ford_c4_simpson.toml", 150, 0x0c4c_4c4c);
}

#[test]
fn ford_aod_ravigneaux_efficiency_with_random_teeth() {
    check_layout("ford_aod_ravigneaux.toml", 150, 0xa0d0_a0d0);
}

#[test]
fn zf_6hp26_lepelletier_efficiency_with_random_teeth() {
    check_layout("zf_6hp26_lepelletier.toml", 120, 0x6426_6426);
}

//! A counting global allocator, and proofs that the per-scenario paths
//! allocate nothing: `Worker::eval` for kinematics, dynamics and lossy power
//! flow on every test train, `PreparedTrain::solve` (also with a whole mass
//! matrix and in the forces-only mode of the single analyses),
//! `MassModel::fill`, and the kinematics alone (dense and sparse).
//!
//! The count is per thread (the test harness runs tests on several threads),
//! kept in a `const`-initialised thread-local `Cell`, which itself never allocates.

// Implementing `GlobalAlloc` is unsafe by definition; this is the only unsafe
// code in the workspace and it only forwards to the system allocator.
#![allow(unsafe_code)]

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use egt_core::solve::prepared::{Compute, MassModel, PreparedTrain, Scenario};

use crate::util::{self, one_dof_trains, plan};

struct Counting;

thread_local! {
    static ALLOCATIONS: Cell<u64> = const { Cell::new(0) };
    /// Bytes this thread holds (allocated less freed) and the most it held.
    static HELD: Cell<i64> = const { Cell::new(0) };
    static PEAK: Cell<i64> = const { Cell::new(0) };
}

fn hold(bytes: i64) {
    let now = HELD.with(|h| {
        h.set(h.get() + bytes);
        h.get()
    });
    PEAK.with(|p| p.set(p.get().max(now)));
}

fn size(layout: Layout) -> i64 {
    i64::try_from(layout.size()).unwrap_or(i64::MAX)
}

// SAFETY: every call is forwarded unchanged to `System`; the counter is a
// plain thread-local integer.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.with(|c| c.set(c.get() + 1));
        hold(size(layout));
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.with(|c| c.set(c.get() + 1));
        hold(size(layout));
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.with(|c| c.set(c.get() + 1));
        hold(i64::try_from(new_size).unwrap_or(i64::MAX) - size(layout));
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        hold(-size(layout));
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Allocations made by this thread while running `f`.
pub fn allocations<R>(f: impl FnOnce() -> R) -> (u64, R) {
    let before = ALLOCATIONS.with(Cell::get);
    let r = f();
    (ALLOCATIONS.with(Cell::get) - before, r)
}

/// The most bytes this thread held at once while running `f`, beyond what
/// it held before (memory freed by other threads is not seen).
pub fn peak_bytes<R>(f: impl FnOnce() -> R) -> (i64, R) {
    let before = HELD.with(Cell::get);
    PEAK.with(|p| p.set(before));
    let r = f();
    (PEAK.with(Cell::get) - before, r)
}

#[test]
fn the_counter_sees_allocations() {
    // Guards the guard: a test that cannot fail proves nothing.
    let (n, v) = allocations(|| vec![1.0_f64; 64]);
    assert_eq!(v.len(), 64);
    assert!(n >= 1);
    let (peak, v) = peak_bytes(|| {
        let big = vec![1.0_f64; 1 << 20];
        drop(big);
        vec![2.0_f64; 64]
    });
    assert_eq!(v.len(), 64);
    assert!(peak >= 8 << 20, "peak {peak}");
}

/// Vary every parameter a little around the base row, deterministically.
fn perturbed(base: &[f64], k: usize) -> Vec<f64> {
    base.iter()
        .enumerate()
        .map(|(c, &v)| v * (1.0 + 0.01 * (((k * 7 + c * 3) % 11) as f64 - 5.0) / 5.0))
        .collect()
}

#[test]
fn batch_rows_allocate_nothing() {
    for (name, t) in one_dof_trains() {
        for (compute, sparse) in [Compute::Kinematics, Compute::Dynamics, Compute::Power]
            .into_iter()
            .flat_map(|c| [(c, false), (c, true)])
        {
            let p = plan(&t, compute)
                .with_sparse(sparse)
                .unwrap_or_else(|e| panic!("{e}"));
            let rows: Vec<Vec<f64>> = (0..50).map(|k| perturbed(p.base(), k)).collect();
            let mut out = vec![0.0; p.outputs().len()];
            let mut w = p.worker();
            w.eval(&rows[0], &mut out)
                .unwrap_or_else(|e| panic!("{name} {compute:?}: {e}"));
            let (n, ok) = allocations(|| rows.iter().all(|r| w.eval(r, &mut out).is_ok()));
            assert!(ok, "{name} {compute:?}: a row failed");
            assert_eq!(
                n, 0,
                "{name} {compute:?} (sparse {sparse}): {n} allocations in 50 rows"
            );
        }
    }
}

/// A small batch call on the calling thread reuses the buffers the plan
/// kept from the call before: after the first, a call of 64 rows allocates
/// only its task lists (one vector row-major; the columns and one task's
/// column list column-major), and gives the first call's numbers bit for
/// bit, after a call with a bad row too. Every path: the program (bounds),
/// row by row, and the linear path (a load sweep); kinematics and dynamics.
#[test]
fn small_batch_calls_reuse_the_plans_buffers() {
    use egt_core::batch::{Layout, Threads};
    for (name, t) in one_dof_trains() {
        for compute in [Compute::Kinematics, Compute::Dynamics] {
            for bounds in [false, true] {
                let p = plan(&t, compute).with_condition_bounds(bounds);
                let (np, nq) = (p.parameters().len(), p.outputs().len());
                let rows = 64;
                for sweep in ["ratio.", "torque."] {
                    let Some(c) = p.parameters().iter().position(|n| n.starts_with(sweep)) else {
                        continue;
                    };
                    let mut params: Vec<f64> = (0..rows).flat_map(|_| p.base().to_vec()).collect();
                    for r in 0..rows {
                        params[r * np + c] *= 1.0 + 0.001 * r as f64;
                    }
                    let columns: Vec<f64> = (0..np)
                        .flat_map(|k| params[k..].iter().step_by(np).copied().collect::<Vec<_>>())
                        .collect();
                    let mut bad = params.clone();
                    bad[5 * np + c] = f64::NAN;
                    let what = format!("{name} {compute:?} bounds {bounds} {sweep}");
                    let (mut first, mut again) = (vec![0.0; rows * nq], vec![0.0; rows * nq]);
                    let e = p
                        .run(Layout::Rows(&params), &mut first, Threads::Calling)
                        .errors;
                    assert!(e.is_empty(), "{what}: {e:?}");
                    let e = p
                        .run(Layout::Rows(&bad), &mut again, Threads::Calling)
                        .errors;
                    assert_eq!(e.iter().map(|e| e.row).collect::<Vec<_>>(), [5], "{what}");
                    let (n, e) = allocations(|| {
                        p.run(Layout::Rows(&params), &mut again, Threads::Calling)
                            .errors
                    });
                    assert!(e.is_empty(), "{what}");
                    assert!(n <= 1, "{what}: {n} allocations row-major");
                    let same = first
                        .iter()
                        .zip(&again)
                        .all(|(a, b)| a.to_bits() == b.to_bits());
                    assert!(same, "{what}: the kept buffers changed the numbers");
                    p.run(Layout::Columns(&columns), &mut again, Threads::Calling);
                    let (n, e) = allocations(|| {
                        p.run(Layout::Columns(&columns), &mut again, Threads::Calling)
                            .errors
                    });
                    assert!(e.is_empty(), "{what}");
                    assert!(n <= 3, "{what}: {n} allocations column-major");
                    let same = (0..rows).all(|r| {
                        (0..nq)
                            .all(|o| first[r * nq + o].to_bits() == again[o * rows + r].to_bits())
                    });
                    assert!(same, "{what}: column-major with kept buffers differs");
                }
            }
        }
    }
}

#[test]
fn prepared_solves_and_mass_fill_allocate_nothing() {
    for (name, t) in one_dof_trains() {
        let mm = MassModel::new(&t).unwrap_or_else(|e| panic!("{name}: {e}"));
        let (inertia, mass) = mm.train_values(&t);
        let mut m = vec![0.0; mm.n() * mm.n()];
        let (n, ()) = allocations(|| mm.fill(&inertia, &mass, &mut m));
        assert_eq!(n, 0, "{name}: MassModel::fill");

        // The pre-existing plans claim the same; check them here too.
        let ratios = t.ratios().unwrap_or_else(|e| panic!("{e}"));
        let inputs: Vec<_> = t.analysis().speeds.iter().map(|s| s.0).collect();
        let speeds: Vec<f64> = t.analysis().speeds.iter().map(|s| s.1).collect();
        // The speeds alone (the single-scenario kinematics' solver), dense
        // and sparse: factor, condition and solve reuse the workspace.
        for sparse in [false, true] {
            let pt = PreparedTrain::for_analysis(&t, &inputs, &inputs, &inputs, &[])
                .and_then(|p| p.with_sparse(sparse))
                .unwrap_or_else(|e| panic!("{e}"));
            let mut ws = pt.workspace();
            let s = Scenario::kinematic(&ratios, &speeds);
            pt.solve(&mut ws, &s, Compute::Kinematics)
                .unwrap_or_else(|e| panic!("{e}"));
            // New ratios (bitwise), so the factorisation is redone.
            let other: Vec<f64> = ratios.iter().map(|r| r * (1.0 + 1e-9)).collect();
            let s2 = Scenario::kinematic(&other, &speeds);
            let (n, r) = allocations(|| pt.solve(&mut ws, &s2, Compute::Kinematics));
            assert!(r.is_ok());
            assert_eq!(
                n, 0,
                "{name}: PreparedTrain::solve (kinematics, sparse {sparse})"
            );
        }

        // The single analyses' mode: a whole [M], forces only (eq. 8, 10),
        // dense and sparse (the sparse LUs and [M] as terms of large trains).
        let whole = t.mass_matrix().unwrap_or_else(|e| panic!("{e}"));
        for sparse in [false, true] {
            let req = util::request(&t);
            let links: Vec<_> = req.accelerations.iter().map(|a| a.0).collect();
            let pt = PreparedTrain::for_analysis(&t, &links, &links, &req.driving, &req.extras)
                .and_then(|p| p.with_sparse(sparse))
                .unwrap_or_else(|e| panic!("{e}"));
            let nc = t.coordinates().len();
            let mut q = vec![0.0; nc];
            for &(l, v) in &req.torques {
                q[t.coordinate(l).unwrap_or(0)] += v;
            }
            let alpha: Vec<f64> = req.accelerations.iter().map(|a| a.1).collect();
            let zeros = vec![0.0; alpha.len()];
            let ones = vec![1.0; ratios.len()];
            let s = Scenario {
                ratios: &ratios,
                speeds: &zeros,
                accelerations: &alpha,
                torques: &q,
                inertia: &[],
                mass: &[],
                efficiency: &ones,
                mass_matrix: Some(&whole),
            };
            let mut ws = pt.workspace();
            pt.solve(&mut ws, &s, Compute::Forces)
                .unwrap_or_else(|e| panic!("{e}"));
            let (n, r) = allocations(|| pt.solve(&mut ws, &s, Compute::Forces));
            assert!(r.is_ok());
            assert_eq!(
                n, 0,
                "{name}: PreparedTrain::solve (forces, whole [M], sparse {sparse})"
            );
        }
    }
}

//! Fuzz target: the batch's straight-line program compiled to machine code
//! against the same program interpreted, bit for bit. The bytes choose a
//! small valid train (a random one of 1 to 4 planetary sets, or a chain of
//! 1 to 4 sets), kinematics or dynamics, some of its outputs, and rows
//! around its base row (a whole block of 64 and a part block, some values
//! bad, zero or far off); both executors must give the same outputs (a
//! NaN's payload apart) and refuse the same rows with the same errors,
//! row-major and column-major. Without the jit feature's code on this
//! machine both are the interpreter, and the target only runs the program.
#![no_main]

use egt_core::batch::{BatchPlan, BatchSpec, Executor, Layout, Threads};
use egt_core::solve::prepared::Compute;
use egt_core::{Format, Train};
use libfuzzer_sys::fuzz_target;

#[allow(dead_code)]
#[path = "../../crates/egt-core/lab/families.rs"]
mod families;

/// The fuzz bytes as a stream, zeros once they run out.
struct Bytes<'a>(&'a [u8]);

impl Bytes<'_> {
    fn u8(&mut self) -> u8 {
        let (&b, rest) = self.0.split_first().unwrap_or((&0, &[]));
        self.0 = rest;
        b
    }
    fn u64(&mut self) -> u64 {
        (0..8).fold(0, |a, _| a << 8 | u64::from(self.u8()))
    }
}

fuzz_target!(|data: &[u8]| {
    let mut b = Bytes(data);
    let head = b.u8();
    let sets = 1 + usize::from(head >> 1) % 4;
    let text = match head & 1 {
        0 => families::random_train(b.u64() % 10_000, sets, f64::from(b.u8() % 8)),
        _ => families::planetary_chain(sets),
    };
    let Ok(train) = Train::from_str(&text, Format::Toml, "fuzz") else {
        return;
    };
    let compute = match b.u8() & 1 {
        0 => Compute::Kinematics,
        _ => Compute::Dynamics,
    };
    let Ok(spec) = BatchSpec::from_analysis(&train, compute) else {
        return;
    };
    let Ok(plan) = BatchPlan::new(&train, &spec) else {
        return;
    };
    // Some of the outputs (each kept by one bit), or all.
    let mask = b.u64();
    let some: Vec<String> = (plan.outputs().iter().enumerate())
        .filter(|(k, _)| mask >> (k % 64) & 1 == 1)
        .map(|(_, n)| n.clone())
        .collect();
    let plan = if some.is_empty() {
        plan
    } else {
        match plan.with_outputs(&some) {
            Ok(p) => p,
            Err(_) => return,
        }
    };
    let plan = plan.with_condition_bounds(true);
    if !plan.has_program() {
        return;
    }
    // Rows around the base row: each value moved by up to 10 %, a few bad,
    // zero or far off.
    let (np, rows) = (plan.parameters().len(), 64 + usize::from(b.u8() % 80));
    let mut params = Vec::with_capacity(rows * np);
    for _ in 0..rows {
        for &v in plan.base() {
            let v = if v.is_nan() { 1.0 } else { v };
            let x = b.u8();
            params.push(match x {
                250 => f64::NAN,
                251 => 0.0,
                252 => f64::INFINITY,
                253 => -v,
                254 => v * 1e6,
                255 => f64::MAX,
                _ => v * (1.0 + (f64::from(x) - 125.0) / 1250.0),
            });
        }
    }
    let columns: Vec<f64> = (0..np)
        .flat_map(|k| params[k..].iter().step_by(np).copied())
        .collect();
    let nq = plan.outputs().len();
    let run = |executor: Executor| {
        let p = plan.clone().with_executor(executor);
        let (mut by_rows, mut by_columns) = (vec![0.0; rows * nq], vec![0.0; rows * nq]);
        let errors = |e: Vec<egt_core::batch::RowError>| {
            (e.into_iter())
                .map(|e| (e.row, e.error.to_string()))
                .collect::<Vec<_>>()
        };
        let e_rows = errors(
            p.run(Layout::Rows(&params), &mut by_rows, Threads::Pool)
                .errors,
        );
        let e_columns = errors(
            p.run(Layout::Columns(&columns), &mut by_columns, Threads::Pool)
                .errors,
        );
        (p.program_compiled(), by_rows, by_columns, e_rows, e_columns)
    };
    let interpreted = run(Executor::Interpreted);
    let auto = run(Executor::Auto);
    assert!(!interpreted.0, "interpreted, yet compiled");
    let same = |a: &[f64], b: &[f64], what: &str| {
        for (i, (x, y)) in a.iter().zip(b).enumerate() {
            assert!(
                x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan()),
                "{what} cell {i}: {x} compiled (compiled: {}) against {y} interpreted",
                auto.0
            );
        }
    };
    same(&auto.1, &interpreted.1, "rows");
    same(&auto.2, &interpreted.2, "columns");
    assert_eq!(auto.3, interpreted.3, "rows: other rows refused");
    assert_eq!(auto.4, interpreted.4, "columns: other rows refused");
});

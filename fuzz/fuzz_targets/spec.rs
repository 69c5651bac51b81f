//! Fuzz target: a whole spec (TOML or JSON, by the first byte) through parsing,
//! validation and every analysis the spec's `[analysis]` table can drive:
//! kinematics, inverse dynamics and power (as the batch plan builds them,
//! and with condition bounds, by the straight-line program, compiled where
//! the machine runs the code against interpreted, bit for bit, and with every other
//! parameter column given as one value against the matrix written out),
//! stability and the shift table. Any error is fine; a panic, an abort,
//! compiled code that disagrees with the interpreter, or fixed columns that
//! change a number are bugs.
#![no_main]

use egt_core::batch::{BatchPlan, BatchSpec, Column, Executor, Layout, Threads};
use egt_core::solve::prepared::Compute;
use egt_core::{Format, Train};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let format = Format::sniff(text);
    let Ok(train) = Train::from_str(text, format, "fuzz") else {
        return;
    };
    for compute in [Compute::Kinematics, Compute::Dynamics, Compute::Power] {
        if let Ok(spec) = BatchSpec::from_analysis(&train, compute) {
            if let Ok(plan) = BatchPlan::new(&train, &spec) {
                let mut out = vec![0.0; plan.outputs().len()];
                let _ = plan
                    .run(Layout::Rows(plan.base()), &mut out, Threads::Pool)
                    .errors;
                // The straight-line program, compiled to machine code where
                // the machine has AVX-512 or AVX2: a whole block of the base
                // row (rows), and of the base row's values mixed (columns).
                let plan = plan.with_condition_bounds(true);
                let rows: Vec<f64> = (0..64).flat_map(|_| plan.base().iter().copied()).collect();
                let mut out = vec![0.0; 64 * plan.outputs().len()];
                let _ = plan
                    .run(Layout::Columns(&rows), &mut out, Threads::Pool)
                    .errors;
                let _ = plan
                    .run(Layout::Rows(&rows), &mut out, Threads::Pool)
                    .errors;
                // Compiled (where the machine runs the code) and
                // interpreted: the same bits and the same refused rows.
                let mut first: Option<(Vec<f64>, Vec<usize>)> = None;
                for code in [Executor::Interpreted, Executor::Auto] {
                    let p = plan.clone().with_executor(code);
                    let mut out = vec![0.0; 64 * p.outputs().len()];
                    let failed: Vec<usize> = p
                        .run(Layout::Columns(&rows), &mut out, Threads::Pool)
                        .errors
                        .iter()
                        .map(|e| e.row)
                        .collect();
                    match &first {
                        None => first = Some((out, failed)),
                        Some((o, f)) => {
                            assert_eq!(&failed, f, "{code:?}: other rows refused");
                            for (i, (a, b)) in out.iter().zip(o).enumerate() {
                                assert!(
                                    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()),
                                    "{code:?} cell {i}: {a} against {b} interpreted"
                                );
                            }
                        }
                    }
                }
                // Every even column as one value (its first row's): the
                // numbers and refused rows of the matrix written out.
                let np = plan.parameters().len();
                let fixed: Vec<f64> = (0..np)
                    .flat_map(|k| {
                        let c = &rows[k * 64..(k + 1) * 64];
                        (0..64).map(move |r| if k % 2 == 0 { c[0] } else { c[r] })
                    })
                    .collect();
                let set: Vec<Column<'_>> = (0..np)
                    .map(|k| match k % 2 {
                        0 => Column::Every(fixed[k * 64]),
                        _ => Column::Rows(&fixed[k * 64..(k + 1) * 64]),
                    })
                    .collect();
                let q = plan.outputs().len();
                let (mut a, mut b) = (vec![0.0; 64 * q], vec![0.0; 64 * q]);
                let rows_a: Vec<usize> = plan
                    .run(Layout::Columns(&fixed), &mut a, Threads::Pool)
                    .errors
                    .iter()
                    .map(|e| e.row)
                    .collect();
                let rows_b: Vec<usize> = (plan
                    .run(
                        Layout::ColumnSet {
                            columns: &set,
                            rows: 64,
                        },
                        &mut b,
                        Threads::Calling,
                    )
                    .errors
                    .iter())
                .map(|e| e.row)
                .collect();
                assert_eq!(rows_a, rows_b, "fixed columns: other rows refused");
                for (i, (x, y)) in a.iter().zip(&b).enumerate() {
                    assert!(
                        x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan()),
                        "fixed columns, cell {i}: {y} against {x} written out"
                    );
                }
            }
        }
    }
    let _ = train.stability(&Default::default());
    let _ = train.shift_table();
});

//! Fuzz target: a whole spec (TOML or JSON, by the first byte) through parsing,
//! validation and every analysis the spec's `[analysis]` table can drive:
//! kinematics, inverse dynamics and power (as the batch plan builds them,
//! and with condition bounds, by the straight-line program, each code the
//! machine has against the interpreter, bit for bit),
//! stability and the shift table. Any error is fine; a panic, an abort, or
//! compiled code that disagrees with the interpreter is a bug.
#![no_main]

use egt_core::batch::{BatchPlan, BatchSpec};
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
                let _ = plan.run(plan.base(), &mut out);
                // The straight-line program, compiled to machine code where
                // the machine has AVX-512 or AVX2: a whole block of the base
                // row (rows), and of the base row's values mixed (columns).
                let plan = plan.with_condition_bounds(true);
                let rows: Vec<f64> = (0..64).flat_map(|_| plan.base().iter().copied()).collect();
                let mut out = vec![0.0; 64 * plan.outputs().len()];
                let _ = plan.run_columns(&rows, &mut out);
                let _ = plan.run(&rows, &mut out);
                // Every code the machine has, and the interpreter: the same
                // bits and the same refused rows.
                let mut first: Option<(Vec<f64>, Vec<usize>)> = None;
                for code in [None, Some("AVX2"), Some("AVX-512")] {
                    let Ok(p) = plan.clone().with_program_instructions(code) else {
                        continue;
                    };
                    let mut out = vec![0.0; 64 * p.outputs().len()];
                    let failed: Vec<usize> = p
                        .run_columns(&rows, &mut out)
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
            }
        }
    }
    let _ = train.stability(&Default::default());
    let _ = train.shift_table();
});

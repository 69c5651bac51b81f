//! Fuzz target: a whole spec (TOML or JSON, by the first byte) through parsing,
//! validation and every analysis the spec's `[analysis]` table can drive:
//! kinematics, inverse dynamics and power (as the batch plan builds them,
//! and with condition bounds, by the straight-line program),
//! stability and the shift table. Any error is fine; a panic, an abort, or an
//! accepted spec with a non-finite kinematic result is a bug.
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
                // the machine has AVX-512: a whole block of the base row.
                let plan = plan.with_condition_bounds(true);
                let rows: Vec<f64> = (0..64).flat_map(|_| plan.base().iter().copied()).collect();
                let mut out = vec![0.0; 64 * plan.outputs().len()];
                let _ = plan.run_columns(&rows, &mut out);
                let _ = plan.run(&rows, &mut out);
            }
        }
    }
    let _ = train.stability(&Default::default());
    let _ = train.shift_table();
});

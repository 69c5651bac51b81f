//! Fuzz target: `egt shift-sim`'s arguments on the 8HP70 (one argument a
//! line: gears, speeds, torques, torque tables, road load, friction, ramps,
//! times, tolerances, method). The harness adds `--max-steps 3000` (a step
//! budget the fuzzer cannot raise: a second one is a usage error), so that a
//! run stays short. Any refusal is fine; a panic, an abort or a hang is a bug.
#![no_main]

use libfuzzer_sys::fuzz_target;

#[path = "common/args.rs"]
mod args;

fuzz_target!(|data: &[u8]| {
    let spec = args::example("zf_8hp70.toml");
    let _ = args::run(data, &["shift-sim", &spec], &["--max-steps", "3000"]);
});

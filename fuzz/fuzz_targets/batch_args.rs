//! Fuzz target: `egt batch`'s design arguments (`--set`, `--vary`, `--grid`,
//! `--state`, `--columns`, `--compute`, `--output`, ...) on the Fig. 3
//! train, one argument a line. The harness adds `--max-rows 2000` (a row
//! budget the fuzzer cannot raise: a second `--max-rows` is a usage error),
//! so that a run stays short. Any refusal is fine; a panic, an abort or a
//! hang is a bug.
#![no_main]

use libfuzzer_sys::fuzz_target;

#[path = "common/args.rs"]
mod args;

fuzz_target!(|data: &[u8]| {
    let spec = args::example("fig3_example61.toml");
    let _ = args::run(data, &["batch", &spec], &["--max-rows", "2000"]);
});

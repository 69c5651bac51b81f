//! The `egt` binary's integration tests (registered by `crates/egt-cli`): the
//! command line as a user runs it on the bundled examples. The library's own
//! tests (paper, exact, properties, dynamics, stability, transmission) are in
//! `crates/egt-core/tests/analyses` and run with `cargo test -p egt-core`.

// Running `egt` from the workspace root.
mod util;

// Exit codes, stdin, JSON fields, table and snapshot output.
mod cli;

// `egt dynamics` and `egt power`: power balance of the JSON, asking only for what is used.
mod dynamics;

// `egt shift` and `egt graph`, and the gear table pasted in docs/transmission.md.
mod transmission;

// `egt stability` and `egt simulate`, and the output pasted in docs/stability.md.
mod stability;

// Issue 43: `egt modes`, torsional natural frequencies, on the compliant example.
mod modes;

// Issue 10: every bundled example through every analysis, against committed JSON snapshots.
mod golden;

// Issue 12: one row per class of bad input through the binary (exit code, words in the message).
mod bad_inputs;

// Issue 15: `egt enumerate`, the atlas of gear-train graphs, read back by `egt check`.
mod enumerate;

// Issue 16: `egt synth`, the design search, against the real transmissions and `egt shift`.
mod synth;

// Issue 14: `egt shift-sim`, a gear change in time, on the 8HP example.
mod shift_sim;

// Issue 44: `egt fmu`, a transmission packaged as an FMI 2.0 Co-Simulation unit.
mod fmu;

// Issue 42: every flag of every subcommand run with a valid value.
mod flags;

// Issue 42: Ctrl-C stops synth, enumerate and batch with exit 130 and whole output so far; --progress on stderr only.
#[cfg(unix)]
mod interrupt;

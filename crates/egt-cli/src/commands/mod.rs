//! One module per subcommand. Each has an `Args` struct (clap) and a
//! `run(&Args, &mut dyn Write)`; `cli.rs` dispatches to them. No command
//! imports another command or `cli.rs` (`scripts/layers.py`).

pub mod batch;
pub mod check;
pub mod circuits;
pub mod completions;
pub mod dynamics;
pub mod enumerate;
pub mod fmu;
pub mod graph;
pub mod kinematics;
pub mod modes;
pub mod power;
pub mod schema;
pub mod shift;
pub mod shift_sim;
pub mod simulate;
pub mod stability;
pub mod synth;

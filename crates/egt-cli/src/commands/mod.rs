//! One module per subcommand. Each has an `Args` struct (clap) and a
//! `run(&Args, &mut dyn Write)`; `run` here dispatches on the enum in `cli.rs`.

use std::io::Write;

use crate::cli::Command;

pub mod batch;
pub mod check;
pub mod circuits;
pub mod completions;
pub mod dynamics;
pub mod enumerate;
pub mod graph;
pub mod kinematics;
pub mod power;
pub mod schema;
pub mod shift;
pub mod shift_sim;
pub mod simulate;
pub mod stability;
pub mod synth;

/// Refuse, before any work, what cannot go to this stdout: a binary batch
/// output (Parquet, Arrow) to a terminal.
///
/// # Errors
/// A spec error naming `--output`.
pub fn preflight(command: &Command, stdout_is_terminal: bool) -> anyhow::Result<()> {
    match command {
        Command::Batch(args) if stdout_is_terminal => batch::refuse_binary_to_terminal(args),
        _ => Ok(()),
    }
}

/// Run one subcommand, writing its report to `out`.
///
/// # Errors
/// Whatever the subcommand reports; `main` maps it to an exit code.
pub fn run(command: &Command, out: &mut dyn Write) -> anyhow::Result<()> {
    match command {
        Command::Check(args) => check::run(args, out),
        Command::Circuits(args) => circuits::run(args, out),
        Command::Kinematics(args) => kinematics::run(args, out),
        Command::Dynamics(args) => dynamics::run(args, out),
        Command::Power(args) => power::run(args, out),
        Command::Shift(args) => shift::run(args, out),
        Command::ShiftSim(args) => shift_sim::run(args, out),
        Command::Graph(args) => graph::run(args, out),
        Command::Stability(args) => stability::run(args, out),
        Command::Simulate(args) => simulate::run(args, out),
        Command::Batch(args) => batch::run(args, out),
        Command::Schema(args) => schema::run(args, out),
        Command::Completions(args) => completions::run(args, out),
        Command::Man(args) => completions::man(args, out),
        Command::Enumerate(args) => enumerate::run(args, out),
        Command::Synth(args) => synth::run(args, out),
    }
}

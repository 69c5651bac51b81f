//! The command line's grammar and dispatch (clap derive): one enum variant
//! per subcommand, whose arguments live beside its implementation in
//! `commands/`, and the one match that runs it.

use std::io::Write;

use clap::{CommandFactory, Parser, Subcommand};

use crate::commands;

/// Graph-based kinematics of epicyclic gear trains (after Pennestrì).
#[derive(Debug, Parser)]
#[command(name = "egt", version, about, long_about = None)]
pub struct Cli {
    /// The subcommand.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands. To add one: a file in `commands/`, a variant here and a
/// line in [`run`].
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Validate a spec: degree of freedom, topology checks, circuit table.
    Check(commands::check::Args),
    /// Print the fundamental-circuit table (the paper's Table 1).
    Circuits(commands::circuits::Args),
    /// Solve every link's speed from input speeds (Willis equations, eq. 2).
    Kinematics(commands::kinematics::Args),
    /// Inverse dynamics (eq. 6-11): driving torques, meshing forces, reactions, equivalent inertia.
    Dynamics(commands::dynamics::Args),
    /// Power flow: per-mesh power, mesh losses, efficiency, circulating power.
    Power(commands::power::Args),
    /// Automatic transmission: per-gear ratios, element torques, efficiency, steps and shifts.
    Shift(commands::shift::Args),
    /// Simulate a gear change in time (a spec with a `[transmission]`): the off-going element releases, the on-coming one slips and locks.
    ShiftSim(commands::shift_sim::Args),
    /// A transmission as an FMI 2.0 Co-Simulation unit (.fmu): shift elements driven by their capacities.
    Fmu(commands::fmu::Args),
    /// Write the train's graph as Graphviz DOT (links, turning and gear pairs, shift elements).
    Graph(commands::graph::Args),
    /// Stability of the linearised motion (eq. 19-27): [V], [M], [K], eigenvalues, modes, verdict.
    Stability(commands::stability::Args),
    /// Torsional natural frequencies and mode shapes (a spring along each mesh, `[compliance]`), bare or in a gear state.
    Modes(commands::modes::Args),
    /// Forward dynamics in time under the torque-speed curves (RK4 or implicit); CSV/JSON, SVG plot.
    Simulate(commands::simulate::Args),
    /// Many scenarios in parallel (parameter arrays, grids, rows, gear states, or a file of specs) as JSON Lines or CSV.
    Batch(commands::batch::Args),
    /// Print the JSON Schema of the spec format.
    Schema(commands::schema::Args),
    /// Print a shell completion script (bash, zsh, fish, elvish, powershell).
    Completions(commands::completions::Args),
    /// Print the man page (roff).
    Man(commands::completions::ManArgs),
    /// The atlas of non-isomorphic gear train graphs with N links and F DOF, one per line.
    Enumerate(commands::enumerate::Args),
    /// Design search: tooth counts of a transmission's planetary sets for target ratios.
    Synth(commands::synth::Args),
}

/// Refuse, before any work, what cannot go to this stdout: a binary batch
/// output (Parquet, Arrow) to a terminal.
///
/// # Errors
/// A spec error naming `--output`.
pub fn preflight(command: &Command, stdout_is_terminal: bool) -> anyhow::Result<()> {
    match command {
        Command::Batch(args) if stdout_is_terminal => {
            commands::batch::refuse_binary_to_terminal(args)
        }
        _ => Ok(()),
    }
}

/// The commands whose loops stop on Ctrl-C and write what they finished
/// (the binary catches SIGINT for them only; the others end at once).
pub fn stops_on_ctrl_c(command: &Command) -> bool {
    matches!(
        command,
        Command::Synth(_) | Command::Enumerate(_) | Command::Batch(_)
    )
}

/// Run one subcommand, writing its report to `out`.
///
/// # Errors
/// Whatever the subcommand reports; `main` maps it to an exit code.
pub fn run(command: &Command, out: &mut dyn Write) -> anyhow::Result<()> {
    match command {
        Command::Check(args) => commands::check::run(args, out),
        Command::Circuits(args) => commands::circuits::run(args, out),
        Command::Kinematics(args) => commands::kinematics::run(args, out),
        Command::Dynamics(args) => commands::dynamics::run(args, out),
        Command::Power(args) => commands::power::run(args, out),
        Command::Shift(args) => commands::shift::run(args, out),
        Command::ShiftSim(args) => commands::shift_sim::run(args, out),
        Command::Fmu(args) => commands::fmu::run(args, out),
        Command::Graph(args) => commands::graph::run(args, out),
        Command::Stability(args) => commands::stability::run(args, out),
        Command::Modes(args) => commands::modes::run(args, out),
        Command::Simulate(args) => commands::simulate::run(args, out),
        Command::Batch(args) => commands::batch::run(args, out),
        Command::Schema(args) => commands::schema::run(args, out),
        Command::Completions(args) => commands::completions::run(args, &mut Cli::command(), out),
        Command::Man(args) => commands::completions::man(args, Cli::command(), out),
        Command::Enumerate(args) => commands::enumerate::run(args, out),
        Command::Synth(args) => commands::synth::run(args, out),
    }
}

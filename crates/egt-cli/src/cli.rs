//! Command-line definitions (clap derive). One enum variant per subcommand;
//! each subcommand's arguments live beside its implementation in `commands/`.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand, ValueEnum};

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
/// line in `commands::run`.
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
    /// Simulate a gear change in time: the off-going element releases, the on-coming one slips and locks.
    ShiftSim(commands::shift_sim::Args),
    /// Write the train's graph as Graphviz DOT (links, turning and gear pairs, shift elements).
    Graph(commands::graph::Args),
    /// Stability of the linearised motion (eq. 19-27): [V], [M], [K], eigenvalues, modes, verdict.
    Stability(commands::stability::Args),
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

/// How results are printed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, ValueEnum)]
pub enum OutputFormat {
    /// Aligned, readable tables.
    #[default]
    Table,
    /// One JSON document (names, not ids; exact values as strings like "162/77").
    Json,
}

/// The text format of a spec.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SpecFormat {
    /// TOML.
    Toml,
    /// JSON.
    Json,
}

/// Arguments shared by every command that reads a spec.
#[derive(Debug, Clone, Args)]
pub struct SpecArgs {
    /// The spec file (TOML or JSON), or `-` for standard input.
    #[arg(value_name = "SPEC")]
    pub spec: PathBuf,
    /// Spec format; by default from the extension (`.json` is JSON), or sniffed on stdin.
    #[arg(long, value_enum, value_name = "FORMAT")]
    pub spec_format: Option<SpecFormat>,
    /// Output format.
    #[arg(long, value_enum, default_value_t = OutputFormat::Table)]
    pub format: OutputFormat,
}

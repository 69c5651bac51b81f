//! The `egt` binary: parse the command line, run one subcommand, map the
//! outcome to an exit code. 0 on success (and when stdout is a closed pipe);
//! 2 for usage, syntax, spec, topology and gear-state errors; 1 for analysis and I/O errors.
//! Errors print to stderr as `error: ...`.

mod cli;
mod commands;
mod input;
mod report;

use std::io::{self, Write};
use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    // clap exits with 2 on usage errors by itself (0 for --help/--version).
    let cli = cli::Cli::parse();
    let mut out = io::BufWriter::new(io::stdout().lock());
    let result = commands::run(&cli.command, &mut out).and_then(|()| Ok(out.flush()?));
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if is_broken_pipe(&e) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(exit_code(&e))
        }
    }
}

/// 2 when the user's input is wrong (spec or topology), 1 when a valid train
/// cannot be analysed as asked, or the spec could not be read.
fn exit_code(e: &anyhow::Error) -> u8 {
    for cause in e.chain() {
        if let Some(core) = cause.downcast_ref::<egt_core::Error>() {
            return match core {
                egt_core::Error::Syntax(_)
                | egt_core::Error::Spec { .. }
                | egt_core::Error::Topology(_)
                // A gear state that does not leave one DOF is a wrong spec too.
                | egt_core::Error::Transmission(_) => 2,
                _ => 1,
            };
        }
    }
    1
}

fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<io::Error>()
            .is_some_and(|io| io.kind() == io::ErrorKind::BrokenPipe)
    })
}

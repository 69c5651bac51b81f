//! The `egt` binary: the command line of `egt_cli::run`, its exit code the
//! process's.

use std::process::ExitCode;

fn main() -> ExitCode {
    ExitCode::from(egt_cli::run(std::env::args_os()))
}

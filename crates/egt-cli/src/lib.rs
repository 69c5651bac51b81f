//! The `egt` command line as a library: [`run`] parses arguments, runs one
//! subcommand and returns the exit code. The `egt` binary is a one-line
//! `main` over it, and the Python package exposes the same entry point
//! (`python -m egt`, the `egt` console script), so both give one CLI.
//!
//! Exit codes: 0 on success (and when stdout is a closed pipe); 2 for usage,
//! syntax, spec, topology and gear-state errors; 1 for analysis and I/O
//! errors; 130 when Ctrl-C stopped a long command (only in the binary, see
//! [`run_handling_ctrl_c`]). Errors print to stderr as `error: ...`.

mod args;
pub mod cli;
pub mod commands;
mod input;
mod interrupt;
mod progress;
mod report;
mod svg;

use std::ffi::OsString;
use std::io::{self, Write};

use clap::Parser;

/// Run the command line `args` (the first is the program name) and return
/// the exit code. Output goes to the process's stdout and stderr. No signal
/// handler is set: Ctrl-C does what the hosting program makes of it.
pub fn run<I, T>(args: I) -> u8
where
    I: IntoIterator<Item = T>,
    T: Into<OsString> + Clone,
{
    run_with(args.into_iter().map(Into::into).collect(), false)
}

/// [`run`] for the `egt` binary: a long command (`synth`, `enumerate`,
/// `batch`) catches Ctrl-C, stops at its next block, writes what it
/// finished, prints `interrupted: ...` on stderr and returns 130. Other
/// commands keep the default (Ctrl-C ends the process at once).
pub fn run_handling_ctrl_c<I, T>(args: I) -> u8
where
    I: IntoIterator<Item = T>,
    T: Into<OsString> + Clone,
{
    run_with(args.into_iter().map(Into::into).collect(), true)
}

fn run_with(args: Vec<OsString>, ctrl_c: bool) -> u8 {
    let json = wants_json(&args);
    let cli = match cli::Cli::try_parse_from(&args) {
        Ok(cli) => cli,
        Err(e) => {
            // Help and version print to stdout with 0; usage errors to stderr with 2.
            let _ = e.print();
            return u8::try_from(e.exit_code()).unwrap_or(2);
        }
    };
    if ctrl_c && cli::stops_on_ctrl_c(&cli.command) {
        interrupt::install();
    }
    let terminal = io::IsTerminal::is_terminal(&io::stdout());
    let mut out = io::BufWriter::new(io::stdout().lock());
    let result = cli::preflight(&cli.command, terminal)
        .and_then(|()| cli::run(&cli.command, &mut out))
        .and_then(|()| Ok(out.flush()?));
    match result {
        Ok(()) => 0,
        Err(e) if is_broken_pipe(&e) => 0,
        Err(e) if interrupted(&e).is_some() => {
            // What the command finished is on stdout; no error document
            // after it (it would spoil a valid partial output).
            let _ = out.flush();
            eprintln!("interrupted: {}", interrupted(&e).unwrap_or_default());
            interrupt::EXIT
        }
        Err(e) => {
            let code = exit_code(&e);
            eprintln!("error: {e:#}");
            if json {
                // A program that asked for JSON gets the failure as JSON on stdout too.
                let _ = report::json(&mut out, &error_document(&e, code));
                let _ = out.flush();
            }
            code
        }
    }
}

/// `--format json` among the arguments.
fn wants_json(args: &[OsString]) -> bool {
    args.windows(2)
        .any(|w| w[0] == "--format" && w[1] == "json")
        || args.iter().any(|a| a == "--format=json")
}

/// The JSON form of a failure: a stable code, the message, the exit code and,
/// where known, the spec field and the line and column.
fn error_document(e: &anyhow::Error, exit: u8) -> serde_json::Value {
    let core = e.chain().find_map(|c| c.downcast_ref::<egt_core::Error>());
    let (path, position) = core.map_or((None, None), egt_core::Error::location);
    serde_json::json!({
        "error": {
            "code": core.map_or("io", egt_core::Error::code),
            "message": format!("{e:#}"),
            "exit": exit,
            "path": path,
            "line": position.map(|p| p.0),
            "column": position.map(|p| p.1),
        }
    })
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

/// What a run stopped by Ctrl-C left, if that is what `e` is.
fn interrupted(e: &anyhow::Error) -> Option<&str> {
    e.chain()
        .find_map(|c| c.downcast_ref::<interrupt::Interrupted>())
        .map(|i| i.0.as_str())
}

fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<io::Error>()
            .is_some_and(|io| io.kind() == io::ErrorKind::BrokenPipe)
    })
}

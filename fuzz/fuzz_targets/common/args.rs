//! The fuzz targets' command lines: the input's lines as arguments after a
//! fixed command and spec, run through the CLI's grammar and dispatch into
//! a buffer (`egt_cli::cli`), as `egt` runs them minus the process.

use clap::Parser as _;

/// Run `egt <fixed...> <the input's lines...> <last...>`; None when the
/// input is not a command line the harness runs: not UTF-8, or an argument
/// that reads standard input (`-`), names a path (`/`), or writes a file
/// (`--plot`, `--write-specs`). Any error is fine; a panic is a bug.
pub fn run(data: &[u8], fixed: &[&str], last: &[&str]) -> Option<Vec<u8>> {
    let text = std::str::from_utf8(data).ok()?;
    let given: Vec<&str> = text.lines().take(64).collect();
    if given
        .iter()
        .any(|a| *a == "-" || a.contains('/') || a.contains("--plot") || a.contains("--write"))
    {
        return None;
    }
    let args = ["egt"].iter().chain(fixed).chain(&given).chain(last);
    let cli = egt_cli::cli::Cli::try_parse_from(args).ok()?;
    let mut out = Vec::new();
    let _ = egt_cli::cli::run(&cli.command, &mut out);
    Some(out)
}

/// A bundled example's path.
pub fn example(name: &str) -> String {
    format!("{}/../examples/{name}", env!("CARGO_MANIFEST_DIR"))
}

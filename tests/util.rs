//! Running the `egt` binary as a user runs it.

use std::io::Write;
use std::path::PathBuf;
use std::process::{Command, Stdio};

/// The workspace root (where `examples/` is).
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// What one run of `egt` left: exit code and both streams.
pub struct Run {
    /// The exit code.
    pub code: i32,
    /// Standard output.
    pub stdout: String,
    /// Standard error.
    pub stderr: String,
}

/// Run `egt args` from the workspace root, feeding `stdin` (or nothing) on standard input.
pub fn egt(args: &[&str], stdin: Option<&str>) -> Run {
    let mut child = Command::new(env!("CARGO_BIN_EXE_egt"))
        .args(args)
        .current_dir(root())
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn egt");
    let mut pipe = child.stdin.take().expect("stdin");
    pipe.write_all(stdin.unwrap_or_default().as_bytes())
        .expect("write stdin");
    drop(pipe);
    let out = child.wait_with_output().expect("wait for egt");
    Run {
        code: out.status.code().expect("an exit code, not a signal"),
        stdout: String::from_utf8(out.stdout).expect("utf8 stdout"),
        stderr: String::from_utf8(out.stderr).expect("utf8 stderr"),
    }
}

/// Standard output of `egt args`, which must succeed.
pub fn stdout(args: &[&str]) -> String {
    let r = egt(args, None);
    assert_eq!(r.code, 0, "egt {args:?}: {}", r.stderr);
    r.stdout
}

/// Path of a bundled example.
pub fn example_path(name: &str) -> PathBuf {
    root().join("examples").join(name)
}

/// A bundled example as the library reads it (to compare the binary's output with).
pub fn example(name: &str) -> egt_core::Train {
    let path = example_path(name);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    egt_core::Train::from_str(&text, egt_core::Format::from_path(name), name)
        .unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// |a - b| <= rel * max(|a|, |b|).
pub fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()).max(1e-300)
}

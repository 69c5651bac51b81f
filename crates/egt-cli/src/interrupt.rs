//! Ctrl-C in the long commands (`egt synth`, `egt enumerate`, `egt batch`):
//! the `egt` binary's handler sets one flag, their loops read it between
//! blocks, write what they finished and return [`Interrupted`], which
//! `lib.rs` prints as one `interrupted: ...` line and exit code 130.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, LazyLock};

/// Set by the first Ctrl-C. An `Arc`, because the design search keeps it.
static FLAG: LazyLock<Arc<AtomicBool>> = LazyLock::new(|| Arc::new(AtomicBool::new(false)));

/// The exit code of a run stopped by Ctrl-C: 128 + SIGINT, the shells'
/// convention for a command that SIGINT ended.
pub const EXIT: u8 = 130;

/// The flag the long commands read (and hand to the core's searches).
pub(crate) fn flag() -> Arc<AtomicBool> {
    Arc::clone(&FLAG)
}

/// Whether Ctrl-C has been pressed.
pub(crate) fn requested() -> bool {
    FLAG.load(Ordering::Relaxed)
}

/// Catch SIGINT (Ctrl-C) for the rest of the process: the first sets the
/// flag, a second exits at once with [`EXIT`] (whatever was being written
/// may then be cut). Only the binary calls this (`run_handling_ctrl_c`):
/// the library never takes a signal from the program that hosts it (the
/// Python module's `egt` command). SIGINT that was not at its default when
/// egt started is left as it was: ignored (`nohup`, a script's background
/// job, which Ctrl-C must not reach) or another handler's; then no flag is
/// set and nothing changes.
pub(crate) fn install() {
    let _ = ctrlc::try_set_handler(|| {
        if FLAG.swap(true, Ordering::SeqCst) {
            eprintln!("\ninterrupted twice: exiting at once (the output may be cut short)");
            std::process::exit(i32::from(EXIT));
        }
    });
}

/// A run that Ctrl-C stopped, and what it left: the text says what was
/// written and whether it is whole (e.g. "12345 of 1000000 scenarios
/// written"). Not a failure of the input or the analysis: `lib.rs` prints
/// `interrupted: <text>` and exits with [`EXIT`], after flushing what the
/// command wrote.
#[derive(Debug)]
pub struct Interrupted(pub String);

impl std::fmt::Display for Interrupted {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Interrupted {}

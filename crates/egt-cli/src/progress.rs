//! The progress line of the long commands (`egt synth`, `egt enumerate`,
//! `egt batch`): done / total and the rate, on standard error only, at most
//! a few times a second; drawn in place on a terminal, written as plain
//! lines with `--progress` elsewhere, and off otherwise.

use std::io::{IsTerminal, Write};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, mpsc};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// How often the line is redrawn on a terminal.
const TERMINAL_EVERY: Duration = Duration::from_millis(250);

/// How often a line is written when standard error is a file or a pipe
/// (`--progress`): a log gains a line a second, not a screenful.
const LINES_EVERY: Duration = Duration::from_secs(1);

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Mode {
    Off,
    /// Redrawn in place (`\r`), cleared at the end.
    Terminal,
    /// One line each time, and a last one at the end.
    Lines,
}

/// One command's progress: `done` of `total` units (`what`: "scenarios",
/// "trees", "parts"), with an optional note (e.g. the members found). The
/// command updates the counts as its units finish (a mutex taken once a
/// unit); a thread of its own draws the line on a clock, so that it moves
/// (the time elapsed) even while a long unit runs, and never more often
/// than its interval.
#[derive(Debug)]
pub(crate) struct Progress {
    shared: Arc<Shared>,
    /// Dropped to stop the drawing thread.
    stop: Option<mpsc::Sender<()>>,
    ticker: Option<JoinHandle<()>>,
}

#[derive(Debug)]
struct Shared {
    mode: Mode,
    what: &'static str,
    start: Instant,
    counts: Mutex<Counts>,
    /// A line is on the terminal (to clear at the end).
    drawn: AtomicBool,
}

#[derive(Debug, Default)]
struct Counts {
    total: Option<u64>,
    done: u64,
    note: String,
}

impl Progress {
    /// A progress line for `total` units (None: not known before the end),
    /// shown when standard error is a terminal, or anywhere when `asked`
    /// (`--progress`).
    pub(crate) fn new(asked: bool, what: &'static str, total: Option<u64>) -> Self {
        let terminal = std::io::stderr().is_terminal();
        let mode = match (terminal, asked) {
            (true, _) => Mode::Terminal,
            (false, true) => Mode::Lines,
            (false, false) => Mode::Off,
        };
        Self::with_mode(mode, what, total)
    }

    /// No line, whatever standard error is.
    pub(crate) fn hidden() -> Self {
        Self::with_mode(Mode::Off, "", None)
    }

    fn with_mode(mode: Mode, what: &'static str, total: Option<u64>) -> Self {
        let shared = Arc::new(Shared {
            mode,
            what,
            start: Instant::now(),
            counts: Mutex::new(Counts {
                total,
                ..Counts::default()
            }),
            drawn: AtomicBool::new(false),
        });
        let every = match mode {
            Mode::Off => {
                return Progress {
                    shared,
                    stop: None,
                    ticker: None,
                };
            }
            Mode::Terminal => TERMINAL_EVERY,
            Mode::Lines => LINES_EVERY,
        };
        let (stop, wait) = mpsc::channel::<()>();
        let drawn = Arc::clone(&shared);
        // No thread (a process out of threads): no line, the run goes on.
        let ticker = std::thread::Builder::new()
            .name("egt-progress".into())
            .spawn(move || {
                while let Err(mpsc::RecvTimeoutError::Timeout) = wait.recv_timeout(every) {
                    drawn.draw();
                }
            })
            .ok();
        Progress {
            shared,
            stop: Some(stop),
            ticker,
        }
    }

    fn counts(&self) -> std::sync::MutexGuard<'_, Counts> {
        self.shared
            .counts
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    /// `n` more units done.
    pub(crate) fn add(&self, n: u64) {
        let mut c = self.counts();
        c.done = c.done.saturating_add(n);
    }

    /// `done` units done.
    pub(crate) fn set(&self, done: u64) {
        self.counts().done = done;
    }

    /// The total, when it is known only once the work has started.
    pub(crate) fn total(&self, total: u64) {
        self.counts().total = Some(total);
    }

    /// The note after the counts (e.g. "1234 members").
    pub(crate) fn note(&self, note: String) {
        self.counts().note = note;
    }
}

impl Shared {
    /// The line: `progress: 1200/10000 scenarios (12.0 %), 3400/s, 0:02
    /// elapsed, 0:24 left`.
    fn line(&self) -> String {
        let c = self
            .counts
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        let seconds = self.start.elapsed().as_secs_f64();
        let rate = if seconds > 0.0 {
            c.done as f64 / seconds
        } else {
            0.0
        };
        let mut s = format!("progress: {}", c.done);
        if let Some(total) = c.total {
            s += &format!("/{total} {}", self.what);
            if total > 0 {
                s += &format!(" ({:.1} %)", 100.0 * c.done as f64 / total as f64);
            }
        } else {
            s += &format!(" {}", self.what);
        }
        s += &format!(", {}/s, {} elapsed", rate_text(rate), clock(seconds));
        if let Some(total) = c.total
            && rate > 0.0
            && c.done < total
        {
            let left = (total - c.done) as f64 / rate;
            s += &format!(", {} left", clock(left));
        }
        if !c.note.is_empty() {
            s += &format!(", {}", c.note);
        }
        s
    }

    fn draw(&self) {
        let line = self.line();
        let mut err = std::io::stderr().lock();
        // A closed stderr is no reason to stop the command.
        let _ = match self.mode {
            Mode::Off => Ok(()),
            // Back to the start of the line, clear it, draw.
            Mode::Terminal => write!(err, "\r\x1b[2K{line}").and_then(|()| err.flush()),
            Mode::Lines => writeln!(err, "{line}"),
        };
        self.drawn.store(true, Ordering::Relaxed);
    }
}

impl Drop for Progress {
    /// The end (a finished run, an error or Ctrl-C): the drawing thread
    /// stops; a terminal's line is cleared, so that what follows starts on
    /// a clean line; a log gets the last counts.
    fn drop(&mut self) {
        drop(self.stop.take());
        if let Some(t) = self.ticker.take() {
            let _ = t.join();
        }
        match self.shared.mode {
            Mode::Off => {}
            Mode::Terminal => {
                if self.shared.drawn.load(Ordering::Relaxed) {
                    let mut err = std::io::stderr().lock();
                    let _ = write!(err, "\r\x1b[2K").and_then(|()| err.flush());
                }
            }
            Mode::Lines => self.shared.draw(),
        }
    }
}

/// A rate with three significant digits: `950`, `12300`, `1.23e6`.
fn rate_text(rate: f64) -> String {
    if rate < 1e5 {
        format!("{}", (rate * 10.0).round() / 10.0)
    } else {
        format!("{rate:.2e}")
    }
}

/// Seconds as `m:ss` (or `h:mm:ss`).
fn clock(seconds: f64) -> String {
    let s = seconds.round().min(u32::MAX as f64) as u64;
    let (h, m, s) = (s / 3600, s / 60 % 60, s % 60);
    if h > 0 {
        format!("{h}:{m:02}:{s:02}")
    } else {
        format!("{m}:{s:02}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_line_gives_counts_percent_rate_and_times() {
        let p = Progress::with_mode(Mode::Off, "scenarios", Some(1000));
        p.add(200);
        p.add(50);
        let line = p.shared.line();
        assert!(
            line.starts_with("progress: 250/1000 scenarios (25.0 %), "),
            "{line}"
        );
        assert!(line.contains("/s, 0:00 elapsed"), "{line}");
        let q = Progress::with_mode(Mode::Off, "specs", None);
        q.set(7);
        q.note("2 failed".into());
        let line = q.shared.line();
        assert!(line.starts_with("progress: 7 specs, "), "{line}");
        assert!(line.ends_with(", 2 failed"), "{line}");
        assert_eq!(clock(59.6), "1:00");
        assert_eq!(clock(3725.0), "1:02:05");
        assert_eq!(rate_text(12.34), "12.3");
        assert_eq!(rate_text(1.234e6), "1.23e6");
    }
}

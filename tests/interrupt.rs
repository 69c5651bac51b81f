//! Issue 42: Ctrl-C (SIGINT, sent by `kill -INT`) stops `egt enumerate`,
//! `egt batch` and `egt synth` mid-run with exit code 130, one
//! `interrupted: ...` line on stderr, no panic, and an output that is whole
//! as far as it goes; `--progress` writes progress lines on stderr and
//! nothing on stdout.

// A failed unwrap is a failed test, with its location.
#![allow(clippy::unwrap_used)]

use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use serde_json::Value;

use crate::util::{egt, root};

/// When a run gets its SIGINT.
#[derive(Clone, Copy)]
enum When {
    /// After this long: past the start (the handler is set right after the
    /// arguments are read), well before the end of a job of seconds.
    After(Duration),
    /// Once its stdout holds more than this many bytes: part of the output
    /// written (whole blocks or trees), however fast the build.
    Output(u64),
}

/// The most a run may take to write its first output.
const OUTPUT_WITHIN: Duration = Duration::from_secs(180);

/// The most a run may take to stop after its SIGINT.
const STOP_WITHIN: Duration = Duration::from_secs(60);

/// What an interrupted run left: its exit code, stderr, and the path its
/// stdout went to.
struct Stopped {
    code: Option<i32>,
    stderr: String,
    stdout: PathBuf,
}

/// A fresh path in the temporary directory for `name`.
fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("egt-interrupt-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// The `egt` binary to spawn, with SIGINT at its default: egt leaves an
/// ignored SIGINT ignored, and a test runner started in the background of
/// a script passes SIGINT on ignored. `env --default-signal` (GNU
/// coreutils) resets it, where there is one.
fn egt_with_sigint_at_default() -> Command {
    let reset = Command::new("env")
        .args(["--default-signal=INT", "true"])
        .status()
        .is_ok_and(|s| s.success());
    if reset {
        let mut c = Command::new("env");
        c.args(["--default-signal=INT", env!("CARGO_BIN_EXE_egt")]);
        c
    } else {
        Command::new(env!("CARGO_BIN_EXE_egt"))
    }
}

/// Run `egt args` with stdout into the file `name`, send SIGINT `when`, and
/// wait for it to stop.
fn interrupt(args: &[&str], name: &str, when: When) -> Stopped {
    let stdout = temp(name);
    let mut child = egt_with_sigint_at_default()
        .args(args)
        .current_dir(root())
        .stdin(Stdio::null())
        .stdout(std::fs::File::create(&stdout).unwrap())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    match when {
        When::After(wait) => std::thread::sleep(wait),
        When::Output(bytes) => {
            let start = Instant::now();
            while std::fs::metadata(&stdout).unwrap().len() <= bytes
                && child.try_wait().unwrap().is_none()
            {
                if start.elapsed() > OUTPUT_WITHIN {
                    let _ = child.kill();
                    panic!("egt {args:?} wrote no {bytes} bytes within {OUTPUT_WITHIN:?}");
                }
                std::thread::sleep(Duration::from_millis(20));
            }
        }
    }
    assert!(
        child.try_wait().unwrap().is_none(),
        "egt {args:?} ended before its SIGINT: pick a longer job"
    );
    let kill = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > STOP_WITHIN {
            let _ = child.kill();
            panic!("egt {args:?} did not stop within {STOP_WITHIN:?} of its SIGINT");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = child.wait_with_output().unwrap();
    let stopped = Stopped {
        code: out.status.code(),
        stderr: String::from_utf8(out.stderr).unwrap(),
        stdout,
    };
    // Exit 130 (not killed by the signal), the one line, no panic.
    assert_eq!(stopped.code, Some(130), "egt {args:?}: {}", stopped.stderr);
    assert!(
        !stopped.stderr.contains("panicked"),
        "egt {args:?}: {}",
        stopped.stderr
    );
    assert_eq!(
        stopped
            .stderr
            .lines()
            .filter(|l| l.starts_with("interrupted: "))
            .count(),
        1,
        "egt {args:?}: {}",
        stopped.stderr
    );
    stopped
}

impl Stopped {
    /// The `interrupted: ...` line.
    fn line(&self) -> &str {
        self.stderr
            .lines()
            .find(|l| l.starts_with("interrupted: "))
            .unwrap()
    }

    /// The number before `word` in the interrupted line (`12 of 30 trees`: 12).
    fn count_before(&self, word: &str) -> usize {
        let line = self.line();
        let words: Vec<&str> = line.split_whitespace().collect();
        let at = words.iter().position(|w| *w == word).unwrap();
        words[at - 1].parse().unwrap()
    }

    fn text(&self) -> String {
        std::fs::read_to_string(&self.stdout).unwrap()
    }
}

/// Links of an atlas that takes tens of seconds in this build (the first
/// trees are the slow ones): 8 links unoptimised, 9 optimised.
const LINKS: &str = if cfg!(debug_assertions) { "8" } else { "9" };

/// The whole members of the trees done: as many JSON lines as the line
/// says, each of them whole; stopped once the first trees are written.
#[test]
fn enumerate_stops_after_whole_trees_with_exit_130() {
    let r = interrupt(
        &["enumerate", "--links", LINKS, "--jsonl"],
        "atlas.jsonl",
        When::Output(0),
    );
    let written = r.count_before("members");
    assert!(written > 0, "{}", r.line());
    assert!(r.line().contains("trees enumerated"), "{}", r.line());
    let text = r.text();
    assert!(text.is_empty() || text.ends_with('\n'));
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), written, "{}", r.line());
    for l in lines {
        let v: Value = serde_json::from_str(l).unwrap();
        assert_eq!(v["links"].to_string(), LINKS);
    }
}

/// `--count` of part of the atlas is not its size: nothing on stdout.
#[test]
fn enumerate_count_prints_no_partial_count() {
    let r = interrupt(
        &["enumerate", "--links", "9", "--count"],
        "count.txt",
        When::After(Duration::from_millis(800)),
    );
    assert_eq!(r.text(), "");
    assert!(r.line().contains("no count printed"), "{}", r.line());
}

/// A grid of 10^9 rows to CSV, stopped once 200 kB are written: the file
/// is the header and the first rows, numbered from 0, each line whole.
#[test]
fn batch_csv_stops_with_the_first_rows_whole() {
    let r = interrupt(
        &[
            "batch",
            "examples/fig3_example61.toml",
            "--grid",
            "speed.2=1:2:100000",
            "--grid",
            "torque.2=0:1:10000",
            "--columns",
            "speed.3",
            "--output",
            "csv",
        ],
        "batch.csv",
        When::Output(200_000),
    );
    let written = r.count_before("of");
    assert!(written > 0, "{}", r.line());
    assert!(
        r.line().contains("of 1000000000 scenarios written"),
        "{}",
        r.line()
    );
    let text = r.text();
    assert!(text.ends_with('\n'));
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    assert_eq!(header, "row,speed.2,torque.2,speed.3,warning,error");
    let mut n = 0;
    for (i, l) in lines.enumerate() {
        let fields: Vec<&str> = l.split(',').collect();
        assert_eq!(fields.len(), 6, "{l}");
        assert_eq!(fields[0], i.to_string());
        n += 1;
    }
    assert_eq!(n, written, "{}", r.line());
}

/// The same grid to Parquet, stopped once its first row group is written:
/// the file is closed (footer written) and holds the rows the line says,
/// rows 0 to n - 1.
#[test]
fn batch_parquet_stops_with_a_readable_file() {
    use arrow_array::{Array, UInt64Array};
    let r = interrupt(
        &[
            "batch",
            "examples/fig3_example61.toml",
            "--grid",
            "speed.2=1:2:100000",
            "--grid",
            "torque.2=0:1:10000",
            "--columns",
            "speed.3",
            "--output",
            "parquet",
        ],
        "batch.parquet",
        When::Output(10_000),
    );
    let written = r.count_before("of");
    assert!(written > 0, "{}", r.line());
    let file = std::fs::File::open(&r.stdout).unwrap();
    let reader = parquet::arrow::arrow_reader::ParquetRecordBatchReaderBuilder::try_new(file)
        .unwrap()
        .build()
        .unwrap();
    let mut rows = 0;
    for batch in reader {
        let batch = batch.unwrap();
        let row = batch
            .column_by_name("row")
            .unwrap()
            .as_any()
            .downcast_ref::<UInt64Array>()
            .unwrap();
        for k in 0..row.len() {
            assert_eq!(row.value(k), (rows + k) as u64);
        }
        rows += batch.num_rows();
    }
    assert_eq!(rows, written, "{}", r.line());
}

/// The C4 search at a tolerance that prunes nothing, with no leaf budget to
/// speak of (minutes of exact confirmations): stopped, the report is
/// printed and says it is partial.
#[test]
fn synth_stops_and_prints_the_report_marked_interrupted() {
    let search = std::fs::read_to_string(root().join("examples/synth/ford_c4_simpson.toml"))
        .unwrap()
        .replace(
            "../ford_c4_simpson.toml",
            &root()
                .join("examples/ford_c4_simpson.toml")
                .to_string_lossy(),
        )
        .replace("tolerance = 0.005", "tolerance = 100");
    let path = temp("c4_wide.toml");
    std::fs::write(&path, search).unwrap();
    let r = interrupt(
        &[
            "synth",
            &path.to_string_lossy(),
            "--max-leaves",
            "100000000",
            "--format",
            "json",
        ],
        "synth.json",
        When::After(Duration::from_millis(800)),
    );
    assert!(r.line().contains("the search stopped"), "{}", r.line());
    let report: Value = serde_json::from_str(&r.text()).unwrap();
    assert_eq!(report["stats"]["interrupted"], true, "{report}");
    assert!(report["candidates"].is_array());
}

/// Lines starting `progress: ` on stderr.
fn progress_lines(stderr: &str) -> Vec<&str> {
    stderr
        .lines()
        .filter(|l| l.starts_with("progress: "))
        .collect()
}

/// `--progress` with stderr a pipe: progress lines on stderr, ending at the
/// total, and stdout byte for byte as without it; without it, none.
#[test]
fn progress_goes_to_stderr_only() {
    let batch = [
        "batch",
        "examples/fig3_example61.toml",
        "--grid",
        "speed.2=1:2:300",
        "--grid",
        "torque.2=0:1:300",
        "--output",
        "csv",
    ];
    let enumerate = ["enumerate", "--links", "6", "--count"];
    for (args, last) in [
        (&batch[..], "progress: 90000/90000 scenarios (100.0 %)"),
        (&enumerate[..], " trees (100.0 %)"),
    ] {
        let plain = egt(args, None);
        assert_eq!(plain.code, 0, "{}", plain.stderr);
        assert!(progress_lines(&plain.stderr).is_empty(), "{}", plain.stderr);
        let shown = egt(&[args, &["--progress"][..]].concat(), None);
        assert_eq!(shown.code, 0, "{}", shown.stderr);
        assert_eq!(shown.stdout, plain.stdout, "{args:?}");
        let lines = progress_lines(&shown.stderr);
        assert!(!lines.is_empty(), "{args:?}: {}", shown.stderr);
        assert!(lines[lines.len() - 1].contains(last), "{}", shown.stderr);
        assert!(lines[lines.len() - 1].contains("/s"), "{}", shown.stderr);
        assert!(
            !shown.stdout.contains("progress"),
            "{args:?}: progress on stdout"
        );
    }
    // The search in parts: the same candidates as one run.
    let synth = [
        "synth",
        "examples/synth/ford_c4_simpson.toml",
        "--format",
        "json",
    ];
    let plain: Value = serde_json::from_str(&egt(&synth, None).stdout).unwrap();
    let shown = egt(&[&synth[..], &["--progress"][..]].concat(), None);
    assert_eq!(shown.code, 0, "{}", shown.stderr);
    let lines = progress_lines(&shown.stderr);
    assert!(
        lines.last().is_some_and(|l| l.contains(" parts (100.0 %)")),
        "{}",
        shown.stderr
    );
    let with: Value = serde_json::from_str(&shown.stdout).unwrap();
    assert_eq!(plain["candidates"], with["candidates"]);
}

//! `egt batch` end to end: rows, designs, text output, `--specs`.

use clap::Parser;

use crate::cli::{Cli, Command};

const FIG3: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../examples/fig3_example61.toml"
);

/// Run `egt batch ARGS...`; the bytes written and the outcome.
pub(super) fn batch_bytes(args: &[&str]) -> (Vec<u8>, anyhow::Result<()>) {
    let cli =
        Cli::try_parse_from(["egt", "batch"].iter().chain(args)).unwrap_or_else(|e| panic!("{e}"));
    let Command::Batch(a) = cli.command else {
        panic!("not a batch command")
    };
    let mut out = Vec::new();
    let r = super::run(&a, &mut out);
    (out, r)
}

/// Run `egt batch ARGS...`; the text written and the outcome.
fn batch(args: &[&str]) -> (String, anyhow::Result<()>) {
    let (out, r) = batch_bytes(args);
    (String::from_utf8(out).unwrap_or_default(), r)
}

fn json_lines(text: &str) -> Vec<serde_json::Value> {
    text.lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{e}: {l}")))
        .collect()
}

/// Fig. 3's spec as one line of JSON (a `--specs` line).
pub(super) fn fig3_json() -> String {
    let text = std::fs::read_to_string(FIG3).unwrap_or_else(|e| panic!("{FIG3}: {e}"));
    let good =
        egt_core::parse_spec(&text, egt_core::Format::Toml, "x").unwrap_or_else(|e| panic!("{e}"));
    serde_json::to_string(&good).unwrap_or_else(|e| panic!("{e}"))
}

fn temp(name: &str, text: &str) -> String {
    let dir = std::env::temp_dir().join(format!("egt-batch-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{e}"));
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap_or_else(|e| panic!("{e}"));
    p.display().to_string()
}

#[test]
fn bad_rows_are_reported_in_place_and_the_rest_go_on() {
    let rows = temp(
        "rows.jsonl",
        "{\"torque.4\": -10}\nnot json\n{\"torque.9\": 1}\n{\"ratio.G1\": 0}\n{\"inertia.2\": -1}\n{\"torque.4\": -20, \"accel.4\": 0}\n",
    );
    let (text, r) = batch(&[FIG3, "--rows", &rows]);
    let lines = json_lines(&text);
    assert_eq!(lines.len(), 6, "{text}");
    for (k, l) in lines.iter().enumerate() {
        assert_eq!(l["row"], k);
    }
    let failed: Vec<usize> = (0..6)
        .filter(|&k| lines[k].get("error").is_some())
        .collect();
    assert_eq!(failed, vec![1, 2, 3, 4]);
    assert!(
        lines[2]["error"]
            .as_str()
            .unwrap_or("")
            .contains("torque.9")
    );
    assert!(
        lines[3]["error"]
            .as_str()
            .unwrap_or("")
            .contains("ratio.G1")
    );
    // The good rows carry results that differ as their loads do.
    let t0 = lines[0]["driving_torque.2"].as_f64().unwrap_or(f64::NAN);
    let t5 = lines[5]["driving_torque.2"].as_f64().unwrap_or(f64::NAN);
    assert!(t0.is_finite() && t5.is_finite() && t0 != t5);
    let e = r.expect_err("failed rows make the run fail");
    assert!(e.to_string().starts_with("4 of 6 scenarios failed"), "{e}");
}

/// Asking for no `cond.*` column (condition bounds in the program) keeps
/// every number, warning and error: Fig. 3 swept through its lock
/// (tau_2 = 1 / tau_1 = -1.5), where the rows next to it are warned
/// about and the lock itself refused.
#[test]
fn columns_without_conditions_keep_the_warnings_and_errors() {
    let args = [
        FIG3,
        "--grid",
        "ratio.G2=-1.5000001:-1.4999999:21",
        "--grid",
        "torque.4=-10:-50:8",
        "--output",
        "csv",
    ];
    let table = |extra: &[&str]| {
        let all: Vec<&str> = args.iter().chain(extra).copied().collect();
        let (text, r) = batch(&all);
        assert!(r.is_err(), "the locked rows fail");
        let mut lines = text.lines();
        let header: Vec<String> = lines
            .next()
            .unwrap_or_default()
            .split(',')
            .map(String::from)
            .collect();
        let rows: Vec<Vec<String>> = lines
            .map(|l| l.split(',').map(String::from).collect())
            .collect();
        (header, rows)
    };
    let (h_all, all) = table(&[]);
    let (h_one, one) = table(&["--columns", "driving_torque.2"]);
    assert_eq!(all.len(), 168);
    assert_eq!(one.len(), all.len());
    let (mut warned, mut failed) = (0, 0);
    for name in ["row", "driving_torque.2", "warning", "error"] {
        let (i, j) = (
            h_all.iter().position(|h| h == name),
            h_one.iter().position(|h| h == name),
        );
        let (Some(i), Some(j)) = (i, j) else {
            panic!("no column {name}: {h_all:?} {h_one:?}")
        };
        for (a, b) in all.iter().zip(&one) {
            assert_eq!(a[i], b[j], "{name}, row {}", a[0]);
            warned += usize::from(name == "warning" && !a[i].is_empty());
            failed += usize::from(name == "error" && !a[i].is_empty());
        }
    }
    assert!(
        warned >= 16 && failed >= 8,
        "{warned} warned, {failed} failed"
    );
}

/// `number` writes what `{v:?}` writes, for every kind of double: edge
/// values, random bit patterns, log-uniform magnitudes across the plain
/// decimal range, short decimals, and doubles of few significant bits
/// (where two shortest decimals are often equally near, the case zmij
/// and std decide otherwise), of either sign; NaN and infinities empty
/// in CSV, null in JSON.
#[test]
fn numbers_are_written_as_std_writes_them() {
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let mut values = vec![
        0.0,
        -0.0,
        1e-4,
        f64::from_bits(1e-4f64.to_bits() - 1),
        1e16,
        f64::from_bits(1e16f64.to_bits() - 1),
        1e-5,
        f64::MAX,
        f64::MIN_POSITIVE,
        5e-324,
        0.1,
        1.0 / 3.0,
        100.0,
        637_158_808_661_681.0 + 0.25,
        1.0 + 2f64.powi(-17),
    ];
    for i in 0..500_000u64 {
        let r = next();
        let sign = if r >> 63 == 0 { 1.0 } else { -1.0 };
        let unit = (r >> 11) as f64 / (1u64 << 53) as f64;
        values.push(match i % 5 {
            0 => f64::from_bits(r),
            1 => sign * 10f64.powf(-4.0 + 20.0 * unit),
            2 => sign * (r >> 11) as f64 / 10f64.powi((r % 12) as i32),
            3 => sign * (1.0 + (r >> 40) as f64 * 2f64.powi(-((r % 30) as i32 + 1))),
            _ => sign * (r >> 20) as f64 * 2f64.powi(-((r % 64) as i32)),
        });
    }
    let mut otherwise = 0;
    for v in values {
        for json in [false, true] {
            let mut got = String::new();
            super::text::number(&mut got, v, json);
            let want = match (v.is_finite(), json) {
                (true, _) => format!("{v:?}"),
                (false, true) => "null".to_string(),
                (false, false) => String::new(),
            };
            assert_eq!(got, want, "{v:e} ({:#x})", v.to_bits());
            let mut digits = zmij::Buffer::new();
            otherwise += usize::from(v.is_finite() && !json && digits.format_finite(v) != want);
        }
    }
    // Many of them zmij alone writes otherwise (a tie, or an exponent).
    assert!(
        otherwise > 1000,
        "{otherwise} numbers zmij writes otherwise"
    );
}

#[test]
fn vary_zips_grid_crosses_and_set_fixes() {
    let (text, r) = batch(&[
        FIG3,
        "--vary",
        "ratio.G1=-0.7,-0.6",
        "--vary",
        "accel.4=1,2",
        "--grid",
        "torque.4=-10:-30:3",
        "--set",
        "speed.2=50",
        "--output",
        "csv",
    ]);
    r.unwrap_or_else(|e| panic!("{e}"));
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap_or("").split(',').collect();
    let col = |n: &str| {
        header
            .iter()
            .position(|h| *h == n)
            .unwrap_or_else(|| panic!("{n}"))
    };
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 6);
    let got: Vec<(&str, &str, &str, &str)> = rows
        .iter()
        .map(|r| {
            (
                r[col("ratio.G1")],
                r[col("accel.4")],
                r[col("torque.4")],
                r[col("speed.2")],
            )
        })
        .collect();
    assert_eq!(
        got,
        vec![
            ("-0.7", "1.0", "-10.0", "50.0"),
            ("-0.7", "1.0", "-20.0", "50.0"),
            ("-0.7", "1.0", "-30.0", "50.0"),
            ("-0.6", "2.0", "-10.0", "50.0"),
            ("-0.6", "2.0", "-20.0", "50.0"),
            ("-0.6", "2.0", "-30.0", "50.0"),
        ]
    );
    let (_, r) = batch(&[
        FIG3,
        "--vary",
        "ratio.G1=-0.7,-0.6",
        "--vary",
        "accel.4=1,2,3",
    ]);
    assert!(r.is_err(), "zipped arrays of unequal length");
    let (_, r) = batch(&[FIG3, "--grid", "ratio.G9=1,2"]);
    let e = r.expect_err("unknown parameter");
    assert!(format!("{e:#}").contains("ratio.G9"));
}

#[test]
fn specs_file_one_train_per_line_with_a_broken_line() {
    let json = fig3_json();
    let specs = temp(
        "specs.jsonl",
        &format!("{json}\n{{\"frame\": 3}}\n{json}\n"),
    );
    let (text, r) = batch(&["--specs", &specs, "--columns", "driving_torque.2"]);
    let lines = json_lines(&text);
    assert_eq!(lines.len(), 3);
    assert!(lines[1].get("error").is_some());
    assert_eq!(lines[0]["driving_torque.2"], lines[2]["driving_torque.2"]);
    assert!(lines[0]["driving_torque.2"].as_f64().is_some());
    assert!(r.is_err());
}

/// A `--specs` input is read a block at a time: at most SPECS_BLOCK_BYTES
/// of text (here 1 MiB lines: 16 a block), blank lines skipped, the line
/// numbers running on across blocks.
#[test]
fn specs_lines_come_in_blocks_of_bounded_text() {
    use super::specs::{SPECS_BLOCK_BYTES, SpecLines};
    let line = "x".repeat(1 << 20);
    let mut text = String::new();
    for k in 0..40 {
        text.push_str(&line);
        text.push('\n');
        if k % 10 == 3 {
            text.push_str("  \n");
        }
    }
    let mut lines = SpecLines {
        reader: std::io::Cursor::new(text.into_bytes()),
        source: "mem".into(),
        read: 0,
    };
    let (mut sizes, mut numbers) = (Vec::new(), Vec::new());
    loop {
        let block = lines.next_block().unwrap_or_else(|e| panic!("{e}"));
        if block.is_empty() {
            break;
        }
        let bytes: usize = block
            .iter()
            .map(|(_, l)| l.as_ref().map_or(0, String::len))
            .sum();
        assert!(bytes < SPECS_BLOCK_BYTES + (1 << 20));
        sizes.push(block.len());
        numbers.extend(block.iter().map(|(k, _)| *k));
    }
    assert_eq!(sizes, [16, 16, 8]);
    // Lines 4, 15, 26, 37 (from 0) are blank.
    let expected: Vec<usize> = (0..44).filter(|k| ![4, 15, 26, 37].contains(k)).collect();
    assert_eq!(numbers, expected);
}

/// A `--specs` line past the spec size limit (256 MiB + 1 byte, in a
/// sparse file) is refused in its row, naming the limit, without
/// stopping the lines after it.
#[test]
fn a_specs_line_past_the_size_limit_is_refused_in_its_row() {
    use std::io::{Seek, SeekFrom, Write as _};
    let json = fig3_json();
    let path = temp("huge.jsonl", "");
    let mut f = std::fs::OpenOptions::new()
        .write(true)
        .open(&path)
        .unwrap_or_else(|e| panic!("{e}"));
    let limit = egt_core::spec::parse::MAX_SPEC_BYTES as u64;
    f.seek(SeekFrom::Start(limit + 1))
        .and_then(|_| f.write_all(format!("\n{json}\n").as_bytes()))
        .unwrap_or_else(|e| panic!("{e}"));
    drop(f);
    let (text, r) = batch(&["--specs", &path, "--columns", "driving_torque.2"]);
    let _ = std::fs::remove_file(&path);
    let lines = json_lines(&text);
    assert_eq!(lines.len(), 2, "{text}");
    let e = lines[0]["error"].as_str().unwrap_or_default();
    assert!(e.contains("huge.jsonl:1") && e.contains("256 MiB"), "{e}");
    assert!(
        lines[1]["driving_torque.2"].as_f64().is_some(),
        "{}",
        lines[1]
    );
    assert!(r.is_err());
}

#[test]
fn shift_table_states_share_a_csv_header() {
    let spec = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/zf_8hp70.toml");
    let (text, r) = batch(&[
        spec,
        "--state",
        "all",
        "--set",
        "speed.input=100",
        "--set",
        "torque.input=200",
        "--compute",
        "power",
        "--output",
        "csv",
        "--columns",
        "speed.output,power.efficiency",
    ]);
    r.unwrap_or_else(|e| panic!("{e}"));
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(
        lines[0],
        "row,state,speed.output,power.efficiency,warning,error"
    );
    assert_eq!(lines.len(), 10, "nine gear states");
    for l in &lines[1..] {
        let f: Vec<&str> = l.split(',').collect();
        let eta: f64 = f[3].parse().unwrap_or(f64::NAN);
        assert!(eta > 0.9 && eta <= 1.0, "{l}");
    }
}

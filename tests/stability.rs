//! `egt stability` and `egt simulate` as a user runs them (issue 4): the JSON
//! reports what the library computes, `--slope` overrides, CSV and plots, the
//! exit code when RK4 blows up past its step limit, and the output pasted in
//! `docs/stability.md`. The library's checks are in egt-core's tests.

// A failed unwrap is a failed test that prints the error: what a test wants.
#![allow(clippy::unwrap_used)]

use egt_core::StabilityRequest;

use crate::util::{Run, close, example};

fn egt(args: &[&str]) -> Run {
    crate::util::egt(args, None)
}

/// `egt stability --format json` reports what the library computes; `--slope`
/// moves motor 2 up its rising branch until the train turns unstable.
#[test]
fn cli_stability_json_and_slope_override() {
    let out = egt(&[
        "stability",
        "examples/fig5_stability.toml",
        "--format",
        "json",
    ]);
    assert!((out.code == 0), "{}", out.stderr.as_str());
    let v: serde_json::Value = serde_json::from_str(&out.stdout).unwrap();
    assert_eq!(v["verdict"], "stable");
    assert_eq!(v["coordinates"], serde_json::json!(["2", "4"]));
    let t = example("fig5_stability.toml");
    let rep = t.stability(&StabilityRequest::default()).unwrap();
    // JSON round trip: within an ulp or two.
    let same = |a: &serde_json::Value, b: f64| close(a.as_f64().unwrap(), b, 1e-15);
    for (k, lam) in rep.stability.eigenvalues.iter().enumerate() {
        assert!(same(&v["eigenvalues"][k], *lam));
        assert!(same(&v["modes"][k]["eigenvalue"], *lam));
    }
    assert!(same(&v["mass"][0][1], rep.model.mass[(0, 1)]));
    assert!(same(&v["slope"][1][1], rep.model.slope[(1, 1)]));
    assert!(v["operating"]["steady"].as_bool().unwrap());

    // Critical slope of motor 2: det [K] = 0 with K11 = k2 + K11(0).
    let k = &rep.model.slope;
    let critical = 0.02 - k[(0, 0)] + k[(0, 1)] * k[(1, 0)] / k[(1, 1)];
    for (slope, want) in [(0.98 * critical, "stable"), (1.02 * critical, "unstable")] {
        let s = format!("2={slope}");
        let out = egt(&[
            "stability",
            "examples/fig5_stability.toml",
            "--format",
            "json",
            "--slope",
            &s,
        ]);
        assert!((out.code == 0));
        let v: serde_json::Value = serde_json::from_str(&out.stdout).unwrap();
        assert_eq!(v["verdict"], want, "slope {slope}");
    }
    let out = egt(&[
        "stability",
        "examples/fig5_stability.toml",
        "--slope",
        "3=0.1",
    ]);
    assert_eq!(
        Some(out.code),
        Some(2),
        "a link without a curve is a spec error"
    );
    assert!(out.stderr.as_str().contains("no curve"));
}

/// `egt simulate`: CSV with every stored sample, the SVG plot, the table's
/// checks, and exit 1 with the series when RK4 blows up past its step limit.
#[test]
fn cli_simulate_csv_plot_and_blow_up() {
    let dir = std::env::temp_dir().join(format!("egt-sim-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let svg = dir.join("fig5.svg");
    let out = egt(&[
        "simulate",
        "examples/fig5_stability.toml",
        "--format",
        "csv",
        "--every",
        "10",
        "--plot",
        svg.to_str().unwrap(),
    ]);
    assert!((out.code == 0), "{}", out.stderr.as_str());
    let csv = out.stdout;
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines[0], "t,w_2,w_3,w_4,w_5,w_6,drift,energy,work,power");
    assert_eq!(lines.len(), 1 + 101);
    let first: Vec<f64> = lines[1].split(',').map(|x| x.parse().unwrap()).collect();
    assert!((first[1] - 330.0).abs() < 1e-9 && (first[3] - 80.0).abs() < 1e-9);
    let last: Vec<f64> = lines[101].split(',').map(|x| x.parse().unwrap()).collect();
    assert_eq!(last[0], 1.0);
    let plot = std::fs::read_to_string(&svg).unwrap();
    assert!(
        plot.starts_with("<svg") && plot.matches("<polyline").count() == 10,
        "two panels of five links"
    );

    let out = egt(&[
        "simulate",
        "examples/fig5_stability.toml",
        "--method",
        "implicit",
        "--dt",
        "0.02",
    ]);
    assert!((out.code == 0));
    let table = out.stdout;
    assert!(
        table.contains("method: implicit") && table.contains("Newton iterations"),
        "{table}"
    );

    let out = egt(&[
        "simulate",
        "examples/fig5_stability.toml",
        "--dt",
        "0.04",
        "--t-end",
        "20",
    ]);
    assert_eq!(Some(out.code), Some(1));
    let err = out.stderr.as_str();
    assert!(
        err.contains("blew up") && err.contains("stability limit"),
        "{err}"
    );
    assert!(
        !out.stdout.is_empty(),
        "the series up to the blow-up is still written"
    );

    let out = egt(&["simulate", "examples/fig5_example62.toml"]);
    assert_eq!(Some(out.code), Some(2));
    assert!(out.stderr.as_str().contains("t_end"));
    std::fs::remove_dir_all(&dir).ok();
}

/// The output pasted in `docs/stability.md` for the bundled example is what
/// `egt stability` prints today (every pasted line, except elided ones).
#[test]
fn docs_stability_block_is_current() {
    let doc = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../docs/stability.md"
    ))
    .unwrap();
    let start = doc
        .find("For the bundled example")
        .expect("the pasted block");
    let block = &doc[start..];
    let block = &block[block.find("```text").unwrap() + 7..];
    let block = &block[..block.find("```").unwrap()];
    let out = egt(&["stability", "examples/fig5_stability.toml"]);
    let printed = out.stdout;
    let mut checked = 0;
    for line in block
        .lines()
        .filter(|l| !l.trim().is_empty() && !l.contains("..."))
    {
        assert!(
            printed.lines().any(|p| p == line),
            "docs line not printed any more:\n{line}\n---\n{printed}"
        );
        checked += 1;
    }
    assert!(checked >= 12, "{checked}");
}

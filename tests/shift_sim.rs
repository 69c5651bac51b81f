//! `egt shift-sim` as a user runs it: a 2-3 upshift on the 8HP example with a
//! pressure ramp, its summary, JSON, CSV and plot; bad shifts exit 2 naming
//! the flag or field.

use serde_json::Value;

use crate::util::{egt, root};

const UPSHIFT: &[&str] = &[
    "shift-sim",
    "examples/zf_8hp70.toml",
    "--from",
    "2",
    "--to",
    "3",
    "--input-speed",
    "250",
    "--input-torque",
    "300",
    "--road-load",
    "20,0.2,0.002",
    "--vehicle-inertia",
    "12",
    "--off-going",
    "0.05:0.15:5000:0",
    "--on-coming",
    "0.05:0.3:0:9000",
];

fn with(extra: &[&str]) -> Vec<String> {
    UPSHIFT.iter().chain(extra).map(|s| s.to_string()).collect()
}

fn run(args: &[String]) -> crate::util::Run {
    let a: Vec<&str> = args.iter().map(String::as_str).collect();
    egt(&a, None)
}

#[test]
fn the_8hp_2_3_upshift_gives_its_shift_time_and_clutch_energy_in_one_command() {
    let r = run(&with(&[]));
    assert_eq!(r.code, 0, "{}", r.stderr);
    for words in [
        "off-going `A`, on-coming `C`",
        "locked throughout: `B`, `E`",
        "shift time:",
        "energy dissipated: `A`",
    ] {
        assert!(r.stdout.contains(words), "{words}\n{}", r.stdout);
    }
    let r = run(&with(&["--format", "json"]));
    assert_eq!(r.code, 0, "{}", r.stderr);
    let v: Value = serde_json::from_str(&r.stdout).expect("json");
    let lock = v["lock_time"].as_f64().expect("the clutch locks");
    let start = v["shift_start"].as_f64().expect("a torque phase");
    assert!((v["shift_time"].as_f64().expect("shift time") - (lock - start)).abs() < 1e-12);
    let clutch = v["dissipated"][1].as_f64().expect("energy");
    assert!(clutch > 0.0);
    // The energy balance holds to the integrator's tolerance.
    assert!(v["max_energy_residual"].as_f64().expect("residual") < 1e-7 * clutch);
    // Ends in third: input over output speed is third's ratio (egt shift).
    let (_, table, _) = {
        let s = egt(
            &["shift", "examples/zf_8hp70.toml", "--format", "json"],
            None,
        );
        (s.code, s.stdout, s.stderr)
    };
    let shift: Value = serde_json::from_str(&table).expect("json");
    let third = shift["gears"]
        .as_array()
        .expect("gears")
        .iter()
        .find(|g| g["state"] == "3")
        .expect("third")["ratio"]
        .as_f64()
        .expect("ratio");
    let last = v["samples"]
        .as_array()
        .expect("samples")
        .last()
        .expect("a sample")
        .clone();
    let speed = last["speed"].as_array().expect("speeds");
    let names: Vec<Value> = serde_json::from_str::<Value>(
        &egt(
            &["graph", "examples/zf_8hp70.toml", "--format", "json"],
            None,
        )
        .stdout,
    )
    .expect("json")["nodes"]
        .as_array()
        .expect("nodes")
        .clone();
    let index = |name: &str| names.iter().position(|n| n["link"] == name).expect("link");
    let ratio = speed[index("input")].as_f64().expect("speed")
        / speed[index("output")].as_f64().expect("speed");
    assert!((ratio - third).abs() < 1e-9 * third, "{ratio} vs {third}");
}

#[test]
fn csv_and_plot_carry_the_time_series() {
    let dir = std::env::temp_dir().join(format!("egt-shift-sim-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let svg = dir.join("shift.svg");
    let r = run(&with(&[
        "--format",
        "csv",
        "--plot",
        svg.to_str().expect("utf-8"),
    ]));
    assert_eq!(r.code, 0, "{}", r.stderr);
    let mut lines = r.stdout.lines();
    let header = lines.next().expect("header");
    for col in [
        "t",
        "w_input",
        "w_output",
        "slip_A",
        "torque_C",
        "dissipated_C",
        // the kept elements' torques
        "torque_B",
        "torque_E",
        "output_torque",
        "dof",
    ] {
        assert!(header.split(',').any(|h| h == col), "{col} in {header}");
    }
    let rows: Vec<&str> = lines.collect();
    assert!(rows.len() > 100);
    let plot = std::fs::read_to_string(&svg).expect("plot written");
    assert!(
        plot.starts_with("<svg")
            && plot.contains("output torque")
            && plot.contains("element torques")
    );
    // the phases shaded, the dip and the overshoot marked
    for words in [
        "torque phase</text>",
        "inertia phase</text>",
        ">dip -",
        ">overshoot ",
    ] {
        assert!(plot.contains(words), "{words}");
    }
    let _ = std::fs::remove_dir_all(&dir);
    let _ = root();
}

#[test]
fn bad_shifts_exit_2_naming_the_flag_or_field() {
    let mut double = with(&[]);
    // 1 (A B C) -> 4 (B D E) swaps two elements each way: `--off-going`
    // names no single element, and each changing element needs its `--ramp`.
    double[3] = "1".into();
    double[5] = "4".into();
    let mut unramped: Vec<String> = double[..double.len() - 4].to_vec();
    for r in [
        "A=0.05:0.15:5000:0",
        "C=0.05:0.15:5000:0",
        "D=0.05:0.3:0:9000",
    ] {
        unramped.extend(["--ramp".to_string(), r.to_string()]);
    }
    for (args, words) in [
        (double, "--off-going"),
        (unramped, "element `E`"),
        (
            // D is engaged in neither 2 nor 3 (B, kept, may have a capacity)
            with(&["--ramp", "D=1000"]),
            "`D` is not engaged in `2` or `3`",
        ),
        (with(&["--ramp", "1000"]), "NAME=RAMP"),
        (with(&["--mu", "0.1"]), "--mu"),
        (with(&["--t-end=-1"]), "shift.t_end"),
    ] {
        let r = run(&args);
        assert_eq!(r.code, 2, "{args:?}: {}", r.stderr);
        assert!(r.stderr.contains(words), "{words}: {}", r.stderr);
    }
    // A spec without inertias cannot be simulated; the message says what to give.
    let r = egt(
        &[
            "shift-sim",
            "examples/zf_6hp26_lepelletier.toml",
            "--from",
            "1",
            "--to",
            "2",
            "--input-speed",
            "200",
            "--input-torque",
            "100",
            "--off-going",
            "0",
            "--on-coming",
            "100",
        ],
        None,
    );
    // It is missing data (exit 1, code `missing_data`), not a usage error.
    assert_eq!(r.code, 1, "{}", r.stderr);
    assert!(r.stderr.contains("inertia"), "{}", r.stderr);
}

#[test]
fn the_step_budget_is_a_budget_error_and_an_impossible_tolerance_a_usage_error() {
    let code = |r: &crate::util::Run| -> String {
        let v: Value = serde_json::from_str(&r.stdout).expect("json error document");
        v["error"]["code"].as_str().expect("code").to_string()
    };
    // A tiny step budget: exit 1, code `budget`, naming the flag.
    let r = run(&with(&["--max-steps", "10", "--format", "json"]));
    assert_eq!((r.code, code(&r).as_str()), (1, "budget"), "{}", r.stderr);
    assert!(r.stderr.contains("--max-steps"), "{}", r.stderr);
    // An end time no budget reaches is refused before any work (a step is at
    // most 1 s, so it needs at least 1e300 steps): the same code.
    let r = run(&with(&["--t-end", "1e300", "--format", "json"]));
    assert_eq!((r.code, code(&r).as_str()), (1, "budget"), "{}", r.stderr);
    assert!(r.stderr.contains("1e300 steps"), "{}", r.stderr);
    // A tolerance below what double precision can meet: a usage error.
    let r = run(&with(&["--rtol", "1e-300"]));
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(r.stderr.contains("--rtol"), "{}", r.stderr);
    assert!(!r.stderr.contains("singular"), "{}", r.stderr);
}

/// The ratio input / output speed of the last sample of `egt shift-sim
/// --format json`, and the ratio `egt shift` gives `gear`.
fn ends_in(spec: &str, run: &Value, gear: &str) -> (f64, f64) {
    let shift: Value =
        serde_json::from_str(&egt(&["shift", spec, "--format", "json"], None).stdout)
            .expect("json");
    let ratio = shift["gears"]
        .as_array()
        .expect("gears")
        .iter()
        .find(|g| g["state"] == gear)
        .expect("the gear")["ratio"]
        .as_f64()
        .expect("ratio");
    let nodes: Value =
        serde_json::from_str(&egt(&["graph", spec, "--format", "json"], None).stdout)
            .expect("json");
    let nodes = nodes["nodes"].as_array().expect("nodes");
    let index = |name: &str| nodes.iter().position(|n| n["link"] == name).expect("link");
    let last = run["samples"]
        .as_array()
        .expect("samples")
        .last()
        .expect("a sample");
    let speed = |name: &str| last["speed"][index(name)].as_f64().expect("speed");
    (speed("input") / speed("output"), ratio)
}

#[test]
fn a_coast_1_2_upshift_of_the_c4_overruns_its_one_way_brake_from_the_start() {
    // Foot off: first gear would need the low one-way brake to hold a torque
    // of the sign it cannot, so it overruns at t = 0 and the band shifts the
    // train into second (this was a tie-up, or a band slipping against a
    // one-way brake that held the wrong way).
    let spec = "examples/ford_c4_simpson.toml";
    let r = egt(
        &[
            "shift-sim",
            spec,
            "--from",
            "1",
            "--to",
            "2",
            "--input-speed",
            "300",
            "--input-torque=-50",
            "--road-load",
            "30,0.1,0.001",
            "--vehicle-inertia",
            "15",
            "--off-going",
            "0",
            "--on-coming",
            "0.05:0.35:0:8000",
            "--format",
            "json",
        ],
        None,
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    let v: Value = serde_json::from_str(&r.stdout).expect("json");
    let first = &v["changes"][0];
    assert_eq!(first["t"].as_f64(), Some(0.0));
    assert_eq!(first["element"], "low_one_way");
    assert_eq!(first["now"], "overrunning");
    assert!(v["lock_time"].as_f64().is_some());
    let (ends, second) = ends_in(spec, &v, "2");
    assert!((ends - second).abs() < 1e-9 * second, "{ends} vs {second}");
}

#[test]
fn a_stiff_shift_says_when_the_explicit_method_is_held_back() {
    // A huge viscous road load on the C4's light inertias: decay rates near
    // 6e4 1/s. `auto` notices and goes on implicitly; `explicit` says so.
    let base = [
        "shift-sim",
        "examples/ford_c4_simpson.toml",
        "--from",
        "2",
        "--to",
        "3",
        "--input-speed",
        "300",
        "--input-torque",
        "150",
        "--road-load",
        "0,5000,0",
        "--off-going",
        "0:0.02:6000:0",
        "--on-coming",
        "0.05:0.35:0:8000",
        "--t-end",
        "0.6",
        "--format",
        "json",
    ];
    let steps = |method: &str| {
        let mut args = base.to_vec();
        args.extend(["--method", method]);
        let r = egt(&args, None);
        assert_eq!(r.code, 0, "{}", r.stderr);
        let v: Value = serde_json::from_str(&r.stdout).expect("json");
        assert!(v["stiff"]["rate"].as_f64().expect("stiffness reported") > 1e4);
        (
            v["method"].as_str().expect("method").to_string(),
            v["steps"].as_u64().expect("steps"),
        )
    };
    let (auto, n_auto) = steps("auto");
    let (explicit, n_explicit) = steps("explicit");
    assert_eq!(auto, "explicit, then implicit");
    assert_eq!(explicit, "explicit");
    assert!(n_auto * 10 < n_explicit, "{n_auto} vs {n_explicit}");
    let mut args = base[..base.len() - 2].to_vec();
    args.extend(["--method", "explicit"]);
    let table = egt(&args, None);
    assert!(table.stdout.contains("stiff from t ="), "{}", table.stdout);
}

/// `--torque-table` (which panicked inside clap before it was one value): a
/// flat table is the constant torque, so the run must be the same shift.
#[test]
fn a_flat_torque_table_is_the_constant_torque() {
    let constant = run(&with(&["--format", "json"]));
    assert_eq!(constant.code, 0, "{}", constant.stderr);
    let table: Vec<String> = UPSHIFT
        .iter()
        .map(|s| s.to_string())
        .map(|s| {
            if s == "--input-torque" {
                "--torque-table".into()
            } else {
                s
            }
        })
        .map(|s| {
            if s == "300" {
                "0:300,1000:300".into()
            } else {
                s
            }
        })
        .chain(["--format".into(), "json".into()])
        .collect();
    let flat = run(&table);
    assert_eq!(flat.code, 0, "{}", flat.stderr);
    let a: Value = serde_json::from_str(&constant.stdout).expect("json");
    let b: Value = serde_json::from_str(&flat.stdout).expect("json");
    for key in ["lock_time", "shift_time"] {
        let (x, y) = (a[key].as_f64().expect(key), b[key].as_f64().expect(key));
        assert!((x - y).abs() <= 1e-12 * x.abs(), "{key}: {x} against {y}");
    }
    // A malformed table is a usage error naming the flag, not a panic.
    let bad: Vec<String> = table
        .iter()
        .map(|s| {
            if s == "0:300,1000:300" {
                "0:300,1000".into()
            } else {
                s.clone()
            }
        })
        .collect();
    let r = run(&bad);
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(r.stderr.contains("--torque-table"), "{}", r.stderr);
}

/// The 8HP shift `from` -> `to` with one `--ramp` each, as JSON.
fn by_ramps(from: &str, to: &str, ramps: &[&str]) -> Value {
    let mut args: Vec<String> = UPSHIFT[..UPSHIFT.len() - 4]
        .iter()
        .map(|s| s.to_string())
        .collect();
    args[3] = from.into();
    args[5] = to.into();
    for r in ramps {
        args.extend(["--ramp".to_string(), r.to_string()]);
    }
    args.extend(["--t-end", "1.5", "--format", "json"].map(String::from));
    let r = run(&args);
    assert_eq!(r.code, 0, "{}", r.stderr);
    serde_json::from_str(&r.stdout).expect("json")
}

#[test]
fn an_8hp_skip_shift_and_double_swap_by_ramp_flags_end_in_the_new_gear() {
    let spec = "examples/zf_8hp70.toml";
    for (from, to, ramps) in [
        // 2 (A B E) -> 4 (B D E): a skip shift, A off, D on
        ("2", "4", &["A=0.05:0.15:20000:0", "D=0.05:0.4:0:20000"][..]),
        // 1 (A B C) -> 4 (B D E): A and C off, D and E on
        (
            "1",
            "4",
            &[
                "A=0.05:0.15:20000:0",
                "C=0.05:0.15:20000:0",
                "D=0.05:0.4:0:20000",
                "E=0.05:0.4:0:20000",
            ][..],
        ),
    ] {
        let v = by_ramps(from, to, ramps);
        let (ends, ratio) = ends_in(spec, &v, to);
        assert!(
            (ends - ratio).abs() < 1e-9 * ratio,
            "{from}-{to}: {ends} vs {ratio}"
        );
        let dissipated: f64 = v["dissipated"]
            .as_array()
            .expect("per element")
            .iter()
            .map(|d| d.as_f64().expect("J"))
            .sum();
        let residual = v["max_energy_residual"].as_f64().expect("residual");
        assert!(
            residual < 1e-7 * dissipated,
            "{from}-{to}: {residual} of {dissipated}"
        );
        assert_eq!(
            v["elements"].as_array().expect("elements").len(),
            ramps.len()
        );
    }
}

#[test]
fn a_single_swap_by_ramp_flags_is_bit_for_bit_the_off_going_on_coming_run() {
    let roles = run(&with(&["--format", "json"]));
    assert_eq!(roles.code, 0, "{}", roles.stderr);
    let mut named: Vec<String> = UPSHIFT[..UPSHIFT.len() - 4]
        .iter()
        .map(|s| s.to_string())
        .collect();
    named.extend(
        [
            "--ramp",
            "C=0.05:0.3:0:9000",
            "--ramp",
            "A=0.05:0.15:5000:0",
            "--format",
            "json",
        ]
        .map(String::from),
    );
    let names = run(&named);
    assert_eq!(names.code, 0, "{}", names.stderr);
    assert_eq!(roles.stdout, names.stdout);
}

#[test]
fn a_shift_the_spec_names_is_bit_for_bit_the_run_its_flags_give() {
    // The 8HP example's [[shift]] "2-3" is the documented upshift of UPSHIFT.
    let flags = run(&with(&["--format", "json"]));
    assert_eq!(flags.code, 0, "{}", flags.stderr);
    let named = egt(
        &[
            "shift-sim",
            "examples/zf_8hp70.toml",
            "--shift",
            "2-3",
            "--format",
            "json",
        ],
        None,
    );
    assert_eq!(named.code, 0, "{}", named.stderr);
    assert_eq!(flags.stdout, named.stdout);
    // "1-4", a double swap, is the ramps of the by-flag double-swap test.
    let by_flags = by_ramps(
        "1",
        "4",
        &[
            "A=0.05:0.15:20000:0",
            "C=0.05:0.15:20000:0",
            "D=0.05:0.4:0:20000",
            "E=0.05:0.4:0:20000",
        ],
    );
    let r = egt(
        &[
            "shift-sim",
            "examples/zf_8hp70.toml",
            "--shift",
            "1-4",
            "--format",
            "json",
        ],
        None,
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    let by_name: Value = serde_json::from_str(&r.stdout).expect("json");
    assert_eq!(by_flags, by_name);
    // The integration settings still come from the command line.
    let loose = egt(
        &[
            "shift-sim",
            "examples/zf_8hp70.toml",
            "--shift",
            "2-3",
            "--rtol",
            "1e-5",
            "--format",
            "json",
        ],
        None,
    );
    assert_eq!(loose.code, 0, "{}", loose.stderr);
    let loose: Value = serde_json::from_str(&loose.stdout).expect("json");
    let tight: Value = serde_json::from_str(&named.stdout).expect("json");
    assert!(loose["steps"].as_u64() < tight["steps"].as_u64());
}

#[test]
fn a_bad_shift_section_or_name_exits_2_naming_it() {
    let spec = std::fs::read_to_string(root().join("examples/zf_8hp70.toml")).expect("example");
    let cut = spec.find("[[shift]]").expect("the example names shifts");
    let (head, shifts) = spec.split_at(cut);
    let no_transmission = {
        let t = head.find("[transmission]").expect("transmission");
        format!("{}{shifts}", &head[..t])
    };
    let twice = format!(
        "{spec}\n{}",
        &shifts[..shifts[9..].find("[[shift]]").expect("two") + 9]
    );
    for (text, args, says) in [
        (
            spec.replace("from = \"1\"", "from = \"9\""),
            &["check", "-"][..],
            "shift[1].from: unknown gear state `9`",
        ),
        (
            spec.replace("to = \"3\"", "to = \"2\""),
            &["check", "-"][..],
            "shift[0].to",
        ),
        (no_transmission, &["check", "-"][..], "shift[0]"),
        (twice, &["check", "-"][..], "shift[2].name: `2-3` names shift[0] too"),
        (
            spec.replace("ramps = { A = [0.05, 0.15, 5000.0, 0.0], ", "ramps = { A = [0.05, 0.15], "),
            &["check", "-"][..],
            "shift[0].ramps.A",
        ),
        (
            spec.replace("name = \"2-3\"", "name = \"2-3\"\ninput_torques = 1"),
            &["check", "-"][..],
            "input_torques",
        ),
        (
            spec.clone(),
            &["shift-sim", "-", "--shift", "2-4"][..],
            "unknown shift `2-4` (did you mean `2-3`?)",
        ),
        (
            spec.replace("input_torque = 300.0\nroad_load = [20.0, 0.2, 0.002]\nvehicle_inertia = 12.0\nramps = { A", "road_load = [20.0, 0.2, 0.002]\nvehicle_inertia = 12.0\nramps = { A"),
            &["shift-sim", "-", "--shift", "2-3"][..],
            "[[shift]] `2-3`: shift.input_torque",
        ),
        (
            spec.replace("ramps = { A = [0.05, 0.15, 5000.0, 0.0], ", "ramps = { "),
            &["shift-sim", "-", "--shift", "2-3"][..],
            "`A`",
        ),
        (
            spec.clone(),
            &["shift-sim", "-", "--shift", "2-3", "--from", "1"][..],
            "cannot be used with",
        ),
    ] {
        let r = egt(args, Some(&text));
        assert_eq!(r.code, 2, "{args:?} {says}: {}", r.stderr);
        assert!(r.stderr.contains(says), "{args:?}: wanted {says:?} in {}", r.stderr);
    }
}

/// The numbers after `label` on the summary's line that starts with it (up
/// to a `(` or a `,`): `0.05 .. 0.133081 s` gives both.
fn numbers_on(stdout: &str, label: &str) -> Vec<f64> {
    let line = stdout
        .lines()
        .find(|l| l.trim_start().starts_with(label))
        .unwrap_or_else(|| panic!("a line `{label}` in\n{stdout}"));
    let rest = &line.trim_start()[label.len()..];
    let rest = rest.split(['(', ',']).next().unwrap_or(rest);
    rest.split_whitespace()
        .filter_map(|w| w.parse::<f64>().ok())
        .collect()
}

#[test]
fn the_summary_names_the_phases_and_quality_measures_of_the_json() {
    let text = run(&with(&[]));
    assert_eq!(text.code, 0, "{}", text.stderr);
    let json = run(&with(&["--format", "json"]));
    let v: Value = serde_json::from_str(&json.stdout).expect("json");
    let q = &v["quality"];
    // printed to 6 decimals
    let close = |printed: f64, exact: &Value| {
        let exact = exact.as_f64().expect("a number");
        assert!(
            (printed - exact).abs() <= 5e-7 * exact.abs().max(1.0),
            "{printed} printed, {exact} in the JSON"
        );
    };
    for (label, key) in [
        ("torque phase:", "torque_phase"),
        ("inertia phase:", "inertia_phase"),
    ] {
        let printed = numbers_on(&text.stdout, label);
        assert_eq!(printed.len(), 2, "{label} {printed:?}");
        close(printed[0], &q[key][0]);
        close(printed[1], &q[key][1]);
    }
    // The phases meet at the release and end at the lock.
    assert_eq!(q["torque_phase"][0], v["shift_start"]);
    assert_eq!(q["torque_phase"][1], q["inertia_phase"][0]);
    assert_eq!(q["inertia_phase"][1], v["lock_time"]);
    for (label, key) in [
        ("dip (torque phase)", "dip"),
        ("overshoot (inertia phase to lock)", "overshoot"),
        ("jerk", "jerk"),
        ("largest step", "largest_step"),
    ] {
        let printed = numbers_on(&text.stdout, label);
        close(printed[0], &q[key]["value"]);
        close(printed[1], &q[key]["t"]);
    }
    // A power-on upshift: the output torque dips in the torque phase and
    // overshoots its final value before the lock.
    assert!(q["dip"]["value"].as_f64().expect("dip") < 0.0);
    assert!(q["overshoot"]["value"].as_f64().expect("overshoot") > 0.0);
    let oscillation = numbers_on(&text.stdout, "oscillation after lock");
    close(oscillation[0], &q["oscillation_after_lock"]);
    for (k, e) in ["A", "C"].iter().enumerate() {
        let element = &q["elements"][k];
        assert_eq!(element["element"], *e);
        assert_eq!(element["energy"], v["dissipated"][k]);
        let printed = numbers_on(&text.stdout, &format!("`{e}` peak power"));
        close(printed[0], &element["peak_power"]["value"]);
        close(printed[1], &element["peak_power"]["t"]);
    }
}

#[test]
fn kept_elements_report_their_torques_and_hold_by_a_capacity_when_given_one() {
    let rigid = run(&with(&["--format", "json"]));
    assert_eq!(rigid.code, 0, "{}", rigid.stderr);
    let rigid: Value = serde_json::from_str(&rigid.stdout).expect("json");
    assert_eq!(rigid["kept"], serde_json::json!(["B", "E"]));
    let range = rigid["kept_torque_range"].as_array().expect("ranges");
    assert_eq!(range.len(), 2);
    let text = run(&with(&[]));
    assert!(
        text.stdout
            .contains("torque of the elements locked throughout: `B` max"),
        "{}",
        text.stdout
    );
    // E given a capacity below its largest torque: held by it, it slips.
    let peak = range[1]
        .as_array()
        .expect("[max, min]")
        .iter()
        .map(|v| v.as_f64().expect("N m").abs())
        .fold(0.0, f64::max);
    let cap = format!("E={}", 0.5 * peak / 0.15);
    let held = run(&with(&["--ramp", &cap, "--format", "json"]));
    assert_eq!(held.code, 0, "{}", held.stderr);
    let held: Value = serde_json::from_str(&held.stdout).expect("json");
    assert_eq!(held["kept"], serde_json::json!(["B"]));
    assert_eq!(held["held"], serde_json::json!(["E"]));
    assert_eq!(held["elements"], serde_json::json!(["A", "C", "E"]));
    assert!(
        held["changes"]
            .as_array()
            .expect("changes")
            .iter()
            .any(|c| c["element"] == "E" && c["now"] == "slipping"),
        "{}",
        held["changes"]
    );
    let text = run(&with(&["--ramp", &cap]));
    assert!(
        text.stdout.contains("held by a capacity: `E`"),
        "{}",
        text.stdout
    );
}

#[test]
fn a_compliant_output_from_the_flag_or_the_spec_is_one_run_and_bad_shafts_exit_2() {
    let spec = std::fs::read_to_string(root().join("examples/zf_8hp70.toml")).expect("example");
    let with_shaft = spec.replace(
        "name = \"2-3\"\n",
        "name = \"2-3\"\noutput_shaft = { stiffness = 5000.0, damping = 1.0 }\n",
    );
    let mut flags: Vec<String> = UPSHIFT.iter().map(|s| s.to_string()).collect();
    flags[1] = "-".into();
    flags.extend(
        [
            "--output-shaft",
            "5000,1",
            "--rtol",
            "1e-9",
            "--format",
            "json",
        ]
        .map(String::from),
    );
    let flags: Vec<&str> = flags.iter().map(String::as_str).collect();
    let by_flag = egt(&flags, Some(&spec));
    assert_eq!(by_flag.code, 0, "{}", by_flag.stderr);
    let by_spec = egt(
        &[
            "shift-sim",
            "-",
            "--shift",
            "2-3",
            "--rtol",
            "1e-9",
            "--format",
            "json",
        ],
        Some(&with_shaft),
    );
    assert_eq!(by_spec.code, 0, "{}", by_spec.stderr);
    assert_eq!(by_flag.stdout, by_spec.stdout);
    // The shaft changes the run (the shuffle) and keeps the energy balanced
    // (the residual is the integrator's: 1.3e-3, 1.3e-4, 1.3e-5 J at rtol
    // 1e-8, 1e-9, 1e-10, of about 4 100 J dissipated).
    let rigid = run(&with(&["--format", "json"]));
    assert_ne!(rigid.stdout, by_flag.stdout);
    let v: Value = serde_json::from_str(&by_flag.stdout).expect("json");
    let dissipated: f64 = (v["dissipated"].as_array().expect("J").iter())
        .map(|d| d.as_f64().expect("J"))
        .sum();
    assert!(v["max_energy_residual"].as_f64().expect("J") < 1e-7 * dissipated);
    for (bad, says) in [
        (&["--output-shaft", "0"][..], "--output-shaft"),
        (&["--output-shaft", "5000,-1"][..], "--output-shaft"),
        (&["--output-shaft", "5000,1,2"][..], "--output-shaft"),
        (
            &["--output-shaft", "5000", "--vehicle-inertia", "0"][..],
            "--vehicle-inertia",
        ),
    ] {
        let mut args: Vec<&str> = UPSHIFT
            .iter()
            .copied()
            .filter(|a| *a != "--vehicle-inertia")
            .collect();
        if let Some(i) = args.iter().position(|a| *a == "12") {
            args.remove(i);
        }
        args.extend(if bad.contains(&"--vehicle-inertia") {
            bad.to_vec()
        } else {
            [bad, &["--vehicle-inertia", "12"][..]].concat()
        });
        let r = egt(&args, None);
        assert_eq!(r.code, 2, "{bad:?}: {}", r.stderr);
        assert!(r.stderr.contains(says), "{bad:?}: {}", r.stderr);
    }
}

#[test]
fn mesh_losses_from_the_flag_or_the_spec_are_one_run_in_the_energy_balance() {
    let spec = std::fs::read_to_string(root().join("examples/zf_8hp70.toml")).expect("example");
    let with_losses = spec.replace("name = \"2-3\"\n", "name = \"2-3\"\nlosses = true\n");
    let mut flags: Vec<String> = UPSHIFT.iter().map(|s| s.to_string()).collect();
    flags[1] = "-".into();
    flags.extend(["--losses", "--format", "json"].map(String::from));
    let flags: Vec<&str> = flags.iter().map(String::as_str).collect();
    let by_flag = egt(&flags, Some(&spec));
    assert_eq!(by_flag.code, 0, "{}", by_flag.stderr);
    let by_spec = egt(
        &["shift-sim", "-", "--shift", "2-3", "--format", "json"],
        Some(&with_losses),
    );
    assert_eq!(by_spec.code, 0, "{}", by_spec.stderr);
    assert_eq!(by_flag.stdout, by_spec.stdout);
    let v: Value = serde_json::from_str(&by_flag.stdout).expect("json");
    let mesh = v["mesh_loss"].as_f64().expect("mesh loss");
    let friction: f64 = (v["dissipated"].as_array().expect("J").iter())
        .map(|d| d.as_f64().expect("J"))
        .sum();
    assert!(mesh > 0.0 && mesh < friction, "{mesh} of {friction}");
    assert!(v["max_energy_residual"].as_f64().expect("J") < 1e-7 * (mesh + friction));
    // Without the option the document has no mesh loss at all.
    let ideal = run(&with(&["--format", "json"]));
    let ideal: Value = serde_json::from_str(&ideal.stdout).expect("json");
    assert!(ideal.get("mesh_loss").is_none());
    assert!(ideal["samples"][0].get("mesh_loss").is_none());
    // The table names it, and the CSV carries it as a column.
    let text = run(&with(&["--losses"]));
    assert!(text.stdout.contains("mesh loss: "), "{}", text.stdout);
    assert!(text.stdout.contains("- E_mesh)"), "{}", text.stdout);
    let csv = run(&with(&["--losses", "--format", "csv"]));
    assert!(
        csv.stdout
            .lines()
            .next()
            .expect("header")
            .ends_with(",mesh_loss")
    );
}

#[test]
fn a_train_braked_to_rest_by_both_elements_rests_instead_of_a_tie_up() {
    // `A` keeps holding (20 000, far above its torque) while `C` applies:
    // the two drag the train to a standstill, where it rests, held by both
    // (before: exit 1, "singular: tie-up").
    let args = [
        "shift-sim",
        "examples/zf_8hp70.toml",
        "--from",
        "2",
        "--to",
        "3",
        "--input-speed",
        "250",
        "--input-torque",
        "0",
        "--vehicle-inertia",
        "12",
        "--off-going",
        "20000",
        "--on-coming",
        "0.05:0.3:0:9000",
        "--t-end",
        "2",
    ];
    let text = egt(&args, None);
    assert_eq!(text.code, 0, "{}", text.stderr);
    assert!(text.stdout.contains("at rest from:"), "{}", text.stdout);
    let json = egt(&[&args[..], &["--format", "json"]].concat(), None);
    let v: Value = serde_json::from_str(&json.stdout).expect("json");
    let rest = v["rest_time"].as_f64().expect("at rest");
    assert_eq!(v["lock_time"].as_f64(), Some(rest));
    let samples = v["samples"].as_array().expect("samples");
    let last = samples.last().expect("a sample");
    assert_eq!(last["t"].as_f64(), Some(2.0));
    assert!((last["speed"].as_array().expect("speeds").iter()).all(|w| w.as_f64() == Some(0.0)));
    assert_eq!(last["dof"].as_u64(), Some(0));
    let dissipated: f64 = (v["dissipated"].as_array().expect("J").iter())
        .map(|d| d.as_f64().expect("J"))
        .sum();
    assert!(v["max_energy_residual"].as_f64().expect("J") < 1e-9 * dissipated);
    // Without a rest, the document has no rest_time.
    let moving = run(&with(&["--format", "json"]));
    let moving: Value = serde_json::from_str(&moving.stdout).expect("json");
    assert!(moving.get("rest_time").is_none());
}

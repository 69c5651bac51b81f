//! The `egt` binary, run as a user runs it: exit codes (0 success, 2 usage /
//! syntax / spec / topology errors, 1 analysis and I/O errors), standard input,
//! JSON output fields, table output, and snapshots of real invocations on the
//! bundled examples (run from the workspace root, so paths are relative).

use std::process::{Command, Stdio};

use serde_json::Value;

use crate::util::{egt, root};

fn ok(args: &[&str]) -> String {
    let r = egt(args, None);
    assert_eq!(r.code, 0, "egt {args:?} failed:\n{}", r.stderr);
    r.stdout
}

fn json(args: &[&str]) -> Value {
    serde_json::from_str(&ok(args)).expect("valid JSON")
}

const EXAMPLES: [&str; 6] = [
    "examples/fig3_example61.toml",
    "examples/fig5_example62.toml",
    "examples/simple_planetary.toml",
    "examples/ford_aod_ravigneaux.toml",
    "examples/ford_c4_simpson.toml",
    "examples/adjacency_enumerated.json",
];

#[test]
fn every_example_checks_and_solves_from_its_analysis_speeds() {
    for ex in EXAMPLES {
        let out = ok(&["check", ex]);
        assert!(out.contains("valid geared kinematic chain"), "{out}");
        assert!(
            out.contains("#m  gear pair  ") && out.contains("transfer vertex k"),
            "{out}"
        );
        let out = ok(&["kinematics", ex]);
        assert!(
            out.contains("absolute speeds:") && out.contains("Willis residual"),
            "{out}"
        );
    }
}

#[test]
fn circuits_json_has_the_table_by_names() {
    let v = json(&[
        "circuits",
        "examples/fig5_example62.toml",
        "--format",
        "json",
    ]);
    let c = v["circuits"].as_array().expect("circuits");
    let triples: Vec<(&str, &str, &str)> = c
        .iter()
        .map(|r| {
            (
                r["gear_i"].as_str().expect("i"),
                r["gear_j"].as_str().expect("j"),
                r["carrier"].as_str().expect("k"),
            )
        })
        .collect();
    assert_eq!(
        triples,
        vec![("2", "3", "1"), ("5", "4", "3"), ("5", "6", "3")]
    );
    assert_eq!(c[1]["ratio_exact"], "-3/2");
    assert_eq!(c[2]["ratio"], 3.5);
    assert_eq!(c[0]["level_i"], "a");
    assert_eq!(c[0]["m"], 1);
}

#[test]
fn check_json_lists_dof_and_checks() {
    let v = json(&["check", "examples/ford_c4_simpson.toml", "--format", "json"]);
    assert_eq!(v["dof"], 3);
    assert_eq!(v["frame"], "case");
    assert!(
        v["checks"]
            .as_array()
            .expect("checks")
            .iter()
            .any(|c| c.as_str().is_some_and(|s| s.contains("planar")))
    );
    assert_eq!(v["circuits"].as_array().expect("circuits").len(), 4);
}

#[test]
fn kinematics_json_uses_names_and_exact_strings() {
    let v = json(&[
        "kinematics",
        "examples/fig3_example61.toml",
        "--format",
        "json",
    ]);
    let link = |name: &str| {
        v["links"]
            .as_array()
            .expect("links")
            .iter()
            .find(|l| l["name"] == name)
            .expect("link")
            .clone()
    };
    assert_eq!(v["inputs"][0]["link"], "2");
    assert_eq!(link("4")["exact"], "125/8");
    assert_eq!(link("4")["ratio_exact"], "32/5");
    assert_eq!(link("1")["frame"], true);
    assert_eq!(v["relative"][0]["link"], "3");
    assert_eq!(v["relative"][0]["carrier"], "2");
    assert!(v["residual"].as_f64().expect("residual") < 1e-12);
    assert!(v["condition"].as_f64().expect("condition") >= 1.0);

    // --input overrides the spec, exactly.
    let v = json(&[
        "kinematics",
        "examples/fig3_example61.toml",
        "--input",
        "4=5/32",
        "--format",
        "json",
    ]);
    let two = v["links"]
        .as_array()
        .expect("links")
        .iter()
        .find(|l| l["name"] == "2")
        .expect("2")
        .clone();
    assert_eq!(two["exact"], "1");

    // Unsized planets are unknown, not numbers.
    let v = json(&[
        "kinematics",
        "examples/ford_aod_ravigneaux.toml",
        "--format",
        "json",
    ]);
    let pinion = v["links"]
        .as_array()
        .expect("links")
        .iter()
        .find(|l| l["name"] == "long_pinion")
        .expect("pinion")
        .clone();
    assert_eq!(pinion["known"], false);
    assert_eq!(pinion["speed"], Value::Null);
}

#[test]
fn stdin_is_read_and_sniffed() {
    let toml = std::fs::read_to_string(root().join("examples/fig3_example61.toml")).expect("read");
    let r = egt(&["circuits", "-"], Some(&toml));
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(r.stdout.contains("-16/9"));
    let json_text =
        std::fs::read_to_string(root().join("examples/adjacency_enumerated.json")).expect("read");
    let r = egt(&["kinematics", "-", "--format", "json"], Some(&json_text));
    assert_eq!(r.code, 0, "{}", r.stderr);
    let v: Value = serde_json::from_str(&r.stdout).expect("json");
    assert_eq!(v["source"], "<stdin>");
    // An explicit --spec-format wins over sniffing.
    let r = egt(&["check", "-", "--spec-format", "toml"], Some(&json_text));
    assert_eq!(r.code, 2);
    assert!(r.stderr.starts_with("error: <stdin>:1:"), "{}", r.stderr);
}

#[test]
fn syntax_errors_exit_2_with_file_line_column() {
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
    let path = dir.join("egt_cli_syntax_error.toml");
    std::fs::write(&path, "frame = \"1\"\n[[links]\nname = \"2\"\n").expect("write");
    let r = egt(&["check", path.to_str().expect("utf8 path")], None);
    assert_eq!(r.code, 2);
    assert!(
        r.stderr
            .starts_with(&format!("error: {}:2:", path.display())),
        "{}",
        r.stderr
    );
}

#[test]
fn spec_and_topology_errors_exit_2_and_name_the_place() {
    let r = egt(
        &["check", "-"],
        Some(
            "frame = \"1\"\nadjacency = \"1-2:a 2-3:b 1-3:G=-2\"\n[[gears]]\nlinks = [\"2\", \"33\"]\nratio = 2\n",
        ),
    );
    assert_eq!(r.code, 2);
    assert!(
        r.stderr.contains("gears[0].links[1]") && r.stderr.contains("unknown link `33`"),
        "{}",
        r.stderr
    );

    let r = egt(
        &["check", "-"],
        Some("frame = \"1\"\nadjacency = \"1-2:a 1-4:a 2-4:G=-2\"\n"),
    );
    assert_eq!(r.code, 2);
    assert!(
        r.stderr.contains("topology") && r.stderr.contains("gear pair G1"),
        "{}",
        r.stderr
    );
}

#[test]
fn usage_errors_exit_2() {
    assert_eq!(egt(&["check"], None).code, 2);
    assert_eq!(egt(&["frobnicate"], None).code, 2);
    let r = egt(
        &[
            "kinematics",
            "examples/fig3_example61.toml",
            "--input",
            "2:100",
        ],
        None,
    );
    assert_eq!(r.code, 2);
    assert!(r.stderr.contains("LINK=SPEED"), "{}", r.stderr);
    let r = egt(
        &[
            "kinematics",
            "examples/fig3_example61.toml",
            "--input",
            "2=fast",
        ],
        None,
    );
    assert_eq!(r.code, 2);
    let r = egt(
        &[
            "kinematics",
            "examples/fig3_example61.toml",
            "--input",
            "carier=1",
        ],
        None,
    );
    assert_eq!(r.code, 2, "an unknown input link is the user's error");
    assert!(r.stderr.contains("unknown link `carier`"), "{}", r.stderr);
    assert_eq!(egt(&["check", "x.toml", "--format", "xml"], None).code, 2);
}

#[test]
fn analysis_and_io_errors_exit_1() {
    let r = egt(
        &[
            "kinematics",
            "examples/fig3_example61.toml",
            "-i",
            "2=1",
            "-i",
            "4=1",
        ],
        None,
    );
    assert_eq!(r.code, 1);
    assert!(
        r.stderr
            .contains("1 degree(s) of freedom but 2 input speeds"),
        "{}",
        r.stderr
    );

    // Fig. 3 with tau_1 tau_2 = 1, output held: carrier and planet are free.
    let singular = "frame = \"1\"\nadjacency = \"1-2:a 2-3:b 1-4:a 1-3:G=-2/3 3-4:G=-3/2\"\n";
    let r = egt(&["kinematics", "-", "-i", "4=0"], Some(singular));
    assert_eq!(r.code, 1);
    assert!(
        r.stderr.contains("links `2`, `3` are left free"),
        "{}",
        r.stderr
    );

    let r = egt(&["check", "examples/no_such_file.toml"], None);
    assert_eq!(r.code, 1);
    assert!(
        r.stderr
            .starts_with("error: reading examples/no_such_file.toml"),
        "{}",
        r.stderr
    );
}

#[test]
fn schema_is_json_schema_of_the_spec() {
    let v = json(&["schema"]);
    assert!(v["properties"]["frame"].is_object(), "{v}");
    assert!(v["properties"]["planetary"].is_object());
    assert_eq!(v["required"], serde_json::json!(["frame"]));
}

#[test]
fn closed_stdout_is_not_an_error() {
    let mut child = Command::new(env!("CARGO_BIN_EXE_egt"))
        .args(["schema"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn");
    drop(child.stdout.take());
    let out = child.wait_with_output().expect("wait");
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

// Snapshots of real invocations (tests/snapshots/); review changes with
// `cargo insta review` or by reading the `.snap.new` files. The residual and
// condition lines depend on round-off in the solver, so they are masked (other
// tests bound them).

/// `ok(args)` with the round-off-dependent numbers masked.
fn snap(args: &[&str]) -> String {
    ok(args)
        .lines()
        .map(|l| {
            if l.starts_with("Willis residual:") {
                "Willis residual: [masked]; condition number: [masked]"
            } else {
                l
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn snapshot_check_fig3() {
    insta::assert_snapshot!(snap(&["check", "examples/fig3_example61.toml"]));
}

#[test]
fn snapshot_circuits_fig5() {
    insta::assert_snapshot!(snap(&["circuits", "examples/fig5_example62.toml"]));
}

#[test]
fn snapshot_kinematics_fig3() {
    insta::assert_snapshot!(snap(&["kinematics", "examples/fig3_example61.toml"]));
}

#[test]
fn snapshot_kinematics_fig5() {
    insta::assert_snapshot!(snap(&["kinematics", "examples/fig5_example62.toml"]));
}

#[test]
fn snapshot_kinematics_simple_planetary() {
    insta::assert_snapshot!(snap(&["kinematics", "examples/simple_planetary.toml"]));
}

#[test]
fn snapshot_kinematics_ford_aod_second_gear() {
    insta::assert_snapshot!(snap(&[
        "kinematics",
        "examples/ford_aod_ravigneaux.toml",
        "-i",
        "input=1",
        "-i",
        "small_sun=1",
        "-i",
        "large_sun=0"
    ]));
}

#[test]
fn snapshot_kinematics_ford_c4_first_gear() {
    insta::assert_snapshot!(snap(&[
        "kinematics",
        "examples/ford_c4_simpson.toml",
        "-i",
        "input=1",
        "-i",
        "front_ring=1",
        "-i",
        "rear_carrier=0"
    ]));
}

#[test]
fn snapshot_errors() {
    let cases = [
        ("syntax", "frame = \"1\"\nadjacency = \"1-2:a\"\n[[links]\n"),
        (
            "type",
            "frame = \"1\"\n[[gears]]\nlinks = [\"1\", \"2\"]\nteeth = [30, \"x\"]\n",
        ),
        (
            "unknown link",
            "frame = \"case\"\n[[links]]\nname = \"carrier\"\n[[revolutes]]\nlinks = [\"case\", \"carier\"]\nlevel = \"a\"\n",
        ),
        (
            "no transfer vertex",
            "frame = \"1\"\nadjacency = \"1-2:a 1-3:b 3-5:c 1-4:b 1-6:a 2-3:G 5-4:G 5-6:G\"\n",
        ),
        (
            "fractionated",
            "frame = \"1\"\nadjacency = \"1-2:a 2-3:b 1-3:G=-2 1-4:c 4-5:d 1-5:G=-3\"\n",
        ),
    ];
    let mut all = String::new();
    for (what, text) in cases {
        let r = egt(&["check", "-"], Some(text));
        all.push_str(&format!("# {what}: exit {}\n{}", r.code, r.stderr));
    }
    insta::assert_snapshot!(all);
}

/// Issue 17: completions for the common shells name every subcommand (the
/// bash script also passes `bash -n`), and the man page is valid roff with
/// the commands in it; all exit 0 and carry the version.
#[test]
fn completions_and_man_page() {
    for shell in ["bash", "zsh", "fish"] {
        let script = ok(&["completions", shell]);
        for sub in ["check", "kinematics", "dynamics", "batch", "completions"] {
            assert!(script.contains(sub), "{shell}: no `{sub}`");
        }
        if shell == "bash" {
            let dir = std::env::temp_dir().join(format!("egt-completion-{}", std::process::id()));
            std::fs::write(&dir, &script).expect("write script");
            let status = Command::new("bash")
                .arg("-n")
                .arg(&dir)
                .status()
                .expect("bash");
            let _ = std::fs::remove_file(&dir);
            assert!(status.success(), "bash -n rejects the completion script");
        }
    }
    let man = ok(&["man"]);
    assert!(
        man.contains(".TH egt 1") && man.contains("kinematics"),
        "{man}"
    );
    assert!(man.contains(env!("CARGO_PKG_VERSION")));
    let r = egt(&["completions", "tcsh"], None);
    assert_eq!(r.code, 2, "{}", r.stderr);
}

/// Issue 17: every JSON report says which egt wrote it.
#[test]
fn json_reports_carry_the_version() {
    for args in [
        &["check", "examples/fig3_example61.toml", "--format", "json"][..],
        &[
            "kinematics",
            "examples/fig3_example61.toml",
            "--format",
            "json",
        ][..],
        &["shift", "examples/zf_8hp70.toml", "--format", "json"][..],
    ] {
        assert_eq!(json(args)["version"], env!("CARGO_PKG_VERSION"), "{args:?}");
    }
}

/// Issue 11: the table's force per copy keeps the sign of F_i (the JSON's),
/// and equals F_i over the copies.
#[test]
fn force_per_copy_keeps_its_sign() {
    let table = ok(&["dynamics", "examples/fig3_example61.toml", "--forces"]);
    let header = table
        .lines()
        .find(|l| l.contains("F per copy"))
        .expect("forces table");
    let cols: Vec<&str> = header.split_whitespace().collect();
    let at = |name: &str| cols.iter().position(|c| *c == name).expect(name);
    let (fi, copies) = (at("F_i"), at("copies"));
    let mut negative = false;
    for row in table.lines().filter(|l| l.trim_start().starts_with('G')) {
        let v: Vec<&str> = row.split_whitespace().collect();
        let f: f64 = v[fi].parse().expect("F_i");
        let n: f64 = v[copies].parse().expect("copies");
        let per: f64 = v.last().expect("per copy").parse().expect("F per copy");
        assert!((per - f / n).abs() <= 1e-6 * f.abs(), "{row}");
        negative |= per < 0.0;
    }
    assert!(negative, "the example has a negative force\n{table}");
}

/// Issues 12 and 17: with `--format json` a failure is also a JSON document on
/// stdout (a stable code, the message, the exit code, the field and the
/// line/column where known), with the same exit code.
#[test]
fn failures_are_json_when_json_is_asked() {
    let bad = "frame = \"f\"\nlinks = [{ name = \"a\" }, { name = \"b\" }]\nrevolutes = [{ links = [\"f\", \"a\", \"b\"], level = \"a\" }]\n";
    let r = egt(&["check", "-", "--format", "json"], Some(bad));
    assert_eq!(r.code, 2);
    let v: Value = serde_json::from_str(&r.stdout).expect("a JSON error document");
    assert_eq!(v["error"]["code"], "syntax");
    assert_eq!(v["error"]["exit"], 2);
    assert_eq!(v["error"]["path"], "revolutes[0].links");
    assert_eq!(v["error"]["line"], 3);
    assert_eq!(v["version"], env!("CARGO_PKG_VERSION"));
    assert!(r.stderr.starts_with("error: "), "{}", r.stderr);

    let r = egt(
        &[
            "kinematics",
            "examples/fig3_example61.toml",
            "-i",
            "2=1/3/4",
            "--format",
            "json",
        ],
        None,
    );
    assert_eq!(r.code, 2, "usage errors stay clap's: {}", r.stderr);

    let locked =
        "frame = \"X\"\nadjacency = \"X-A:p X-B:p X-C:p A-Y:q A-Z:r B-Y:G B-Z:G C-Y:G C-Z:G\"\n";
    let r = egt(&["check", "-", "--format", "json"], Some(locked));
    let v: Value = serde_json::from_str(&r.stdout).expect("JSON");
    assert_eq!(
        (r.code, v["error"]["code"].as_str()),
        (2, Some("non_planar"))
    );

    let r = egt(
        &["check", "examples/no_such_file.toml", "--format", "json"],
        None,
    );
    let v: Value = serde_json::from_str(&r.stdout).expect("JSON");
    assert_eq!((r.code, v["error"]["code"].as_str()), (1, Some("io")));
}

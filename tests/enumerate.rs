//! `egt enumerate` as a user runs it: every printed line is read back by
//! `egt check` (adjacency form, any frame), JSON Lines carry the class data,
//! partitions cover the atlas, bad requests exit non-zero naming the field.

use serde_json::Value;

fn egt(args: &[&str], stdin: Option<&str>) -> (i32, String, String) {
    let r = crate::util::egt(args, stdin);
    (r.code, r.stdout, r.stderr)
}

#[test]
fn every_printed_train_passes_egt_check_with_each_link_as_frame() {
    let (code, out, err) = egt(
        &["enumerate", "--links", "5", "--level", "displacement"],
        None,
    );
    assert_eq!(code, 0, "{err}");
    let lines: Vec<&str> = out.lines().collect();
    assert!(!lines.is_empty());
    for line in &lines {
        for frame in 1..=5 {
            let spec = format!("frame = \"{frame}\"\nadjacency = \"{line}\"\n");
            let (c, _, e) = egt(&["check", "-", "--spec-format", "toml"], Some(&spec));
            assert_eq!(c, 0, "{line} with frame {frame}: {e}");
        }
    }
}

#[test]
fn jsonl_partitions_and_counts_agree() {
    let (_, whole, _) = egt(&["enumerate", "--links", "6", "--jsonl"], None);
    let mut codes: Vec<String> = whole
        .lines()
        .map(|l| {
            let v: Value = serde_json::from_str(l).expect("json line");
            assert_eq!(v["links"], 6);
            assert_eq!(v["dof"], 1);
            v["code"].as_str().expect("code").to_string()
        })
        .collect();
    let (_, count, _) = egt(&["enumerate", "--links", "6", "--count"], None);
    assert_eq!(count.trim().parse::<usize>().expect("count"), codes.len());
    let mut parts: Vec<String> = (0..3)
        .flat_map(|p| {
            let part = format!("{p}/3");
            let (_, o, _) = egt(
                &["enumerate", "--links", "6", "--jsonl", "--part", &part],
                None,
            );
            o.lines()
                .map(|l| {
                    let v: Value = serde_json::from_str(l).expect("json line");
                    v["code"].as_str().expect("code").to_string()
                })
                .collect::<Vec<_>>()
        })
        .collect();
    codes.sort();
    parts.sort();
    assert_eq!(codes, parts);
}

#[test]
fn bad_requests_exit_non_zero_naming_the_field() {
    for (args, field) in [
        (vec!["enumerate", "--links", "2"], "links"),
        (vec!["enumerate", "--links", "5", "--dof", "4"], "dof"),
        (vec!["enumerate", "--links", "5", "--part", "3/3"], "part"),
        (
            vec![
                "enumerate",
                "--links",
                "6",
                "--search",
                "levels",
                "--part",
                "0/2",
            ],
            "part",
        ),
    ] {
        let (code, _, err) = egt(&args, None);
        assert_ne!(code, 0, "{args:?}");
        assert!(err.contains(field), "{args:?}: {err}");
    }
}

#[test]
fn seven_link_counts_equal_the_published_atlas() {
    // Yang & Ding, ASME J. Mech. Des. 141(4):043301 (2019): 152 r-graphs,
    // 647 d-graphs; by either search.
    for search in ["trees", "levels"] {
        for (level, want) in [("rotation", 152), ("displacement", 647)] {
            let (code, out, err) = egt(
                &[
                    "enumerate",
                    "--links",
                    "7",
                    "--level",
                    level,
                    "--search",
                    search,
                    "--count",
                ],
                None,
            );
            assert_eq!(code, 0, "{err}");
            assert_eq!(out.trim(), want.to_string(), "{level}, {search}");
        }
    }
}

#[test]
fn the_levels_first_search_prints_the_same_lines_and_splits_the_displacement_level() {
    let lines = |args: &[&str]| {
        let (code, out, err) = egt(args, None);
        assert_eq!(code, 0, "{err}");
        let mut v: Vec<String> = out.lines().map(str::to_string).collect();
        v.sort();
        v
    };
    let whole = lines(&[
        "enumerate",
        "--links",
        "7",
        "--level",
        "displacement",
        "--search",
        "levels",
        "--jsonl",
    ]);
    let trees = lines(&[
        "enumerate",
        "--links",
        "7",
        "--level",
        "displacement",
        "--jsonl",
    ]);
    let code = |l: &String| serde_json::from_str::<Value>(l).expect("json")["code"].clone();
    let codes = |v: &[String]| {
        let mut c: Vec<String> = v.iter().map(|l| code(l).to_string()).collect();
        c.sort();
        c
    };
    assert_eq!(codes(&whole), codes(&trees));
    // The parts' lines (a part's JSON counts only its own displacement
    // graphs of a rotation graph, so the plain lines are compared).
    let plain = lines(&[
        "enumerate",
        "--links",
        "7",
        "--level",
        "displacement",
        "--search",
        "levels",
    ]);
    assert_eq!(plain.len(), 647);
    let mut parts = Vec::new();
    for p in ["0/3", "1/3", "2/3"] {
        parts.extend(lines(&[
            "enumerate",
            "--links",
            "7",
            "--level",
            "displacement",
            "--search",
            "levels",
            "--part",
            p,
        ]));
    }
    parts.sort();
    assert_eq!(parts, plain);
}

#[test]
fn identify_prints_the_member_a_train_is() {
    // The paper's Fig. 5 drive is a six-link two-DOF member; its printed line
    // is in the listing of that atlas.
    let (code, line, err) = egt(
        &[
            "enumerate",
            "--identify",
            crate::util::example_path("fig5_example62.toml")
                .to_str()
                .expect("utf-8 path"),
            "--level",
            "displacement",
        ],
        None,
    );
    assert_eq!(code, 0, "{err}");
    let (_, all, _) = egt(
        &[
            "enumerate",
            "--links",
            "6",
            "--dof",
            "2",
            "--level",
            "displacement",
        ],
        None,
    );
    assert!(
        all.lines().any(|l| l == line.trim()),
        "{line} not in\n{all}"
    );
    // A housing on a bearing only has no place in the atlas: exit 2, named.
    let (code, _, err) = egt(
        &[
            "enumerate",
            "--identify",
            crate::util::example_path("ford_c4_simpson.toml")
                .to_str()
                .expect("utf-8 path"),
        ],
        None,
    );
    assert_eq!(code, 2);
    assert!(err.contains("case"), "{err}");
}

#[test]
fn eight_link_counts_equal_the_published_atlas_at_both_levels() {
    // Yang & Ding (2019): 1070 r-graphs and 6360 d-graphs. One run: each
    // rotation graph says how many displacement graphs it has.
    let (code, out, err) = egt(&["enumerate", "--links", "8", "--jsonl"], None);
    assert_eq!(code, 0, "{err}");
    let members: Vec<Value> = out
        .lines()
        .map(|l| serde_json::from_str(l).expect("json line"))
        .collect();
    assert_eq!(members.len(), 1070);
    let d: u64 = members
        .iter()
        .map(|m| m["displacement_graphs"].as_u64().expect("count"))
        .sum();
    assert_eq!(d, 6360);
}

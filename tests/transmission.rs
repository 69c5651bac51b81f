//! `egt shift` and `egt graph` as a user runs them (issue 5): the JSON carries
//! what the library computes, the table and plot options, the DOT graph, and
//! the gear table pasted in `docs/transmission.md`. The library's checks
//! (published ratios, hand statics, one-way elements, bad gear states) are in
//! egt-core's tests.

// A failed unwrap is a failed test, with its location.
#![allow(clippy::unwrap_used)]

use egt_core::numerics::exact;
use serde_json::Value;

use crate::util::{Run, example, example_path, root, stdout};

fn egt(args: &[&str]) -> Run {
    crate::util::egt(args, None)
}

#[test]
fn cli_shift_json_has_everything() {
    let v: Value = serde_json::from_str(&stdout(&[
        "shift",
        "examples/zf_8hp70.toml",
        "--format",
        "json",
    ]))
    .expect("json");
    let gears = v["gears"].as_array().expect("gears");
    assert_eq!(gears.len(), 9);
    let table = example("zf_8hp70.toml").shift_table().unwrap();
    assert_eq!(gears.len(), table.gears.len());
    for (g, lib) in gears.iter().zip(&table.gears) {
        assert_eq!(g["state"], lib.state.as_str());
        let exact = exact::parse_rational(g["ratio_exact"].as_str().unwrap()).unwrap();
        assert_eq!(Some(&exact), lib.ratio_exact.as_ref());
        assert_eq!(exact::to_f64(&exact), g["ratio"].as_f64().unwrap());
        assert_eq!(g["engaged"].as_array().unwrap().len(), 3);
        assert_eq!(g["slips"].as_array().unwrap().len(), 2);
        assert_eq!(g["elements"].as_array().unwrap().len(), 3);
        assert_eq!(g["speeds"].as_array().unwrap().len(), 13);
        assert_eq!(g["relative"].as_array().unwrap().len(), 4);
        assert_eq!(g["meshes"].as_array().unwrap().len(), 8);
        assert!(g["meshes"][0]["power"].is_array());
        assert!(g["efficiency"].as_f64().unwrap() <= 1.0);
        assert!(g["circulation_ratio"].as_f64().is_some());
        assert!(g["largest_element"]["element"].is_string());
    }
    assert_eq!(v["steps"].as_array().unwrap().len(), 7);
    assert_eq!(v["spread"]["exact"], "162/23"); // (108/23) / (2/3)
    assert_eq!(v["shifts"].as_array().unwrap().len(), 8);
}

#[test]
fn cli_shift_table_details_and_plot() {
    let dir = std::env::temp_dir().join(format!("egt-shift-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let svg_path = dir.join("zf.svg");
    let text = stdout(&[
        "shift",
        "examples/zf_8hp70.toml",
        "--state",
        "4",
        "--plot",
        svg_path.to_str().unwrap(),
    ]);
    assert!(text.contains("spread (1 / 8)"), "{text}");
    assert!(
        text.contains("gear 4: engaged B D E; ratio 1.666667 (5/3)"),
        "{text}"
    );
    assert!(text.contains("slip across open elements"), "{text}");
    let svg = std::fs::read_to_string(&svg_path).expect("svg written");
    assert!(svg.starts_with("<svg"));
    // One line per shaft (8 central members) and one bar per engaged element.
    assert_eq!(svg.matches("<polyline").count(), 8);
    assert_eq!(svg.matches("<title>").count(), 27);
    std::fs::remove_dir_all(&dir).ok();

    // A bad state fails with the state and the elements named.
    let text = std::fs::read_to_string(example_path("zf_8hp70.toml")).expect("read");
    let bad = text.replace(r#""2" = ["A", "B", "E"]"#, r#""2" = ["A", "B"]"#);
    let path = std::env::temp_dir().join(format!("egt-bad-{}.toml", std::process::id()));
    std::fs::write(&path, bad).expect("write");
    let out = egt(&["shift", path.to_str().unwrap()]);
    std::fs::remove_file(&path).ok();
    assert_ne!(out.code, 0);
    let err = out.stderr.as_str();
    assert!(
        err.contains("gear state `2` leaves 2 degrees of freedom"),
        "{err}"
    );
    // An unknown --state.
    let out = egt(&["shift", "examples/zf_8hp70.toml", "--state", "9"]);
    assert_ne!(out.code, 0);
    assert!(out.stderr.as_str().contains("unknown gear state `9`"));
}

#[test]
fn cli_graph_writes_dot_with_every_pair_and_element() {
    let dot = stdout(&["graph", "examples/zf_8hp70.toml"]);
    assert!(dot.starts_with("graph \"ZF 8HP70\" {") && dot.trim_end().ends_with('}'));
    let train = example("zf_8hp70.toml");
    let edges: Vec<&str> = dot.lines().filter(|l| l.contains(" -- ")).collect();
    assert_eq!(
        edges.len(),
        train.revolutes().len() + train.gears().len() + train.elements().len()
    );
    assert_eq!(
        edges.iter().filter(|l| l.contains("style=dashed")).count(),
        5
    );
    assert_eq!(
        edges.iter().filter(|l| l.contains("penwidth")).count(),
        train.gears().len()
    );
    assert!(
        dot.contains(r#""sun12" -- "case" [label="A (brake)""#),
        "{dot}"
    );
    assert!(
        dot.contains(r#""input" -- "ring3_sun4" [label="C (clutch)""#),
        "{dot}"
    );
    // Revolute edges carry their level.
    assert!(dot.contains(r#""case" -- "sun12" [label="a""#), "{dot}");
    let v: Value = serde_json::from_str(&stdout(&[
        "graph",
        "examples/zf_8hp70.toml",
        "--format",
        "json",
    ]))
    .expect("json");
    assert_eq!(v["nodes"].as_array().unwrap().len(), train.links().len());
}

/// The gear table pasted in `docs/transmission.md` is what the command prints.
#[test]
fn docs_transmission_md_table_is_current() {
    let doc = std::fs::read_to_string(root().join("docs/transmission.md")).expect("docs");
    let start = doc
        .find("$ egt shift examples/zf_8hp70.toml\n")
        .expect("the pasted run");
    let block = &doc[start..];
    let block = &block[block.find('\n').unwrap() + 1..block.find("```").unwrap()];
    assert_eq!(block, stdout(&["shift", "examples/zf_8hp70.toml"]));
}

//! `egt modes` as a user runs it (issue 43): the JSON is what the library
//! computes, the text table, `--state`, and a spec without compliance data
//! refused with `missing_data` naming the gear pairs. The physics is tested
//! in egt-core's tests (`crates/egt-core/tests/analyses/modes.rs`).

// A failed unwrap is a failed test that prints the error: what a test wants.
#![allow(clippy::unwrap_used)]

use egt_core::ModesRequest;

use crate::util::{Run, close, example};

const SPEC: &str = "examples/simple_planetary_compliant.toml";

fn egt(args: &[&str]) -> Run {
    crate::util::egt(args, None)
}

#[test]
fn cli_modes_json_is_the_librarys_modes() {
    let t = example("simple_planetary_compliant.toml");
    for state in [None, Some("low"), Some("direct")] {
        let mut args = vec!["modes", SPEC, "--format", "json"];
        if let Some(s) = state {
            args.extend(["--state", s]);
        }
        let out = egt(&args);
        assert_eq!(out.code, 0, "{}", out.stderr);
        let v: serde_json::Value = serde_json::from_str(&out.stdout).unwrap();
        let m = t
            .modes(&ModesRequest {
                state: state.map(String::from),
                ..ModesRequest::default()
            })
            .unwrap();
        assert_eq!(v["dof"], m.dof);
        assert_eq!(v["state"], serde_json::json!(state));
        assert_eq!(v["coordinates"][2]["name"], m.model.coordinates[2].name);
        let modes = v["modes"].as_array().unwrap();
        assert_eq!(modes.len(), m.modes.len());
        for (j, x) in modes.iter().zip(&m.modes) {
            assert!(close(j["hertz"].as_f64().unwrap(), x.hertz, 1e-15));
            assert!(close(j["omega"].as_f64().unwrap(), x.omega, 1e-15));
            assert_eq!(j["multiplicity"], x.multiplicity);
            assert_eq!(j["rigid"], x.rigid);
        }
        // Three planets: one planet mode of multiplicity 2 in every state.
        assert_eq!(
            modes
                .iter()
                .filter(|x| x["rigid"] == false && x["multiplicity"] == 2)
                .count(),
            2,
            "{state:?}"
        );
    }
}

#[test]
fn cli_modes_table_names_the_modes() {
    let out = egt(&["modes", SPEC, "--state", "low"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let s = &out.stdout;
    assert!(s.contains("torsional modes in gear state low"), "{s}");
    assert!(
        s.contains("held rigidly: B; rigid-body modes (DOF): 1"),
        "{s}"
    );
    assert!(s.contains("2 (degenerate)"), "{s}");
    assert!(s.contains("P.planet#3"), "{s}");
    assert!(s.contains("strain energy per spring"), "{s}");
}

#[test]
fn cli_modes_without_stiffness_is_missing_data_naming_the_gear_pairs() {
    let out = egt(&[
        "modes",
        "examples/simple_planetary.toml",
        "--format",
        "json",
    ]);
    assert_eq!(out.code, 1);
    let v: serde_json::Value = serde_json::from_str(&out.stdout).unwrap();
    assert_eq!(v["error"]["code"], "missing_data");
    let msg = v["error"]["message"].as_str().unwrap();
    assert!(
        msg.contains("`P/sun-planet`") && msg.contains("`P/planet-ring`"),
        "{msg}"
    );
    assert!(out.stderr.contains("compliance.meshes"), "{}", out.stderr);

    let out = egt(&["modes", SPEC, "--state", "lo"]);
    assert_eq!(out.code, 2);
    assert!(out.stderr.contains("low"), "{}", out.stderr);
}

/// The frequency table pasted in docs/vibration.md is what `egt modes` prints.
#[test]
fn docs_vibration_md_shows_the_real_output() {
    let out = egt(&["modes", SPEC, "--state", "low"]);
    let doc = std::fs::read_to_string(crate::util::root().join("docs/vibration.md")).unwrap();
    for line in out.stdout.lines().take(10) {
        assert!(
            doc.contains(line),
            "docs/vibration.md lacks the line\n{line}"
        );
    }
}

/// `--campbell --speed MIN:MAX`: the crossings of the JSON are the
/// library's, within the range; `--speed` alone is a usage error.
#[test]
fn cli_modes_campbell_crossings() {
    let out = egt(&[
        "modes",
        SPEC,
        "--state",
        "low",
        "--campbell",
        "--speed",
        "0:55000",
        "--format",
        "json",
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let v: serde_json::Value = serde_json::from_str(&out.stdout).unwrap();
    let m = &v["meshing"];
    assert_eq!(m["input"], "sun");
    assert_eq!(m["range"], serde_json::json!([0.0, 55000.0]));
    let crossings = m["crossings"].as_array().unwrap();
    // Two meshes of order 30 x 72 / 102 cross the two lowest distinct
    // elastic frequencies (7928 Hz, 19233 Hz) below 55 000 rpm.
    assert_eq!(crossings.len(), 4);
    for c in crossings {
        let speed = c["speed"].as_f64().unwrap();
        let f = c["hertz"].as_f64().unwrap();
        assert!(close(speed, 60.0 * f / (30.0 * 72.0 / 102.0), 1e-12));
        assert!(speed <= 55000.0);
    }
    let out = egt(&["modes", SPEC, "--speed", "0:10"]);
    assert_eq!(out.code, 2);
    let out = egt(&["modes", SPEC, "--campbell"]);
    assert_eq!(out.code, 1);
    assert!(out.stderr.contains("one rigid-body mode"), "{}", out.stderr);
}

/// The Campbell table pasted in docs/vibration.md is what `egt modes` prints.
#[test]
fn docs_vibration_md_shows_the_real_campbell_table() {
    let out = egt(&[
        "modes",
        SPEC,
        "--state",
        "low",
        "--campbell",
        "--speed",
        "0:55000",
    ]);
    let doc = std::fs::read_to_string(crate::util::root().join("docs/vibration.md")).unwrap();
    let start = out.stdout.find("mesh (tooth-pass)").unwrap();
    for line in out.stdout[start..].lines() {
        assert!(
            doc.contains(line),
            "docs/vibration.md lacks the line\n{line}"
        );
    }
}

/// `--static TORQUE`: the springs' mesh torques agree with eq. (11)'s, and
/// the output reacts the input by the gear's published ratio; `--static` without `--state` is a usage error
/// and a non-finite torque is refused naming the flag.
#[test]
fn cli_modes_static_deflection_carries_eq_11s_mesh_torques() {
    const HP: &str = "examples/zf_8hp70_compliant.toml";
    let out = egt(&[
        "modes", HP, "--state", "2", "--static", "300", "--format", "json",
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let v: serde_json::Value = serde_json::from_str(&out.stdout).unwrap();
    let s = &v["static_load"];
    assert_eq!(s["input_torque"], 300.0);
    // Second gear's ratio is 3.130 (published, three decimals): the output
    // reacts -300 x 3.130 N m.
    let ratio = -s["output_torque"].as_f64().unwrap() / 300.0;
    assert!((ratio - 3.130).abs() < 5e-4, "ratio {ratio}");
    let meshes = s["meshes"].as_array().unwrap();
    assert_eq!(meshes.len(), 8);
    let top = meshes
        .iter()
        .map(|m| m["rigid_torque"].as_f64().unwrap().abs())
        .fold(0.0, f64::max);
    assert!(top > 10.0);
    for m in meshes {
        let (a, b) = (
            m["rigid_torque"].as_f64().unwrap(),
            m["compliant_torque"].as_f64().unwrap(),
        );
        assert!(
            (a - b).abs() < 1e-10 * top,
            "{}: {a} against {b}",
            m["gear"]
        );
    }
    assert_eq!(s["elements"].as_array().unwrap().len(), 3);
    let table = egt(&["modes", HP, "--state", "2", "--static", "300"]);
    assert_eq!(table.code, 0, "{}", table.stderr);
    assert!(
        table
            .stdout
            .contains("static deflection: 300 N m on the input"),
        "{}",
        table.stdout
    );
    assert!(
        table.stdout.contains("held elements' torques: A "),
        "{}",
        table.stdout
    );
    let out = egt(&["modes", HP, "--static", "300"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    let out = egt(&["modes", HP, "--state", "2", "--static", "NaN"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(out.stderr.contains("--static"), "{}", out.stderr);
}

/// `--plot FILE` writes a Campbell diagram: an SVG with a ray per mesh, a
/// line per drawn frequency group and a circle per crossing; without
/// `--campbell` it is a usage error.
#[test]
fn cli_modes_campbell_plot_draws_every_crossing() {
    let dir = std::env::temp_dir().join(format!("egt-campbell-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("campbell.svg");
    let p = path.to_str().unwrap();
    let out = egt(&[
        "modes",
        SPEC,
        "--state",
        "low",
        "--campbell",
        "--speed",
        "0:55000",
        "--plot",
        p,
        "--format",
        "json",
    ]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let v: serde_json::Value = serde_json::from_str(&out.stdout).unwrap();
    let svg = std::fs::read_to_string(&path).unwrap();
    assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
    let crossings = v["meshing"]["crossings"].as_array().unwrap().len();
    assert_eq!(svg.matches("<circle").count(), crossings);
    assert_eq!(
        svg.matches("<polyline").count(),
        v["meshing"]["orders"].as_array().unwrap().len()
    );
    assert!(svg.contains("input speed [rpm]"));
    std::fs::remove_dir_all(&dir).unwrap();
    let out = egt(&["modes", SPEC, "--plot", p]);
    assert_eq!(out.code, 2, "{}", out.stderr);
}

/// The 8HP70 table of docs/vibration.md is what `egt modes` gives in each
/// gear: the three lowest distinct elastic frequencies (rounded to Hz) and
/// the number of Campbell crossings from 0 to 7000 rpm.
#[test]
fn docs_vibration_md_8hp_table_is_the_real_output() {
    let doc = std::fs::read_to_string(crate::util::root().join("docs/vibration.md")).unwrap();
    let mut seen = 0;
    for gear in ["1", "2", "3", "4", "5", "6", "7", "8", "R"] {
        let row = doc
            .lines()
            .find(|l| {
                l.starts_with(&format!("| {gear} | ")) && l.contains("Hz)")
                    || l.starts_with(&format!("| {gear} | ")) && l.ends_with("| 0 | - |")
            })
            .unwrap_or_else(|| panic!("no row for gear {gear}"));
        let out = egt(&[
            "modes",
            "examples/zf_8hp70_compliant.toml",
            "--state",
            gear,
            "--campbell",
            "--format",
            "json",
        ]);
        assert_eq!(out.code, 0, "{}", out.stderr);
        let v: serde_json::Value = serde_json::from_str(&out.stdout).unwrap();
        let modes = v["modes"].as_array().unwrap();
        let lowest: Vec<String> = modes
            .iter()
            .enumerate()
            .filter(|(k, m)| !m["rigid"].as_bool().unwrap() && m["group"] == *k)
            .take(3)
            .map(|(_, m)| format!("{:.0} (", m["hertz"].as_f64().unwrap()))
            .collect();
        for f in &lowest {
            assert!(row.contains(f.as_str()), "gear {gear}: {f} not in\n{row}");
        }
        let crossings = v["meshing"]["crossings"].as_array().unwrap().len();
        assert!(
            row.contains(&format!(" | {crossings} | ")),
            "gear {gear}: {crossings} crossings, doc row\n{row}"
        );
        seen += 1;
    }
    assert_eq!(seen, 9);
}

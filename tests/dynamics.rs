//! `egt dynamics` and `egt power` as a user runs them: the JSON satisfies
//! power balance and housing torque balance, and each command asks only for
//! the data it uses (issue 3; the library's checks are in egt-core's tests).

// A panic is how a test reports; unwrapping here is the point.
#![allow(clippy::unwrap_used)]

use crate::util::close;

fn egt(args: &[&str]) -> (i32, String, String) {
    let r = crate::util::egt(args, None);
    (r.code, r.stdout, r.stderr)
}

fn example(name: &str) -> String {
    crate::util::example_path(name).display().to_string()
}

/// `egt dynamics` and `egt power` on the Fig. 3 example: JSON that satisfies
/// power balance (input = output + losses + dK/dt) and housing torque balance.
#[test]
fn cli_dynamics_and_power_balance() {
    let (code, out, err) = egt(&[
        "dynamics",
        &example("fig3_example61.toml"),
        "--format",
        "json",
        "--forces",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["meshes"].as_array().unwrap().len(), 2);
    assert!(v["meshes"][0]["force"].is_array());
    assert!(v["equivalent_inertia"][1].as_f64().unwrap() > 0.0);

    let (code, out, err) = egt(&["power", &example("fig3_example61.toml"), "--format", "json"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let g = |k: &str| v[k].as_f64().unwrap();
    assert!(close(
        g("input_power"),
        g("output_power") + g("loss") + g("kinetic_rate"),
        1e-12
    ));
    assert!(g("loss") > 0.0 && g("efficiency") < 1.0);
    let (code, out, _) = egt(&[
        "power",
        &example("fig3_example61.toml"),
        "--format",
        "json",
        "--ideal",
        "--accel",
        "4=0",
    ]);
    assert_eq!(code, 0);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert!(close(v["efficiency"].as_f64().unwrap(), 1.0, 1e-14));
}

/// Data not needed is never demanded, data needed is named: a static analysis
/// needs no inertia, forces need radii, inverse dynamics needs driving links.
#[test]
fn cli_dynamics_asks_only_for_what_it_uses() {
    let dir = std::env::temp_dir().join(format!("egt-dyn-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let spec = dir.join("bare.toml");
    std::fs::write(
        &spec,
        "frame = \"ring\"\n[[planetary]]\nname = \"P\"\nsun = \"sun\"\nring = \"ring\"\ncarrier = \"carrier\"\nteeth = { sun = 30, ring = 72, planet = 21 }\n",
    )
    .unwrap();
    let s = spec.to_str().unwrap();
    let (code, out, err) = egt(&[
        "dynamics",
        s,
        "--torque",
        "sun=10",
        "--driving",
        "carrier",
        "--format",
        "json",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    // Static: the carrier carries -(1 + 72/30) of the sun torque.
    assert!(close(
        v["driving_torques"][0][1].as_f64().unwrap(),
        -10.0 * (1.0 + 72.0 / 30.0),
        1e-12
    ));
    let (code, _, err) = egt(&[
        "dynamics",
        s,
        "--torque",
        "sun=10",
        "--driving",
        "carrier",
        "--forces",
    ]);
    assert_eq!(code, 1);
    assert!(
        err.contains("pitch radii") && err.contains("P/sun-planet"),
        "{err}"
    );
    let (code, _, err) = egt(&["dynamics", s, "--torque", "sun=10"]);
    assert_eq!(code, 1);
    assert!(err.contains("driving"), "{err}");
    let (code, _, err) = egt(&["dynamics", s, "--torque", "sunn=10", "--driving", "carrier"]);
    assert_eq!(code, 2);
    assert!(err.contains("did you mean `sun`"), "{err}");
    // Accelerating a planet whose inertia is given but tooth count is not: named.
    std::fs::write(
        &spec,
        "frame = \"ring\"\n[[planetary]]\nname = \"P\"\nsun = \"sun\"\nring = \"ring\"\ncarrier = \"carrier\"\nteeth = { sun = 30, ring = 72 }\n[[links]]\nname = \"P.planet\"\ninertia = 0.001\n",
    )
    .unwrap();
    let (code, _, err) = egt(&[
        "dynamics",
        s,
        "--torque",
        "sun=10",
        "--driving",
        "carrier",
        "--accel",
        "carrier=5",
    ]);
    assert_eq!(code, 1);
    assert!(err.contains("tooth count of planet `P.planet`"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

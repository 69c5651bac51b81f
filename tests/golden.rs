//! Every bundled example through every analysis, as JSON, against committed
//! snapshots: a refactor that changes any number egt prints (to 10
//! significant digits; round-off diagnostics such as residuals and condition
//! estimates masked) fails here. Failed analyses are part of the record (exit
//! code and message).

use serde_json::Value;

use crate::util::egt;

const ANALYSES: [&[&str]; 7] = [
    &["check"],
    &["circuits"],
    &["kinematics"],
    &["dynamics", "--forces"],
    &["power"],
    &["stability"],
    &["shift"],
];

/// Keys whose values are round-off diagnostics, not results.
fn masked(key: &str) -> bool {
    [
        "residual",
        "condition",
        "orthogonality",
        "balance",
        "drift",
        "tolerance",
        "iterations",
        "version",
    ]
    .iter()
    .any(|m| key.contains(m))
}

fn normalise(v: &mut Value) {
    match v {
        Value::Number(n) => {
            if let Some(x) = n.as_f64().filter(|x| x.fract() != 0.0 || x.abs() > 1e15) {
                *v = Value::String(format!("{x:.9e}"));
            }
        }
        Value::Array(a) => a.iter_mut().for_each(normalise),
        Value::Object(o) => {
            for (k, x) in o.iter_mut() {
                if masked(k) {
                    *x = Value::String("[masked]".into());
                } else {
                    normalise(x);
                }
            }
        }
        _ => {}
    }
}

fn record(example: &str) -> String {
    let mut out = serde_json::Map::new();
    for args in ANALYSES {
        let argv: Vec<&str> = args
            .iter()
            .copied()
            .chain([example, "--format", "json"])
            .collect();
        let r = egt(&argv, None);
        let mut entry = serde_json::json!({ "exit": r.code });
        if r.code == 0 {
            let mut v: Value = serde_json::from_str(&r.stdout).expect("JSON output");
            normalise(&mut v);
            entry["output"] = v;
        } else {
            entry["error"] = Value::String(r.stderr.trim().to_string());
        }
        out.insert(args.join(" "), entry);
    }
    serde_json::to_string_pretty(&out).expect("serialise")
}

macro_rules! golden {
    ($($name:ident => $file:literal),* $(,)?) => {$(
        #[test]
        fn $name() {
            insta::assert_snapshot!(record(concat!("examples/", $file)));
        }
    )*};
}

golden! {
    golden_fig3_example61 => "fig3_example61.toml",
    golden_fig5_example62 => "fig5_example62.toml",
    golden_fig5_stability => "fig5_stability.toml",
    golden_simple_planetary => "simple_planetary.toml",
    golden_ford_aod_ravigneaux => "ford_aod_ravigneaux.toml",
    golden_ford_c4_simpson => "ford_c4_simpson.toml",
    golden_zf_8hp70 => "zf_8hp70.toml",
    golden_zf_6hp26_lepelletier => "zf_6hp26_lepelletier.toml",
    golden_adjacency_enumerated => "adjacency_enumerated.json",
    golden_simple_planetary_compliant => "simple_planetary_compliant.toml",
}

/// `egt modes` (issue 43) on the one example with compliance data, bare and
/// in each gear state (the other examples have none: `egt modes` refuses them).
#[test]
fn golden_modes_simple_planetary_compliant() {
    let spec = "examples/simple_planetary_compliant.toml";
    let mut out = serde_json::Map::new();
    for state in [None, Some("low"), Some("direct")] {
        let mut argv = vec!["modes", spec, "--format", "json"];
        argv.extend(state.iter().flat_map(|s| ["--state", s]));
        let r = egt(&argv, None);
        assert_eq!(r.code, 0, "{}", r.stderr);
        let mut v: Value = serde_json::from_str(&r.stdout).expect("JSON output");
        // Within a degenerate frequency (the planet modes; the rigid-body
        // modes of a bare train with 2 DOF) the basis is the eigensolver's
        // choice: only the frequencies are results there.
        for m in v["modes"].as_array_mut().expect("modes") {
            if m["multiplicity"].as_u64() != Some(1) {
                let m = m.as_object_mut().expect("a mode");
                for k in ["shape", "strain_energy", "kinetic_energy", "damping_ratio"] {
                    m.remove(k);
                }
            }
        }
        normalise(&mut v);
        out.insert(argv[4..].join(" "), v);
    }
    insta::assert_snapshot!(serde_json::to_string_pretty(&out).expect("serialise"));
}

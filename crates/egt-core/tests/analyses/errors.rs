//! One test per class of bad input. Each asserts the error variant and that
//! the message names the offending link, pair or field.

// A failed unwrap is a failed test, with its location.
#![allow(clippy::unwrap_used)]

use egt_core::numerics::exact;
use egt_core::{AnalysisError, Error, Format, SpecErrorKind, TopologyError, Train};

use crate::paper::fig3;
use crate::util::{fr, input, toml, toml_err};

/// Fig. 3 written out, with `extra` appended (more links, pairs or fields).
fn fig3_with(extra: &str) -> String {
    format!("frame = \"1\"\nadjacency = \"1-2:a 2-3:b 1-4:a 1-3:G=-2/3 3-4:G=-16/9\"\n{extra}")
}

fn spec_error(e: Error) -> (String, SpecErrorKind) {
    match e {
        Error::Spec { path, kind } => (path, kind),
        other => panic!("expected a spec error, got {other:?}"),
    }
}

fn topology_error(e: Error) -> TopologyError {
    match e {
        Error::Topology(t) => t,
        other => panic!("expected a topology error, got {other:?}"),
    }
}

fn analysis_error(e: Error) -> AnalysisError {
    match e {
        Error::Analysis(a) => a,
        other => panic!("expected an analysis error, got {other:?}"),
    }
}

#[test]
fn unknown_link_with_suggestion() {
    let e = toml_err(
        "frame = \"case\"\n[[links]]\nname = \"carrier\"\n[[revolutes]]\nlinks = [\"case\", \"carier\"]\nlevel = \"a\"\n",
    );
    let msg = e.to_string();
    let (path, kind) = spec_error(e);
    assert_eq!(path, "revolutes[0].links[1]");
    assert!(
        matches!(kind, SpecErrorKind::UnknownLink { ref name, suggestion: Some(ref s) } if name == "carier" && s == "carrier"),
        "{kind:?}"
    );
    assert!(msg.contains("did you mean `carrier`"), "{msg}");
}

#[test]
fn duplicate_link() {
    let e = toml_err(&fig3_with(
        "[[links]]\nname = \"2\"\n[[links]]\nname = \"2\"\n",
    ));
    let (path, kind) = spec_error(e);
    assert_eq!(path, "links[1].name");
    assert!(matches!(kind, SpecErrorKind::DuplicateLink { ref name } if name == "2"));
}

#[test]
fn duplicate_turning_pair() {
    let e = toml_err(&fig3_with(
        "[[revolutes]]\nlinks = [\"2\", \"1\"]\nlevel = \"a\"\n",
    ));
    let msg = e.to_string();
    let (_, kind) = spec_error(e);
    assert!(matches!(kind, SpecErrorKind::Duplicate { .. }), "{kind:?}");
    assert!(msg.contains("`2`") && msg.contains("`1`"), "{msg}");
}

#[test]
fn duplicate_gear_pair() {
    let e = toml_err(&fig3_with("[[gears]]\nlinks = [\"3\", \"1\"]\nratio = 2\n"));
    let msg = e.to_string();
    let (path, kind) = spec_error(e);
    assert_eq!(path, "gears[0]");
    assert!(
        matches!(kind, SpecErrorKind::Duplicate { ref first, .. } if first.contains("adjacency")),
        "{kind:?}"
    );
    assert!(msg.contains("gear pair between `3` and `1`"), "{msg}");
}

#[test]
fn self_loops() {
    let e = toml_err(&fig3_with(
        "[[revolutes]]\nlinks = [\"4\", \"4\"]\nlevel = \"a\"\n",
    ));
    let (path, kind) = spec_error(e);
    assert_eq!(path, "revolutes[0].links");
    assert!(matches!(kind, SpecErrorKind::SelfLoop { ref link } if link == "4"));

    let e = toml_err(&fig3_with("[[gears]]\nlinks = [\"3\", \"3\"]\nratio = 2\n"));
    let (path, kind) = spec_error(e);
    assert_eq!(path, "gears[0].links");
    assert!(matches!(kind, SpecErrorKind::SelfLoop { ref link } if link == "3"));
}

#[test]
fn zero_and_negative_teeth() {
    for (z, field) in [
        ("[0, 20]", "gears[0].teeth[0]"),
        ("[20, -7]", "gears[0].teeth[1]"),
    ] {
        let e = toml_err(&format!(
            "frame = \"1\"\nadjacency = \"1-2:a 2-3:b 1-4:a 3-4:G=-16/9\"\n[[gears]]\nlinks = [\"1\", \"3\"]\nteeth = {z}\nmesh = \"external\"\n"
        ));
        let (path, kind) = spec_error(e);
        assert_eq!(path, field);
        assert!(matches!(kind, SpecErrorKind::InvalidTeeth { value } if value <= 0));
    }
    // In the planetary shorthand too.
    let e = toml_err(
        "frame = \"F\"\n[[planetary]]\nname = \"P\"\nsun = \"s\"\nring = \"F\"\ncarrier = \"c\"\nteeth = { sun = 0, ring = 72 }\n",
    );
    assert!(
        matches!(
            e,
            Error::Spec {
                kind: SpecErrorKind::InvalidTeeth { value: 0 },
                ..
            }
        ),
        "{e:?}"
    );
    assert!(e.to_string().contains("planetary[0]"), "{e}");
}

#[test]
fn non_finite_numbers() {
    let e = toml_err(&fig3_with("[[links]]\nname = \"2\"\ninertia = nan\n"));
    let (path, kind) = spec_error(e);
    assert_eq!(path, "links[0].inertia");
    assert!(matches!(kind, SpecErrorKind::NonFinite { .. }));

    let e = toml_err(
        "frame = \"1\"\nadjacency = \"1-2:a 2-3:b 1-4:a 3-4:G=-16/9\"\n[[gears]]\nlinks = [\"1\", \"3\"]\nratio = inf\n",
    );
    let (path, kind) = spec_error(e);
    assert_eq!(path, "gears[0].ratio");
    assert!(matches!(kind, SpecErrorKind::NonFinite { .. }));

    let e = toml_err(&fig3_with("[analysis]\nspeeds = { \"2\" = -inf }\n"));
    let (path, _) = spec_error(e);
    assert_eq!(path, "analysis.speeds.2");
}

#[test]
fn wrong_dof_for_the_given_inputs() {
    let train = fig3(&fr(-2, 3), &fr(-16, 9));
    let e = train
        .kinematics(&[
            input(&train, "2", exact::q(1)),
            input(&train, "4", exact::q(1)),
        ])
        .expect_err("1 DOF, 2 inputs");
    assert!(matches!(
        analysis_error(e),
        AnalysisError::WrongInputCount {
            dof: 1,
            given: 2,
            ..
        }
    ));
    let e = train.kinematics(&[]).expect_err("1 DOF, no input");
    assert!(matches!(
        analysis_error(e),
        AnalysisError::WrongInputCount {
            dof: 1,
            given: 0,
            ..
        }
    ));
}

#[test]
fn disconnected_links() {
    let e = toml_err(&fig3_with("[[links]]\nname = \"lonely\"\n"));
    assert_eq!(
        topology_error(e),
        TopologyError::Disconnected {
            links: vec!["lonely".into()]
        }
    );
}

#[test]
fn link_with_no_turning_path() {
    // 5 meshes with 3 but is not mounted on anything.
    let e = toml_err(&fig3_with(
        "[[gears]]\nlinks = [\"3\", \"5\"]\nratio = -2\n[[links]]\nname = \"5\"\n",
    ));
    assert_eq!(
        topology_error(e),
        TopologyError::NoTurningPath {
            links: vec!["5".into()]
        }
    );
}

#[test]
fn turning_pair_cycle() {
    let e = toml_err(&fig3_with(
        "[[revolutes]]\nlinks = [\"3\", \"4\"]\nlevel = \"c\"\n",
    ));
    match topology_error(e) {
        TopologyError::RevoluteCycle { links } => {
            for l in ["3", "4"] {
                assert!(links.contains(&l.to_string()), "{links:?}");
            }
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn no_transfer_vertex_when_both_gears_are_coaxial() {
    // 2 and 4 both turn on the frame about axis a: the circuit of their mesh has one level.
    let e = toml_err("frame = \"1\"\nadjacency = \"1-2:a 1-4:a 2-4:G=-2\"\n");
    match topology_error(e) {
        TopologyError::NoTransferVertex { pair, levels } => {
            assert_eq!(pair, "G1");
            assert_eq!(levels, vec!["a", "a"]);
        }
        other => panic!("{other:?}"),
    }
}

/// K3,3 as a chain that passes every earlier check (spanning tree, L_ind = j_G,
/// a transfer vertex per circuit): a carrier A with two planets Y, Z, each
/// meshing two suns B, C. Planarity (rustworkx) rejects it.
#[test]
fn non_planar_graph() {
    let e = toml_err(
        "frame = \"X\"\nadjacency = \"X-A:p X-B:p X-C:p A-Y:q A-Z:r B-Y:G B-Z:G C-Y:G C-Z:G\"\n",
    );
    // The six links of the K3,3 are named.
    match topology_error(e) {
        TopologyError::NonPlanar { links } => {
            assert_eq!(links, vec!["X", "A", "B", "C", "Y", "Z"]);
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn no_mobility() {
    // Fig. 3 with a second planet 5 meshing 1 and 4 too: F = 3(5-1) - 2*4 - 4 = 0.
    let e = toml_err(
        "frame = \"1\"\nadjacency = \"1-2:a 2-3:b 1-4:a 2-5:c 1-3:G=-2/3 3-4:G=-16/9 1-5:G=-1/2 5-4:G=-3/2\"\n",
    );
    assert_eq!(topology_error(e), TopologyError::NoMobility { dof: 0 });
}

#[test]
fn locked_sub_chain() {
    // Carrier 2 with planets 3 and 5, both meshing 1 and 4 (locked for generic
    // ratios), beside a free-running set 6/7 that gives the chain F = 1.
    let e = toml_err(
        "frame = \"1\"\nadjacency = \"1-2:a 2-3:b 1-4:a 2-5:c 1-3:G 3-4:G 1-5:G 5-4:G 1-6:a 6-7:d 1-7:G\"\n",
    );
    match topology_error(e) {
        TopologyError::Locked { links } => assert_eq!(links, vec!["1", "2", "3", "4", "5"]),
        other => panic!("{other:?}"),
    }
}

/// An over-constrained block: carrier x with planets y and w, each meshing the
/// fixed wheel on the frame F and the sun z, and meshing each other: five
/// Willis equations that never involve the frame among the four links x, y, w,
/// z, so at most four are independent for any ratios. (Planar: K5 less the
/// edge x-z.) Two differentials, one on z and one on x, give the chain F = 1.
#[test]
fn redundant_gear_pairs() {
    let e = toml_err(
        "frame = \"F\"\nadjacency = \"F-x:a x-y:b x-w:c F-z:a y-z:G y-F:G w-z:G w-F:G y-w:G \
         F-CA:a CA-PA:d F-RA:a z-PA:G PA-RA:G F-CB:a CB-PB:e F-RB:a x-PB:G PB-RB:G\"\n",
    );
    match topology_error(e) {
        TopologyError::Redundant { pairs } => {
            assert!(pairs.len() >= 2, "{pairs:?}");
            for p in &pairs {
                assert!(
                    !p.contains('P'),
                    "only the block's pairs are dependent: {pairs:?}"
                );
            }
            assert!(pairs.iter().any(|p| p.contains("y-w")), "{pairs:?}");
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn fractionated_mobility() {
    // Two independent sets sharing only the frame: 2/3 and 4/5.
    let e = toml_err("frame = \"1\"\nadjacency = \"1-2:a 2-3:b 1-3:G=-2 1-4:c 4-5:d 1-5:G=-3\"\n");
    match topology_error(e) {
        TopologyError::Fractionated { link, parts } => {
            assert_eq!(link, "1");
            assert_eq!(
                parts,
                vec![
                    vec!["2".to_string(), "3".to_string()],
                    vec!["4".to_string(), "5".to_string()]
                ]
            );
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn free_link() {
    let e = toml_err(&fig3_with(
        "[[links]]\nname = \"5\"\n[[revolutes]]\nlinks = [\"1\", \"5\"]\nlevel = \"a\"\n",
    ));
    assert_eq!(
        topology_error(e),
        TopologyError::FreeLinks {
            links: vec!["5".into()]
        }
    );
}

/// Fig. 3 with tau_1 tau_2 = 1: the output cannot move. Driving the output is
/// inconsistent (both circuits named); holding it leaves carrier and planet free.
#[test]
fn singular_ratio_is_an_exact_error() {
    let train = fig3(&fr(-2, 3), &fr(-3, 2));
    let e = train
        .kinematics(&[input(&train, "4", exact::q(1))])
        .expect_err("singular");
    match analysis_error(e) {
        AnalysisError::Inconsistent { conflicting } => {
            assert_eq!(conflicting.len(), 2, "{conflicting:?}");
            assert!(
                conflicting[0].contains("G1") && conflicting[1].contains("G2"),
                "{conflicting:?}"
            );
        }
        other => panic!("{other:?}"),
    }
    let e = train
        .kinematics(&[input(&train, "4", exact::q(0))])
        .expect_err("singular");
    assert_eq!(
        analysis_error(e),
        AnalysisError::Underdetermined {
            free: vec!["2".into(), "3".into()]
        }
    );
    // Driving the carrier is fine: the output stands still.
    let s = train
        .kinematics(&[input(&train, "2", exact::q(1))])
        .expect("regular");
    assert_eq!(s.exact.expect("exact")[3], exact::q(0));
}

/// Fig. 5 (2 DOF) driven at 2 and 3: 3 is already fixed by 2, so 4, 5, 6 are left free
/// (or, with speeds that disagree with tau_1, circuit #1 conflicts).
#[test]
fn inputs_that_leave_links_free() {
    let train = crate::paper::fig5(&fr(-3, 1), &fr(-3, 2), &fr(7, 2));
    let e = train
        .kinematics(&[
            input(&train, "2", exact::q(3)),
            input(&train, "3", exact::q(-1)),
        ])
        .expect_err("underdetermined");
    match analysis_error(e) {
        AnalysisError::Underdetermined { mut free } => {
            free.sort();
            assert_eq!(free, vec!["4", "5", "6"]);
        }
        other => panic!("{other:?}"),
    }
    let e = train
        .kinematics(&[
            input(&train, "2", exact::q(3)),
            input(&train, "3", exact::q(5)),
        ])
        .expect_err("inconsistent");
    match analysis_error(e) {
        AnalysisError::Inconsistent { conflicting } => {
            assert_eq!(conflicting, vec!["circuit #1 (gear pair G1)".to_string()])
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn syntax_error_has_file_line_column() {
    let text = "frame = \"1\"\nadjacency = \"1-2:a\"\n[[links]\nname = \"2\"\n";
    let e = Train::from_str(text, Format::Toml, "bad.toml").expect_err("syntax");
    let Error::Syntax(s) = &e else {
        panic!("{e:?}")
    };
    assert_eq!(s.line, 3);
    assert!(
        e.to_string()
            .starts_with(&format!("bad.toml:3:{}:", s.column)),
        "{e}"
    );

    let json = "{\n  \"frame\": \"1\",\n  \"adjacency\": \"1-2:a\"\n  \"links\": []\n}\n";
    let e = Train::from_str(json, Format::Json, "bad.json").expect_err("syntax");
    let Error::Syntax(s) = &e else {
        panic!("{e:?}")
    };
    assert_eq!(s.line, 4);
    assert!(e.to_string().starts_with("bad.json:4:"), "{e}");
}

#[test]
fn type_error_has_field_path() {
    let text = fig3_with("[[links]]\nname = \"3\"\ncopies = \"three\"\n");
    let e = Train::from_str(&text, Format::Toml, "bad.toml").expect_err("type");
    let Error::Syntax(s) = &e else {
        panic!("{e:?}")
    };
    assert_eq!(s.path.as_deref(), Some("links[0].copies"));
    assert_eq!(s.line, 5);
    assert!(e.to_string().contains("links[0].copies"), "{e}");
}

/// The bundled examples all validate (and the fixtures above are otherwise valid).
#[test]
fn fixtures_are_valid_without_the_fault() {
    let t = toml(&fig3_with(""));
    assert_eq!(t.dof(), 1);
}

/// A planetary set whose sun and ring are one link is refused by name.
#[test]
fn planetary_members_on_one_link() {
    let e = toml_err(
        "frame = \"f\"\n[[planetary]]\nname = \"P\"\nsun = \"s\"\nring = \"s\"\ncarrier = \"c\"\nteeth = { sun = 20, ring = 60 }\n",
    );
    let msg = e.to_string();
    assert!(
        matches!(e, egt_core::Error::Spec { ref path, .. } if path == "planetary[0]"),
        "{msg}"
    );
    assert!(msg.contains("same link `s`"), "{msg}");
}

/// Tooth counts that are valid but suspect are warned about, by set and
/// with the numbers: a ring not larger than its sun, non-coaxial planets of
/// unshifted gears, equally spaced planets that cannot be assembled; the
/// counts that satisfy both conditions give no warning.
#[test]
fn planetary_design_warnings_name_the_set_and_the_condition() {
    let set = |teeth: &str, copies: u32| {
        crate::util::toml(&format!(
            r#"
            frame = "ring"
            links = [{{ name = "P.planet", copies = {copies} }}]
            [[planetary]]
            name = "P"
            sun = "sun"
            ring = "ring"
            carrier = "carrier"
            teeth = {teeth}
            "#
        ))
    };
    // 30 + 2 * 21 = 72 and (30 + 72) / 3 = 34: clean.
    assert!(
        set("{ sun = 30, ring = 72, planet = 21 }", 3)
            .design_warnings()
            .is_empty()
    );
    let w = set("{ sun = 30, ring = 72, planet = 20 }", 3)
        .design_warnings()
        .to_vec();
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].contains("`P`") && w[0].contains("70") && w[0].contains("coaxial"),
        "{w:?}"
    );
    let w = set("{ sun = 30, ring = 72, planet = 21 }", 4)
        .design_warnings()
        .to_vec();
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].contains("(30 + 72) / 4") && w[0].contains("assembled"),
        "{w:?}"
    );
    let w = set("{ sun = 72, ring = 30 }", 1).design_warnings().to_vec();
    assert!(
        w.len() == 1 && w[0].contains("not larger than the sun"),
        "{w:?}"
    );
}

/// Issue 11: a JSON spec and the equal TOML spec read every decimal as the
/// same double, the correctly rounded one (serde_json's `float_roundtrip`).
#[test]
fn json_and_toml_decimals_are_the_same_doubles() {
    let mut x: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut mismatches = Vec::new();
    for _ in 0..2000 {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        let digits = format!("{:017}", x % 100_000_000_000_000_000);
        let exp = i32::try_from(x % 41).unwrap() - 20;
        let text = format!("0.{digits}e{exp}");
        let expected: f64 = text.parse().unwrap();
        for (format, spec) in [
            (
                Format::Json,
                format!(r#"{{"frame": "f", "links": [{{"name": "a", "inertia": {text}}}]}}"#),
            ),
            (
                Format::Toml,
                format!("frame = \"f\"\nlinks = [{{ name = \"a\", inertia = {text} }}]\n"),
            ),
        ] {
            let read = egt_core::parse_spec(&spec, format, "test").unwrap().links[0]
                .inertia
                .unwrap();
            if read.to_bits() != expected.to_bits() {
                mismatches.push(format!("{format:?} {text}: {read:e} != {expected:e}"));
            }
        }
    }
    assert!(
        mismatches.is_empty(),
        "{} misread, e.g. {:?}",
        mismatches.len(),
        &mismatches[..mismatches.len().min(3)]
    );
}

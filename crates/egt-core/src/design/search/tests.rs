//! The design search's unit tests.

use super::*;
use crate::design::spec::SynthSpec;
use crate::model::train::Train;
use crate::spec::parse::{Format, parse_spec};

const ZF: &str = include_str!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../examples/zf_8hp70.toml"
));

fn zf_search(sets: &str) -> Search {
    zf_search_with(sets, "")
}

/// The 8HP search with more lines under `[targets]`.
fn zf_search_with(sets: &str, targets: &str) -> Search {
    let text = format!(
        "base = \"zf_8hp70.toml\"\ntop = 5\n{sets}\n[targets]\nratios = {{ \"1\" = 4.696, \"2\" = 3.130, \"3\" = 2.104, \"4\" = 1.667, \"5\" = 1.285, \"6\" = 1.000, \"7\" = 0.839, \"8\" = 0.667, \"R\" = -3.297 }}\n{targets}\n"
    );
    let spec: SynthSpec = toml::from_str(&text).expect("test input");
    Search::new(
        spec,
        parse_spec(ZF, Format::Toml, "zf").expect("test input"),
    )
    .expect("test input")
}

/// Rediscovery of the 8HP teeth from the published ratios (to three
/// decimals) within small ranges around them; every candidate's ratios
/// come from the exact analysis and meet the targets.
#[test]
fn rediscovers_8hp_teeth() {
    let s = zf_search(
        "[sets]\nP1 = { sun = [44, 52], ring = [90, 100] }\nP2 = { sun = [44, 52], ring = [90, 100] }\nP3 = { sun = [64, 72], ring = [106, 114] }\nP4 = { sun = [20, 26], ring = [80, 88] }",
    );
    let (found, stats) = s.run().expect("test input");
    assert!(stats.leaves as f64 <= stats.ratio_space);
    let real = [(48, 96), (48, 96), (69, 111), (23, 85)];
    // The real set or one with identical basic ratios (ring/sun).
    assert!(found.iter().any(|c| {
        c.teeth
            .iter()
            .zip(real)
            .all(|(t, (zs, zr))| t.ring * zs == zr * t.sun)
    }));
    for c in &found {
        for (state, ratio, exact) in &c.ratios {
            let q = crate::numerics::exact::parse_rational(exact).expect("test input");
            assert!((crate::numerics::exact::to_f64(&q) - ratio).abs() < 1e-12);
            let t = s.spec.targets.ratios[state];
            assert!((ratio - t).abs() <= 5e-4, "{state}: {ratio} vs {t}");
        }
    }
}

/// Targets only the exact analysis checks, at the edges of the real
/// 8HP's figures (`egt shift examples/zf_8hp70.toml`): largest element
/// torque 2.642 (brake B in R), lowest efficiency 0.9462 (R), steps from
/// 1.192 to 1.500, not progressive (1.262 then 1.297). Each target passes
/// the real teeth on one side of its figure and rejects them on the other.
#[test]
fn analysis_targets_accept_and_reject_the_real_8hp() {
    let sets = "[sets]\nP3 = { sun = [66, 72], ring = [108, 114] }\nP4 = { sun = [21, 25], ring = [82, 88] }";
    let found = |targets: &str| {
        let (c, stats) = zf_search_with(sets, targets).run().expect("test input");
        (c.len(), stats.rejected)
    };
    assert_eq!(found(""), (1, 0));
    for (pass, fail) in [
        ("max_element_torque = 2.65", "max_element_torque = 2.6"),
        ("efficiency = 0.946", "efficiency = 0.95"),
        ("steps = [1.19, 1.5001]", "steps = [1.2, 1.6]"),
        ("progressive = false", "progressive = true"),
        ("single_swap = true", "steps = [1.0, 1.2]"),
        ("max_mesh_torque = 100.0", "max_mesh_torque = 0.5"),
    ] {
        assert_eq!(found(pass), (1, 0), "{pass}");
        assert_eq!(found(fail), (0, 1), "{fail}");
    }
    let bad = SynthSpec::from_str(
        "base = \"x\"\n[sets]\nP3 = { sun = [66, 72], ring = [108, 114] }\n[targets]\nratios = { \"1\" = 4.7 }\nefficiency = -1\n",
        Format::Toml,
        "s",
    )
    .expect("test input");
    let err = Search::new(bad, parse_spec(ZF, Format::Toml, "zf").expect("test input"))
        .expect_err("must refuse");
    assert!(err.to_string().contains("targets.efficiency"), "{err}");
}

/// Free element positions: the three clutches anywhere (21 952 layouts)
/// with two sets' teeth free. The real layout is found (clutch E on any
/// two of P3's members: three equivalent placements, each reported), with
/// the real basic ratios; every candidate's written spec, analysed
/// exactly, has the reported ratios; bad placements are refused by field.
#[test]
fn free_clutch_positions_find_the_real_layout() {
    let sets = "[sets]\nP3 = { sun = [60, 76], ring = [100, 120] }\nP4 = { sun = [20, 28], ring = [76, 92] }\n[layout]\nC = \"any\"\nD = \"any\"\nE = \"any\"";
    let s = zf_search(sets);
    let (found, stats) = s.run().expect("test input");
    assert_eq!(stats.layouts + stats.skipped_layouts, 28 * 28 * 28);
    let real = |c: &Candidate| {
        let links = |e: &str| {
            let mut l = c.layout.iter().find(|x| x.0 == e).expect("freed").1.clone();
            l.sort();
            l
        };
        links("C") == ["input", "ring3_sun4"] && links("D") == ["carrier3", "output"]
    };
    assert_eq!(found.len(), 3, "{found:?}");
    for c in &found {
        assert!(real(c), "{:?}", c.layout);
        assert_eq!(c.basic, ["37/23", "85/23"]);
        let table = Train::from_spec(&s.candidate_spec(&c.teeth, &c.layout))
            .expect("candidate spec")
            .shift_table()
            .expect("analysis");
        for (g, (state, _, exact)) in table.gears.iter().zip(&c.ratios) {
            assert_eq!(&g.state, state);
            assert_eq!(
                &crate::numerics::exact::display(g.ratio_exact.as_ref().expect("exact")),
                exact
            );
        }
    }
    for (layout, field) in [
        ("C = [[\"input\"]]", "layout.C[0]"),
        ("C = [[\"input\", \"nowhere\"]]", "layout.C[0]"),
        ("Z = \"any\"", "layout.Z"),
        ("C = \"all\"", "layout.C"),
    ] {
        let text = format!(
            "base = \"x\"\n[sets]\nP4 = {{ sun = [20, 28], ring = [76, 92] }}\n[layout]\n{layout}\n[targets]\nratios = {{ \"1\" = 4.7 }}\n"
        );
        let spec: SynthSpec = toml::from_str(&text).expect("test input");
        let err = Search::new(
            spec,
            parse_spec(ZF, Format::Toml, "zf").expect("test input"),
        )
        .expect_err("must refuse");
        assert!(err.to_string().starts_with(field), "{layout}: {err}");
    }
}

/// Partitions are disjoint and cover the space: their merged candidates
/// equal the one-partition run.
#[test]
fn partitions_merge_to_the_whole() {
    let s = zf_search(
        "[sets]\nP3 = { sun = [60, 76], ring = [100, 120] }\nP4 = { sun = [20, 28], ring = [76, 92] }",
    );
    let (whole, _) = s.run().expect("test input");
    let mut merged = Vec::new();
    for p in 0..3 {
        merged.extend(s.run_partition(p, 3).expect("test input").0);
    }
    rank(&mut merged, 5);
    let key = |c: &Vec<Candidate>| c.iter().map(|x| x.teeth.clone()).collect::<Vec<_>>();
    assert_eq!(key(&whole), key(&merged));
    assert!(!whole.is_empty());
}

/// Sequential parts with progress give the one-partition result.
#[test]
fn run_in_parts_reports_progress_and_equals_run() {
    let s = zf_search(
        "[sets]\nP3 = { sun = [60, 76], ring = [100, 120] }\nP4 = { sun = [20, 28], ring = [76, 92] }",
    );
    let (whole, ws) = s.run().expect("test input");
    let mut seen = Vec::new();
    let (parts, ps) = s
        .run_in_parts(4, |done, of, best| {
            assert!(best.len() <= 5);
            seen.push((done, of));
        })
        .expect("test input");
    assert_eq!(seen, [(1, 4), (2, 4), (3, 4), (4, 4)]);
    let key = |c: &Vec<Candidate>| c.iter().map(|x| x.teeth.clone()).collect::<Vec<_>>();
    assert_eq!(key(&whole), key(&parts));
    assert_eq!(ws.tooth_space, ps.tooth_space);
}

const AOD: &str = include_str!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../examples/ford_aod_ravigneaux.toml"
));

/// A Ravigneaux set's two searched ratios: the branch and bound keeps
/// exactly the tooth sets that an exhaustive run of the exact transmission
/// analysis over every admissible (small sun, large sun, ring) accepts.
#[test]
fn ravigneaux_search_equals_exhaustive_exact_analysis() {
    let text = "base = \"aod\"\ntop = 100000\n[sets]\nR = { sun = [24, 36], sun2 = [28, 44], ring = [60, 84] }\n[targets]\ntolerance = 0.03\nratios = { \"1\" = 2.40, \"2\" = 1.47, \"4\" = 0.67, \"R\" = -2.00 }\n";
    let spec: SynthSpec = toml::from_str(text).expect("test input");
    let s = Search::new(
        spec,
        parse_spec(AOD, Format::Toml, "aod").expect("test input"),
    )
    .expect("test input");
    let (found, stats) = s.run().expect("test input");
    let mut got: Vec<(String, String)> = found
        .iter()
        .map(|c| (c.basic[0].clone(), c.basic2[0].clone().expect("Ravigneaux")))
        .collect();
    got.sort();
    // Every admissible tooth set, analysed exactly; its basic ratios kept
    // when every targeted ratio is within the tolerance.
    let mut want = std::collections::BTreeSet::new();
    let teeth: Vec<Teeth> = s.unknowns[0].teeth.values().map(|t| t[0]).collect();
    assert_eq!(teeth.len() as f64, stats.ratio_space);
    for t in teeth {
        let table = Train::from_spec(&s.candidate_spec(&[t], &[]))
            .expect("admissible teeth make a train")
            .shift_table()
            .expect("every state solves");
        let ok = table.gears.iter().all(|g| {
            s.spec
                .targets
                .ratios
                .get(&g.state)
                .is_none_or(|&r| (g.ratio - r).abs() <= 0.03)
        });
        if ok {
            let q =
                |z: i64| crate::numerics::exact::display(&crate::numerics::exact::frac(t.ring, z));
            want.insert((q(t.sun), q(t.sun2.expect("Ravigneaux"))));
        }
    }
    let want: Vec<_> = want.into_iter().collect();
    assert!(
        want.len() > 3,
        "a loose tolerance admits several sets: {want:?}"
    );
    assert_eq!(got, want);
    assert!(got.contains(&("12/5".into(), "2".into())));
}

#[test]
fn unknown_names_are_errors() {
    let spec: SynthSpec = toml::from_str(
        "base = \"x\"\n[sets]\nP9 = { sun = [20, 30], ring = [60, 80] }\n[targets]\nratios = { \"1\" = 4.7 }",
    )
    .expect("test input");
    let err = Search::new(
        spec,
        parse_spec(ZF, Format::Toml, "zf").expect("test input"),
    )
    .expect_err("must fail");
    assert!(err.to_string().contains("sets.P9"), "{err}");
}

/// Ranges that would take minutes or exhaust memory are refused by name
/// before any pair is visited.
#[test]
fn huge_ranges_are_refused_by_field() {
    let err = Search::new(
        toml::from_str(
            "base = \"x\"\n[sets]\nP1 = { sun = [20, 100000], ring = [60, 200000] }\n[targets]\nratios = { \"1\" = 4.7 }",
        )
        .expect("test input"),
        parse_spec(ZF, Format::Toml, "zf").expect("test input"),
    )
    .expect_err("must refuse");
    assert!(
        err.to_string().contains("sets.P1.ring") && err.to_string().contains("10000000"),
        "{err}"
    );
    let err = Search::new(
        toml::from_str(
            "base = \"x\"\n[sets]\nP1 = { sun = [20, 30], ring = [60, 2000000] }\n[targets]\nratios = { \"1\" = 4.7 }",
        )
        .expect("test input"),
        parse_spec(ZF, Format::Toml, "zf").expect("test input"),
    )
    .expect_err("must refuse");
    assert!(err.to_string().contains("1000000"), "{err}");
}

/// The ranges (suns 20-80, rings 60-130, all four sets unknown,
/// 8.9e10 tooth combinations): the bound leaves one candidate, the 8HP's
/// basic ratios 2, 2, 111/69, 85/23.
#[test]
fn rediscovers_8hp_full_ranges() {
    let r = "{ sun = [20, 80], ring = [60, 130] }";
    let s = zf_search(&format!("[sets]\nP1 = {r}\nP2 = {r}\nP3 = {r}\nP4 = {r}"));
    let (found, stats) = s.run().expect("test input");
    assert!(stats.tooth_space > 1e10);
    assert_eq!(found[0].basic, ["2", "2", "37/23", "85/23"]);
}

/// A run stopped by its caller's flag says so, and what it returns is
/// what it finished: nothing when stopped before the start, the first
/// part's candidates when stopped after the first part.
#[test]
fn a_cancelled_run_stops_and_says_so() {
    use std::sync::Arc;
    use std::sync::atomic::{AtomicBool, Ordering::Relaxed};
    let sets = "[sets]\nP3 = { sun = [60, 76], ring = [100, 120] }\nP4 = { sun = [20, 28], ring = [76, 92] }";
    let flag = Arc::new(AtomicBool::new(false));
    let s = zf_search(sets).with_cancel(flag.clone());
    let (whole, ws) = s.run().expect("test input");
    assert!(!ws.interrupted && !whole.is_empty());
    flag.store(true, Relaxed);
    let (none, ns) = s.run().expect("test input");
    assert!(ns.interrupted);
    assert!(none.is_empty());
    assert_eq!(ns.nodes, 0);
    flag.store(false, Relaxed);
    let mut seen = Vec::new();
    let (first, fs) = s
        .run_in_parts(4, |done, of, _| {
            seen.push((done, of));
            flag.store(true, Relaxed);
        })
        .expect("test input");
    assert_eq!(seen, [(1, 4)]);
    assert!(fs.interrupted);
    let (part0, _) = zf_search(sets).run_partition(0, 4).expect("test input");
    let key = |c: &Vec<Candidate>| c.iter().map(|x| x.teeth.clone()).collect::<Vec<_>>();
    assert_eq!(key(&first), key(&part0));
    // Not in the serde form unless set: reports of whole runs are unchanged.
    let text = serde_json::to_string(&ws).expect("stats");
    assert!(!text.contains("interrupted"), "{text}");
}

const C4: &str = include_str!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../examples/ford_c4_simpson.toml"
));

/// The C4 search with `layout` under `[layout]`, both sets' teeth free near
/// the real 33/72 (three planets, profiles shifted by one tooth as the
/// C4's are), the published ratios to three decimals.
fn c4_search(layout: &str) -> Result<Search, DesignError> {
    let text = format!(
        "base = \"ford_c4_simpson.toml\"\ntop = 5\n[sets]\nfront = {{ sun = [30, 36], ring = [68, 76], planets = 3 }}\nrear = {{ sun = [30, 36], ring = [68, 76], planets = 3 }}\n[constraints]\nprofile_shift = 1\n[layout]\n{layout}\n[targets]\nratios = {{ \"1\" = 2.458, \"2\" = 1.458, \"3\" = 1.000, \"R\" = -2.182 }}\n"
    );
    let spec: SynthSpec = toml::from_str(&text).expect("test input");
    Search::new(
        spec,
        parse_spec(C4, Format::Toml, "c4").expect("test input"),
    )
}

/// A brake and a one-way brake on one member (the C4's low-reverse band and
/// low one-way clutch on the rear carrier, as the NAG1's brake and freewheel)
/// is a layout, not a doubled element: freeing both finds the real one.
#[test]
fn a_brake_beside_a_one_way_brake_on_one_member_is_searched() {
    let s = c4_search("low_reverse_band = \"any\"\nlow_one_way = \"any\"").expect("test input");
    let (found, stats) = s.run().expect("test input");
    assert!(stats.layouts > 0);
    let real = found.iter().any(|c| {
        c.layout
            .iter()
            .all(|(name, links)| links == &["rear_carrier".to_string()] || !name.starts_with("low"))
            && c.teeth.iter().all(|t| t.sun * 72 == t.ring * 33)
    });
    assert!(
        real,
        "{:?}",
        found.iter().map(|c| &c.layout).collect::<Vec<_>>()
    );
}

/// A layout filter that leaves no layout is an error naming `layout` and
/// why, not an empty result: two friction brakes on one member.
#[test]
fn a_layout_filter_that_leaves_nothing_says_so() {
    let Err(err) = c4_search("intermediate_band = [[\"rear_carrier\"]]") else {
        panic!("every layout doubles a brake");
    };
    let text = err.to_string();
    assert!(text.starts_with("layout:"), "{text}");
    assert!(text.contains("1 put two elements of one kind"), "{text}");
}

/// A base built from gear pairs declares no sets: naming one under `[sets]`
/// says what to declare instead of "no set of that name".
#[test]
fn a_gear_built_base_is_told_to_declare_its_sets() {
    let base = "frame = \"H\"\nadjacency = \"H-sun:a H-ring:a H-carrier:a carrier-planet:b sun-planet:G=-21/30 planet-ring:G=72/21\"\n[[elements]]\nname = \"B\"\nkind = \"brake\"\nlinks = [\"ring\"]\n[transmission]\ninput = \"sun\"\noutput = \"carrier\"\nstates = { low = [\"B\"] }\n";
    let spec: SynthSpec = toml::from_str(
        "base = \"gears.toml\"\n[sets]\nP = { sun = [20, 40], ring = [60, 90] }\n[targets]\nratios = { \"low\" = 3.4 }\n",
    )
    .expect("test input");
    let Err(err) = Search::new(
        spec,
        parse_spec(base, Format::Toml, "gears").expect("test input"),
    ) else {
        panic!("no [[planetary]] to search");
    };
    let text = err.to_string();
    assert!(text.starts_with("sets.P:"), "{text}");
    assert!(text.contains("[[planetary]]"), "{text}");
}

/// A double-pinion set as an unknown (issue 45): a two-speed whose first
/// gear (carrier held, sun in, ring out) is z_r / z_s = 77/32 = 2.40625 is
/// found again from 2.406 (three decimals); every candidate is a train egt
/// accepts, with the ratios the search reported, and pinions that fit.
#[test]
fn a_double_pinion_unknown_set_is_found_again_from_its_ratio() {
    let base = "frame = \"H\"\n[[planetary]]\nname = \"D\"\nkind = \"double_pinion\"\nsun = \"sun\"\nring = \"ring\"\ncarrier = \"carrier\"\nteeth = { sun = 32, ring = 77, planet = 15, planet2 = 15 }\n[[elements]]\nname = \"B\"\nkind = \"brake\"\nlinks = [\"carrier\"]\n[[elements]]\nname = \"C\"\nkind = \"clutch\"\nlinks = [\"sun\", \"carrier\"]\n[transmission]\ninput = \"sun\"\noutput = \"ring\"\nstates = { \"1\" = [\"B\"], \"2\" = [\"C\"] }\n";
    let spec: SynthSpec = toml::from_str(
        "base = \"dp.toml\"\ntop = 20\n[sets]\nD = { sun = [26, 38], ring = [66, 88], planets = 3 }\n[targets]\nratios = { \"1\" = 2.406, \"2\" = 1.0 }\n",
    )
    .expect("test input");
    let s = Search::new(
        spec,
        parse_spec(base, Format::Toml, "dp").expect("test input"),
    )
    .expect("a double-pinion unknown is searched");
    let (found, _) = s.run().expect("test input");
    assert!(
        found
            .iter()
            .any(|c| c.teeth[0].sun == 32 && c.teeth[0].ring == 77),
        "{:?}",
        found.iter().map(|c| &c.teeth).collect::<Vec<_>>()
    );
    for c in &found {
        let t = &c.teeth[0];
        assert!((t.ring as f64 / t.sun as f64 - 2.406).abs() <= 5e-4);
        assert_eq!((t.ring - t.sun) % 3, 0, "assembly");
        assert!(t.planet2 == Some(t.planet) && 2 * t.planet + 2 <= t.ring - t.sun);
        let table = Train::from_spec(&s.candidate_spec(&c.teeth, &c.layout))
            .expect("candidate spec")
            .shift_table()
            .expect("analysis");
        let first = table.gears.iter().find(|g| g.state == "1").expect("gear 1");
        assert!((first.ratio - t.ring as f64 / t.sun as f64).abs() < 1e-12);
    }
}

/// The rank's keys in order: score, then the higher lowest efficiency, the
/// smaller largest element torque, the smaller largest mesh torque, then the
/// slower fastest planet; analysis keys equal but for round-off are equal
/// (the slower planet first, not the mesh torque's last bits).
#[test]
fn rank_orders_by_score_efficiency_torques_then_planet_speed() {
    let base = Candidate {
        basic: vec!["2".into()],
        basic2: vec![None],
        teeth: vec![Teeth {
            sun: 30,
            ring: 60,
            planet: 15,
            sun2: None,
            planet2: None,
        }],
        alternatives: vec![1],
        ratios: Vec::new(),
        spread: None,
        layout: Vec::new(),
        score: 1e-3,
        same_ratio_teeth: Vec::new(),
        efficiency: Some(0.95),
        element_torque: Some(2.0),
        mesh_torque: Some(5.0),
        planet_speed: Some(3.0),
        concept: None,
    };
    let with = |f: &dyn Fn(&mut Candidate)| {
        let mut c = base.clone();
        f(&mut c);
        c
    };
    let mut c = vec![
        with(&|c| c.planet_speed = Some(4.0)),
        with(&|c| {
            c.mesh_torque = Some(5.0 + 8.0 * f64::EPSILON);
            c.planet_speed = Some(2.5);
        }),
        with(&|c| c.mesh_torque = Some(6.0)),
        with(&|c| c.element_torque = Some(3.0)),
        with(&|c| c.efficiency = Some(0.9)),
        with(&|c| c.score = 2e-3),
        base.clone(),
    ];
    rank(&mut c, 10);
    let keys: Vec<_> = c
        .iter()
        .map(|c| {
            (
                c.score,
                c.efficiency,
                c.element_torque,
                c.mesh_torque,
                c.planet_speed,
            )
        })
        .collect();
    assert_eq!(
        keys,
        [
            (
                1e-3,
                Some(0.95),
                Some(2.0),
                Some(5.0 + 8.0 * f64::EPSILON),
                Some(2.5)
            ),
            (1e-3, Some(0.95), Some(2.0), Some(5.0), Some(3.0)),
            (1e-3, Some(0.95), Some(2.0), Some(5.0), Some(4.0)),
            (1e-3, Some(0.95), Some(2.0), Some(6.0), Some(3.0)),
            (1e-3, Some(0.95), Some(3.0), Some(5.0), Some(3.0)),
            (1e-3, Some(0.9), Some(2.0), Some(5.0), Some(3.0)),
            (2e-3, Some(0.95), Some(2.0), Some(5.0), Some(3.0)),
        ]
    );
}

/// Whether `planets` equally spaced stepped planets assemble, tried on the
/// meshes' tooth phases (in revolutions) rather than the closed form: planet
/// 0 fixes where the sun's and the ring's teeth stand and the angle between
/// the planet's two wheels; planet j, 1/planets of a turn on, must find a
/// turn of its own (one of the first step's `planet` pitches) at which both
/// its wheels fall into tooth gaps.
fn assembles_by_phases(sun: i64, ring: i64, planet: i64, planet2: i64, planets: i64) -> bool {
    let whole = |x: f64| (x - x.round()).abs() < 1e-9;
    (1..planets).all(|j| {
        let at = j as f64 / planets as f64;
        // Sun mesh (external): sun (0 - at) + planet (turn - at - 1/2) = -planet / 2 (mod 1).
        // Ring mesh (internal): ring (0 - at) - planet2 (turn - at) = 0 (mod 1).
        (0..planet).any(|m| {
            let turn = ((sun + planet) as f64 * at + m as f64) / planet as f64;
            whole(-(ring as f64) * at - planet2 as f64 * (turn - at))
        })
    })
}

/// The stepped planets' assembly condition (sun planet2 + ring planet)
/// divisible by planets gcd(planet, planet2) agrees with the tooth phases
/// of every planet, and the phase model agrees with the published
/// condition of a simple set, (sun + ring) / planets, when both wheels are
/// one.
#[test]
fn stepped_planets_assemble_as_their_tooth_phases_say() {
    let (mut yes, mut no) = (0, 0);
    for planets in 2..=5 {
        for sun in 12..=24 {
            for planet in 8..=20 {
                for planet2 in 8..=20 {
                    let ring = sun + planet + planet2;
                    let phases = assembles_by_phases(sun, ring, planet, planet2, planets);
                    assert_eq!(
                        space::stepped_assembles(sun, ring, planet, planet2, planets),
                        phases,
                        "sun {sun} ring {ring} planets {planet}/{planet2} n {planets}"
                    );
                    if planet == planet2 {
                        assert_eq!(phases, (sun + ring) % planets == 0);
                    }
                    if phases { yes += 1 } else { no += 1 }
                }
            }
        }
    }
    assert!(yes > 1000 && no > 1000, "{yes} assemble, {no} do not");
}

/// A one-set two-speed with a stepped planet: ring held, sun in, carrier
/// out, 1 + k with k = ring planet / (sun planet2).
const STEPPED: &str = "frame = \"H\"\n[[planetary]]\nname = \"S\"\nkind = \"stepped\"\nsun = \"sun\"\nring = \"ring\"\ncarrier = \"carrier\"\nteeth = { sun = 23, ring = 73, planet = 31, planet2 = 19 }\n[[elements]]\nname = \"B\"\nkind = \"brake\"\nlinks = [\"ring\"]\n[[elements]]\nname = \"C\"\nkind = \"clutch\"\nlinks = [\"sun\", \"carrier\"]\n[transmission]\ninput = \"sun\"\noutput = \"carrier\"\nstates = { \"1\" = [\"B\"], \"2\" = [\"C\"] }\n";

fn stepped_search(sets: &str, targets: &str) -> Search {
    let spec: SynthSpec = toml::from_str(&format!(
        "base = \"stepped.toml\"\ntop = 100000\n[sets]\n{sets}\n[targets]\n{targets}\n"
    ))
    .expect("test input");
    Search::new(
        spec,
        parse_spec(STEPPED, Format::Toml, "stepped").expect("test input"),
    )
    .expect("a stepped unknown is searched")
}

/// A stepped set as an unknown: the real 23/31/19/73 (first gear
/// 1 + 2263/437 = 6.17849...) is found again from 6.178, and every
/// candidate is coaxial, assembles and is a train egt's exact analysis
/// confirms with that ratio.
#[test]
fn a_stepped_unknown_set_is_found_again_from_its_ratio() {
    let s = stepped_search(
        "S = { sun = [18, 30], ring = [60, 80], planet = [14, 34], planets = 3 }",
        "ratios = { \"1\" = 6.178, \"2\" = 1.0 }",
    );
    let (found, _) = s.run().expect("test input");
    let real = Teeth {
        sun: 23,
        ring: 73,
        planet: 31,
        sun2: None,
        planet2: Some(19),
    };
    let hit = found
        .iter()
        .find(|c| c.same_ratio_teeth[0].contains(&real))
        .expect("the real set is among the candidates");
    assert_eq!(hit.basic, ["2263/437"]);
    for c in &found {
        for t in &c.same_ratio_teeth[0] {
            let p2 = t.planet2.expect("a stepped planet's second wheel");
            assert_eq!(t.sun + t.planet, t.ring - p2, "coaxial");
            assert!(space::stepped_assembles(t.sun, t.ring, t.planet, p2, 3));
            let table = Train::from_spec(&s.candidate_spec(&[*t], &c.layout))
                .expect("candidate spec")
                .shift_table()
                .expect("analysis");
            let first = table.gears.iter().find(|g| g.state == "1").expect("gear 1");
            let k = (t.ring * t.planet) as f64 / (t.sun * p2) as f64;
            assert!((first.ratio - (1.0 + k)).abs() < 1e-12, "{t:?}");
            assert!((first.ratio - 6.178).abs() <= s.spec.targets.tolerance);
        }
    }
}

/// A stepped set's searched ratio: the branch and bound keeps exactly the
/// basic ratios that the exact analysis of every admissible stepped set of
/// the ranges accepts.
#[test]
fn stepped_search_equals_exhaustive_exact_analysis() {
    let s = stepped_search(
        "S = { sun = [18, 26], ring = [56, 72], planet = [14, 26], planets = 4 }",
        "tolerance = 0.05\nratios = { \"1\" = 5.0 }",
    );
    let (found, stats) = s.run().expect("test input");
    let mut got: Vec<String> = found.iter().map(|c| c.basic[0].clone()).collect();
    got.sort();
    let teeth: Vec<Teeth> = s.unknowns[0].teeth.values().flatten().copied().collect();
    assert!(teeth.len() > 20, "{}", teeth.len());
    assert_eq!(s.unknowns[0].teeth.len() as f64, stats.ratio_space);
    let mut want = std::collections::BTreeSet::new();
    for t in teeth {
        let table = Train::from_spec(&s.candidate_spec(&[t], &[]))
            .expect("admissible teeth make a train")
            .shift_table()
            .expect("every state solves");
        let first = table.gears.iter().find(|g| g.state == "1").expect("gear 1");
        if (first.ratio - 5.0).abs() <= 0.05 {
            let (n, d) = t.basic();
            want.insert(crate::numerics::exact::display(
                &crate::numerics::exact::frac(n, d),
            ));
        }
    }
    let want: Vec<String> = want.into_iter().collect();
    assert!(
        want.len() > 3,
        "a loose tolerance admits several ratios: {want:?}"
    );
    assert_eq!(got, want);
}

/// A stepped set needs its first step's range, which no other kind takes.
#[test]
fn a_planet_range_belongs_to_a_stepped_set() {
    let spec: SynthSpec = toml::from_str(
        "base = \"stepped.toml\"\n[sets]\nS = { sun = [18, 30], ring = [60, 80] }\n[targets]\nratios = { \"1\" = 6.178 }\n",
    )
    .expect("test input");
    let base = parse_spec(STEPPED, Format::Toml, "stepped").expect("test input");
    let Err(err) = Search::new(spec, base) else {
        panic!("a stepped set without a planet range");
    };
    assert!(err.to_string().starts_with("sets.S.planet:"), "{err}");
    let spec: SynthSpec = toml::from_str(
        "base = \"dp.toml\"\n[sets]\nD = { sun = [26, 38], ring = [66, 88], planet = [14, 20] }\n[targets]\nratios = { \"1\" = 2.406 }\n",
    )
    .expect("test input");
    let base = STEPPED
        .replace("kind = \"stepped\"", "kind = \"double_pinion\"")
        .replace("name = \"S\"", "name = \"D\"");
    let Err(err) = Search::new(
        spec,
        parse_spec(&base, Format::Toml, "dp").expect("test input"),
    ) else {
        panic!("a planet range on a double-pinion set");
    };
    assert!(err.to_string().starts_with("sets.D.planet:"), "{err}");
    // A first-step range past the tooth limit, or one that alone takes the
    // set past the combination budget, is refused by its own field.
    for planet in ["[14, 1000001]", "[14, 100000]"] {
        let spec: SynthSpec = toml::from_str(&format!(
            "base = \"stepped.toml\"\n[sets]\nS = {{ sun = [18, 30], ring = [60, 80], planet = {planet} }}\n[targets]\nratios = {{ \"1\" = 6.178 }}\n"
        ))
        .expect("test input");
        let base = parse_spec(STEPPED, Format::Toml, "stepped").expect("test input");
        let Err(err) = Search::new(spec, base) else {
            panic!("planet = {planet} is refused");
        };
        assert!(
            err.to_string().starts_with("sets.S.planet:"),
            "{planet}: {err}"
        );
    }
}

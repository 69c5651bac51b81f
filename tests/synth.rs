//! `egt synth` as a user runs it (issue 16): the 8HP70's tooth counts
//! rediscovered from its published ratios, every candidate re-run through
//! `egt shift` giving exactly the ratios the search reported, the Ford C4's
//! real sets among the candidates, partitions that merge to the whole
//! search, and bad search specs refused by field with exit 2.

// A failed unwrap is a failed test, with its location.
#![allow(clippy::unwrap_used)]

use serde_json::Value;

use crate::util::{Run, egt, root, stdout};

fn synth(args: &[&str]) -> Value {
    serde_json::from_str(&stdout(args)).unwrap()
}

/// (sun, ring) pairs of one candidate, by set.
fn teeth(c: &Value) -> Vec<(i64, i64)> {
    c["sets"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| (s["sun"].as_i64().unwrap(), s["ring"].as_i64().unwrap()))
        .collect()
}

/// A candidate's exact ratios are those of an `egt shift` document's gears.
fn assert_gear_ratios(shift: &Value, candidate: &Value) {
    for r in candidate["ratios"].as_array().unwrap() {
        let g = shift["gears"]
            .as_array()
            .unwrap()
            .iter()
            .find(|g| g["state"] == r["state"])
            .unwrap();
        assert_eq!(g["ratio_exact"], r["exact"], "state {}", r["state"]);
        assert_eq!(g["ratio"], r["ratio"], "state {}", r["state"]);
    }
}

#[test]
fn rediscovers_the_8hp_and_every_candidate_passes_egt_shift() {
    let dir = std::env::temp_dir().join(format!("egt-synth-{}", std::process::id()));
    let dir_s = dir.display().to_string();
    let v = synth(&[
        "synth",
        "examples/synth/zf_8hp70.toml",
        "--format",
        "json",
        "--write-specs",
        &dir_s,
    ]);
    let cands = v["candidates"].as_array().unwrap();
    assert!(!cands.is_empty());
    // The real sets (48/96, 48/96, 69/111, 23/85), or sets with the same ring/sun.
    let real = [(48, 96), (48, 96), (69, 111), (23, 85)];
    let best = teeth(&cands[0]);
    assert!(
        best.iter()
            .zip(real)
            .all(|(&(zs, zr), (s, r))| zr * s == r * zs),
        "{best:?}"
    );
    assert!(v["stats"]["tooth_space"].as_f64().unwrap() > 1e10);
    for c in cands {
        let spec = c["spec"].as_str().unwrap();
        let shift: Value =
            serde_json::from_str(&stdout(&["shift", spec, "--format", "json"])).unwrap();
        assert_gear_ratios(&shift, c);
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn finds_the_c4_simpson_sets() {
    let v = synth(&[
        "synth",
        "examples/synth/ford_c4_simpson.toml",
        "--format",
        "json",
    ]);
    let cands = v["candidates"].as_array().unwrap();
    assert!(
        cands.iter().any(|c| teeth(c) == [(33, 72), (33, 72)]),
        "the real 33/72 sets are not among {} candidates",
        cands.len()
    );
    for c in cands {
        for r in c["ratios"].as_array().unwrap() {
            let target = match r["state"].as_str().unwrap() {
                "1" => 2.46,
                "2" => 1.46,
                "3" => 1.00,
                _ => -2.18,
            };
            assert!((r["ratio"].as_f64().unwrap() - target).abs() <= 0.005);
        }
    }
}

/// Ravigneaux sets in the search: the 6HP26 (a simple set and a Ravigneaux
/// set, six tooth counts free) comes out with its real teeth; the AOD's
/// Ravigneaux set with its real basic ratios 72/30 and 72/36. Every
/// candidate's written spec, re-run through `egt shift`, gives the reported
/// exact ratios.
#[test]
fn finds_ravigneaux_sets_and_every_candidate_passes_egt_shift() {
    let dir = std::env::temp_dir().join(format!("egt-synth-rv-{}", std::process::id()));
    // Each search writes its candidates' specs to its own folder.
    let run = |spec: &str, sub: &str| {
        let out = dir.join(sub).display().to_string();
        synth(&["synth", spec, "--format", "json", "--write-specs", &out])["candidates"]
            .as_array()
            .unwrap()
            .clone()
    };
    let lepelletier = run("examples/synth/zf_6hp26_lepelletier.toml", "6hp26");
    let best = &lepelletier[0]["sets"];
    assert_eq!(
        (best[0]["sun"].clone(), best[0]["ring"].clone()),
        (37.into(), 71.into())
    );
    let rv = &best[1];
    assert_eq!(
        [&rv["sun"], &rv["sun2"], &rv["ring"]],
        [&Value::from(31), &Value::from(38), &Value::from(85)]
    );
    assert_eq!(
        (rv["basic"].as_str(), rv["basic2"].as_str()),
        (Some("85/31"), Some("85/38"))
    );
    let aod = run("examples/synth/ford_aod_ravigneaux.toml", "aod");
    assert!(aod.iter().any(|c| {
        let s = &c["sets"][0];
        s["basic"] == "12/5" && s["basic2"] == "2" && s["alternatives"].as_u64().unwrap() >= 2
    }));
    for c in lepelletier.iter().chain(&aod) {
        let spec = c["spec"].as_str().unwrap();
        let shift: Value =
            serde_json::from_str(&stdout(&["shift", spec, "--format", "json"])).unwrap();
        assert_gear_ratios(&shift, c);
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// A stepped planet as the unknown: the bundled two-speed's 2263/437 found
/// from 6.178, both steps in the JSON, the candidate's spec confirmed by
/// `egt shift`; a stepped set with no first-step range is refused by field.
#[test]
fn finds_a_stepped_planet_and_its_candidate_passes_egt_shift() {
    let dir = std::env::temp_dir().join(format!("egt-synth-stepped-{}", std::process::id()));
    let out = dir.display().to_string();
    let found = synth(&[
        "synth",
        "examples/synth/stepped_two_speed.toml",
        "--format",
        "json",
        "--write-specs",
        &out,
    ]);
    let best = &found["candidates"][0];
    let set = &best["sets"][0];
    assert_eq!(set["basic"], "2263/437");
    assert_eq!(set["alternatives"], 2);
    let (sun, ring) = (set["sun"].as_i64().unwrap(), set["ring"].as_i64().unwrap());
    let (p1, p2) = (
        set["planet"].as_i64().unwrap(),
        set["planet2"].as_i64().unwrap(),
    );
    assert_eq!(sun + p1, ring - p2, "coaxial");
    assert_eq!(ring * p1 * 437, sun * p2 * 2263);
    let shift: Value = serde_json::from_str(&stdout(&[
        "shift",
        best["spec"].as_str().unwrap(),
        "--format",
        "json",
    ]))
    .unwrap();
    assert_gear_ratios(&shift, best);
    let text = std::fs::read_to_string(root().join("examples/synth/stepped_two_speed.toml"))
        .unwrap()
        .replace("base = \"../", "base = \"examples/")
        .replace(" planet = [14, 34],", "");
    let r = egt(&["synth", "-", "--spec-format", "toml"], Some(&text));
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(r.stderr.contains("sets.S.planet"), "{}", r.stderr);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn partitions_merge_to_the_whole_search() {
    let whole = synth(&[
        "synth",
        "examples/synth/ford_c4_simpson.toml",
        "--format",
        "json",
        "--top",
        "50",
    ]);
    let mut merged: Vec<(f64, Vec<(i64, i64)>)> = Vec::new();
    for i in 0..3 {
        let part = format!("{i}/3");
        let v = synth(&[
            "synth",
            "examples/synth/ford_c4_simpson.toml",
            "--format",
            "json",
            "--top",
            "50",
            "--part",
            &part,
        ]);
        assert_eq!(v["part"], serde_json::json!([i, 3]));
        for c in v["candidates"].as_array().unwrap() {
            merged.push((c["score"].as_f64().unwrap(), teeth(c)));
        }
    }
    merged.sort_by(|a, b| a.0.total_cmp(&b.0).then_with(|| a.1.cmp(&b.1)));
    let whole: Vec<Vec<(i64, i64)>> = whole["candidates"]
        .as_array()
        .unwrap()
        .iter()
        .map(teeth)
        .collect();
    let merged: Vec<Vec<(i64, i64)>> = merged.into_iter().map(|x| x.1).take(whole.len()).collect();
    assert_eq!(whole, merged);
    assert!(!whole.is_empty());
}

#[test]
fn bad_search_specs_are_refused_by_field() {
    let spec = "base = \"examples/zf_8hp70.toml\"\n[sets]\nP9 = { sun = [20, 30], ring = [60, 80] }\n[targets]\nratios = { \"1\" = 4.7 }\n";
    let r = egt(&["synth", "-", "--spec-format", "toml"], Some(spec));
    assert_eq!(r.code, 2, "{}", r.stderr);
    assert!(r.stderr.contains("sets.P9"), "{}", r.stderr);
    let r = egt(&["synth", "-", "--spec-format", "toml"], Some("base = 3\n"));
    assert_eq!(r.code, 2);
    assert!(r.stderr.contains("<stdin>:1:"), "{}", r.stderr);
    let r = egt(
        &["synth", "-", "--spec-format", "toml"],
        Some(&spec.replace("P9", "P1").replace("\"1\"", "\"9\"")),
    );
    assert_eq!(r.code, 2);
    assert!(r.stderr.contains("targets.ratios.9"), "{}", r.stderr);
    let r = egt(
        &[
            "synth",
            "examples/synth/ford_c4_simpson.toml",
            "--part",
            "3/3",
        ],
        None,
    );
    assert_ne!(r.code, 0);
    assert!(r.stderr.contains("partition"), "{}", r.stderr);
}

/// `--stream`: JSON Lines, the best so far after each part (never more than
/// `top`, improving as parts finish), then the whole report, equal to the
/// one-shot JSON; `--tables` gives each candidate's `egt shift` document,
/// whose exact ratios are the candidate's.
#[test]
fn stream_gives_the_best_so_far_then_the_report_with_tables() {
    let text = stdout(&[
        "synth",
        "examples/synth/ford_c4_simpson.toml",
        "--stream",
        "--tables",
    ]);
    let lines: Vec<Value> = text
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let (last, progress) = lines.split_last().unwrap();
    assert!(progress.len() >= 2);
    for (k, p) in progress.iter().enumerate() {
        assert_eq!(p["event"], "progress");
        assert_eq!(p["done"], k + 1);
        assert!(p["best"].as_array().unwrap().len() <= 10);
    }
    assert_eq!(
        progress.last().unwrap()["best"].as_array().unwrap().len(),
        10
    );
    assert_eq!(last["event"], "done");
    let once = synth(&[
        "synth",
        "examples/synth/ford_c4_simpson.toml",
        "--format",
        "json",
    ]);
    let cands = last["candidates"].as_array().unwrap();
    let key = |v: &Value| v.as_array().unwrap().iter().map(teeth).collect::<Vec<_>>();
    assert_eq!(key(&last["candidates"]), key(&once["candidates"]));
    for c in cands {
        assert_gear_ratios(&c["shift"], c);
    }
}

/// Issue 42: a search spec gets a train spec's checks. The base train is
/// checked as `egt check` would (a clutch with no links used to index out of
/// bounds; a brake on three links, on the frame, or a clutch joining a link
/// to itself were searched), every number is range-checked by field (NaN
/// targets, an efficiency above 1, a NaN `ring_sun`, `min_planet = -5`, a
/// range of three, bounds that overflow when subtracted), and a tolerance
/// that prunes nothing is refused at the leaf budget (code `budget`, with
/// the flag that raises it) instead of confirming every leaf.
#[test]
fn search_specs_are_checked_like_train_specs_and_bounded() {
    let search = std::fs::read_to_string(root().join("examples/synth/ford_c4_simpson.toml"))
        .expect("the C4 search")
        .replace("../ford_c4_simpson.toml", "BASE");
    let c4 = std::fs::read_to_string(root().join("examples/ford_c4_simpson.toml")).expect("C4");
    let dir = std::env::temp_dir().join(format!("egt-synth-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let run = |base: &str, search: &str| {
        let path = dir.join("base.toml");
        std::fs::write(&path, base).expect("write base");
        let text = search.replace("BASE", &path.to_string_lossy());
        egt(
            &["synth", "-", "--spec-format", "toml", "--format", "json"],
            Some(&text),
        )
    };
    let refused = |r: &Run, code: &str, path: &str| {
        assert_eq!(r.code, 2, "{path}: {}", r.stderr);
        let e: Value = serde_json::from_str(&r.stdout).expect("a JSON error");
        assert_eq!(e["error"]["code"], code, "{}", r.stdout);
        assert_eq!(e["error"]["path"], path, "{}", r.stdout);
    };
    // The base train, as `egt check` sees it.
    for (from, to, path) in [
        (
            r#"links = ["input", "front_ring"]"#,
            "links = []",
            "base.elements[0].links",
        ),
        (
            r#"links = ["sun"]"#,
            r#"links = ["sun", "input", "output"]"#,
            "base.elements[2].links",
        ),
        (
            r#"links = ["sun"]"#,
            r#"links = ["case"]"#,
            "base.elements[2].links",
        ),
        (
            r#"links = ["input", "sun"]"#,
            r#"links = ["sun", "sun"]"#,
            "base.elements[1].links",
        ),
    ] {
        assert!(c4.contains(from));
        let r = run(&c4.replacen(from, to, 1), &search);
        assert_eq!(r.code, 2, "{to}: {}", r.stderr);
        assert!(
            r.stdout.contains(&format!("\"path\": \"{path}\"")),
            "{to}: {}",
            r.stdout
        );
    }
    // The search's own numbers, by field.
    for (from, to, code, path) in [
        (
            r#""1" = 2.46"#,
            r#""1" = nan"#,
            "invalid",
            "targets.ratios.1",
        ),
        (
            r#""1" = 2.46, "2" = 1.46, "3" = 1.00, "R" = -2.18"#,
            "",
            "invalid",
            "targets.ratios",
        ),
        (
            "[targets]",
            "[targets]\nefficiency = 1.5",
            "invalid",
            "targets.efficiency",
        ),
        (
            "profile_shift = 1 ",
            "ring_sun = [nan, 3]\nprofile_shift = 1 ",
            "invalid",
            "constraints.ring_sun",
        ),
        (
            "profile_shift = 1 ",
            "min_planet = -5\nprofile_shift = 1 ",
            "invalid",
            "constraints.min_planet",
        ),
        (
            "sun = [20, 60], ring",
            "sun = [20, 40, 60], ring",
            "syntax",
            "sets.front.sun",
        ),
        (
            "ring = [50, 110]",
            "ring = [-9223372036854775807, 110]",
            "invalid",
            "sets.front.ring",
        ),
        ("top = 10", "top = 0", "invalid", "top"),
    ] {
        assert!(search.contains(from), "{from}");
        refused(&run(&c4, &search.replacen(from, to, 1)), code, path);
    }
    // A tolerance that prunes nothing: refused at the leaf budget, quickly.
    let loose = search.replace("tolerance = 0.005", "tolerance = 100");
    let r = run(&c4, &format!("max_leaves = 50\n{loose}"));
    assert_eq!(r.code, 1, "{}", r.stderr);
    let e: Value = serde_json::from_str(&r.stdout).expect("a JSON error");
    assert_eq!(e["error"]["code"], "budget", "{}", r.stdout);
    assert!(r.stderr.contains("--max-leaves"), "{}", r.stderr);
    // The flag overrides the spec: the same budget from the command line,
    // and the real search is well within the default.
    let path = dir.join("base.toml");
    let text = loose.replace("BASE", &path.to_string_lossy());
    let r = egt(
        &[
            "synth",
            "-",
            "--spec-format",
            "toml",
            "--format",
            "json",
            "--max-leaves",
            "50",
        ],
        Some(&text),
    );
    assert_eq!(r.code, 1, "{}", r.stderr);
    assert!(run(&c4, &search).code == 0);
    std::fs::remove_dir_all(&dir).ok();
}

/// A `[layout]` that leaves no layout to search exits 2 naming `layout`
/// and why (here the intermediate band moved onto the rear carrier beside
/// the low-reverse band: two friction brakes on one member), instead of
/// reporting "no tooth counts" with exit 0; a brake beside the one-way
/// brake on the rear carrier, the C4's own layout, is searched and found.
#[test]
fn a_layout_that_leaves_nothing_exits_2_and_a_brake_beside_a_one_way_is_found() {
    let search = std::fs::read_to_string(root().join("examples/synth/ford_c4_simpson.toml"))
        .expect("the C4 search")
        .replace(
            "../ford_c4_simpson.toml",
            &root()
                .join("examples/ford_c4_simpson.toml")
                .to_string_lossy(),
        );
    let with =
        |layout: &str| search.replace("[targets]", &format!("[layout]\n{layout}\n\n[targets]"));
    let r = egt(
        &["synth", "-", "--spec-format", "toml", "--format", "json"],
        Some(&with("intermediate_band = [[\"rear_carrier\"]]")),
    );
    assert_eq!(r.code, 2, "{}", r.stderr);
    let e: Value = serde_json::from_str(&r.stdout).expect("a JSON error");
    assert_eq!(e["error"]["path"], "layout", "{}", r.stdout);
    let r = egt(
        &["synth", "-", "--spec-format", "toml", "--format", "json"],
        Some(&with("low_reverse_band = \"any\"\nlow_one_way = \"any\"")),
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    let v: Value = serde_json::from_str(&r.stdout).unwrap();
    let found = v["candidates"].as_array().unwrap().iter().any(|c| {
        teeth(c) == [(33, 72), (33, 72)]
            && c["layout"]
                .as_array()
                .is_some_and(|l| l.iter().all(|x| x.to_string().contains("rear_carrier")))
    });
    assert!(found, "{}", r.stdout);
}

/// A concept search (`[concept]`): the structure, layout and teeth of a
/// transmission from its ratios. Every candidate's written train passes
/// `egt shift` with exactly the reported ratios, and the parts of the
/// structure space merge to the whole search.
#[test]
fn a_concept_search_finds_trains_egt_shift_confirms_and_its_parts_merge() {
    let dir = std::env::temp_dir().join(format!("egt-concept-{}", std::process::id()));
    let dir_s = dir.display().to_string();
    let spec = "examples/synth/concept_ford_c4.toml";
    let v = synth(&["synth", spec, "--format", "json", "--write-specs", &dir_s]);
    let found = v["candidates"].as_array().unwrap();
    // Eight concepts (structure and layout, each once; top = 10) meet the
    // C4's rounded ratios, each listing its other tooth sets.
    assert_eq!(found.len(), 8);
    assert!(v["stats"]["structures"].as_u64().unwrap() > 100);
    assert!(
        !found[0]["concept"]["tooth_options"]
            .as_array()
            .unwrap()
            .is_empty()
    );
    for c in found {
        let concept = &c["concept"];
        assert!(
            concept["shafts"].as_array().unwrap().len() >= 5,
            "{concept}"
        );
        let shift = synth(&["shift", c["spec"].as_str().unwrap(), "--format", "json"]);
        assert_gear_ratios(&shift, c);
    }
    let whole: Vec<Value> = found.iter().map(|c| c["ratios"].clone()).collect();
    let mut parts = Vec::new();
    for i in 0..3 {
        let part = format!("{i}/3");
        let p = synth(&["synth", spec, "--format", "json", "--part", &part]);
        parts.extend(p["candidates"].as_array().unwrap().iter().cloned());
    }
    // The best of the parts' candidates are the whole search's (scores
    // equal, in order).
    let mut scores: Vec<f64> = parts.iter().map(|c| c["score"].as_f64().unwrap()).collect();
    scores.sort_by(f64::total_cmp);
    let want: Vec<f64> = found.iter().map(|c| c["score"].as_f64().unwrap()).collect();
    assert_eq!(&scores[..want.len()], &want[..]);
    assert_eq!(whole.len(), 8);
    // Each concept's tooth options are the same from the parts.
    let concepts = |v: &[Value]| {
        let mut c: Vec<String> = v.iter().map(|c| c["concept"].to_string()).collect();
        c.sort();
        c
    };
    assert_eq!(concepts(&parts), concepts(found));
    // A table names the structure.
    let table = stdout(&["synth", spec]);
    assert!(
        table.contains("concept search over the whole space"),
        "{table}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A concept search's progress counts structures (all 261 of the C4's
/// space at the end) and says the best score so far.
#[test]
fn a_concept_search_reports_structures_done_and_the_best_so_far() {
    let out = egt(
        &["synth", "examples/synth/concept_ford_c4.toml", "--progress"],
        None,
    );
    assert_eq!(out.code, 0, "{}", out.stderr);
    let last = out.stderr.lines().rfind(|l| l.starts_with("progress:"));
    let last = last.unwrap_or_else(|| panic!("no progress line: {}", out.stderr));
    assert!(last.starts_with("progress: 261/261 structures"), "{last}");
    assert!(last.contains("best score 2.87"), "{last}");
    // Run in parts for the line, the best concepts still list their teeth
    // options (added once, after the parts merge).
    let out = egt(
        &[
            "synth",
            "examples/synth/concept_ford_c4.toml",
            "--progress",
            "--format",
            "json",
        ],
        None,
    );
    assert_eq!(out.code, 0, "{}", out.stderr);
    let v: Value = serde_json::from_str(&out.stdout).unwrap();
    let options = v["candidates"][0]["concept"]["tooth_options"].as_array();
    assert_eq!(options.map(Vec::len), Some(17), "{v}");
}

#[test]
fn bad_concept_specs_are_refused_by_field() {
    let bad = |(from, to): (&str, &str), field: &str| {
        let text = std::fs::read_to_string(root().join("examples/synth/concept_ford_c4.toml"))
            .unwrap()
            .replace(from, to);
        let extra = to;
        let out = egt(&["synth", "-", "--spec-format", "toml"], Some(&text));
        assert_eq!(out.code, 2, "{extra}: {}", out.stderr);
        assert!(out.stderr.contains(field), "{extra}: {}", out.stderr);
    };
    bad(("held = [0, 1]", "held = [2, 1]"), "concept.held");
    bad(("input = \"any\"", "input = \"wheel\""), "input");
    bad(
        ("held = [0, 1]", "held = [0, 1]\noptions = 5000"),
        "concept.options",
    );
    let text = std::fs::read_to_string(root().join("examples/synth/concept_ford_c4.toml")).unwrap();
    let r = "\"R\" = [\"reverse_high_clutch\", \"low_reverse_band\"]";
    let changed = text.replace(r, "\"R\" = [\"reverse_high_clutch\"]");
    let out = egt(&["synth", "-", "--spec-format", "toml"], Some(&changed));
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(out.stderr.contains("concept.states.R"), "{}", out.stderr);
    let one = "\"1\" = [\"forward_clutch\", \"low_one_way\"]";
    let changed = text.replace(one, "\"1\" = [\"forward_clutch\", \"band\"]");
    let out = egt(&["synth", "-", "--spec-format", "toml"], Some(&changed));
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(out.stderr.contains("concept.states.1"), "{}", out.stderr);
}

/// The concept search's own budgets: too many structures is refused with
/// the code `budget` naming how to raise it; a structure's tooth search
/// stopped at `max_nodes` is counted in the report's `cut`.
#[test]
fn a_concept_search_is_bounded_and_says_where_it_was_cut() {
    let text = std::fs::read_to_string(root().join("examples/synth/concept_ford_c4.toml")).unwrap();
    let few = text.replace("held = [0, 1]", "held = [0, 1]\nmax_structures = 10");
    let out = egt(&["synth", "-", "--spec-format", "toml"], Some(&few));
    assert_eq!(out.code, 1, "{}", out.stderr);
    assert!(out.stderr.contains("max_structures"), "{}", out.stderr);
    let cut = text.replace("held = [0, 1]", "held = [0, 1]\nmax_nodes = 1");
    let out = egt(
        &["synth", "-", "--spec-format", "toml", "--format", "json"],
        Some(&cut),
    );
    assert_eq!(out.code, 0, "{}", out.stderr);
    let v: Value = serde_json::from_str(&out.stdout).unwrap();
    assert!(v["stats"]["cut"].as_u64().unwrap() > 0, "{}", v["stats"]);
}

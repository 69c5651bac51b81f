//! Fuzz target: a design-search spec (`egt synth`'s parser, validation and a
//! bounded search) over the bundled base train its `base` names (the C4 by
//! default). Any refusal is fine; a panic, an abort, a hang, or a candidate
//! with a non-finite score or ratio is a bug. The harness bounds each run
//! below the CLI's budgets (at most 50 leaves, each range cut to 6 values,
//! two freed elements), so that an execution of the unoptimised build CI
//! runs stays within seconds: with 24 values a Ravigneaux search whose
//! tolerance prunes nothing (13 824 combinations) took 27.9 s there, and
//! with 200 leaves the 6HP26 search at tolerance 1.0005 (every leaf
//! confirmed by an exact analysis, beside the wheel's build) took 12 s.
#![no_main]

use std::sync::LazyLock;

use egt_core::design::{Search, SynthSpec};
use egt_core::{Format, Spec, parse_spec};
use libfuzzer_sys::fuzz_target;

fn base(text: &str, name: &str) -> Spec {
    parse_spec(text, Format::Toml, name).unwrap_or_else(|e| panic!("{name}: {e}"))
}

static C4: LazyLock<Spec> =
    LazyLock::new(|| base(include_str!("../../examples/ford_c4_simpson.toml"), "c4"));
static ZF8: LazyLock<Spec> =
    LazyLock::new(|| base(include_str!("../../examples/zf_8hp70.toml"), "8hp70"));
static AOD: LazyLock<Spec> = LazyLock::new(|| {
    base(
        include_str!("../../examples/ford_aod_ravigneaux.toml"),
        "aod",
    )
});
static ZF6: LazyLock<Spec> = LazyLock::new(|| {
    base(
        include_str!("../../examples/zf_6hp26_lepelletier.toml"),
        "6hp26",
    )
});

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(mut spec) = SynthSpec::from_str(text, Format::sniff(text), "fuzz") else {
        return;
    };
    if spec.layout.len() > 2 {
        return;
    }
    // Each range cut to its first 6 values (a reversed or negative range
    // stays one, and validation refuses it as before).
    let cut = |r: &mut [i64; 2]| r[1] = r[1].min(r[0].saturating_add(5));
    for s in spec.sets.values_mut() {
        cut(&mut s.sun);
        cut(&mut s.ring);
        if let Some(s2) = s.sun2.as_mut() {
            cut(s2);
        }
        if let Some(p) = s.planet.as_mut() {
            cut(p);
        }
    }
    spec.max_leaves = spec.max_leaves.min(50);
    spec.top = spec.top.min(20);
    let base = match spec.base.rsplit('/').next() {
        Some("zf_8hp70.toml") => &*ZF8,
        Some("ford_aod_ravigneaux.toml") => &*AOD,
        Some("zf_6hp26_lepelletier.toml") => &*ZF6,
        _ => &*C4,
    };
    let Ok(search) = Search::new(spec, base.clone()) else {
        return;
    };
    if let Ok((candidates, _)) = search.run() {
        for c in &candidates {
            assert!(c.score.is_finite(), "score {}", c.score);
            assert!(c.ratios.iter().all(|r| r.1.is_finite()), "{:?}", c.ratios);
        }
    }
});

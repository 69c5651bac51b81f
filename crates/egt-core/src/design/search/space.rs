//! The search space: each set's admissible tooth counts (coaxial,
//! non-interference, assembly) grouped by basic ratio: simple,
//! double-pinion, stepped-planet and Ravigneaux sets.

use std::collections::HashMap;

use num_rational::Ratio;
use serde::{Deserialize, Serialize};

use crate::design::spec::{Constraints, SetRange};
use crate::error::DesignError;

/// One way to build a set: sun, ring and planet teeth (and for a Ravigneaux
/// set the large sun and the long pinion; for a double-pinion set the outer
/// pinion; for a stepped set the planet's second step).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Teeth {
    /// Sun (the small, forward sun of a Ravigneaux set).
    pub sun: i64,
    /// Ring.
    pub ring: i64,
    /// Planet meshing the sun (the short pinion of a Ravigneaux set), as the spec's `planet`.
    pub planet: i64,
    /// Large sun of a Ravigneaux set.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sun2: Option<i64>,
    /// Long pinion of a Ravigneaux set (meshing the short pinion, the large
    /// sun and the ring), outer pinion of a double-pinion set, or second step
    /// (meshing the ring) of a stepped planet, as the spec's `planet2`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub planet2: Option<i64>,
}

impl Teeth {
    /// The basic ratio k as (numerator, denominator), unreduced: ring / sun
    /// (the small sun of a Ravigneaux set), or ring planet / (sun planet2)
    /// through a planet with two wheels and one sun (a stepped planet; equal
    /// for the two pinions of a double-pinion set).
    pub fn basic(&self) -> (i64, i64) {
        match (self.sun2, self.planet2) {
            (None, Some(p2)) => (self.ring * self.planet, self.sun * p2),
            _ => (self.ring, self.sun),
        }
    }
}

/// A basic ratio k (ring / sun; ring planet / (sun planet2) for a stepped
/// set), reduced, and every admissible tooth set giving it.
#[derive(Debug, Clone)]
pub(super) struct Basic {
    pub(super) k: f64,
    pub(super) teeth: Vec<Teeth>,
}

/// One searched basic ratio: its distinct values, ascending, and the sign of
/// its Willis row w_s + sign k w_r - (1 + sign k) w_c = 0.
#[derive(Debug, Clone)]
pub(crate) struct Dim {
    pub(crate) ks: Vec<f64>,
    pub(crate) sign: f64,
}
/// Most (sun, ring) pairs one set's ranges may span (each is visited once).
pub const MAX_SET_PAIRS: i64 = 10_000_000;

/// Most equally spaced planets of a searched set.
pub const MAX_PLANETS: i64 = 100;

/// The planet between a sun and a ring on one axis (the coaxial condition,
/// within the profile-shift allowance), if the constraints admit it; the
/// non-interference and assembly tests of `planets` equally spaced copies.
pub(super) fn coaxial_planet(sun: i64, ring: i64, planets: i64, c: &Constraints) -> Option<i64> {
    let diff = ring - sun;
    if diff <= 0 {
        return None;
    }
    let planet = diff / 2;
    if (diff - 2 * planet).abs() > c.profile_shift || planet < c.min_planet {
        return None;
    }
    if c.assembly && (sun + ring) % planets != 0 {
        return None;
    }
    if c.non_interference && planets > 1 {
        let s = (std::f64::consts::PI / planets as f64).sin();
        if (sun + planet) as f64 * s <= (planet + 2) as f64 {
            return None;
        }
    }
    Some(planet)
}

/// The checks every unknown set's ranges share; `bad(field, message)` names the field.
pub(super) fn check_ranges(
    r: &SetRange,
    c: &Constraints,
    bad: &dyn Fn(&str, &str) -> DesignError,
) -> Result<(), DesignError> {
    for (field, range) in [("sun", Some(r.sun)), ("sun2", r.sun2), ("planet", r.planet)] {
        if let Some([lo, hi]) = range
            && (lo < 3 || lo > hi)
        {
            return Err(bad(field, "need 3 <= min <= max"));
        }
    }
    if r.ring[0] < 3 || r.ring[0] > r.ring[1] || r.ring[1] <= r.sun[0] {
        return Err(bad(
            "ring",
            "need 3 <= min <= max and max above the smallest sun",
        ));
    }
    if !(1..=MAX_PLANETS).contains(&r.planets) {
        return Err(bad(
            "planets",
            &format!("need 1 to {MAX_PLANETS} equally spaced planets"),
        ));
    }
    let max = crate::error::MAX_TEETH;
    for (field, range) in [
        ("sun", Some(r.sun)),
        ("ring", Some(r.ring)),
        ("sun2", r.sun2),
        ("planet", r.planet),
    ] {
        if range.is_some_and(|x| x[1] > max) {
            return Err(bad(
                field,
                &format!("tooth counts above {max} are not searched"),
            ));
        }
    }
    // Bounded work per set: every tooth combination of the ranges is visited once.
    // The bounds are 3..=MAX_TEETH here, so a span cannot overflow; i128 keeps
    // the product exact.
    let span = |x: [i64; 2]| i128::from(x[1]) - i128::from(x[0]) + 1;
    // A stepped set also visits every first step and, per one, the second
    // steps the profile-shift allowance admits: past the budget only with
    // them, the planet range is named.
    let pairs = span(r.sun) * span(r.ring) * r.sun2.map_or(1, span);
    let combos = pairs
        * r.planet
            .map_or(1, |p| span(p) * (2 * i128::from(c.profile_shift) + 1));
    if combos > i128::from(MAX_SET_PAIRS) {
        return Err(bad(
            if pairs > i128::from(MAX_SET_PAIRS) {
                "ring"
            } else {
                "planet"
            },
            &format!(
                "{combos} tooth combinations in this set; at most {MAX_SET_PAIRS} are searched per set"
            ),
        ));
    }
    Ok(())
}

/// Admissible tooth triples of one simple set, grouped by reduced ring/sun, sorted by k.
pub(super) fn basics(name: &str, r: &SetRange, c: &Constraints) -> Result<Vec<Basic>, DesignError> {
    by_ratio(name, r, c, &|sun, ring, out| {
        out.extend(
            coaxial_planet(sun, ring, r.planets, c).map(|p| (Ratio::new(ring, sun), p, None)),
        );
    })
}

/// The pinions of a double-pinion set (in modules, equal pinions p): the
/// inner pinion meshes the sun at radius (s + p) / 2, the outer one the ring
/// at (r - p) / 2, and they mesh each other at distance p, which a triangle
/// reaches when r - s <= 4 p; the outer pinion's tip clears the sun and the
/// inner one's the ring when 2 p + 2 <= r - s. The pinions are the smallest
/// count meeting both and `min_planet`; assembly asks (r - s) / planets
/// integer (the double-pinion condition).
pub(super) fn double_pinion_planet(
    sun: i64,
    ring: i64,
    planets: i64,
    c: &Constraints,
) -> Option<i64> {
    let diff = ring - sun;
    let p = c.min_planet.max((diff + 3) / 4);
    if 2 * p + 2 > diff {
        return None;
    }
    if c.assembly && diff % planets != 0 {
        return None;
    }
    Some(p)
}

/// Admissible teeth of one double-pinion set by basic ratio k = ring / sun,
/// as [`basics`] for a simple set; both pinions as `planet` and `planet2`.
pub(super) fn double_pinion_basics(
    name: &str,
    r: &SetRange,
    c: &Constraints,
) -> Result<Vec<Basic>, DesignError> {
    by_ratio(name, r, c, &|sun, ring, out| {
        out.extend(
            double_pinion_planet(sun, ring, r.planets, c)
                .map(|p| (Ratio::new(ring, sun), p, Some(p))),
        );
    })
}

/// Whether `planets` identical stepped planets (first step `planet` on the
/// sun, second step `planet2` on the ring), equally spaced, assemble:
/// (sun planet2 + ring planet) / (planets gcd(planet, planet2)) an integer.
/// Planet j sits 2 pi j / planets on from planet 0; turned by x, it meshes
/// the sun when planet x = (sun + planet) 2 pi j / planets (mod 2 pi), and
/// the ring when planet2 x = (planet2 - ring) 2 pi j / planets (mod 2 pi);
/// one x meets both exactly when this holds (derivation in docs/synth.md).
/// With planet = planet2 it is a simple set's (sun + ring) / planets.
pub(crate) fn stepped_assembles(
    sun: i64,
    ring: i64,
    planet: i64,
    planet2: i64,
    planets: i64,
) -> bool {
    let g = num_integer::Integer::gcd(&planet, &planet2);
    (sun * planet2 + ring * planet) % (planets * g) == 0
}

/// The second steps of a stepped planet on `sun` and `ring` whose first
/// step has `planet` teeth (at least `min_planet`): one module for both meshes, so the coaxial
/// condition sun + planet = ring - planet2 within the profile-shift
/// allowance; `min_planet`, assembly, and neighbouring planets' larger steps
/// clear of each other: (sun + planet) sin(pi / n) > max(planet, planet2) + 2.
pub(super) fn stepped_planet2s(
    sun: i64,
    ring: i64,
    planet: i64,
    planets: i64,
    c: &Constraints,
) -> impl Iterator<Item = i64> + '_ {
    let centre = ring - sun - planet;
    (centre - c.profile_shift..=centre + c.profile_shift).filter(move |&planet2| {
        planet2 >= c.min_planet
            && (!c.assembly || stepped_assembles(sun, ring, planet, planet2, planets))
            && (!c.non_interference
                || planets == 1
                || (sun + planet) as f64 * (std::f64::consts::PI / planets as f64).sin()
                    > (planet.max(planet2) + 2) as f64)
    })
}

/// Admissible teeth of one stepped-planet set (sun, ring, both steps) by
/// basic ratio k = ring planet / (sun planet2), as [`basics`] for a simple set.
pub(super) fn stepped_basics(
    name: &str,
    r: &SetRange,
    c: &Constraints,
) -> Result<Vec<Basic>, DesignError> {
    let bad = |f: &str, m: &str| DesignError::Invalid {
        field: format!("sets.{name}.{f}"),
        message: m.into(),
    };
    let Some(first) = r.planet else {
        return Err(bad(
            "planet",
            "a stepped set needs its first step's range `planet = [min, max]` (the second step follows from the coaxial condition)",
        ));
    };
    by_ratio(name, r, c, &|sun, ring, out| {
        for planet in first[0].max(c.min_planet)..=first[1] {
            for planet2 in stepped_planet2s(sun, ring, planet, r.planets, c) {
                out.push((
                    Ratio::new(ring * planet, sun * planet2),
                    planet,
                    Some(planet2),
                ));
            }
        }
    })
}

/// Every (sun, ring) of the ranges that `planets` gives pinions for (each
/// basic ratio with its pinions), grouped by basic ratio, ascending.
#[allow(clippy::type_complexity)]
fn by_ratio(
    name: &str,
    r: &SetRange,
    c: &Constraints,
    planets: &dyn Fn(i64, i64, &mut Vec<(Ratio<i64>, i64, Option<i64>)>),
) -> Result<Vec<Basic>, DesignError> {
    let bad = |f: &str, m: &str| DesignError::Invalid {
        field: format!("sets.{name}.{f}"),
        message: m.into(),
    };
    check_ranges(r, c, &bad)?;
    let mut map: HashMap<Ratio<i64>, Vec<Teeth>> = HashMap::new();
    let mut found = Vec::new();
    for sun in r.sun[0]..=r.sun[1] {
        for ring in r.ring[0]..=r.ring[1] {
            found.clear();
            planets(sun, ring, &mut found);
            for &(q, planet, planet2) in &found {
                let k = *q.numer() as f64 / *q.denom() as f64;
                if let Some([lo, hi]) = c.ring_sun
                    && (k < lo || k > hi)
                {
                    continue;
                }
                map.entry(q).or_default().push(Teeth {
                    sun,
                    ring,
                    planet,
                    sun2: None,
                    planet2,
                });
            }
        }
    }
    let mut out: Vec<Basic> = map
        .into_iter()
        .map(|(q, mut teeth)| {
            teeth.sort_by_key(|t| (t.sun, t.ring, t.planet));
            Basic {
                k: *q.numer() as f64 / *q.denom() as f64,
                teeth,
            }
        })
        .collect();
    out.sort_by(|a, b| a.k.total_cmp(&b.k));
    if out.is_empty() {
        return Err(bad(
            "sun",
            "no tooth counts in these ranges meet the constraints",
        ));
    }
    Ok(out)
}

/// Admissible teeth of one Ravigneaux set: the two searched dimensions
/// (ring/small sun, ring/large sun: distinct values, ascending) and the teeth
/// of every index pair that teeth can make.
///
/// Geometry (in modules): the long pinion meshes the ring and the large sun
/// on one axis (the coaxial condition, with the allowance, assembly and
/// non-interference of a simple set); the short pinion meshes the small sun
/// and the long pinion: its centre distance to the long pinion reaches it
/// when 2 p_short >= s_large - s_small, and its tip clears the ring when
/// s_small + 2 p_short + 4 <= ring. The short pinion is the smallest count
/// meeting both and `min_planet`; the small sun is smaller than the large.
#[allow(clippy::type_complexity)]
pub(super) fn ravigneaux(
    name: &str,
    r: &SetRange,
    c: &Constraints,
) -> Result<(Vec<f64>, Vec<f64>, HashMap<Vec<usize>, Vec<Teeth>>), DesignError> {
    let bad = |f: &str, m: &str| DesignError::Invalid {
        field: format!("sets.{name}.{f}"),
        message: m.into(),
    };
    check_ranges(r, c, &bad)?;
    let large = r
        .sun2
        .ok_or_else(|| bad("sun2", "a Ravigneaux set needs the large sun's range"))?;
    let mut found: HashMap<(Ratio<i64>, Ratio<i64>), Vec<Teeth>> = HashMap::new();
    for ring in r.ring[0]..=r.ring[1] {
        for sun2 in large[0]..=large[1] {
            let Some(long) = coaxial_planet(sun2, ring, r.planets, c) else {
                continue;
            };
            for sun in r.sun[0]..=r.sun[1].min(sun2 - 1) {
                let short = c.min_planet.max((sun2 - sun + 1) / 2);
                if sun + 2 * short + 4 > ring {
                    continue;
                }
                let k = ring as f64 / sun as f64;
                if let Some([lo, hi]) = c.ring_sun
                    && (k < lo || k > hi)
                {
                    continue;
                }
                found
                    .entry((Ratio::new(ring, sun), Ratio::new(ring, sun2)))
                    .or_default()
                    .push(Teeth {
                        sun,
                        ring,
                        planet: short,
                        sun2: Some(sun2),
                        planet2: Some(long),
                    });
            }
        }
    }
    if found.is_empty() {
        return Err(bad(
            "sun",
            "no tooth counts in these ranges meet the constraints",
        ));
    }
    let sorted = |pick: fn(&(Ratio<i64>, Ratio<i64>)) -> Ratio<i64>| {
        let mut v: Vec<Ratio<i64>> = found.keys().map(pick).collect();
        v.sort();
        v.dedup();
        v
    };
    let (k1, k2) = (sorted(|k| k.0), sorted(|k| k.1));
    let value = |q: &Ratio<i64>| *q.numer() as f64 / *q.denom() as f64;
    let mut teeth = HashMap::new();
    for ((a, b), mut t) in found {
        t.sort_by_key(|t| (t.sun, t.sun2, t.ring));
        let i = k1.binary_search(&a).unwrap_or_default();
        let j = k2.binary_search(&b).unwrap_or_default();
        teeth.insert(vec![i, j], t);
    }
    Ok((
        k1.iter().map(value).collect(),
        k2.iter().map(value).collect(),
        teeth,
    ))
}

/// One unknown set's searched space: its dimensions (one basic ratio, two
/// for a Ravigneaux set) and the admissible teeth of every combination of
/// their indices that teeth make. Listed once per set and kind; a concept
/// search shares it between structures.
#[derive(Debug, Clone)]
pub(crate) struct SetSpace {
    pub(crate) dims: Vec<Dim>,
    pub(crate) teeth: HashMap<Vec<usize>, Vec<Teeth>>,
}

impl SetSpace {
    /// The space of set `name` of `kind` in `range` under `c`.
    pub(crate) fn new(
        name: &str,
        kind: crate::spec::PlanetaryKind,
        range: &SetRange,
        c: &Constraints,
    ) -> Result<SetSpace, DesignError> {
        use crate::spec::PlanetaryKind;
        let one = |b: Vec<Basic>, sign: f64| SetSpace {
            dims: vec![Dim {
                ks: b.iter().map(|x| x.k).collect(),
                sign,
            }],
            teeth: b
                .into_iter()
                .enumerate()
                .map(|(i, x)| (vec![i], x.teeth))
                .collect(),
        };
        let bad = |message: &str| DesignError::Invalid {
            field: format!("sets.{name}.sun2"),
            message: message.into(),
        };
        if range.planet.is_some() && kind != PlanetaryKind::Stepped {
            return Err(DesignError::Invalid {
                field: format!("sets.{name}.planet"),
                message: "only a stepped set's planet has a range; the other kinds' planets follow from sun and ring".into(),
            });
        }
        match kind {
            PlanetaryKind::Simple | PlanetaryKind::DoublePinion if range.sun2.is_some() => {
                Err(bad("a simple or double-pinion set has one sun"))
            }
            PlanetaryKind::Simple => Ok(one(basics(name, range, c)?, 1.0)),
            PlanetaryKind::DoublePinion => Ok(one(double_pinion_basics(name, range, c)?, -1.0)),
            PlanetaryKind::Stepped if range.sun2.is_some() => Err(bad(
                "the search finds stepped sets with a sun and a ring (a stepped set with two suns is analysed with its teeth given)",
            )),
            PlanetaryKind::Stepped => Ok(one(stepped_basics(name, range, c)?, 1.0)),
            PlanetaryKind::Ravigneaux => {
                let (k1, k2, teeth) = ravigneaux(name, range, c)?;
                Ok(SetSpace {
                    dims: vec![Dim { ks: k1, sign: -1.0 }, Dim { ks: k2, sign: 1.0 }],
                    teeth,
                })
            }
        }
    }
}

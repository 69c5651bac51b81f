//! Preparing a search: the [`Search`] and its construction from the spec
//! and the base train.

use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use crate::design::spec::SynthSpec;
use crate::error::DesignError;
use crate::spec::{PlanetaryKind, Spec};

use super::layouts::{Layouts, doubled, layouts};
use super::space::{Dim, SetSpace};
use super::systems::{Rows, Unknown, WillisRow, col, generic, states};

/// A prepared search: the per-set candidate ratios and, per element layout,
/// the per-state systems.
#[derive(Debug, Clone)]
pub struct Search {
    pub(super) spec: SynthSpec,
    pub(super) base: Spec,
    pub(super) set_names: Vec<String>,
    pub(super) dims: Vec<Dim>,
    pub(super) unknowns: Vec<Unknown>,
    pub(super) rows: Rows,
    pub(super) layouts: Layouts,
    /// The layouts searched (one pick per freed element; one empty pick
    /// without `[layout]`).
    pub(super) variants: Vec<Vec<u32>>,
    /// Layouts skipped before the search: an element doubled, a gear state
    /// that is not one DOF, or one whose system is singular for any teeth.
    pub(super) skipped_layouts: u64,
    /// Set by the caller to stop a run early ([`Search::with_cancel`]).
    pub(super) cancel: Option<Arc<AtomicBool>>,
    /// The best scores shared with other searches (a concept search's
    /// structures): leaves that cannot make the top are not confirmed.
    pub(super) incumbent: Option<Arc<super::incumbent::Incumbent>>,
    /// Most nodes one run may visit before it stops and says so
    /// ([`Stats::cut`](super::Stats::cut)); None: no limit.
    pub(super) node_limit: Option<u64>,
    /// A concept search's structure: each layout reports its best teeth
    /// only ([`Search::best_per_layout`]).
    pub(super) per_layout: Option<u64>,
}

impl Search {
    /// Prepare a search: check names against the base train, list each set's
    /// admissible teeth, and build each gear state's system once.
    ///
    /// # Errors
    /// [`DesignError`] naming the offending field, set or state.
    pub fn new(spec: SynthSpec, base: Spec) -> Result<Search, DesignError> {
        Search::build(spec, base, None, None)
    }

    /// [`Search::new`] with each set's ratios listed already (`cache`, by
    /// set name) and, when `variants` is given, those layouts (an option
    /// index per `[layout]` element) searched as they are, unjudged: a
    /// concept search judges its layouts itself.
    pub(crate) fn build(
        spec: SynthSpec,
        base: Spec,
        cache: Option<&std::collections::HashMap<String, SetSpace>>,
        variants: Option<Vec<Vec<u32>>>,
    ) -> Result<Search, DesignError> {
        let tx = base
            .transmission
            .clone()
            .ok_or_else(|| DesignError::Invalid {
                field: "base".into(),
                message: "the base train has no [transmission] section".into(),
            })?;
        check_numbers(&spec)?;
        for s in spec.targets.ratios.keys() {
            if !tx.states.contains_key(s) {
                return Err(DesignError::UnknownState(s.clone()));
            }
        }
        let mut links: Vec<String> = Vec::new();
        // The Willis rows of every set (name, sun, ring, carrier, k, sign):
        // one for a simple, double-pinion or stepped set, two for a Ravigneaux set
        // (small sun, then large sun). Known sets get their k now.
        let mut willis: Vec<WillisRow> = Vec::new();
        for p in &base.planetary {
            let ring = p.ring.clone().ok_or_else(|| DesignError::Invalid {
                field: format!("planetary.{}", p.name),
                message:
                    "synth handles sets with a ring (simple, double-pinion, stepped, Ravigneaux)"
                        .into(),
            })?;
            let k = |z: Option<i64>| match (z, p.teeth.ring) {
                (Some(zs), Some(zr)) => zr as f64 / zs as f64,
                _ => f64::NAN,
            };
            // A stepped planet: k = ring planet / (sun planet2).
            let stepped = match (p.teeth.sun, p.teeth.ring, p.teeth.planet, p.teeth.planet2) {
                (Some(zs), Some(zr), Some(z1), Some(z2)) => (zr * z1) as f64 / (zs * z2) as f64,
                _ => f64::NAN,
            };
            let (s, r, c) = (
                col(&p.sun, &mut links),
                col(&ring, &mut links),
                col(&p.carrier, &mut links),
            );
            match p.kind {
                PlanetaryKind::Simple => {
                    willis.push((p.name.clone(), s, r, c, k(p.teeth.sun), 1.0))
                }
                PlanetaryKind::DoublePinion => {
                    willis.push((p.name.clone(), s, r, c, k(p.teeth.sun), -1.0));
                }
                PlanetaryKind::Stepped => willis.push((p.name.clone(), s, r, c, stepped, 1.0)),
                PlanetaryKind::Ravigneaux => {
                    let large = p.sun2.as_deref().ok_or_else(|| DesignError::Invalid {
                        field: format!("planetary.{}.sun2", p.name),
                        message: "a Ravigneaux set needs its large sun".into(),
                    })?;
                    let s2 = col(large, &mut links);
                    willis.push((p.name.clone(), s, r, c, k(p.teeth.sun), -1.0));
                    willis.push((p.name.clone(), s2, r, c, k(p.teeth.sun2), 1.0));
                }
            }
        }
        let set_names: Vec<String> = spec.sets.keys().cloned().collect();
        // Per Willis row, the searched dimension it carries (if any).
        let mut dim_of: Vec<Option<usize>> = vec![None; willis.len()];
        let mut dims = Vec::new();
        let mut unknowns = Vec::new();
        for (name, range) in &spec.sets {
            let rows: Vec<usize> = (0..willis.len())
                .filter(|&i| &willis[i].0 == name)
                .collect();
            let kind = base
                .planetary
                .iter()
                .find(|p| &p.name == name)
                .map(|p| p.kind);
            let local = match (kind, rows.as_slice()) {
                (None, _) if base.planetary.is_empty() => {
                    return Err(DesignError::Invalid {
                        field: format!("sets.{name}"),
                        message: format!(
                            "the base train declares no planetary sets: synth searches the teeth of sets given as [[planetary]] entries (name, sun, ring, carrier, teeth; kind for a double-pinion, stepped or Ravigneaux set), so write the gear pairs of `{name}` as one, with `name = \"{name}\"`"
                        ),
                    });
                }
                (None, _) => return Err(DesignError::UnknownSet(name.clone())),
                (Some(kind), _)
                    if rows.len()
                        != if kind == PlanetaryKind::Ravigneaux {
                            2
                        } else {
                            1
                        } =>
                {
                    return Err(DesignError::Invalid {
                        field: format!("sets.{name}"),
                        message: "the search finds the teeth of simple, double-pinion, stepped and Ravigneaux sets".into(),
                    });
                }
                (Some(kind), _) => match cache.and_then(|c| c.get(name)) {
                    Some(space) => space.clone(),
                    None => SetSpace::new(name, kind, range, &spec.constraints)?,
                },
            };
            let first = dims.len();
            for (row, dim) in rows.iter().zip(local.dims) {
                dim_of[*row] = Some(dims.len());
                dims.push(dim);
            }
            let unknown = Unknown {
                dims: (first..dims.len()).collect(),
                teeth: local.teeth,
            };
            unknowns.push(unknown);
        }
        for (i, w) in willis.iter().enumerate() {
            if w.4.is_nan() && dim_of[i].is_none() {
                return Err(DesignError::Invalid {
                    field: format!("planetary.{}.teeth", w.0),
                    message: "give sun and ring teeth (and planet and planet2 for a stepped set), or list the set under [sets]".into(),
                });
            }
        }
        let layouts = layouts(&spec, &base, &links)?;
        let rows = Rows {
            tx,
            willis,
            dim_of,
            links,
        };
        let mut search = Search {
            spec,
            base,
            set_names,
            dims,
            unknowns,
            rows,
            layouts,
            variants: Vec::new(),
            skipped_layouts: 0,
            cancel: None,
            incumbent: None,
            node_limit: None,
            per_layout: None,
        };
        search.check_base()?;
        if let Some(v) = variants {
            search.variants = v;
        } else if search.layouts.names.is_empty() {
            // The base layout's errors are the spec's: say them.
            search.states(&[])?;
            search.variants.push(Vec::new());
        } else {
            // Every layout checked in parallel; only the picks that pass are kept.
            use rayon::prelude::*;
            let total = search.layouts.count();
            // Each layout kept, or why not: 0 an element doubled, 1 a gear
            // state that is not one DOF, 2 singular for any teeth.
            let judged: Vec<Result<Vec<u32>, usize>> = (0..total)
                .into_par_iter()
                .map(|i| {
                    let pick = search.layouts.pick(i);
                    let elements = search.elements(&pick);
                    if doubled(&elements) {
                        return Err(0);
                    }
                    let states = states(
                        &elements,
                        &search.base.frame,
                        &search.rows,
                        &search.spec.targets,
                    )
                    .map_err(|_| 1_usize)?;
                    if generic(&states, &search.dims) {
                        Ok(pick)
                    } else {
                        Err(2)
                    }
                })
                .collect();
            let mut why = [0_u64; 3];
            let mut kept = Vec::new();
            for j in judged {
                match j {
                    Ok(pick) => kept.push(pick),
                    Err(k) => why[k] += 1,
                }
            }
            if kept.is_empty() {
                return Err(DesignError::Invalid {
                    field: "layout".into(),
                    message: format!(
                        "no layout of the free elements can be searched: of {total}, {} put two elements of one kind (both friction, or both one-way) on the same links, {} leave a gear state that is not one DOF, {} are singular for any teeth",
                        why[0], why[1], why[2]
                    ),
                });
            }
            search.skipped_layouts = (total - kept.len()) as u64;
            search.variants = kept;
        }
        Ok(search)
    }
}

/// The search spec's numbers that the bound and the confirmation trust: every
/// target finite and non-zero, the ranges' limits positive with min <= max,
/// an efficiency in (0, 1], the constraints' counts in range.
pub(crate) fn check_numbers(spec: &SynthSpec) -> Result<(), DesignError> {
    let bad = |field: String, message: &str| {
        Err(DesignError::Invalid {
            field,
            message: message.into(),
        })
    };
    let t = &spec.targets;
    for (field, v) in [
        ("tolerance", Some(t.tolerance)),
        ("max_element_torque", t.max_element_torque),
        ("max_mesh_torque", t.max_mesh_torque),
    ] {
        if v.is_some_and(|v| !(v > 0.0 && v.is_finite())) {
            return bad(format!("targets.{field}"), "must be a positive number");
        }
    }
    if t.ratios.is_empty() {
        return bad(
            "targets.ratios".into(),
            "give at least one gear state's target ratio",
        );
    }
    for (state, r) in &t.ratios {
        if !(r.is_finite() && *r != 0.0) {
            return bad(
                format!("targets.ratios.{state}"),
                "a ratio target must be a finite, non-zero number",
            );
        }
    }
    if let Some(e) = t.efficiency
        && !(e > 0.0 && e <= 1.0)
    {
        return bad("targets.efficiency".into(), "need 0 < efficiency <= 1");
    }
    let c = &spec.constraints;
    for (field, v) in [
        ("targets.spread", t.spread),
        ("targets.steps", t.steps),
        ("constraints.ring_sun", c.ring_sun),
    ] {
        if let Some([lo, hi]) = v
            && !(lo.is_finite() && hi.is_finite() && 0.0 < lo && lo <= hi)
        {
            return bad(field.into(), "need [min, max] with 0 < min <= max");
        }
    }
    if !(3..=crate::error::MAX_TEETH).contains(&c.min_planet) {
        return bad(
            "constraints.min_planet".into(),
            "need a planet of at least 3 teeth",
        );
    }
    if !(0..=crate::error::MAX_TEETH).contains(&c.profile_shift) {
        return bad(
            "constraints.profile_shift".into(),
            "need an allowance of 0 or more teeth",
        );
    }
    if spec.top == 0 {
        return bad("top".into(), "keep at least one candidate");
    }
    Ok(())
}

impl Search {
    /// The base train as `egt check` sees it (structure, elements, gear
    /// states' names), each searched set given its first admissible teeth;
    /// errors carry the base's field path after `base.`. A searched set
    /// with no admissible teeth is refused here rather than searched empty.
    fn check_base(&self) -> Result<(), DesignError> {
        let mut teeth = Vec::with_capacity(self.unknowns.len());
        for (name, u) in self.set_names.iter().zip(&self.unknowns) {
            let first = u
                .teeth
                .iter()
                .min_by(|a, b| a.0.cmp(b.0))
                .and_then(|(_, t)| t.first());
            let Some(first) = first else {
                return Err(DesignError::Invalid {
                    field: format!("sets.{name}"),
                    message: "no tooth set in these ranges meets the constraints".into(),
                });
            };
            teeth.push(*first);
        }
        crate::model::train::Train::from_spec(&self.candidate_spec(&teeth, &[]))
            .map(drop)
            .map_err(|e| {
                DesignError::Egt(match e {
                    crate::Error::Spec { path, kind } => crate::Error::Spec {
                        path: format!("base.{path}"),
                        kind,
                    },
                    e => e,
                })
            })
    }
}

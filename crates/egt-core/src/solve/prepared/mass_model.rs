//! The mass matrix \[M\] of eq. (3)-(5) as a fill from parameter slices
//! ([`MassModel`]), built once from the eq. (4) offset chains.

use super::*;

/// One link's share of the mass matrix.
#[derive(Debug, Clone)]
pub(super) struct MassEntry {
    /// Its coordinate and its slot among the inertia parameters (own rotation, eq. 3).
    pub(super) spin: Option<(usize, usize)>,
    /// Its slot among the mass parameters and its eq. (4) terms (translation on carriers).
    pub(super) float: Option<(usize, Range<usize>)>,
    pub(super) copies: f64,
}

/// The mass matrix \[M\] (eq. 3-5) prepared for varying inertias and masses.
///
/// Built once from the train's eq. (4) offset chains; [`MassModel::fill`] then
/// writes \[M\] for any inertias and masses into a caller's buffer. With the
/// train's own values it reproduces [`Train::mass_matrix`] exactly.
#[derive(Debug, Clone)]
pub struct MassModel {
    pub(super) n: usize,
    pub(super) entries: Vec<MassEntry>,
    pub(super) terms: Vec<(usize, f64)>,
    pub(super) inertia_links: Vec<LinkId>,
    pub(super) mass_links: Vec<LinkId>,
    notes: Vec<String>,
}

impl MassModel {
    /// Prepare from the train: an inertia slot for every sized moving link, a
    /// mass slot for every link that floats on a moving carrier with known offsets.
    ///
    /// # Errors
    /// As [`Train::mass_matrix`]: a link with a mass whose offsets are unknown,
    /// or an inertia given for a planet whose speed is unknown.
    pub fn new(train: &Train) -> Result<Self> {
        // The offsets, the arms and the errors come from the one definition in mass.rs.
        let (offsets, notes) = train.axis_offsets();
        let offsets = crate::model::mass::offset_index(&offsets);
        let n = train.coordinates().len();
        let mut entries = Vec::new();
        let mut terms = Vec::new();
        let (mut inertia_links, mut mass_links) = (Vec::new(), Vec::new());
        let mut varying = Vec::new();
        for (li, link) in train.links().iter().enumerate() {
            let l = LinkId::from_index(li);
            let Some(c) = train.coordinate(l) else {
                continue;
            };
            let spin = link.sized.then(|| {
                inertia_links.push(l);
                (c, inertia_links.len() - 1)
            });
            let copies = f64::from(link.copies);
            // A satellite's arms add w_k^2 d^2 each; their cross terms cancel
            // over evenly spaced copies or vary with the configuration.
            let arms = match train.floating_terms(l, &offsets) {
                // No mass slot where the arms do not balance: [M] would vary.
                Ok(f) if !f.varying.is_empty() => {
                    if link.mass.is_some_and(|m| m > 0.0) {
                        varying.push(link.name.clone());
                    }
                    Vec::new()
                }
                Ok(f) => f.arms,
                Err(_) => Vec::new(),
            };
            let mut float = None;
            if !arms.is_empty() {
                mass_links.push(l);
                float = Some(mass_links.len() - 1);
            }
            entries.push(MassEntry {
                spin,
                float: float.map(|s| (s, terms.len()..terms.len() + 1)),
                copies,
            });
            if let Some(s) = float {
                terms.push(arms[0]);
                for &arm in &arms[1..] {
                    entries.push(MassEntry {
                        spin: None,
                        float: Some((s, terms.len()..terms.len() + 1)),
                        copies,
                    });
                    terms.push(arm);
                }
            }
        }
        if !varying.is_empty() {
            return Err(AnalysisError::ConfigurationDependent {
                links: varying,
                analysis: "a prepared (batch) train".into(),
            }
            .into());
        }
        // The errors of the one definition: missing offsets, unsized planets.
        train.mass_matrix()?;
        Ok(MassModel {
            n,
            entries,
            terms,
            inertia_links,
            mass_links,
            notes,
        })
    }

    /// A model with no inertia or mass slots, for analyses that are given
    /// their \[M\] whole ([`Scenario::mass_matrix`]) or need none.
    pub fn empty(n: usize) -> Self {
        MassModel {
            n,
            entries: Vec::new(),
            terms: Vec::new(),
            inertia_links: Vec::new(),
            mass_links: Vec::new(),
            notes: Vec::new(),
        }
    }

    /// Order of \[M\] (the number of coordinates).
    pub fn n(&self) -> usize {
        self.n
    }
    /// The links whose inertia [`MassModel::fill`] reads, in slot order.
    pub fn inertia_links(&self) -> &[LinkId] {
        &self.inertia_links
    }
    /// The links whose mass [`MassModel::fill`] reads, in slot order: those
    /// carried on moving carriers (eq. 4).
    pub fn mass_links(&self) -> &[LinkId] {
        &self.mass_links
    }
    /// Notes from [`Train::mass_matrix`] (nested carriers, disagreeing offsets).
    pub fn notes(&self) -> &[String] {
        &self.notes
    }
    /// The train's own inertias and masses, in slot order (0 where not given).
    pub fn train_values(&self, train: &Train) -> (Vec<f64>, Vec<f64>) {
        let value = |v: Option<f64>| v.filter(|&x| x > 0.0).unwrap_or(0.0);
        (
            self.inertia_links
                .iter()
                .map(|&l| value(train.link(l).inertia))
                .collect(),
            self.mass_links
                .iter()
                .map(|&l| value(train.link(l).mass))
                .collect(),
        )
    }

    /// Write \[M\] (row-major, n x n) for one inertia per [`MassModel::inertia_links`]
    /// and one mass per [`MassModel::mass_links`]. Allocates nothing.
    pub fn fill(&self, inertia: &[f64], mass: &[f64], m: &mut [f64]) {
        let n = self.n;
        debug_assert_eq!(m.len(), n * n);
        m.iter_mut().for_each(|v| *v = 0.0);
        self.for_each_term(inertia, mass, |a, b, v| m[a * n + b] += v);
    }

    /// [`MassModel::fill`] as a list of (row, column, value) terms (repeated
    /// positions add), for a sparse workspace. Allocates nothing once `m`
    /// has held a fill.
    pub fn fill_entries(&self, inertia: &[f64], mass: &[f64], m: &mut Vec<(usize, usize, f64)>) {
        m.clear();
        self.for_each_term(inertia, mass, |a, b, v| m.push((a, b, v)));
    }

    /// Every term of \[M\] as (row, column, value), in the one order both
    /// fills add them: each link's own rotation (eq. 3), then its eq. (4)
    /// arms, `(copies m d_a) d_b`.
    #[inline]
    fn for_each_term(&self, inertia: &[f64], mass: &[f64], mut f: impl FnMut(usize, usize, f64)) {
        for e in &self.entries {
            if let Some((c, s)) = e.spin {
                f(c, c, e.copies * inertia[s]);
            }
            if let Some((s, range)) = &e.float {
                let w = e.copies * mass[*s];
                let terms = &self.terms[range.clone()];
                for &(a, da) in terms {
                    for &(b, db) in terms {
                        f(a, b, w * da * db);
                    }
                }
            }
        }
    }
}

impl MassModel {
    /// \[M\] in exact rationals, from exact inertias and masses (the offsets
    /// taken exactly as their f64 values): a reference to verify the float
    /// fill against (the accuracy study in `lab/` does).
    pub fn fill_exact(&self, inertia: &[Q], mass: &[Q]) -> QMatrix {
        let n = self.n;
        let mut m = vec![vec![Q::zero(); n]; n];
        for e in &self.entries {
            let copies = exact_of(e.copies);
            if let Some((c, s)) = e.spin {
                m[c][c] += &copies * &inertia[s];
            }
            if let Some((s, range)) = &e.float {
                let w = &copies * &mass[*s];
                let terms = &self.terms[range.clone()];
                for &(a, da) in terms {
                    for &(b, db) in terms {
                        let (da, db) = (exact_of(da), exact_of(db));
                        m[a][b] += &w * &da * &db;
                    }
                }
            }
        }
        m
    }
}

/// The exact rational value of a finite float (0 for a non-finite one).
pub(crate) fn exact_of(v: f64) -> Q {
    exact::from_f64(v).unwrap_or_else(Q::zero)
}

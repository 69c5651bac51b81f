//! Kinetic energy and the mass matrix (paper section 3, eq. 3-5).
//!
//! Each link contributes its own rotation, I_l w_l^2 / 2 (eq. 3), and, when it
//! floats on carriers, the translation of its centre built from the chain of
//! axis offsets along its path in the turning-pair tree (eq. 4): every link
//! l_t on the path where the level changes from x to y carries the offset
//! delta_xy and adds w_{l_t} x delta_xy to the centre's velocity. Identical
//! satellites count `copies` times. Offsets come from the spec or are derived
//! from the pitch radii of the gears meshing across two levels.
//!
//! The offsets rotate with their carriers: the centre of a link on nested
//! carriers is p = sum_s d_s e^(i theta_s), theta_s the direction of carrier
//! s's arm, so its squared speed has cross terms 2 d_s d_t w_s w_t
//! cos(theta_s - theta_t) (eq. 4 draws the arms aligned, cos = 1). Copies
//! are evenly spaced about the axis of the last carrier: for two or more the
//! cross terms with the last arm cancel exactly (sum_c cos(x + 2 pi c / n) = 0).
//! The remaining cross terms (one satellite, or three or more nested arms)
//! make \[M\] depend on the configuration: they are [`ConfigurationTerm`]s,
//! evaluated at the carrier angles the analysis gives, and they add the
//! velocity-squared torques of [`Train::velocity_torques`] to eq. (6).

use nalgebra::DMatrix;
use serde::Serialize;

use crate::error::{AnalysisError, Result};
use crate::model::train::{LevelId, LinkId, Train, require_dense_links};
use crate::spec::MeshKind;

/// |sum_c e^(i psi_c)| at or below this multiple of the copies counts as
/// balanced (evenly spaced phases given in degrees sum to round-off).
const PHASE_BALANCE: f64 = 1e-12;
/// Relative tolerance for comparing offsets from different sources.
const OFFSET_AGREEMENT: f64 = 1e-9;

/// An axis offset and where it came from.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Offset {
    /// The two levels (lower id first).
    pub levels: [LevelId; 2],
    /// Distance.
    pub distance: f64,
    /// `spec` or the gear pair it was derived from.
    pub source: String,
}

/// A term of \[M\] that varies with the configuration: M_ab = M_ba =
/// coefficient cos(theta_a - theta_b + phase), with theta the direction of a
/// carrier's offset arm.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ConfigurationTerm {
    /// The floating link whose centre couples the two carriers.
    pub link: LinkId,
    /// The two carriers.
    pub carriers: [LinkId; 2],
    /// Their coordinates.
    pub coordinates: [usize; 2],
    /// m d_a d_b (times the copies when neither arm is the last; times
    /// |sum_c e^(i psi_c)| over the copies' phases psi_c when one is).
    pub coefficient: f64,
    /// The phase: minus the argument of sum_c e^(i psi_c) for a term with the
    /// last arm, else 0.
    pub phase: f64,
}

/// The eq. (4) share of a floating link: its offset terms (coordinate of the
/// carrying link, distance) and the cross terms that depend on the configuration.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct FloatingTerms {
    /// (coordinate, d) of every carrier on the path with a level change.
    pub arms: Vec<(usize, f64)>,
    /// Cross terms that do not cancel, per unit mass: (s, t, factor, phase) over `arms`.
    pub varying: Vec<(usize, usize, f64, f64)>,
}

/// The mass matrix over the coordinates (every link but the frame), held
/// sparse: each link adds to the diagonal (eq. 3, and eq. 4 for the arms of
/// a floating link), and only the configuration terms couple two carriers,
/// so a train of any size holds it in memory linear in its links.
///
/// Serialized as `matrix` (rows) for a train within the dense limit
/// ([`MassMatrix::require_dense`]); past it `matrix` is null and `entries`
/// lists the non-zeros.
#[derive(Debug, Clone, PartialEq)]
pub struct MassMatrix {
    /// Order: the number of coordinates.
    n: usize,
    /// The non-zeros (row, column, value) in row-major order, each position
    /// once, both triangles (it is symmetric), at `angles` when it depends on
    /// the configuration.
    entries: Vec<(usize, usize, f64)>,
    /// The terms that vary with the carrier angles (empty for most trains).
    pub configuration: Vec<ConfigurationTerm>,
    /// The carrier angles \[M\] was evaluated at (empty when it does not depend on them).
    pub angles: Vec<(LinkId, f64)>,
    /// The offsets used.
    pub offsets: Vec<Offset>,
    /// Notes: disagreeing offsets, configuration-dependent coupling.
    pub notes: Vec<String>,
}

impl MassMatrix {
    /// The order (number of coordinates).
    pub fn n(&self) -> usize {
        self.n
    }

    /// The non-zeros (row, column, value), row-major, each position once.
    pub fn entries(&self) -> &[(usize, usize, f64)] {
        &self.entries
    }

    /// Entry (r, c) (zero where none is held).
    pub fn get(&self, r: usize, c: usize) -> f64 {
        self.entries
            .binary_search_by(|e| (e.0, e.1).cmp(&(r, c)))
            .map_or(0.0, |k| self.entries[k].2)
    }

    /// Refuse a dense \[M\] past the dense limit of its train (n + 1
    /// links), as [`Train::require_dense`](crate::Train::require_dense) does.
    ///
    /// # Errors
    /// [`AnalysisError::TooLarge`] naming the size and the limit.
    pub fn require_dense(&self) -> Result<()> {
        require_dense_links(self.n + 1, "the dense mass matrix")
    }

    /// \[M\] as a dense matrix, for the analyses that work on it whole
    /// (stability, simulation, shifts).
    ///
    /// # Errors
    /// [`AnalysisError::TooLarge`] past the dense limit
    /// ([`MassMatrix::require_dense`]).
    pub fn matrix(&self) -> Result<DMatrix<f64>> {
        self.require_dense()?;
        let mut m = DMatrix::zeros(self.n, self.n);
        for &(r, c, v) in &self.entries {
            m[(r, c)] = v;
        }
        Ok(m)
    }

    /// \[M\] {x} for a vector over the coordinates.
    pub fn mul_vec(&self, x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; self.n];
        for &(r, c, v) in &self.entries {
            y[r] += v * x[c];
        }
        y
    }
}

impl Serialize for MassMatrix {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::{Error as _, SerializeStruct};
        let dense = self.require_dense().is_ok();
        let mut st = s.serialize_struct("MassMatrix", if dense { 5 } else { 6 })?;
        if dense {
            let m = self.matrix().map_err(S::Error::custom)?;
            st.serialize_field("matrix", &crate::numerics::linalg::matrix_rows(&m))?;
        } else {
            st.serialize_field("matrix", &None::<()>)?;
            st.serialize_field("entries", &self.entries)?;
        }
        st.serialize_field("configuration", &self.configuration)?;
        st.serialize_field("angles", &self.angles)?;
        st.serialize_field("offsets", &self.offsets)?;
        st.serialize_field("notes", &self.notes)?;
        st.end()
    }
}

/// The distance of each level pair's offset (the first listed wins), for
/// lookups by pair in time independent of the number of offsets.
pub(crate) type OffsetIndex = std::collections::HashMap<[LevelId; 2], f64>;

/// [`OffsetIndex`] of `offsets`.
pub(crate) fn offset_index(offsets: &[Offset]) -> OffsetIndex {
    let mut index = OffsetIndex::default();
    for o in offsets {
        index.entry(o.levels).or_insert(o.distance);
    }
    index
}

fn key(a: LevelId, b: LevelId) -> [LevelId; 2] {
    if a < b { [a, b] } else { [b, a] }
}

impl Train {
    /// Offsets between axis levels: those of the spec, plus those derived from
    /// the pitch radii of gears meshing across two levels (r_i + r_j for an
    /// external mesh, |r_i - r_j| for an internal one). Disagreements are noted.
    pub fn axis_offsets(&self) -> (Vec<Offset>, Vec<String>) {
        let mut out: Vec<Offset> = self
            .offsets()
            .iter()
            .map(|&(a, b, d)| Offset {
                levels: key(a, b),
                distance: d,
                source: "spec".into(),
            })
            .collect();
        let mut notes = Vec::new();
        // Where each level pair's offset sits in `out` (the first given wins).
        let mut at: std::collections::HashMap<[LevelId; 2], usize> = Default::default();
        for (k, o) in out.iter().enumerate() {
            at.entry(o.levels).or_insert(k);
        }
        for (c, g) in self.circuits().iter().zip(self.gears()) {
            let Some([ri, rj]) = g.radii else { continue };
            let external = match (g.mesh, &g.ratio) {
                (Some(m), _) => m == MeshKind::External,
                (None, Some(r)) => r.value < 0.0,
                (None, None) => continue,
            };
            let d = if external { ri + rj } else { (ri - rj).abs() };
            let k = key(c.level_i, c.level_j);
            match at.get(&k).map(|&i| &out[i]) {
                Some(o) if (o.distance - d).abs() > OFFSET_AGREEMENT * o.distance.max(d) => notes
                    .push(format!(
                        "offset {}-{}: {} gives {}, but gear pair `{}` radii give {d} (using {})",
                        self.level_name(k[0]),
                        self.level_name(k[1]),
                        o.source,
                        o.distance,
                        g.name,
                        o.distance
                    )),
                Some(_) => {}
                None => {
                    at.insert(k, out.len());
                    out.push(Offset {
                        levels: k,
                        distance: d,
                        source: format!("gear pair `{}`", g.name),
                    });
                }
            }
        }
        (out, notes)
    }

    /// The terms of eq. (4) for a link: (carrying link, level pair) for every
    /// link on its tree path where the level changes.
    pub fn offset_chain(&self, link: LinkId) -> Vec<(LinkId, [LevelId; 2])> {
        let (verts, edges) = self.tree().path_from_root(link);
        let mut terms = Vec::new();
        for t in 1..edges.len() {
            let x = self.revolutes()[edges[t - 1].index()].level;
            let y = self.revolutes()[edges[t].index()].level;
            if x != y {
                terms.push((verts[t], key(x, y)));
            }
        }
        terms
    }

    /// The mass matrix \[M\] of eq. (6) from the links' inertia, mass and copies.
    /// Links without data contribute nothing; a floating link with mass needs
    /// the offsets along its path.
    ///
    /// # Errors
    /// [`AnalysisError::MissingData`] naming a missing offset, or an inertia
    /// given for a planet whose speed is unknown (no tooth count).
    pub fn mass_matrix(&self) -> Result<MassMatrix> {
        let n = self.coordinates().len();
        // The diagonal, added to in link order; the configuration terms are
        // the only entries off it.
        let mut diag = vec![0.0; n];
        let (offsets, notes) = self.axis_offsets();
        let index = offset_index(&offsets);
        let mut configuration = Vec::new();
        for (li, link) in self.links().iter().enumerate() {
            let l = LinkId::from_index(li);
            let Some(c) = self.coordinate(l) else {
                continue;
            };
            let copies = f64::from(link.copies);
            if let Some(i) = link.inertia.filter(|&i| i > 0.0) {
                if !link.sized {
                    return Err(AnalysisError::MissingData {
                        what: format!("the tooth count of planet `{}`", link.name),
                        analysis: "its rotational kinetic energy (it has an inertia)".into(),
                        hint: "give `teeth.planet` in its planetary set".into(),
                    }
                    .into());
                }
                diag[c] += copies * i;
            }
            let Some(mass) = link.mass.filter(|&v| v > 0.0) else {
                continue;
            };
            let f = self.floating_terms(l, &index)?;
            for &(a, d) in &f.arms {
                diag[a] += copies * mass * d * d;
            }
            for &(s, t, factor, phase) in &f.varying {
                let carrier = |k: usize| self.coordinates()[f.arms[k].0];
                configuration.push(ConfigurationTerm {
                    link: l,
                    carriers: [carrier(s), carrier(t)],
                    coordinates: [f.arms[s].0, f.arms[t].0],
                    coefficient: mass * factor,
                    phase,
                });
            }
        }
        let angles = if configuration.is_empty() {
            Vec::new()
        } else {
            self.configuration_angles(&configuration)?
        };
        let angle = |l: LinkId| angles.iter().find(|a| a.0 == l).map_or(0.0, |a| a.1);
        let mut off: std::collections::BTreeMap<(usize, usize), f64> = Default::default();
        for c in &configuration {
            let [a, b] = c.coordinates;
            let v = c.coefficient * (angle(c.carriers[0]) - angle(c.carriers[1]) + c.phase).cos();
            *off.entry((a, b)).or_insert(0.0) += v;
            *off.entry((b, a)).or_insert(0.0) += v;
        }
        // Row-major: the diagonal merged into the off-diagonal entries.
        let mut entries = Vec::with_capacity(n + off.len());
        let mut off = off.into_iter().peekable();
        for (r, &d) in diag.iter().enumerate() {
            while let Some(((i, c), v)) = off.next_if(|e| e.0 < (r, r)) {
                entries.push((i, c, v));
            }
            if d != 0.0 {
                entries.push((r, r, d));
            }
            while let Some(((_, c), v)) = off.next_if(|e| e.0.0 == r) {
                entries.push((r, c, v));
            }
        }
        Ok(MassMatrix {
            n,
            entries,
            configuration,
            angles,
            offsets,
            notes,
        })
    }

    /// The eq. (4) terms of floating link `l`: its arms, and the cross terms
    /// between them that do not cancel over its evenly spaced copies.
    ///
    /// # Errors
    /// [`AnalysisError::MissingData`] naming an offset that is not known.
    pub(crate) fn floating_terms(&self, l: LinkId, offsets: &OffsetIndex) -> Result<FloatingTerms> {
        let link = self.link(l);
        let mut arms = Vec::new();
        for (carrier, lv) in self.offset_chain(l) {
            let d = offsets.get(&lv).copied().ok_or_else(|| {
                AnalysisError::MissingData {
                    what: format!("the offset between axis levels `{}` and `{}`", self.level_name(lv[0]), self.level_name(lv[1])),
                    analysis: format!("the kinetic energy of link `{}` (eq. 4)", link.name),
                    hint: "give [[offsets]] or the pitch radii (radii, or module and teeth) of a gear pair meshing across those levels".into(),
                }
            })?;
            if let Some(k) = self.coordinate(carrier) {
                arms.push((k, d));
            }
        }
        let copies = f64::from(link.copies);
        let last = arms.len().saturating_sub(1);
        // The copies' positions about the last carrier's axis: the cross terms
        // with the last arm sum to Re(S e^(i (theta_last - theta_s))) with
        // S = sum_c e^(i psi_c), zero for evenly spaced copies.
        let (re, im) = match &link.phases {
            Some(p) => p
                .iter()
                .fold((0.0, 0.0), |(a, b), psi| (a + psi.cos(), b + psi.sin())),
            None if link.copies == 1 => (1.0, 0.0),
            None => (0.0, 0.0),
        };
        let spread = re.hypot(im);
        let balanced = spread <= PHASE_BALANCE * copies;
        let mut varying = Vec::new();
        for s in 0..arms.len() {
            for t in s + 1..arms.len() {
                let d = arms[s].1 * arms[t].1;
                if t < last {
                    varying.push((s, t, copies * d, 0.0));
                } else if !balanced {
                    varying.push((s, t, spread * d, -im.atan2(re)));
                }
            }
        }
        Ok(FloatingTerms { arms, varying })
    }

    /// The floating links with a mass whose arms do not balance: \[M\] varies
    /// with the carrier angles because of them (empty for most trains).
    pub fn configuration_links(&self) -> Vec<LinkId> {
        let (offsets, _) = self.axis_offsets();
        let index = offset_index(&offsets);
        (0..self.links().len())
            .map(LinkId::from_index)
            .filter(|&l| self.link(l).mass.is_some_and(|m| m > 0.0))
            .filter(|&l| {
                self.floating_terms(l, &index)
                    .is_ok_and(|f| !f.varying.is_empty())
            })
            .collect()
    }

    /// [M] for an analysis that needs it constant (the reduced model of
    /// stability and simulation).
    ///
    /// # Errors
    /// [`AnalysisError::ConfigurationDependent`] naming the links that make it
    /// vary; the errors of [`Train::mass_matrix`].
    pub(crate) fn constant_mass_matrix(&self, analysis: &str) -> Result<MassMatrix> {
        let varying = self.configuration_links();
        if !varying.is_empty() {
            return Err(AnalysisError::ConfigurationDependent {
                links: varying
                    .iter()
                    .map(|&l| self.link_name(l).to_string())
                    .collect(),
                analysis: analysis.to_string(),
            }
            .into());
        }
        self.mass_matrix()
    }

    /// The carrier angles the configuration terms need, from `[analysis] angles`.
    ///
    /// # Errors
    /// [`AnalysisError::MissingData`] naming the carriers whose angles are needed.
    fn configuration_angles(&self, terms: &[ConfigurationTerm]) -> Result<Vec<(LinkId, f64)>> {
        let mut needed: Vec<LinkId> = Vec::new();
        for t in terms {
            for c in t.carriers {
                if !needed.contains(&c) {
                    needed.push(c);
                }
            }
        }
        let given = &self.analysis().angles;
        let missing: Vec<String> = needed
            .iter()
            .filter(|l| !given.iter().any(|a| a.0 == **l))
            .map(|&l| format!("`{}`", self.link_name(l)))
            .collect();
        if !missing.is_empty() {
            let riders: Vec<String> = terms
                .iter()
                .map(|t| format!("`{}`", self.link_name(t.link)))
                .collect();
            return Err(AnalysisError::MissingData {
                what: format!("the angles of carriers {}", missing.join(", ")),
                analysis: format!(
                    "the mass matrix: {} ride(s) on nested carriers with arms that do not balance, so [M] varies with their relative angle",
                    riders.join(", ")
                ),
                hint: "give [analysis] angles = { <carrier> = <rad>, ... }, the direction of each carrier's offset arm".into(),
            }
            .into());
        }
        Ok(needed
            .iter()
            .map(|&l| (l, given.iter().find(|a| a.0 == l).map_or(0.0, |a| a.1)))
            .collect())
    }

    /// The velocity-squared torques of a configuration-dependent \[M\], one per
    /// coordinate: -(d/dt(M) w - dK/dq) from the Lagrangian (eq. 5), so that
    /// eq. (6) reads M w' + psi^T lambda = Q + these. For a term c cos(theta_a -
    /// theta_b) they are -c sin(theta_a - theta_b) w_b^2 on a and
    /// +c sin(theta_a - theta_b) w_a^2 on b. Zero when \[M\] is constant.
    pub fn velocity_torques(&self, mass: &MassMatrix, speed: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; self.coordinates().len()];
        let angle = |l: LinkId| mass.angles.iter().find(|a| a.0 == l).map_or(0.0, |a| a.1);
        for c in &mass.configuration {
            let [a, b] = c.coordinates;
            let [la, lb] = c.carriers;
            let sine = c.coefficient * (angle(la) - angle(lb) + c.phase).sin();
            out[a] -= sine * speed[lb.index()].powi(2);
            out[b] += sine * speed[la.index()].powi(2);
        }
        out
    }

    /// Kinetic energy K = w^T M w / 2 for link speeds `speed` (one per link).
    pub fn kinetic_energy(&self, mass: &MassMatrix, speed: &[f64]) -> f64 {
        let w: Vec<f64> = self
            .coordinates()
            .iter()
            .map(|l| speed[l.index()])
            .collect();
        let mw = mass.mul_vec(&w);
        0.5 * w.iter().zip(&mw).map(|(a, b)| a * b).sum::<f64>()
    }
}

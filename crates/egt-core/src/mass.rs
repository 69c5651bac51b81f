//! Kinetic energy and the mass matrix (paper section 3, eq. 3-5).
//!
//! Each link contributes its own rotation, I_l w_l^2 / 2 (eq. 3), and, when it
//! floats on carriers, the translation of its centre built from the chain of
//! axis offsets along its path in the turning-pair tree (eq. 4): every link
//! l_t on the path where the level changes from x to y carries the offset
//! delta_xy and adds w_{l_t} x delta_xy to the centre's velocity. Identical
//! satellites count `copies` times. Offsets come from the spec or are derived
//! from the pitch radii of the gears meshing across two levels.

use nalgebra::DMatrix;
use serde::Serialize;

use crate::error::{AnalysisError, Result};
use crate::spec::MeshKind;
use crate::train::{LevelId, LinkId, Train};

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

/// The mass matrix over the coordinates (every link but the frame).
#[derive(Debug, Clone, PartialEq)]
pub struct MassMatrix {
    /// [M], symmetric, `coordinates().len()` square.
    pub matrix: DMatrix<f64>,
    /// The offsets used.
    pub offsets: Vec<Offset>,
    /// Notes: disagreeing offsets, configuration-dependent coupling.
    pub notes: Vec<String>,
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
        for (c, g) in self.circuits().iter().zip(self.gears()) {
            let Some([ri, rj]) = g.radii else { continue };
            let external = match (g.mesh, &g.ratio) {
                (Some(m), _) => m == MeshKind::External,
                (None, Some(r)) => r.value < 0.0,
                (None, None) => continue,
            };
            let d = if external { ri + rj } else { (ri - rj).abs() };
            let k = key(c.level_i, c.level_j);
            match out.iter().find(|o| o.levels == k) {
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
                None => out.push(Offset {
                    levels: k,
                    distance: d,
                    source: format!("gear pair `{}`", g.name),
                }),
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

    /// The mass matrix [M] of eq. (6) from the links' inertia, mass and copies.
    /// Links without data contribute nothing; a floating link with mass needs
    /// the offsets along its path.
    ///
    /// # Errors
    /// [`AnalysisError::MissingData`] naming a missing offset, or an inertia
    /// given for a planet whose speed is unknown (no tooth count).
    pub fn mass_matrix(&self) -> Result<MassMatrix> {
        let n = self.coordinates().len();
        let mut m = DMatrix::zeros(n, n);
        let (offsets, mut notes) = self.axis_offsets();
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
                m[(c, c)] += copies * i;
            }
            let Some(mass) = link.mass.filter(|&v| v > 0.0) else {
                continue;
            };
            let chain = self.offset_chain(l);
            let mut terms: Vec<(usize, f64)> = Vec::with_capacity(chain.len());
            for (carrier, lv) in &chain {
                let d = offsets.iter().find(|o| o.levels == *lv).map(|o| o.distance).ok_or_else(|| {
                    AnalysisError::MissingData {
                        what: format!("the offset between axis levels `{}` and `{}`", self.level_name(lv[0]), self.level_name(lv[1])),
                        analysis: format!("the kinetic energy of link `{}` (eq. 4)", link.name),
                        hint: "give [[offsets]] or the pitch radii (radii, or module and teeth) of a gear pair meshing across those levels".into(),
                    }
                })?;
                if let Some(k) = self.coordinate(*carrier) {
                    terms.push((k, d));
                }
            }
            if terms.len() > 1 {
                notes.push(format!(
                    "link `{}` rides on nested carriers: its coupling terms vary with their relative angle; evaluated with the offsets aligned, as eq. (4) draws them",
                    link.name
                ));
            }
            for &(a, da) in &terms {
                for &(b, db) in &terms {
                    m[(a, b)] += copies * mass * da * db;
                }
            }
        }
        Ok(MassMatrix {
            matrix: m,
            offsets,
            notes,
        })
    }

    /// Kinetic energy K = w^T M w / 2 for link speeds `speed` (one per link).
    pub fn kinetic_energy(&self, mass: &MassMatrix, speed: &[f64]) -> f64 {
        let w: Vec<f64> = self
            .coordinates()
            .iter()
            .map(|l| speed[l.index()])
            .collect();
        let w = nalgebra::DVector::from_vec(w);
        0.5 * w.dot(&(&mass.matrix * &w))
    }
}

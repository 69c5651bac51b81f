//! The lumped torsional model of a train (Kahraman 1994; Lin & Parker 1999):
//! one rotation per link and per planet copy, a spring along the line of
//! action of every mesh, torsional springs, and a gear state's engaged
//! elements as rigid constraint rows or as springs (docs/vibration.md).
//!
//! The deflection of a mesh along its line of action is the base radius of
//! gear i times the Willis row of its circuit (eq. 2),
//! `delta = r_bi (theta_i - tau theta_j + (tau - 1) theta_k)`: zero for every
//! motion that satisfies the Willis equation, so the stiffness matrix's null
//! space is the kinematics.

use nalgebra::DMatrix;
use serde::Serialize;

use crate::analysis::transmission::{element_constraint, state_index};
use crate::error::{AnalysisError, Error, Result, TransmissionError};
use crate::model::train::{
    Compliance, ElementId, GearId, GearPair, LinkId, MeshStiffness, Train, missing_ratio,
};
use crate::solve::rows::Extra;

const ANALYSIS: &str = "the torsional modes (egt modes)";

/// One coordinate of the model: the rotation of a link, or of one copy of a planet.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ModeCoordinate {
    /// The link.
    pub link: LinkId,
    /// The copy (0 for a link without copies).
    pub copy: u32,
    /// `link`, or `link#c` (c from 1) for one copy of a planet with copies.
    pub name: String,
    /// A copy's angular position about its carrier's axis \[degrees\]
    /// (`phases`, else evenly spaced); None for a link without copies. The
    /// purely torsional model does not depend on it.
    pub angle: Option<f64>,
}

/// What an elastic element of the model is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ElasticKind {
    /// A mesh, along its line of action (stiffness in N/m).
    Mesh,
    /// A torsional spring of `[compliance]` (N m/rad).
    Spring,
    /// An engaged shift element given a stiffness (N m/rad).
    Element,
}

/// One spring of the model: strain energy `k (row . theta)^2 / 2`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ElasticElement {
    /// The gear pair, spring or element, with `#c` for a planet copy's mesh.
    pub name: String,
    /// Mesh, spring or element.
    pub kind: ElasticKind,
    /// Stiffness as given (N/m for a mesh, N m/rad otherwise).
    pub stiffness: f64,
    /// Damping as given (N s/m for a mesh, N m s/rad otherwise).
    pub damping: f64,
    /// Its deflection per unit coordinate (m/rad for a mesh, rad/rad otherwise).
    pub row: Vec<f64>,
    /// For a mesh: its gear pair and the base radius of gear i (m), the
    /// lever of the mesh force about gear i's axis.
    #[serde(skip)]
    pub mesh: Option<(GearId, f64)>,
}

/// The model: coordinates, the diagonal mass matrix, springs, constraints.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TorsionalModel {
    /// The coordinates (every moving link; a planet's copies one by one).
    pub coordinates: Vec<ModeCoordinate>,
    /// The diagonal of \[M\] \[kg m^2\]: each link's inertia, a carrier's
    /// with its planets' masses at their offsets (eq. 4).
    pub mass: Vec<f64>,
    /// The springs.
    pub elastic: Vec<ElasticElement>,
    /// The engaged elements that are rigid, by name.
    pub constraint_names: Vec<String>,
    /// Their rows over the coordinates.
    #[serde(skip)]
    pub constraints: DMatrix<f64>,
}

impl TorsionalModel {
    /// The stiffness matrix \[K\] = sum k row row^T.
    pub fn stiffness(&self) -> DMatrix<f64> {
        let n = self.coordinates.len();
        let mut k = DMatrix::zeros(n, n);
        for e in &self.elastic {
            for (a, &ra) in e.row.iter().enumerate().filter(|x| *x.1 != 0.0) {
                for (b, &rb) in e.row.iter().enumerate().filter(|x| *x.1 != 0.0) {
                    k[(a, b)] += e.stiffness * ra * rb;
                }
            }
        }
        k
    }
}

/// Where each link's coordinates start, and how many copies it has.
struct Layout {
    start: Vec<Option<usize>>,
    copies: Vec<u32>,
}

impl Layout {
    /// The coordinate of copy `c` of link `l` (a link without copies has one
    /// for all); None for the frame.
    fn at(&self, l: LinkId, c: u32) -> Option<usize> {
        let s = self.start[l.index()]?;
        Some(if self.copies[l.index()] > 1 {
            s + c as usize
        } else {
            s
        })
    }
}

fn missing(what: String, hint: String) -> Error {
    AnalysisError::MissingData {
        what,
        analysis: ANALYSIS.into(),
        hint,
    }
    .into()
}

/// The gear state's engaged elements, by name (none for the bare train).
fn engaged(train: &Train, state: Option<&str>) -> Result<Vec<ElementId>> {
    let Some(state) = state else {
        return Ok(Vec::new());
    };
    let states = train
        .transmission()
        .map(|t| t.states.as_slice())
        .unwrap_or_default();
    if states.is_empty() {
        return Err(Error::Transmission(TransmissionError::NoStates));
    }
    let s = &states[state_index(states, state)?];
    Ok(s.engaged.clone())
}

impl Train {
    /// The lumped torsional model of this train, bare or in gear state `state`.
    ///
    /// # Errors
    /// [`AnalysisError::MissingData`] naming the gear pairs without a mesh
    /// stiffness, a base radius, a ratio or an inertia; an unknown state;
    /// a planet with copies where the model needs one body (a spring or an
    /// element on it, or a carrier with copies).
    pub fn torsional_model(&self, state: Option<&str>) -> Result<TorsionalModel> {
        self.require_dense(ANALYSIS)?;
        let empty = Compliance::default();
        let compliance = self.compliance().unwrap_or(&empty);
        let unstiff: Vec<String> = self
            .gears()
            .iter()
            .enumerate()
            .filter(|(g, _)| compliance.mesh(GearId::from_index(*g)).is_none())
            .map(|(_, g)| format!("`{}`", g.name))
            .collect();
        if !unstiff.is_empty() {
            let s = if unstiff.len() == 1 { "" } else { "s" };
            return Err(missing(
                format!("the mesh stiffness of gear pair{s} {}", unstiff.join(", ")),
                "give [[compliance.meshes]] with `gear` and `stiffness` [N/m] for each".into(),
            ));
        }
        let elements = engaged(self, state)?;
        let (layout, coordinates, mass) = self.mode_coordinates()?;
        let n = coordinates.len();
        let mut elastic = Vec::new();
        for (c, g) in self.circuits().iter().zip(self.gears()) {
            let m = compliance
                .mesh(c.gear)
                .expect("every gear pair has a stiffness (checked above)");
            let tau = g
                .ratio
                .as_ref()
                .ok_or_else(|| missing_ratio(g, ANALYSIS))?
                .value;
            for l in [c.gear_i, c.gear_j] {
                if !self.link(l).sized {
                    return Err(missing(
                        format!("the tooth count of planet `{}`", self.link_name(l)),
                        "give `teeth.planet` in its planetary set".into(),
                    ));
                }
            }
            let rb = self.base_radius(g, m)?;
            let links = [c.gear_i, c.gear_j, c.carrier];
            let coefficients = [rb, -tau * rb, (tau - 1.0) * rb];
            let many: Vec<u32> = links
                .iter()
                .map(|l| layout.copies[l.index()])
                .filter(|&k| k > 1)
                .collect();
            let copies = many.first().copied().unwrap_or(1);
            if many.iter().any(|&k| k != copies) {
                return Err(Error::invalid(
                    g.path.clone(),
                    format!(
                        "gear pair `{}` joins planets with different numbers of copies ({many:?}): the torsional model pairs them copy by copy",
                        g.name
                    ),
                ));
            }
            for copy in 0..copies {
                let mut row = vec![0.0; n];
                for (&l, &v) in links.iter().zip(&coefficients) {
                    if let Some(k) = layout.at(l, copy) {
                        row[k] += v;
                    }
                }
                elastic.push(ElasticElement {
                    name: copy_name(&g.name, copies, copy),
                    kind: ElasticKind::Mesh,
                    stiffness: m.stiffness,
                    damping: m.damping,
                    row,
                    mesh: Some((c.gear, rb)),
                });
            }
        }
        for s in &compliance.springs {
            let row = self.single_body_row(&layout, n, s.links, &format!("spring `{}`", s.name))?;
            elastic.push(ElasticElement {
                name: s.name.clone(),
                kind: ElasticKind::Spring,
                stiffness: s.stiffness,
                damping: s.damping,
                row,
                mesh: None,
            });
        }
        let mut rows: Vec<Vec<f64>> = Vec::new();
        let mut constraint_names = Vec::new();
        for &e in &elements {
            let el = &self.elements()[e.index()];
            let pair = match element_constraint(el) {
                Extra::Hold(l) => [l, self.frame()],
                Extra::Join(a, b) => [a, b],
            };
            let row = self.single_body_row(&layout, n, pair, &format!("element `{}`", el.name))?;
            match compliance.element(e) {
                Some(k) => elastic.push(ElasticElement {
                    name: el.name.clone(),
                    kind: ElasticKind::Element,
                    stiffness: k.stiffness,
                    damping: k.damping,
                    row,
                    mesh: None,
                }),
                None => {
                    rows.push(row);
                    constraint_names.push(el.name.clone());
                }
            }
        }
        let constraints = DMatrix::from_fn(rows.len(), n, |r, c| rows[r][c]);
        Ok(TorsionalModel {
            coordinates,
            mass,
            elastic,
            constraint_names,
            constraints,
        })
    }

    /// The coordinates (planets' copies expanded) and the diagonal of \[M\].
    fn mode_coordinates(&self) -> Result<(Layout, Vec<ModeCoordinate>, Vec<f64>)> {
        let m = self.mass_matrix()?;
        if let Some(&(r, c, _)) = m.entries().iter().find(|e| e.0 != e.1) {
            return Err(AnalysisError::ConfigurationDependent {
                links: [r, c]
                    .iter()
                    .map(|&k| self.link_name(self.coordinates()[k]).to_string())
                    .collect(),
                analysis: format!("{ANALYSIS}: the model takes a diagonal mass matrix"),
            }
            .into());
        }
        let carriers: Vec<LinkId> = self.circuits().iter().map(|c| c.carrier).collect();
        let mut layout = Layout {
            start: vec![None; self.links().len()],
            copies: vec![1; self.links().len()],
        };
        let mut coordinates = Vec::new();
        let mut mass = Vec::new();
        for (k, &l) in self.coordinates().iter().enumerate() {
            let link = self.link(l);
            if link.copies > 1 && carriers.contains(&l) {
                return Err(Error::invalid(
                    format!("links (`{}`)", link.name),
                    format!(
                        "`{}` has {} copies and carries a mesh: the torsional model expands planets one level deep only",
                        link.name, link.copies
                    ),
                ));
            }
            let j = m.get(k, k) / f64::from(link.copies);
            if j.is_nan() || j <= 0.0 {
                let what = if link.inertia.is_some() {
                    format!("a positive inertia of link `{}`", link.name)
                } else {
                    format!("the inertia of link `{}`", link.name)
                };
                return Err(missing(
                    what,
                    "every link is a degree of freedom of the torsional model: give `inertia` in its [[links]] entry".into(),
                ));
            }
            layout.start[l.index()] = Some(coordinates.len());
            layout.copies[l.index()] = link.copies;
            for copy in 0..link.copies {
                coordinates.push(ModeCoordinate {
                    link: l,
                    copy,
                    name: copy_name(&link.name, link.copies, copy),
                    angle: (link.copies > 1).then(|| match &link.phases {
                        Some(p) => p[copy as usize].to_degrees(),
                        None => 360.0 * f64::from(copy) / f64::from(link.copies),
                    }),
                });
                mass.push(j);
            }
        }
        Ok((layout, coordinates, mass))
    }

    /// The base radius of gear i of `g`: given, else its pitch radius times
    /// the cosine of the pressure angle.
    fn base_radius(&self, g: &GearPair, m: &MeshStiffness) -> Result<f64> {
        if let Some([rb, _]) = m.base_radii {
            return Ok(rb);
        }
        g.radii
            .map(|[r, _]| r * m.pressure_angle.cos())
            .ok_or_else(|| {
                missing(
                    format!("the base radius of gear pair `{}`", g.name),
                    format!(
                        "give `module` (with `teeth`) or `radii` at {}, or `base_radii` at {}",
                        g.path, m.path
                    ),
                )
            })
    }

    /// The row `theta_a - theta_b` of a spring or element between two
    /// single bodies (the frame has no coordinate).
    fn single_body_row(
        &self,
        layout: &Layout,
        n: usize,
        [a, b]: [LinkId; 2],
        what: &str,
    ) -> Result<Vec<f64>> {
        let mut row = vec![0.0; n];
        for (l, sign) in [(a, 1.0), (b, -1.0)] {
            if layout.copies[l.index()] > 1 {
                return Err(Error::invalid(
                    "compliance",
                    format!(
                        "{what} acts on `{}`, which stands for {} planets: the torsional model needs one body there",
                        self.link_name(l),
                        layout.copies[l.index()]
                    ),
                ));
            }
            if let Some(k) = layout.at(l, 0) {
                row[k] += sign;
            }
        }
        Ok(row)
    }
}

fn copy_name(name: &str, copies: u32, copy: u32) -> String {
    if copies > 1 {
        format!("{name}#{}", copy + 1)
    } else {
        name.to_string()
    }
}

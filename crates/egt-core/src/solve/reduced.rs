//! The reduced model of eq. (19)-(27): F independent driving links, \[V\]
//! of eq. (23) giving every link speed from theirs (w = V w_d), and
//! \[psi_w\]\[V\] = 0 (eq. 24) removing the Willis multipliers from eq. (6)
//! once it is premultiplied by V^T:
//!
//!   V^T M V w_d' = V^T T(V w_d)                                  (eq. 12, 25)
//!
//! with the linearised torque-speed curves T_l = T0_l + K_l (w_l - w0_l)
//! (eq. 13-15). Stability (`analysis::stability`, the eigenproblem of this
//! model) and forward simulation (`motion::simulate`, its time integration)
//! both start from it, so it lives in the layer below both. The paper's
//! eq. (26) is corrected to \[K\] = V^T diag(K_l) V (`docs/errata.md`).

use nalgebra::{DMatrix, DVector, SymmetricEigen};
use serde::Serialize;

use crate::error::{AnalysisError, Error, Result, SpecErrorKind};
use crate::model::train::{Curve, LinkId, Train};
use crate::numerics::exact::{self, Q};
use crate::numerics::linalg::{COND_WARN, Lu};
use crate::solve::kinematics::SpeedInput;
use num_traits::Zero;

/// Largest relative ||psi_w V|| (eq. 24) accepted without a warning.
pub const ORTHOGONALITY_TOL: f64 = 1e-10;
/// A direction of the reduced mass matrix whose inertia is below this
/// fraction of the largest is massless: indistinguishable from the rounding
/// of V^T M V, so it is treated as exactly zero (an algebraic equation).
pub const MASSLESS_REL: f64 = 1e-12;
/// Below this fraction of the largest inertia (but above [`MASSLESS_REL`]) a
/// direction is nearly massless: kept, but reported, since it makes the model stiff.
pub const NEARLY_MASSLESS_REL: f64 = 1e-8;

/// Smallest relative residual of a row of the null-space basis for a link to
/// be picked as an independent driving coordinate.
const SELECT_REL: f64 = 1e-6;

/// Largest degree of freedom for which the signs of the eigenvalues are
/// decided exactly.
pub const EXACT_INERTIA_MAX_DOF: usize = 16;

/// How the driving coordinates were chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum CoordinateSource {
    /// Given by the caller.
    Given,
    /// The links of the spec's `[analysis] speeds` (F of them).
    SpecSpeeds,
    /// Picked for conditioning, preferring the spec's driving links, then
    /// links carrying a curve.
    Automatic,
}

/// The reduced model of eq. (23)-(27) for one choice of driving links.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReducedModel {
    /// The F driving links (columns of \[V\]).
    pub coordinates: Vec<LinkId>,
    /// Where they came from.
    pub source: CoordinateSource,
    /// \[V\] (eq. 23) by link: row `LinkId::index()`, the frame's row zero.
    #[serde(serialize_with = "crate::numerics::linalg::serde_rows")]
    pub velocity: DMatrix<f64>,
    /// 1-norm condition estimate of \[Gamma_w\] (eq. 22-23).
    pub gamma_condition: f64,
    /// max |psi_w V| / (max |psi_w| max |V|): eq. (24), zero in exact arithmetic.
    pub orthogonality: f64,
    /// The full mass matrix \[M\] over `Train::coordinates()` (eq. 3-6).
    #[serde(serialize_with = "crate::numerics::linalg::serde_rows")]
    pub full_mass: DMatrix<f64>,
    /// Reduced mass matrix V^T M V (eq. 25).
    #[serde(serialize_with = "crate::numerics::linalg::serde_rows")]
    pub mass: DMatrix<f64>,
    /// Reduced slope matrix V^T diag(K) V (eq. 26-27, corrected).
    #[serde(serialize_with = "crate::numerics::linalg::serde_rows")]
    pub slope: DMatrix<f64>,
    /// An orthonormal basis N of the motions the Willis equations allow, by
    /// link (psi_w N = 0, N^T N = 1): \[V\] = N N_S^-1, with N_S the rows of the
    /// driving links. The eigenproblem and the simulation use it, so their
    /// conditioning does not depend on which links drive.
    #[serde(skip)]
    pub basis: DMatrix<f64>,
    /// N^T M N: the mass matrix in the basis.
    #[serde(skip)]
    pub basis_mass: DMatrix<f64>,
    /// N^T diag(K) N: the slope matrix in the basis.
    #[serde(skip)]
    pub basis_slope: DMatrix<f64>,
    /// K_l per link (sum of the slopes of the curves on it).
    pub link_slope: Vec<f64>,
    /// T0_l - K_l w0_l per link, so that T_l(w) = offset_l + K_l w_l.
    pub link_offset: Vec<f64>,
    /// True for links carrying at least one curve.
    pub has_curve: Vec<bool>,
    /// The signs of the eigenvalues of N^T diag(K) N, decided in exact
    /// rational arithmetic from the ratios and slopes as given (None past
    /// [`EXACT_INERTIA_MAX_DOF`] degrees of freedom). With \[M\] positive
    /// (semi)definite, Sylvester's law of inertia makes them the signs of the
    /// eigenvalues of the pencil (lambda \[M\] - \[K\]): the verdict does not
    /// depend on the inertias, however badly scaled they are.
    pub slope_inertia: Option<exact::Inertia>,
    /// Link names (by link index), for messages.
    #[serde(skip)]
    pub link_names: Vec<String>,
    /// Warnings (conditioning, curves on the frame, mass-matrix notes).
    pub warnings: Vec<String>,
}

/// [M] = Q diag(mu) Q^T split into directions with inertia (first `r`
/// columns of `q`, inertias `mu`) and massless ones (the rest).
#[derive(Debug, Clone)]
pub(crate) struct InertiaSplit {
    pub q: DMatrix<f64>,
    pub mu: Vec<f64>,
    pub r: usize,
    pub nearly_massless: bool,
}

impl InertiaSplit {
    /// Split a reduced mass matrix.
    pub(crate) fn new(m: &DMatrix<f64>) -> Result<Self> {
        let f = m.nrows();
        if m.iter().any(|v| !v.is_finite()) {
            return Err(AnalysisError::NonFinite {
                what: "the reduced mass matrix".into(),
                detail: "an inertia or mass overflows".into(),
            }
            .into());
        }
        let eig = SymmetricEigen::new(m.clone());
        let mut order: Vec<usize> = (0..f).collect();
        order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
        let top = order.first().map_or(0.0, |&i| eig.eigenvalues[i]);
        if top <= 0.0 {
            return Err(AnalysisError::MissingData {
                what: "an inertia or mass on a moving link".into(),
                analysis: "the dynamics (the reduced mass matrix V^T M V is zero)".into(),
                hint: "give `inertia` (and `mass` for floating links) in [[links]]".into(),
            }
            .into());
        }
        let low = eig.eigenvalues[order[f - 1]];
        if low < -MASSLESS_REL * top {
            return Err(AnalysisError::IndefiniteMass { low, top }.into());
        }
        let mut q = DMatrix::zeros(f, f);
        let mut mu = Vec::new();
        for (c, &i) in order.iter().enumerate() {
            q.set_column(c, &eig.eigenvectors.column(i));
            if eig.eigenvalues[i] > MASSLESS_REL * top {
                mu.push(eig.eigenvalues[i]);
            }
        }
        let r = mu.len();
        let nearly_massless = mu.iter().any(|&v| v < NEARLY_MASSLESS_REL * top);
        Ok(InertiaSplit {
            q,
            mu,
            r,
            nearly_massless,
        })
    }

    /// Directions with inertia (F x r).
    pub(crate) fn q1(&self) -> DMatrix<f64> {
        self.q.columns(0, self.r).into_owned()
    }
    /// Massless directions (F x (F - r)).
    pub(crate) fn q0(&self) -> DMatrix<f64> {
        let f = self.q.ncols();
        self.q.columns(self.r, f - self.r).into_owned()
    }
}

/// A number for messages: 6 decimals for ordinary magnitudes, else scientific.
pub(crate) fn num(v: f64) -> String {
    if v != 0.0 && !(1e-3..1e6).contains(&v.abs()) {
        return format!("{v:.4e}");
    }
    let s = format!("{v:.6}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

pub(crate) fn sym(a: &DMatrix<f64>) -> DMatrix<f64> {
    (a + a.transpose()) * 0.5
}

/// A^T diag(k) A = sum_l k_l a_l a_l^T over the rows a_l of `a`, formed so
/// that it is exactly symmetric (eq. 26-27 corrected).
pub(crate) fn slope_matrix(a: &DMatrix<f64>, k: &[f64]) -> DMatrix<f64> {
    let f = a.ncols();
    let mut s = DMatrix::zeros(f, f);
    for (l, &kl) in k.iter().enumerate() {
        if kl == 0.0 {
            continue;
        }
        for i in 0..f {
            for j in 0..f {
                s[(i, j)] += kl * (a[(l, i)] * a[(l, j)]);
            }
        }
    }
    s
}

impl Train {
    /// The F driving links for the reduced model: `given`, else the links of
    /// the spec's `[analysis] speeds` when there are F of them, else a
    /// well-conditioned choice preferring the spec's `driving` links, then
    /// links carrying a curve, then the rest in link order.
    ///
    /// # Errors
    /// Missing ratios.
    pub fn driving_coordinates(
        &self,
        given: Option<&[LinkId]>,
    ) -> Result<(Vec<LinkId>, CoordinateSource)> {
        if let Some(g) = given {
            return Ok((g.to_vec(), CoordinateSource::Given));
        }
        let f = self.dof();
        let speeds: Vec<LinkId> = self.analysis().speeds.iter().map(|s| s.0).collect();
        let distinct = speeds
            .iter()
            .enumerate()
            .all(|(i, l)| !speeds[..i].contains(l) && *l != self.frame());
        if speeds.len() == f && distinct {
            return Ok((speeds, CoordinateSource::SpecSpeeds));
        }
        Ok((self.automatic_coordinates()?, CoordinateSource::Automatic))
    }

    /// F driving links picked greedily for a well-conditioned \[Gamma_w\] (the
    /// largest residual of their rows of the null-space basis), preferring
    /// the spec's `driving` links, then links carrying a curve.
    ///
    /// # Errors
    /// Missing ratios; Willis equations that lose rank.
    pub fn automatic_coordinates(&self) -> Result<Vec<LinkId>> {
        let f = self.dof();
        let basis = self.null_basis()?;
        let n = self.coordinates().len();
        let scale = (0..n)
            .map(|i| basis.row(i).norm())
            .fold(0.0, f64::max)
            .max(f64::MIN_POSITIVE);
        let mut tiers: Vec<Vec<LinkId>> = vec![
            self.analysis().driving.clone(),
            self.analysis().curves.iter().map(|c| c.link).collect(),
            self.coordinates().to_vec(),
        ];
        for t in &mut tiers {
            t.retain(|&l| l != self.frame());
        }
        let mut chosen: Vec<LinkId> = Vec::new();
        let mut ortho: Vec<DVector<f64>> = Vec::new();
        for tier in &tiers {
            while chosen.len() < f {
                let mut best: Option<(f64, LinkId, DVector<f64>)> = None;
                for &l in tier {
                    if chosen.contains(&l) {
                        continue;
                    }
                    let Some(k) = self.coordinate(l) else {
                        continue;
                    };
                    let mut r: DVector<f64> = basis.row(k).transpose();
                    for b in &ortho {
                        let d = r.dot(b);
                        r -= b * d;
                    }
                    let norm = r.norm() / scale;
                    if best.as_ref().is_none_or(|(bn, _, _)| norm > *bn) {
                        best = Some((norm, l, r));
                    }
                }
                match best {
                    Some((norm, l, r)) if norm > SELECT_REL => {
                        ortho.push(r.normalize());
                        chosen.push(l);
                    }
                    _ => break,
                }
            }
        }
        if chosen.len() < f {
            return Err(AnalysisError::Singular {
                what: "the Willis equations".into(),
                detail: format!("no {f} links are independent (only {} found)", chosen.len()),
            }
            .into());
        }
        Ok(chosen)
    }

    /// An orthonormal basis N (`coordinates()` x F) of the null space of
    /// \[psi_w\]: every motion the Willis equations allow is w = N u (eq. 24
    /// holds with N for \[V\]). The last F columns of the Householder QR of
    /// [psi_w^T | 0].
    ///
    /// # Errors
    /// Missing ratios; [`AnalysisError::Singular`] when the Willis equations
    /// lose rank at these ratios.
    pub fn null_basis(&self) -> Result<DMatrix<f64>> {
        let psi = self.willis_jacobian()?;
        let (jg, n) = psi.shape();
        let f = self.dof();
        if n != jg + f {
            return Err(AnalysisError::Singular {
                what: "the Willis equations".into(),
                detail: format!("{jg} equations on {n} speeds do not leave {f} degrees of freedom"),
            }
            .into());
        }
        let mut a = DMatrix::zeros(n, n);
        a.view_mut((0, 0), (n, jg)).copy_from(&psi.transpose());
        let q = a.qr().q();
        let basis = q.columns(jg, f).into_owned();
        let res = (&psi * &basis).amax() / psi.amax().max(f64::MIN_POSITIVE);
        // NaN fails too.
        if res.is_nan() || res > ORTHOGONALITY_TOL {
            return Err(AnalysisError::Singular {
                what: "the Willis equations".into(),
                detail: format!(
                    "they lose rank at these ratios (null-space residual {res:.2e}): the train gains a degree of freedom"
                ),
            }
            .into());
        }
        Ok(basis)
    }

    /// The exact inertia of N^T diag(K) N for any exact basis N of the
    /// motions the Willis equations allow (congruence leaves it unchanged):
    /// the ratios and slopes are taken as the exact values of the numbers given.
    fn exact_slope_inertia(&self, link_slope: &[f64]) -> Option<exact::Inertia> {
        if self.dof() > EXACT_INERTIA_MAX_DOF {
            return None;
        }
        let taus: Vec<Q> = self
            .gears()
            .iter()
            .map(|g| {
                let r = g.ratio.as_ref()?;
                r.exact.clone().or_else(|| exact::from_f64(r.value))
            })
            .collect::<Option<_>>()?;
        let n = self.coordinates().len();
        let psi = crate::model::topology::willis_exact(
            self.links().len(),
            self.frame(),
            self.circuits(),
            |m| taus[m].clone(),
        );
        let basis = exact::nullspace(&psi, n);
        let slopes: Vec<Q> = self
            .coordinates()
            .iter()
            .map(|l| exact::from_f64(link_slope[l.index()]))
            .collect::<Option<_>>()?;
        let k: exact::QMatrix = basis
            .iter()
            .map(|a| {
                basis
                    .iter()
                    .map(|b| {
                        (0..n)
                            .filter(|&c| !slopes[c].is_zero())
                            .map(|c| &a[c] * &b[c] * &slopes[c])
                            .sum()
                    })
                    .collect()
            })
            .collect();
        Some(exact::symmetric_inertia(&k))
    }

    /// The reduced model (eq. 23-27) for the driving links `coordinates` and
    /// the linearised torque-speed `curves` on any links.
    ///
    /// # Errors
    /// As [`Train::velocity_matrix`] (wrong count, links that do not determine
    /// the train, [`AnalysisError::IllConditioned`] past [`COND_REFUSE`](crate::numerics::linalg::COND_REFUSE)) and
    /// [`Train::mass_matrix`]; a non-finite curve.
    pub fn reduced_model(&self, coordinates: &[LinkId], curves: &[Curve]) -> Result<ReducedModel> {
        self.reduced_model_from(coordinates, CoordinateSource::Given, curves)
    }

    pub(crate) fn reduced_model_from(
        &self,
        coordinates: &[LinkId],
        source: CoordinateSource,
        curves: &[Curve],
    ) -> Result<ReducedModel> {
        let nl = self.links().len();
        let mut warnings = Vec::new();
        let mut link_slope = vec![0.0; nl];
        let mut link_offset = vec![0.0; nl];
        let mut has_curve = vec![false; nl];
        for c in curves {
            let name = self.link_name(c.link);
            for (what, v) in [("torque", c.torque), ("slope", c.slope), ("speed", c.speed)] {
                if !v.is_finite() {
                    return Err(Error::spec(
                        format!("curve on `{name}`: {what}"),
                        SpecErrorKind::NonFinite { value: v },
                    ));
                }
            }
            if c.link == self.frame() {
                warnings.push(format!(
                    "a curve acts on the frame `{name}`: it does no work and is ignored"
                ));
                continue;
            }
            link_slope[c.link.index()] += c.slope;
            link_offset[c.link.index()] += c.torque - c.slope * c.speed;
            has_curve[c.link.index()] = true;
        }
        if coordinates.len() != self.dof() {
            return Err(AnalysisError::WrongInputCount {
                dof: self.dof(),
                given: coordinates.len(),
                what: "driving links".into(),
            }
            .into());
        }
        let (v, gamma_condition) = self.velocity_matrix_cond(coordinates, &[])?;
        if gamma_condition > COND_WARN {
            warnings.push(format!(
                "[Gamma_w] (eq. 23) with driving links {} is ill-conditioned (condition {gamma_condition:.2e}): expect about {:.0} correct digits in [V], [M] and [K]",
                self.names(coordinates),
                (16.0 - gamma_condition.log10()).max(0.0)
            ));
        }
        let f = coordinates.len();
        let mut velocity = DMatrix::zeros(nl, f);
        for (k, l) in self.coordinates().iter().enumerate() {
            velocity.set_row(l.index(), &v.row(k));
        }
        let psi = self.willis_jacobian()?;
        let orthogonality = (&psi * &v).amax() / (psi.amax() * v.amax()).max(f64::MIN_POSITIVE);
        if orthogonality > ORTHOGONALITY_TOL {
            warnings.push(format!(
                "the orthogonality [psi_w][V] = 0 (eq. 24) holds only to {orthogonality:.2e}"
            ));
        }
        let mm =
            self.constant_mass_matrix("the reduced model of stability and simulation (eq. 23-27)")?;
        warnings.extend(mm.notes.iter().cloned());
        let full_mass = mm.matrix()?;
        let mass = sym(&(v.transpose() * &full_mass * &v));
        let slope = slope_matrix(&velocity, &link_slope);
        let nb = self.null_basis()?;
        let mut basis = DMatrix::zeros(nl, f);
        for (k, l) in self.coordinates().iter().enumerate() {
            basis.set_row(l.index(), &nb.row(k));
        }
        let basis_mass = sym(&(nb.transpose() * &full_mass * &nb));
        let basis_slope = slope_matrix(&basis, &link_slope);
        let slope_inertia = self.exact_slope_inertia(&link_slope);
        Ok(ReducedModel {
            coordinates: coordinates.to_vec(),
            source,
            velocity,
            gamma_condition,
            orthogonality,
            full_mass,
            mass,
            slope,
            basis,
            basis_mass,
            basis_slope,
            link_slope,
            link_offset,
            has_curve,
            slope_inertia,
            link_names: self.links().iter().map(|l| l.name.clone()).collect(),
            warnings,
        })
    }

    /// Link names as `` `a`, `b` ``.
    pub(crate) fn names(&self, links: &[LinkId]) -> String {
        links
            .iter()
            .map(|&l| format!("`{}`", self.link_name(l)))
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// Every link's speed from F input speeds (as [`Train::kinematics`]).
    ///
    /// # Errors
    /// As [`Train::kinematics`].
    pub(crate) fn speeds_from(&self, inputs: &[(LinkId, f64)]) -> Result<Vec<f64>> {
        let ins: Vec<SpeedInput> = inputs.iter().map(|&i| SpeedInput::from(i)).collect();
        Ok(self.kinematics(&ins)?.speed)
    }
}

impl ReducedModel {
    /// Number of driving coordinates F.
    pub fn dof(&self) -> usize {
        self.coordinates.len()
    }

    /// Applied torque of the curves on every link at link speeds `speed`.
    pub fn torques(&self, speed: &[f64]) -> Vec<f64> {
        speed
            .iter()
            .enumerate()
            .map(|(l, w)| {
                if self.has_curve[l] {
                    self.link_offset[l] + self.link_slope[l] * w
                } else {
                    0.0
                }
            })
            .collect()
    }

    /// Link speeds w = V x for driving speeds `x`.
    pub fn link_speeds(&self, x: &[f64]) -> Vec<f64> {
        (&self.velocity * DVector::from_column_slice(x))
            .iter()
            .copied()
            .collect()
    }

    /// The equilibrium of the linearised curves, \[K\] x = -V^T offset, as link
    /// speeds, with the condition estimate of \[K\].
    ///
    /// # Errors
    /// [`AnalysisError::Singular`] / [`AnalysisError::IllConditioned`] when \[K\]
    /// is (nearly) singular: no unique equilibrium.
    pub fn equilibrium(&self) -> Result<(Vec<f64>, f64)> {
        let f = self.dof();
        let mut lu = Lu::new(f);
        {
            let a = lu.matrix_mut();
            for i in 0..f {
                for j in 0..f {
                    a[i * f + j] = self.basis_slope[(i, j)];
                }
            }
        }
        let cond = lu.factor_checked(
            "the reduced slope matrix [K] (equilibrium)",
            "the curves do not fix a unique steady state",
        )?;
        let mut b: Vec<f64> = self
            .basis
            .tr_mul(&DVector::from_column_slice(&self.link_offset))
            .iter()
            .map(|v| -v)
            .collect();
        lu.solve(&mut b);
        let w = (&self.basis * DVector::from_vec(b))
            .iter()
            .copied()
            .collect();
        Ok((w, cond))
    }

    /// Link speeds N u for coordinates `u` in the orthonormal basis.
    pub(crate) fn basis_speeds(&self, u: &DVector<f64>) -> Vec<f64> {
        (&self.basis * u).iter().copied().collect()
    }

    /// Scale link speeds so the largest is +1; returns the scaled speeds and
    /// the driving-coordinate values.
    pub(crate) fn normalised(&self, speeds: Vec<f64>) -> (Vec<f64>, Vec<f64>) {
        let (mut top, mut sign) = (0.0_f64, 1.0);
        for &v in &speeds {
            if v.abs() > top {
                top = v.abs();
                sign = v.signum();
            }
        }
        let s = if top > 0.0 { sign / top } else { 1.0 };
        let speeds: Vec<f64> = speeds.iter().map(|v| v * s).collect();
        let coords = self.coordinates.iter().map(|l| speeds[l.index()]).collect();
        (speeds, coords)
    }
}

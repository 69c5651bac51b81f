//! The reduced coordinates of one shift mode. A mode is a set of locked
//! elements (brakes, clutches, engaged one-way elements); its constraint rows
//! are the Willis rows \[psi_w\] (paper eq. 4/10, one per fundamental circuit)
//! plus one row per locked element (`ω_l = 0` for a brake, `ω_a - ω_b = 0` for
//! a clutch). The admissible link speeds are the null space of those rows, so
//! the mode's coordinates are exactly its degrees of freedom: 1 in a gear,
//! 2 while one element slips between two gears, 0 for a tie-up.
//!
//! The basis is orthonormal (from the symmetric eigen-decomposition of
//! `A^T A`), so `v = N q` and the reduced mass matrix is `N^T M N` (eq. 25 with
//! `V = N`).

use nalgebra::{DMatrix, SymmetricEigen};

use crate::analysis::transmission::element_constraint;
use crate::error::{Error, Result};
use crate::model::train::{ElementId, Train};
use crate::solve::rows::Extra;

/// Eigenvalues of `A^T A` below this fraction of the largest span the null space.
pub const NULL_TOLERANCE: f64 = 1e-12;

/// One mode: its constraint rows and an orthonormal basis of its speeds.
#[derive(Debug, Clone, PartialEq)]
pub struct ModeBasis {
    /// The locked elements.
    pub locked: Vec<ElementId>,
    /// Constraint rows over the coordinates (every link but the frame).
    pub rows: DMatrix<f64>,
    /// Orthonormal null-space basis, coordinates x DOF.
    pub basis: DMatrix<f64>,
}

impl ModeBasis {
    /// Degrees of freedom of the mode.
    pub fn dof(&self) -> usize {
        self.basis.ncols()
    }
}

/// The constraint row of one element over the train's coordinates.
pub fn element_row(train: &Train, element: ElementId) -> Result<Vec<f64>> {
    let e = train.elements().get(element.index()).ok_or_else(|| {
        Error::invalid(
            "shift.element",
            format!("no element with index {}", element.index()),
        )
    })?;
    let mut row = vec![0.0; train.coordinates().len()];
    match element_constraint(e) {
        Extra::Hold(l) => {
            if let Some(k) = train.coordinate(l) {
                row[k] = 1.0;
            }
        }
        Extra::Join(a, b) => {
            if let Some(k) = train.coordinate(a) {
                row[k] += 1.0;
            }
            if let Some(k) = train.coordinate(b) {
                row[k] -= 1.0;
            }
        }
    }
    Ok(row)
}

/// Builds the mode with `locked` elements engaged.
///
/// # Errors
/// A missing gear ratio (as [`Train::willis_jacobian`]); an unknown element.
pub fn mode_basis(train: &Train, locked: &[ElementId]) -> Result<ModeBasis> {
    let willis = train.willis_jacobian()?;
    let n = train.coordinates().len();
    let mut rows = DMatrix::zeros(willis.nrows() + locked.len(), n);
    rows.rows_mut(0, willis.nrows()).copy_from(&willis);
    for (r, &e) in locked.iter().enumerate() {
        let row = element_row(train, e)?;
        for (k, v) in row.into_iter().enumerate() {
            rows[(willis.nrows() + r, k)] = v;
        }
    }
    let eig = SymmetricEigen::new(rows.transpose() * &rows);
    let top = eig.eigenvalues.amax().max(1.0);
    let free: Vec<usize> = (0..n)
        .filter(|&k| eig.eigenvalues[k] <= NULL_TOLERANCE * top)
        .collect();
    let mut basis = DMatrix::zeros(n, free.len());
    for (c, &k) in free.iter().enumerate() {
        basis.set_column(c, &eig.eigenvectors.column(k));
    }
    Ok(ModeBasis {
        locked: locked.to_vec(),
        rows,
        basis,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::shift_dynamics::lockup::lock_projection;
    use crate::spec::parse::Format;
    use nalgebra::DVector;

    fn zf() -> Train {
        let text = include_str!(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../examples/zf_8hp70.toml"
        ));
        Train::from_str(text, Format::Toml, "zf_8hp70.toml").expect("example parses")
    }

    #[test]
    fn every_8hp_gear_is_one_dof_with_the_shift_table_ratio() {
        let train = zf();
        let t = train.checked_transmission().expect("transmission").clone();
        let (ki, ko) = (
            train.coordinate(t.input).expect("input moves"),
            train.coordinate(t.output).expect("output moves"),
        );
        for state in &t.states {
            let mode = mode_basis(&train, &state.engaged).expect("mode");
            assert_eq!(mode.dof(), 1, "gear {}", state.name);
            let g = train.analyse_gear(&state.name).expect("gear analyses");
            let col = mode.basis.column(0);
            let ratio = col[ki] / col[ko];
            assert!(
                (ratio - g.ratio).abs() < 1e-10 * g.ratio.abs(),
                "gear {}",
                state.name
            );
            // Every link speed per unit input matches the steady analysis.
            for (l, s) in g.speed.iter().enumerate() {
                let link = crate::model::train::LinkId::from_index(l);
                if let (Some(s), Some(k)) = (s, train.coordinate(link)) {
                    assert!((col[k] / col[ki] - s).abs() < 1e-9 * (1.0 + s.abs()));
                }
            }
        }
    }

    #[test]
    fn releasing_one_element_frees_one_coordinate_and_locking_never_adds_energy() {
        let train = zf();
        let t = train.checked_transmission().expect("transmission").clone();
        let n = train.coordinates().len();
        // A positive diagonal mass matrix: the projection property holds for any.
        let m = DMatrix::from_fn(
            n,
            n,
            |i, j| if i == j { 0.01 + 0.003 * i as f64 } else { 0.0 },
        );
        let mut checked = 0;
        for pair in t.states.windows(2) {
            let (from, to) = (&pair[0], &pair[1]);
            let kept: Vec<ElementId> = from
                .engaged
                .iter()
                .copied()
                .filter(|e| to.engaged.contains(e))
                .collect();
            if kept.len() + 1 != from.engaged.len() {
                continue; // not a single-swap shift
            }
            let shifting = mode_basis(&train, &kept).expect("mode");
            assert_eq!(shifting.dof(), 2, "{} -> {}", from.name, to.name);
            // Any speed of the two-DOF mode projected onto the new gear.
            let q = DVector::from_vec(vec![300.0, -120.0]);
            let v = &shifting.basis * q;
            let target = mode_basis(&train, &to.engaged).expect("mode");
            let lock = lock_projection(&m, &target.rows, &v).expect("projection");
            let ke = |v: &DVector<f64>| 0.5 * v.dot(&(&m * v));
            assert!(ke(&lock.speed) <= ke(&v), "{} -> {}", from.name, to.name);
            assert!((&target.rows * &lock.speed).amax() < 1e-9 * v.amax());
            checked += 1;
        }
        // The 8HP's forward gears 1..8 are all single-element swaps.
        assert!(checked >= 7, "only {checked} single-swap shifts");
    }
}

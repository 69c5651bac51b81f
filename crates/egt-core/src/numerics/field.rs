//! Gauss-Jordan elimination over a field, one algorithm for the exact
//! rationals of [`exact`](super::exact) and the GF(p) residues of
//! [`modp`](super::modp).

/// An element of a field, as the elimination uses it.
pub(crate) trait Field: Clone {
    /// Whether this is zero.
    fn is_zero(&self) -> bool;
    /// The inverse of a non-zero element.
    fn inverse(&self) -> Self;
    /// `self *= by`.
    fn scale(&mut self, by: &Self);
    /// `self -= f * y`.
    fn sub_mul(&mut self, f: &Self, y: &Self);
}

/// Reduce `m` to reduced row-echelon form in place; return the pivot columns.
pub(crate) fn rref<T: Field>(m: &mut [Vec<T>]) -> Vec<usize> {
    let rows = m.len();
    let cols = m.first().map_or(0, Vec::len);
    let mut pivots = Vec::new();
    let mut r = 0;
    for c in 0..cols {
        if r == rows {
            break;
        }
        let Some(p) = (r..rows).find(|&i| !m[i][c].is_zero()) else {
            continue;
        };
        m.swap(r, p);
        let inv = m[r][c].inverse();
        for x in m[r].iter_mut() {
            x.scale(&inv);
        }
        for i in 0..rows {
            if i != r && !m[i][c].is_zero() {
                let f = m[i][c].clone();
                let (pivot_row, row_i) = if i < r {
                    let (a, b) = m.split_at_mut(r);
                    (&b[0], &mut a[i])
                } else {
                    let (a, b) = m.split_at_mut(i);
                    (&a[r], &mut b[0])
                };
                for (x, y) in row_i.iter_mut().zip(pivot_row) {
                    if !y.is_zero() {
                        x.sub_mul(&f, y);
                    }
                }
            }
        }
        pivots.push(c);
        r += 1;
    }
    pivots
}

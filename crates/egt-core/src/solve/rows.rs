//! The constraint rows of the velocity Jacobian by coordinate column: the
//! Willis rows of the fundamental circuits (eq. 2) and the rows of brakes and
//! clutches in force, with the DOF they leave and the columns of named links.

use serde::Serialize;

use crate::error::{AnalysisError, Result};
use crate::model::train::{LinkId, Train};

/// A constraint row besides the Willis equations.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Extra {
    /// w_link = 0 (a brake).
    Hold(LinkId),
    /// w_a - w_b = 0 (a clutch).
    Join(LinkId, LinkId),
}

/// A column of the constraint Jacobian: a coordinate or the frame.
pub(crate) type Col = Option<usize>;

/// The number of coordinates n and the DOF F = n - (j_G + extras) left by `extras`.
///
/// # Errors
/// More constraints than coordinates.
pub(crate) fn dof_with(train: &Train, extras: &[Extra]) -> Result<(usize, usize)> {
    let n = train.coordinates().len();
    let c = train.circuits().len() + extras.len();
    let f = n.checked_sub(c).ok_or(AnalysisError::OverConstrained {
        constraints: c,
        coordinates: n,
    })?;
    Ok((n, f))
}

/// The coordinate columns of `links`, which must be F distinct non-frame links.
///
/// # Errors
/// A wrong count (naming `what`), the frame, or a repeated link.
pub(crate) fn link_columns(
    train: &Train,
    links: &[LinkId],
    f: usize,
    what: &str,
) -> Result<Vec<usize>> {
    if links.len() != f {
        return Err(AnalysisError::WrongInputCount {
            dof: f,
            given: links.len(),
            what: what.to_string(),
        }
        .into());
    }
    let mut out = Vec::with_capacity(f);
    for &l in links {
        let k = train
            .coordinate(l)
            .ok_or_else(|| AnalysisError::FrameInput {
                link: train.link_name(l).to_string(),
            })?;
        if out.contains(&k) {
            return Err(AnalysisError::RepeatedLink {
                link: train.link_name(l).to_string(),
                role: what.to_string(),
            }
            .into());
        }
        out.push(k);
    }
    Ok(out)
}

/// The constraint rows of a plan, by coordinate column.
#[derive(Debug, Clone)]
pub(crate) struct Rows {
    /// Columns of gear i, gear j and the carrier of each Willis row.
    pub(crate) circuits: Vec<[Col; 3]>,
    /// Columns and coefficients of each brake/clutch row.
    pub(crate) extras: Vec<[(Col, f64); 2]>,
}

impl Rows {
    /// The rows of the Willis equations and of `extras`.
    pub(crate) fn new(train: &Train, extras: &[Extra]) -> Self {
        let col = |l: LinkId| train.coordinate(l);
        Rows {
            circuits: train
                .circuits()
                .iter()
                .map(|c| [col(c.gear_i), col(c.gear_j), col(c.carrier)])
                .collect(),
            extras: extras
                .iter()
                .map(|e| match *e {
                    Extra::Hold(l) => [(col(l), 1.0), (None, 0.0)],
                    Extra::Join(a, b) => [(col(a), 1.0), (col(b), -1.0)],
                })
                .collect(),
        }
    }
}

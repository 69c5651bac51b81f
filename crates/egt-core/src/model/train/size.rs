//! The size limits of a train: the most links, and the memory the dense
//! matrices of an analysis may take.

use super::*;

/// The most memory the dense matrices of one analysis may take. The
/// analyses other than the topology check and the kinematics (dynamics,
/// power, stability, simulation, gear states, exact speeds) hold a few dense
/// n x n matrices (f64 or rationals) for n links; [`Train::require_dense`]
/// estimates them with [`dense_bytes`] before any is allocated, so a huge
/// train is refused by name instead of aborting on a failed allocation (or
/// running for minutes, the work being cubic in n). The topology check and
/// the float kinematics are sparse and take any train up to [`MAX_TRAIN_LINKS`].
pub const MAX_DENSE_BYTES: usize = 64 << 20;

/// The most links a train may have: about 5 KB of memory a link while it is
/// read and checked (a 10^5-link spec takes 0.5 GB), so 2^20 links stay
/// within a few GB.
pub const MAX_TRAIN_LINKS: usize = 1 << 20;

/// Estimated bytes of the dense matrices of a train of `links` links: about
/// eight n x n matrices of 8-byte entries (see [`MAX_DENSE_BYTES`]).
pub fn dense_bytes(links: usize) -> usize {
    links.saturating_mul(links).saturating_mul(64)
}

/// The largest train whose dense matrices fit in [`MAX_DENSE_BYTES`].
pub fn most_dense_links() -> usize {
    // dense_bytes is increasing: the largest n with 64 n^2 <= limit.
    let mut n = ((MAX_DENSE_BYTES / 64) as f64).sqrt() as usize + 1;
    while dense_bytes(n) > MAX_DENSE_BYTES {
        n -= 1;
    }
    n
}

impl Train {
    /// Refuse `analysis` when its dense matrices for this train would pass
    /// [`MAX_DENSE_BYTES`]; called before any is allocated.
    ///
    /// # Errors
    /// [`AnalysisError::TooLarge`] naming the analysis, the size and the limit.
    pub fn require_dense(&self, analysis: &str) -> Result<()> {
        require_dense_links(self.links.len(), analysis)
    }
}

/// [`Train::require_dense`] for a train of `links` links (the one rule and
/// message, also for a [`MassMatrix`](crate::MassMatrix) of `links - 1`
/// coordinates).
pub(crate) fn require_dense_links(links: usize, analysis: &str) -> Result<()> {
    if dense_bytes(links) <= MAX_DENSE_BYTES {
        return Ok(());
    }
    Err(AnalysisError::TooLarge {
        analysis: analysis.to_string(),
        links,
        mib: dense_bytes(links) >> 20,
        limit_mib: MAX_DENSE_BYTES >> 20,
        most: most_dense_links(),
        what: "the topology check, the float kinematics, inverse dynamics and power flow are sparse and take it".into(),
    }
    .into())
}

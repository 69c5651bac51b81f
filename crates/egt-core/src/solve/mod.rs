//! Layer 4, the solver: [`PreparedTrain`](prepared::PreparedTrain) and its
//! `Workspace`, the one place where eq. (2), (8), (10) and the lossy mesh rows
//! are assembled and solved; the lossy direction search; exact kinematics with
//! its diagnosis of singular inputs; the reduced model of eq. (19)-(27) that
//! stability and simulation share.

pub mod kinematics;
pub(crate) mod losses;
pub mod prepared;
pub mod reduced;
pub mod rows;

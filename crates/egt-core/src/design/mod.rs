//! Design search: synthesise the tooth counts of a transmission's simple and
//! Ravigneaux planetary sets for target ratios (`egt synth`). `spec` is the search as
//! written; `search` prepares it once and runs partitions of it.

pub mod search;
pub mod spec;

pub use search::{Candidate, DesignError, Search, Stats, Teeth, merge, rank};
pub use spec::{Constraints, DEFAULT_MAX_LEAVES, Placement, SetRange, SynthSpec, Targets};

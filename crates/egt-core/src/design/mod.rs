//! Design search: synthesise the tooth counts of a transmission's simple,
//! double-pinion and Ravigneaux planetary sets for target ratios (`egt
//! synth`), and with `[concept]` its structure and element positions too.
//! `spec` is the search as written; `search` prepares a tooth search once
//! and runs partitions of it; `concept` the structure search over it;
//! `synthesis` is the one front of both.

pub mod concept;
pub mod search;
pub mod spec;
pub mod synthesis;

pub use concept::{ConceptInfo, Concepts, Structure};
pub use search::{Candidate, DesignError, Search, Stats, Teeth, merge, rank};
pub use spec::{
    ConceptSpec, Constraints, DEFAULT_MAX_LEAVES, InputRule, Placement, SetRange, SynthSpec,
    Targets,
};
pub use synthesis::Synthesis;

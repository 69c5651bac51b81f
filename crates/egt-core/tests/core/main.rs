//! egt-core's integration tests: one binary, one module per concern.
//!
//! The binary installs a counting global allocator (see `alloc.rs`) so that the
//! per-scenario hot paths can be shown to allocate nothing.

// The accuracy study: every method against exact rationals, condition estimates, refusal.
mod accuracy;

// Counting allocator and the zero-allocation proofs for every prepared solve.
mod alloc;

// The batch API against the single-scenario analyses (kinematics, inverse dynamics, power flow).
mod batch;

// The accuracy study and the generated train families (not library API).
#[path = "../../lab/mod.rs"]
mod lab;

// Large trains: the sparse Willis solve, and the dense analyses refused past their limit.
mod large;

// Trains used across modules: the bundled examples, generated families, random parameters.
mod util;

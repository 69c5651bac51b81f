//! The workspace's one integration-test binary (registered by `crates/egt-cli`).
//! It drives the core library and the built `egt` binary on the bundled examples.

// Shared helpers: example paths, building trains from text, exact numbers.
mod util;

// The paper's printed Willis Jacobians (examples 6.1, 6.2) and Table 2.
mod paper;

// Exact rational kinematics: closed forms of 6.1/6.2, Ford AOD and C4 ratios from teeth.
mod exact;

// Property tests on random chains and nests of planetary sets (residuals, float vs exact).
mod properties;

// One test per class of bad input: the error variant and what it names.
mod errors;

// The `egt` binary: exit codes, stdin, JSON fields, table and snapshot output.
mod cli;

// The complete spec examples in docs/spec.md validate.
mod docs;

// Issue 3: inverse dynamics, meshing forces, power flow and efficiency against independent relations.
mod dynamics;

// Issue 5: automatic transmissions: published ratios from teeth, element torques, bad gear states, egt shift/graph.
mod transmission;

// Issue 4: stability (example 6.2, eigenvalues vs simulation) and forward dynamics, with the failure edges.
mod stability;

// Issue 11: round-off never decides the direction of power (random teeth, exact reference).
mod efficiency;

// Issue 10: every bundled example through every analysis, against committed JSON snapshots.
mod golden;

// Issue 12: one row per class of bad input through the binary (exit code, words in the message).
mod bad_inputs;

// Issue 15: `egt enumerate`, the atlas of gear-train graphs, read back by `egt check`.
mod enumerate;

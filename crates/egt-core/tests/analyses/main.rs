//! egt-core's analyses against independent relations: one binary, one module
//! per concern. Everything here drives the library only; the `egt` binary's
//! tests live in the workspace's top-level `tests/` (registered by egt-cli).

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

// The complete spec examples in docs/spec.md validate.
mod docs;

// Issue 3: inverse dynamics, meshing forces, power flow and efficiency against independent relations.
mod dynamics;

// Issue 5: automatic transmissions: published ratios from teeth, element torques, bad gear states.
mod transmission;

// Issue 4: stability (example 6.2, eigenvalues vs simulation) and forward dynamics, with the failure edges.
mod stability;

// Issue 11: round-off never decides the direction of power (random teeth, exact reference).
mod efficiency;

// Issue 43: torsional natural frequencies and modes against hand-written models and closed forms.
mod modes;

// Issue 43: the compliant model's static mesh forces against eq. (11).
mod statics;

// Issue 43: the damped modes' complex eigenvalues against the closed form.
mod damped;

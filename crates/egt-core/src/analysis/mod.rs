//! Layer 5, analyses: thin fronts over [`crate::solve`] that turn one solve
//! into a result (inverse dynamics, power flow, stability, torsional modes, gear states and
//! shift tables).

pub mod dynamics;
pub mod modes;
pub mod power;
pub mod stability;
pub mod transmission;

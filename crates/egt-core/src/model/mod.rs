//! Layer 3, the model: a validated [`Train`](train::Train) (typed ids, links,
//! pairs, levels, shift elements), its topology (eq. 1), its fundamental
//! circuits (Table 1), the Willis row of each circuit (eq. 2) and the kinetic
//! energy built from tree paths (eq. 3-5). Built from [`crate::spec`] once;
//! everything above reads it and never the spec.

pub mod circuits;
pub mod equations;
pub mod mass;
pub mod topology;
pub mod train;

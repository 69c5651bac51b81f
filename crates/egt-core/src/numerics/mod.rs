//! Layer 1, numbers: exact rationals, generic rank over a prime field and the
//! checked dense LU. Nothing here knows what a gear train is.

pub mod exact;
mod field;
pub mod linalg;
pub mod modp;
pub mod sparse;

//! Layer 6, motion in time: forward simulation of a train and the pieces of a
//! gear-change simulation.

pub mod shift_dynamics;
pub mod simulate;

//! The tooth-count search: branch and bound over the basic ratios k = z_ring /
//! z_sun of the unknown sets, then exact confirmation of every survivor.
//!
//! Per gear state the Willis rows (eq. 2 of the paper: w_s - w_c + s k (w_r -
//! w_c) = 0 with s = +1 for a simple set and a Ravigneaux set's large sun, -1
//! for its small sun and a double-pinion set), the engaged elements' rows and
//! w_in = 1 form a square system A(k) w = e. A simple set has one searched k, a
//! Ravigneaux set two (ring/small sun, ring/large sun: one ring, so not every
//! pair is made of teeth; the pairs that are, are checked at the leaves).
//! Each k_i sits in one row, so det A and the
//! Cramer numerator of w_out are affine in each k_i: on a box of k values, if
//! det A keeps one sign at every vertex it has no zero inside, and w_out is
//! monotone in each k_i, so its range over the box is spanned by the vertex
//! values. A box whose w_out range misses a target's window is dropped whole;
//! the others are halved along the set with the most candidate ratios. Leaves
//! (one k per set) are checked in floats, then rebuilt as a train and solved
//! exactly by the transmission analysis (`Train::shift_table`), which gives
//! the reported ratios as fractions.

mod bound;
mod candidates;
mod confirm;
mod incumbent;
mod layouts;
mod partitions;
mod prepare;
mod space;
mod systems;

pub use crate::error::DesignError;
pub(crate) use bound::misses;
pub use candidates::{Candidate, Stats, merge, rank};
pub(crate) use confirm::write_teeth;
pub use incumbent::Incumbent;
pub use layouts::MAX_LAYOUTS;
pub(crate) use partitions::check_partition;
pub use prepare::Search;
pub(crate) use prepare::check_numbers;
pub(crate) use space::SetSpace;
pub use space::{MAX_SET_PAIRS, Teeth};
pub(crate) use systems::{same_speed, searched_willis};

#[cfg(test)]
mod tests;

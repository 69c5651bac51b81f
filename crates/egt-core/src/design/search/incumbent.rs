//! The incumbent a branch and bound shares: the scores of the best
//! candidates confirmed so far, across every structure and layout of a
//! concept search. Once `top` are known, a candidate scoring worse than the
//! `top`-th can never be reported, so leaves scoring worse are not
//! confirmed, and each targeted state's window narrows to what such a score
//! allows: RMS of n relative errors <= s means each is <= s sqrt(n).

use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};

/// The best scores so far (at most `top`) and the `top`-th as a threshold.
#[derive(Debug)]
pub struct Incumbent {
    top: usize,
    scores: Mutex<Vec<f64>>,
    /// f64 bits of the threshold: infinite until `top` scores are known.
    threshold: AtomicU64,
}

impl Incumbent {
    /// An incumbent keeping `top` scores.
    pub fn new(top: usize) -> Incumbent {
        Incumbent {
            top: top.max(1),
            scores: Mutex::new(Vec::new()),
            threshold: AtomicU64::new(f64::INFINITY.to_bits()),
        }
    }

    /// The score a candidate must not exceed to be reported (with a margin
    /// of round-off between the float check and the exact confirmation).
    pub fn threshold(&self) -> f64 {
        f64::from_bits(self.threshold.load(Ordering::Relaxed)) * (1.0 + 1e-9)
    }

    /// A confirmed candidate's score.
    pub fn offer(&self, score: f64) {
        let Ok(mut s) = self.scores.lock() else {
            return;
        };
        s.push(score);
        s.sort_by(f64::total_cmp);
        s.truncate(self.top);
        if s.len() == self.top {
            self.threshold
                .store(s[self.top - 1].to_bits(), Ordering::Relaxed);
        }
    }
}

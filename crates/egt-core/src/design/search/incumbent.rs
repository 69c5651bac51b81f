//! The incumbent a branch and bound shares: the scores of the best
//! candidates confirmed so far, across every structure and layout of a
//! concept search. Once `top` are known, a candidate scoring worse than the
//! `top`-th can never be reported, so leaves scoring worse are not
//! confirmed, and each targeted state's window narrows to what such a score
//! allows: RMS of n relative errors <= s means each is <= s sqrt(n).
//! A concept search reports each concept (structure and layout) once, so
//! its scores are kept per concept: the best of each.

use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};

/// The best scores so far (at most `top`) and the `top`-th as a threshold.
#[derive(Debug)]
pub struct Incumbent {
    top: usize,
    /// (concept key, score), best first; None: a candidate of its own.
    scores: Mutex<Vec<(Option<u64>, f64)>>,
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
        self.insert(None, score);
    }

    /// A confirmed candidate's score, as one of concept `key`'s: only the
    /// best of a concept counts towards the `top`.
    pub fn offer_best(&self, key: u64, score: f64) {
        self.insert(Some(key), score);
    }

    fn insert(&self, key: Option<u64>, score: f64) {
        let Ok(mut s) = self.scores.lock() else {
            return;
        };
        match s.iter_mut().find(|e| key.is_some() && e.0 == key) {
            Some(e) => e.1 = e.1.min(score),
            None => s.push((key, score)),
        }
        s.sort_by(|a, b| a.1.total_cmp(&b.1));
        s.truncate(self.top);
        if s.len() == self.top {
            self.threshold
                .store(s[self.top - 1].1.to_bits(), Ordering::Relaxed);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Incumbent;

    #[test]
    fn a_concept_counts_once_towards_the_top() {
        let inc = Incumbent::new(2);
        inc.offer_best(7, 0.3);
        inc.offer_best(7, 0.1);
        // One concept known: no threshold yet.
        assert_eq!(inc.threshold(), f64::INFINITY);
        inc.offer_best(8, 0.2);
        assert!((inc.threshold() - 0.2).abs() < 1e-8);
        // Plain candidates each count.
        let plain = Incumbent::new(2);
        plain.offer(0.3);
        plain.offer(0.1);
        assert!((plain.threshold() - 0.3).abs() < 1e-8);
    }
}

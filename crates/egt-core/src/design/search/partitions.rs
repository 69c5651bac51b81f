//! Running a search whole or in partitions (for Dask): the partition
//! count, one partition, all of them with progress, and stopping a run
//! early.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use crate::error::DesignError;

use super::Search;
use super::candidates::{Candidate, Stats, merge, rank};

impl Search {
    /// How many of the best candidates a run keeps (the spec's `top`).
    pub fn top(&self) -> usize {
        self.spec.top
    }

    /// The unknown sets, in the order of each candidate's lists.
    pub fn set_names(&self) -> &[String] {
        &self.set_names
    }

    /// Stop runs of this search soon after `flag` is set (by another thread:
    /// a Ctrl-C handler, a time limit). The flag is read at each node of the
    /// bound and before each exact confirmation, never inside one. A run
    /// stopped so returns `Ok` with [`Stats::interrupted`] set and the
    /// candidates confirmed before the stop: each is exact and meets the
    /// targets, but the space was not all searched, so better ones may
    /// exist. The library sets no signal handler: the flag is the caller's.
    #[must_use]
    pub fn with_cancel(mut self, flag: Arc<AtomicBool>) -> Self {
        self.cancel = Some(flag);
        self
    }

    /// Share the best scores with other searches (one branch and bound over
    /// a concept search's structures): see [`super::Incumbent`].
    #[must_use]
    pub fn with_incumbent(mut self, incumbent: Arc<super::Incumbent>) -> Self {
        self.incumbent = Some(incumbent);
        self
    }

    /// Report each layout's best teeth only, as concept `structure`'s
    /// layouts: each counts once towards the shared incumbent's top
    /// ([`super::Incumbent::offer_best`], keyed by structure and layout).
    #[must_use]
    pub fn best_per_layout(mut self, structure: u64) -> Self {
        self.per_layout = Some(structure);
        self
    }

    /// Stop a run after `nodes` nodes of the bound; the run then reports
    /// [`Stats::cut`] (its candidates are exact, but the space was not all
    /// searched).
    #[must_use]
    pub fn with_node_limit(mut self, nodes: u64) -> Self {
        self.node_limit = Some(nodes);
        self
    }

    /// Whether the caller asked the run to stop ([`Search::with_cancel`]).
    pub(super) fn cancelled(&self) -> bool {
        self.cancel
            .as_ref()
            .is_some_and(|f| f.load(Ordering::Relaxed))
    }

    /// Number of partitions the first unknown set's ratios can be split into.
    pub fn max_partitions(&self) -> usize {
        self.dims.first().map_or(0, |d| d.ks.len())
    }

    /// Run partition `part` of `parts` (contiguous slices of the first set's
    /// sorted ratios). Partitions are disjoint and cover the space, so their
    /// candidates can be merged and re-ranked in any order.
    ///
    /// # Errors
    /// [`DesignError::Invalid`] for a bad partition, or an exact-analysis failure.
    pub fn run_partition(
        &self,
        part: usize,
        parts: usize,
    ) -> Result<(Vec<Candidate>, Stats), DesignError> {
        check_partition(part, parts)?;
        // In u128: part and parts come from the command line and may be huge.
        let len = self.max_partitions() as u128;
        let slice =
            |p: usize| usize::try_from(len * p as u128 / parts as u128).unwrap_or(usize::MAX);
        let (lo, hi) = (slice(part), slice(part + 1));
        let mut stats = Stats {
            tooth_space: self
                .unknowns
                .iter()
                .map(|u| u.teeth.values().map(|t| t.len() as f64).sum::<f64>())
                .product(),
            ratio_space: self.unknowns.iter().map(|u| u.teeth.len() as f64).product(),
            layouts: self.variants.len() as u64,
            skipped_layouts: self.skipped_layouts,
            ..Stats::default()
        };
        if lo >= hi {
            return Ok((Vec::new(), stats));
        }
        let mut bounds: Vec<(usize, usize)> = self.dims.iter().map(|d| (0, d.ks.len())).collect();
        bounds[0] = (lo, hi);
        let nodes = std::sync::atomic::AtomicU64::new(0);
        let leaves = std::sync::atomic::AtomicU64::new(0);
        // Every layout over the partition's box, in parallel (each bound
        // itself splits its halves with rayon::join).
        use rayon::prelude::*;
        let results: Vec<Result<(Vec<Candidate>, u64), DesignError>> = self
            .variants
            .par_iter()
            .enumerate()
            .map(|(v, pick)| {
                let mut out = Vec::new();
                let mut rejected = 0;
                if self.cancelled() {
                    return Ok((out, rejected));
                }
                let states = self.states(pick)?;
                let survivors = self.branch(&states, &bounds, &nodes, &leaves);
                self.within_leaf_budget(leaves.load(Ordering::Relaxed))?;
                for ks in survivors {
                    if self.cancelled() {
                        break;
                    }
                    match self.confirm(pick, &ks)? {
                        Some(c) => {
                            match (&self.incumbent, self.per_layout) {
                                (Some(inc), Some(s)) => inc.offer_best(s << 32 | v as u64, c.score),
                                (Some(inc), None) => inc.offer(c.score),
                                (None, _) => {}
                            }
                            out.push(c);
                        }
                        None => rejected += 1,
                    }
                }
                rank(
                    &mut out,
                    if self.per_layout.is_some() {
                        1
                    } else {
                        self.spec.top
                    },
                );
                Ok((out, rejected))
            })
            .collect();
        stats.nodes = nodes.into_inner();
        stats.cut = u64::from(self.node_limit.is_some_and(|m| stats.nodes > m));
        stats.leaves = leaves.into_inner();
        // Read once all is done: set at any point, the run was cut short.
        stats.interrupted = self.cancelled();
        let mut out = Vec::new();
        for r in results {
            let (c, rejected) = r?;
            out.extend(c);
            stats.rejected += rejected;
        }
        rank(&mut out, self.spec.top);
        Ok((out, stats))
    }

    /// The leaf budget (`max_leaves`): past it, a [`crate::AnalysisError::Budget`]
    /// saying how to raise it (the bound stops early, so the count is a
    /// lower estimate).
    fn within_leaf_budget(&self, leaves: u64) -> Result<(), DesignError> {
        let max = self.spec.max_leaves;
        if leaves <= max {
            return Ok(());
        }
        Err(DesignError::Egt(
            crate::AnalysisError::Budget {
                what: "the search's bound".into(),
                estimate: format!(
                    "more than {max} leaves (each one confirmed by an exact analysis; the tolerance or the ranges prune too little)"
                ),
                limit: format!("{max} leaves"),
                raise: "tighten `targets.tolerance`, narrow `sets`, or raise `max_leaves` in the search spec (`egt synth --max-leaves N`)".into(),
            }
            .into(),
        ))
    }

    /// Run the whole space as `parts` partitions one after another (each on
    /// all cores), calling `progress(done, parts, best)` after each with the
    /// best candidates so far (ranked, at most `top`): what a progress bar, an
    /// ETA and a stream of results need. Merged and ranked, the result is
    /// [`Search::run`]'s. Stopped ([`Search::with_cancel`]), it runs no
    /// further part and does not report the one cut short; the result is
    /// then the parts run, with [`Stats::interrupted`] set.
    ///
    /// # Errors
    /// As [`Search::run_partition`].
    pub fn run_in_parts(
        &self,
        parts: usize,
        mut progress: impl FnMut(usize, usize, &[Candidate]),
    ) -> Result<(Vec<Candidate>, Stats), DesignError> {
        let parts = parts.clamp(1, self.max_partitions().max(1));
        let mut best: Vec<Candidate> = Vec::new();
        let mut done = Vec::with_capacity(parts);
        for part in 0..parts {
            let (found, stats) = self.run_partition(part, parts)?;
            if stats.interrupted {
                done.push((found, stats));
                break;
            }
            best.extend(found.iter().cloned());
            rank(&mut best, self.spec.top);
            progress(part + 1, parts, &best);
            done.push((found, stats));
        }
        Ok(merge(done, self.spec.top))
    }

    /// Run the whole space (one partition) on all cores.
    ///
    /// # Errors
    /// As [`Search::run_partition`].
    pub fn run(&self) -> Result<(Vec<Candidate>, Stats), DesignError> {
        self.run_partition(0, 1)
    }
}

/// A partition `part` of `parts` that exists (0 <= part < parts), or the
/// `partition` error both searches give.
pub(crate) fn check_partition(part: usize, parts: usize) -> Result<(), DesignError> {
    if parts == 0 || part >= parts {
        return Err(DesignError::Invalid {
            field: "partition".into(),
            message: format!("{part} of {parts}"),
        });
    }
    Ok(())
}

//! A concept's tooth options: once the best concepts (structure and layout,
//! each with its best teeth) are known, each one's other tooth sets that
//! meet the targets are listed, best first. A search ranks concepts, not
//! teeth: with targets given to two decimals many tooth sets fit one
//! concept, and the real one need not be the closest.

use serde::{Deserialize, Serialize};

use crate::design::search::{Candidate, Teeth};
use crate::error::DesignError;

use super::{Concepts, Stats};

/// One other tooth set of a concept (another basic ratio of some set).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ToothOption {
    /// Per set: the basic ratio k as a fraction (as [`Candidate::basic`]).
    pub basic: Vec<String>,
    /// Per set: ring/large sun of a Ravigneaux set.
    pub basic2: Vec<Option<String>>,
    /// Per set: the smallest-sun teeth giving those ratios.
    pub teeth: Vec<Teeth>,
    /// Per gear state: name, ratio (float), exact ratio.
    pub ratios: Vec<(String, f64, String)>,
    /// As [`Candidate::score`].
    pub score: f64,
}

impl Concepts {
    /// Each candidate's tooth options, searched on its own (no shared
    /// incumbent: a concept's options do not depend on the other
    /// concepts, so partitions merge to the same lists).
    pub(super) fn add_tooth_options(&self, found: &mut [Candidate]) -> Result<(), DesignError> {
        let count = self.concept.options;
        if count == 0 {
            return Ok(());
        }
        use rayon::prelude::*;
        let lists: Vec<Result<(Vec<ToothOption>, bool), DesignError>> = found
            .par_iter()
            .map(|c| self.tooth_options(c, count))
            .collect();
        for (c, list) in found.iter_mut().zip(lists) {
            let (options, cut) = list?;
            if let Some(k) = c.concept.as_mut() {
                k.tooth_options = options;
                k.tooth_options_cut = cut;
            }
        }
        Ok(())
    }

    /// Up to `count` tooth sets of `c`'s structure and layout other than
    /// its own, and whether their search was cut at `max_nodes`.
    fn tooth_options(
        &self,
        c: &Candidate,
        count: usize,
    ) -> Result<(Vec<ToothOption>, bool), DesignError> {
        let Some(info) = &c.concept else {
            return Ok((Vec::new(), false));
        };
        let s = &info.structure;
        let mut stats = Stats::default();
        let Some(j) = self.judge(s, &mut stats) else {
            return Ok((Vec::new(), false));
        };
        let Some((pick, _)) = j.picks.iter().find(|(p, _)| j.named(p) == c.layout) else {
            return Ok((Vec::new(), false));
        };
        let Some(search) = self.tooth_search(s, &j, vec![pick.clone()], count + 1)? else {
            return Ok((Vec::new(), false));
        };
        let (found, stats) = search.run()?;
        let options = found
            .into_iter()
            .filter(|o| o.basic != c.basic || o.basic2 != c.basic2)
            .take(count)
            .map(|o| ToothOption {
                basic: o.basic,
                basic2: o.basic2,
                teeth: o.teeth,
                ratios: o.ratios,
                score: o.score,
            })
            .collect();
        Ok((options, stats.cut > 0))
    }
}

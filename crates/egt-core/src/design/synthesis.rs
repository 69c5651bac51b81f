//! One front for the two searches of `egt synth`: the tooth (and layout)
//! search of a given train, or the concept search that also searches its
//! structure. The CLI and the Python module prepare and run either through it.

use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use crate::design::concept::Concepts;
use crate::design::search::{Candidate, Search, Stats};
use crate::design::spec::SynthSpec;
use crate::error::DesignError;
use crate::spec::Spec;

/// A prepared search of either kind.
#[derive(Debug, Clone)]
pub enum Synthesis {
    /// Teeth (and `[layout]` positions) of the base train.
    Teeth(Box<Search>),
    /// Structure, layout and teeth (`[concept]`).
    Concepts(Box<Concepts>),
}

impl Synthesis {
    /// Prepare: a concept search when the spec has `[concept]` (no base
    /// train), else a tooth search of `base`.
    ///
    /// # Errors
    /// [`DesignError`] naming the offending field; a tooth search without
    /// its base train.
    pub fn new(spec: SynthSpec, base: Option<Spec>) -> Result<Synthesis, DesignError> {
        if spec.concept.is_some() {
            return Ok(Synthesis::Concepts(Box::new(Concepts::new(spec)?)));
        }
        let base = base.ok_or_else(|| DesignError::Invalid {
            field: "base".into(),
            message: "give the base train (or a [concept] to search structures)".into(),
        })?;
        Ok(Synthesis::Teeth(Box::new(Search::new(spec, base)?)))
    }

    /// Whether the spec is a concept search (it names no base train).
    pub fn is_concept(spec: &SynthSpec) -> bool {
        spec.concept.is_some()
    }

    /// Stop runs soon after `flag` is set.
    #[must_use]
    pub fn with_cancel(self, flag: Arc<AtomicBool>) -> Self {
        match self {
            Synthesis::Teeth(s) => Synthesis::Teeth(Box::new(s.with_cancel(flag))),
            Synthesis::Concepts(c) => Synthesis::Concepts(Box::new(c.with_cancel(flag))),
        }
    }

    /// How many of the best candidates a run keeps.
    pub fn top(&self) -> usize {
        match self {
            Synthesis::Teeth(s) => s.top(),
            Synthesis::Concepts(c) => c.top(),
        }
    }

    /// The sets, in the order of each candidate's lists.
    pub fn set_names(&self) -> Vec<String> {
        match self {
            Synthesis::Teeth(s) => s.set_names().to_vec(),
            Synthesis::Concepts(c) => c.set_names(),
        }
    }

    /// How many partitions the search splits into at most (a concept
    /// search: one per structure).
    pub fn max_partitions(&self) -> usize {
        match self {
            Synthesis::Teeth(s) => s.max_partitions(),
            Synthesis::Concepts(c) => c.structures().len(),
        }
    }

    /// Run partition `part` of `parts`: disjoint, covering.
    ///
    /// # Errors
    /// As [`Search::run_partition`].
    pub fn run_partition(
        &self,
        part: usize,
        parts: usize,
    ) -> Result<(Vec<Candidate>, Stats), DesignError> {
        match self {
            Synthesis::Teeth(s) => s.run_partition(part, parts),
            Synthesis::Concepts(c) => c.run_partition(part, parts),
        }
    }

    /// Run in `parts` parts one after another with progress.
    ///
    /// # Errors
    /// As [`Search::run_partition`].
    pub fn run_in_parts(
        &self,
        parts: usize,
        progress: impl FnMut(usize, usize, &[Candidate]),
    ) -> Result<(Vec<Candidate>, Stats), DesignError> {
        match self {
            Synthesis::Teeth(s) => s.run_in_parts(parts, progress),
            Synthesis::Concepts(c) => c.run_in_parts(parts, progress),
        }
    }

    /// A concept search's number of structures (None for a tooth search).
    pub fn structures(&self) -> Option<usize> {
        match self {
            Synthesis::Teeth(_) => None,
            Synthesis::Concepts(c) => Some(c.structures().len()),
        }
    }

    /// Run the whole space on all cores.
    ///
    /// # Errors
    /// As [`Search::run_partition`].
    pub fn run(&self) -> Result<(Vec<Candidate>, Stats), DesignError> {
        self.run_partition(0, 1)
    }

    /// A candidate's train spec (its teeth, layout and, in a concept search,
    /// structure), which every egt command reads.
    ///
    /// # Errors
    /// A concept search's candidate without its structure.
    pub fn candidate_spec(&self, c: &Candidate) -> Result<Spec, DesignError> {
        match self {
            Synthesis::Teeth(s) => Ok(s.candidate_spec(&c.teeth, &c.layout)),
            Synthesis::Concepts(k) => k.candidate_spec(c),
        }
    }
}

//! The design search (`egt.synth`) over egt-core's [`Search`]: built from
//! the texts of the search spec and of its base train (so that a worker
//! process can rebuild it from strings), run whole or by partition with the
//! GIL released; results cross through the one conversion (`convert::to_py`).

use egt_core::design::{SynthSpec, Synthesis};
use egt_core::{Format, parse_spec};
use pyo3::prelude::*;
use std::path::Path;

use crate::convert::to_py;
use crate::errors::{Result, guard, value_error};
use crate::train::format_of;

/// A prepared design search (see `egt.synth`).
#[pyclass(frozen, module = "egt._egt", name = "SearchCore")]
#[derive(Debug)]
pub struct SearchCore {
    search: Synthesis,
}

#[pymethods]
impl SearchCore {
    /// Prepare from the search spec's text and the base train's text.
    #[new]
    #[pyo3(signature = (text, base_text, format = "toml", base_format = "toml", source = "<string>", base_source = "<base>", top = None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        text: &str,
        base_text: &str,
        format: &str,
        base_format: &str,
        source: &str,
        base_source: &str,
        top: Option<usize>,
    ) -> Result<Self> {
        let (format, base_format) = (format_of(format)?, format_of(base_format)?);
        guard(|| {
            let mut spec = SynthSpec::from_str(text, format, source)?;
            if let Some(top) = top {
                spec.top = top;
            }
            // A concept search (`[concept]`) has no base train.
            let base = if Synthesis::is_concept(&spec) {
                None
            } else {
                Some(parse_spec(base_text, base_format, base_source)?)
            };
            let search = Synthesis::new(spec, base).map_err(egt_core::Error::from)?;
            Ok(SearchCore { search })
        })
    }

    /// The unknown sets, in the order of each candidate's lists.
    #[getter]
    fn sets(&self) -> Vec<String> {
        self.search.set_names()
    }

    /// How many of the best candidates a run keeps.
    #[getter]
    fn top(&self) -> usize {
        self.search.top()
    }

    /// How many partitions the search splits into at most.
    #[getter]
    fn max_partitions(&self) -> usize {
        self.search.max_partitions()
    }

    /// Run partition `part` of `parts` (the whole search for 0 of 1):
    /// `{"candidates": [...], "stats": {...}}` in the core's serde form.
    #[pyo3(signature = (part = 0, parts = 1))]
    fn run<'py>(&self, py: Python<'py>, part: usize, parts: usize) -> Result<Bound<'py, PyAny>> {
        let found = py.detach(|| self.search.run_partition(part, parts));
        guard(|| {
            let (candidates, stats) = found.map_err(egt_core::Error::from)?;
            to_py(
                py,
                &serde_json::json!({ "candidates": candidates, "stats": stats }),
            )
        })
    }

    /// The base train's spec with a candidate's teeth (and layout) written
    /// in, as JSON text (`candidate`: one candidate of `run`, as JSON text).
    fn candidate_spec(&self, candidate: &str) -> Result<String> {
        let c: egt_core::design::Candidate =
            serde_json::from_str(candidate).map_err(|e| value_error(format!("candidate: {e}")))?;
        let spec = guard(|| {
            Ok(self
                .search
                .candidate_spec(&c)
                .map_err(egt_core::Error::from)?)
        })?;
        serde_json::to_string(&spec).map_err(|e| value_error(e.to_string()))
    }

    /// Partitions' results (`run`'s, as JSON text) merged as one search's by
    /// the core (`design::merge`): ranked together, counts summed, `top` kept.
    fn merge<'py>(&self, py: Python<'py>, results: &str, top: usize) -> Result<Bound<'py, PyAny>> {
        #[derive(serde::Deserialize)]
        struct Part {
            candidates: Vec<egt_core::design::Candidate>,
            stats: egt_core::design::Stats,
        }
        let parts: Vec<Part> =
            serde_json::from_str(results).map_err(|e| value_error(format!("results: {e}")))?;
        let (candidates, stats) = egt_core::design::merge(
            parts.into_iter().map(|p| (p.candidates, p.stats)).collect(),
            top,
        );
        guard(|| {
            to_py(
                py,
                &serde_json::json!({ "candidates": candidates, "stats": stats }),
            )
        })
    }
}

/// The texts a search is built from: `(text, format, source, base_text,
/// base_format, base_source)`, the base found by the core's rule
/// (`SynthSpec::base_path`: relative to the search spec's file; to the
/// working directory for text). Give `path` (a file) or `text` (with `format`).
#[pyfunction]
#[pyo3(signature = (path = None, text = None, format = None))]
pub fn search_inputs(
    path: Option<&str>,
    text: Option<String>,
    format: Option<&str>,
) -> Result<(String, String, String, String, String, String)> {
    let name = |f: Format| match f {
        Format::Toml => "toml".to_string(),
        Format::Json => "json".to_string(),
    };
    guard(|| {
        let (text, source, file) = match (path, text) {
            (Some(p), None) => {
                let t = std::fs::read_to_string(p)
                    .map_err(|e| crate::errors::value_error(format!("reading {p}: {e}")))?;
                (t, p.to_string(), Some(Path::new(p)))
            }
            (None, Some(t)) => (t, "<string>".to_string(), None),
            _ => {
                return Err(crate::errors::value_error(
                    "give `path` or `text`, not both",
                ));
            }
        };
        let format = match format {
            Some(f) => format_of(f)?,
            None if file.is_some() => Format::from_path(&source),
            None => Format::sniff(&text),
        };
        let spec = SynthSpec::from_str(&text, format, &source)?;
        if Synthesis::is_concept(&spec) {
            // A concept search builds its trains: no base to read.
            return Ok((
                text,
                name(format),
                source,
                String::new(),
                "toml".into(),
                String::new(),
            ));
        }
        let base = spec.base_path(file);
        let base_source = base.display().to_string();
        let base_text = std::fs::read_to_string(&base)
            .map_err(|e| egt_core::Error::invalid("base", format!("reading {base_source}: {e}")))?;
        Ok((
            text,
            name(format),
            source,
            base_text,
            name(Format::from_path(&base_source)),
            base_source,
        ))
    })
}

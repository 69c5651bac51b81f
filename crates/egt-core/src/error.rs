//! Typed errors. Every variant names the links, pairs, circuits or spec fields
//! involved, so a user who wrote a wrong spec is told what is wrong and where.

use std::fmt;

/// Result alias for the core.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Every failure the core can report.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The text is not valid TOML/JSON, or a value has the wrong type.
    #[error("{0}")]
    Syntax(SyntaxError),
    /// The spec parses but says something invalid at `path`.
    #[error("{path}: {kind}")]
    Spec {
        /// Field path, e.g. `gears[2].teeth[0]`.
        path: String,
        /// What is wrong there.
        kind: SpecErrorKind,
    },
    /// The graph is not a valid geared kinematic chain (paper section 2).
    #[error("topology: {0}")]
    Topology(TopologyError),
    /// The analysis was asked something the train cannot answer as posed.
    #[error("{0}")]
    Analysis(AnalysisError),
    /// A transmission's gear state cannot be analysed as written.
    #[error("{0}")]
    Transmission(TransmissionError),
}

// Written out rather than `#[from]`, which would also make the inner error the
// `source()` and print every message twice in an error chain.
impl From<SyntaxError> for Error {
    fn from(e: SyntaxError) -> Self {
        Error::Syntax(e)
    }
}

impl From<TopologyError> for Error {
    fn from(e: TopologyError) -> Self {
        Error::Topology(e)
    }
}

impl From<AnalysisError> for Error {
    fn from(e: AnalysisError) -> Self {
        Error::Analysis(e)
    }
}

impl From<TransmissionError> for Error {
    fn from(e: TransmissionError) -> Self {
        Error::Transmission(e)
    }
}

impl Error {
    /// The same error with the hint of a missing-data refusal replaced: how a
    /// front end (the CLI, Python) names its own flag or keyword for the data.
    #[must_use]
    pub fn with_hint(self, hint: &str) -> Self {
        match self {
            Error::Analysis(AnalysisError::MissingData { what, analysis, .. }) => {
                Error::Analysis(AnalysisError::MissingData {
                    what,
                    analysis,
                    hint: hint.into(),
                })
            }
            e => e,
        }
    }

    /// A spec error at `path`.
    pub fn spec(path: impl Into<String>, kind: SpecErrorKind) -> Self {
        Error::Spec {
            path: path.into(),
            kind,
        }
    }

    /// A short code for the error, stable across versions: callers (the
    /// CLI's JSON errors, Python's `kind`, batch row errors) branch on it.
    pub fn code(&self) -> &'static str {
        match self {
            Error::Syntax(_) => "syntax",
            Error::Spec { kind, .. } => match kind {
                SpecErrorKind::UnknownLink { .. } => "unknown_link",
                SpecErrorKind::DuplicateLink { .. } => "duplicate_link",
                SpecErrorKind::Duplicate { .. } => "duplicate",
                SpecErrorKind::SelfLoop { .. } => "self_loop",
                SpecErrorKind::InvalidTeeth { .. } => "invalid_teeth",
                SpecErrorKind::NonFinite { .. } => "non_finite",
                SpecErrorKind::OutOfRange { .. } => "out_of_range",
                SpecErrorKind::Missing { .. } => "missing",
                _ => "invalid",
            },
            Error::Topology(t) => match t {
                TopologyError::Disconnected { .. } => "disconnected",
                TopologyError::NoTurningPath { .. } => "no_turning_path",
                TopologyError::RevoluteCycle { .. } => "revolute_cycle",
                TopologyError::CircuitCount { .. } => "circuit_count",
                TopologyError::NoTransferVertex { .. } => "no_transfer_vertex",
                TopologyError::AmbiguousTransferVertex { .. } => "ambiguous_transfer_vertex",
                TopologyError::NonPlanar { .. } => "non_planar",
                TopologyError::NoMobility { .. } => "no_mobility",
                TopologyError::Locked { .. } => "locked",
                TopologyError::Redundant { .. } => "redundant",
                TopologyError::Fractionated { .. } => "fractionated",
                TopologyError::FreeLinks { .. } => "free_links",
            },
            Error::Analysis(a) => a.code(),
            Error::Transmission(t) => t.code(),
        }
    }

    /// The field path (spec errors, and syntax errors where known) and the
    /// line and column (syntax errors) of the error, for machine-readable reports.
    pub fn location(&self) -> (Option<&str>, Option<(usize, usize)>) {
        match self {
            Error::Syntax(s) => (s.path.as_deref(), Some((s.line, s.column))),
            Error::Spec { path, .. } => (Some(path.as_str()), None),
            _ => (None, None),
        }
    }

    /// An `Invalid` spec error at `path` with a message.
    pub fn invalid(path: impl Into<String>, message: impl Into<String>) -> Self {
        Error::spec(
            path,
            SpecErrorKind::Invalid {
                message: message.into(),
            },
        )
    }
}

/// A syntax or type error, located by line and column (1-based).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub struct SyntaxError {
    /// File name, or `<stdin>` / `<string>`.
    pub source_name: String,
    /// 1-based line.
    pub line: usize,
    /// 1-based column.
    pub column: usize,
    /// Field path where the error was found, when known.
    pub path: Option<String>,
    /// The parser's message.
    pub message: String,
}

impl fmt::Display for SyntaxError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}: ", self.source_name, self.line, self.column)?;
        if let Some(p) = &self.path {
            write!(f, "at `{p}`: ")?;
        }
        write!(f, "{}", self.message)
    }
}

/// What is wrong at a spec path.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SpecErrorKind {
    /// A name that no link has.
    #[error("unknown link `{name}`{}", suggestion.as_ref().map(|s| format!(" (did you mean `{s}`?)")).unwrap_or_default())]
    UnknownLink {
        /// The name written.
        name: String,
        /// The closest declared name, if any is close.
        suggestion: Option<String>,
    },
    /// A link declared twice.
    #[error("link `{name}` is declared twice")]
    DuplicateLink {
        /// The name.
        name: String,
    },
    /// Two pairs (or elements, or states) join the same links / carry the same name.
    #[error("duplicate of {first} ({what})")]
    Duplicate {
        /// Path of the earlier occurrence.
        first: String,
        /// What is duplicated.
        what: String,
    },
    /// A pair joining a link to itself.
    #[error("pair joins link `{link}` to itself")]
    SelfLoop {
        /// The link.
        link: String,
    },
    /// A tooth count that is zero, negative or past [`MAX_TEETH`].
    #[error("tooth count must be an integer from 1 to {MAX_TEETH}, got {value}")]
    InvalidTeeth {
        /// The value written.
        value: i64,
    },
    /// NaN or infinity.
    #[error("value must be finite, got {value}")]
    NonFinite {
        /// The value written.
        value: f64,
    },
    /// A number outside its range.
    #[error("{} is out of range: {expected}", readable(*value))]
    OutOfRange {
        /// The value written.
        value: f64,
        /// The allowed range, in words.
        expected: String,
    },
    /// A required datum is absent.
    #[error("missing {what}")]
    Missing {
        /// What is missing.
        what: String,
    },
    /// Anything else, in words.
    #[error("{message}")]
    Invalid {
        /// The explanation.
        message: String,
    },
}

/// Violations of the topological properties of geared kinematic chains (paper section 2).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum TopologyError {
    /// Some links are not joined to the frame by any pair.
    #[error("links {} are not connected to the frame", list(links))]
    Disconnected {
        /// The unreachable links.
        links: Vec<String>,
    },
    /// Some links are held only by gear meshes: deleting the gear edges does not leave a spanning tree.
    #[error(
        "links {} have no chain of turning pairs to the frame (deleting the gear edges must leave a spanning tree)",
        list(links)
    )]
    NoTurningPath {
        /// The links without a turning-pair path to the frame.
        links: Vec<String>,
    },
    /// The turning pairs close a loop: deleting gear edges leaves a cycle, not a tree.
    #[error(
        "turning pairs close a loop through {} (deleting the gear edges must leave a tree)",
        list(links)
    )]
    RevoluteCycle {
        /// Links on the loop.
        links: Vec<String>,
    },
    /// L_ind differs from the number of gear pairs j_G.
    #[error("{independent} independent circuits but {gears} gear pairs (L_ind = j_G must hold)")]
    CircuitCount {
        /// Independent circuits L_ind.
        independent: usize,
        /// Gear pairs j_G.
        gears: usize,
    },
    /// The fundamental circuit of a gear pair has no transfer vertex (section 2.1).
    #[error(
        "gear pair {pair}: its fundamental circuit has turning pairs at levels {} — a transfer vertex needs exactly two levels meeting at one link",
        list(levels)
    )]
    NoTransferVertex {
        /// The gear pair.
        pair: String,
        /// The levels met on its circuit, in path order.
        levels: Vec<String>,
    },
    /// The fundamental circuit of a gear pair has several candidate transfer vertices.
    #[error(
        "gear pair {pair}: its fundamental circuit has several transfer vertices {}",
        list(candidates)
    )]
    AmbiguousTransferVertex {
        /// The gear pair.
        pair: String,
        /// The candidate links.
        candidates: Vec<String>,
    },
    /// The graph is not planar.
    #[error(
        "the graph is not planar (a geared kinematic chain's graph must be): links {} form a subdivision of K5 or K3,3",
        list(links)
    )]
    NonPlanar {
        /// The links of a Kuratowski subgraph (empty past the size where it is searched).
        links: Vec<String>,
    },
    /// Gruebler-Kutzbach gives no mobility.
    #[error("Gruebler-Kutzbach degree of freedom is {dof}: the chain cannot move")]
    NoMobility {
        /// The computed F.
        dof: i64,
    },
    /// A locked sub-chain: links that cannot turn relative to each other for any ratios (eq. 1).
    #[error(
        "locked sub-chain: links {} cannot turn relative to each other (eq. 1)",
        list(links)
    )]
    Locked {
        /// Links of the locked sub-chain.
        links: Vec<String>,
    },
    /// Gear pairs whose circuits repeat a constraint already imposed (generic rank deficiency).
    #[error(
        "redundant gear pairs {}: their Willis equations are dependent for any ratios (an over-constrained sub-chain, eq. 1)",
        list(pairs)
    )]
    Redundant {
        /// The dependent pairs.
        pairs: Vec<String>,
    },
    /// The mobility is fractionated: a link separates sub-chains that move independently.
    #[error(
        "fractionated mobility at link `{link}`: it separates sub-chains {} that move independently (eq. 1)",
        parts.iter().map(|p| list(p)).collect::<Vec<_>>().join(" and ")
    )]
    Fractionated {
        /// The cut link.
        link: String,
        /// The separated groups of links.
        parts: Vec<Vec<String>>,
    },
    /// Links that turn freely: their turning pairs lie on no fundamental circuit.
    #[error(
        "links {} turn freely: they are on no fundamental circuit (fractionated mobility)",
        list(links)
    )]
    FreeLinks {
        /// The free links.
        links: Vec<String>,
    },
}

/// Analyses asked something the train cannot answer as posed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum AnalysisError {
    /// The number of prescribed quantities does not match the DOF.
    #[error("the train has {dof} degree(s) of freedom but {given} {what} were given")]
    WrongInputCount {
        /// The train's DOF.
        dof: usize,
        /// How many were given.
        given: usize,
        /// What was counted (e.g. `input speeds`).
        what: String,
    },
    /// The frame cannot be an input.
    #[error("link `{link}` is the frame; its speed is zero by definition")]
    FrameInput {
        /// The frame's name.
        link: String,
    },
    /// The chosen inputs leave links undetermined.
    #[error(
        "the inputs do not determine the train: links {} are left free",
        list(free)
    )]
    Underdetermined {
        /// Links whose speed is not fixed by the inputs.
        free: Vec<String>,
    },
    /// The chosen inputs over-determine the train inconsistently.
    #[error(
        "the inputs conflict: the equations of {} cannot all hold",
        list(conflicting)
    )]
    Inconsistent {
        /// The conflicting equations (gear pairs / inputs).
        conflicting: Vec<String>,
    },
    /// A system is exactly singular.
    #[error("{what} is singular: {detail}")]
    Singular {
        /// The system.
        what: String,
        /// Why, in words.
        detail: String,
    },
    /// A system is too ill-conditioned for a trustworthy answer.
    #[error(
        "{what} is ill-conditioned (condition number {condition:.3e} > {threshold:.0e}); the result would not be trustworthy"
    )]
    IllConditioned {
        /// The system.
        what: String,
        /// Estimated 1-norm condition number.
        condition: f64,
        /// The refusal threshold.
        threshold: f64,
    },
    /// A datum this analysis needs is absent.
    #[error("{what} is needed for {analysis} but missing ({hint})")]
    MissingData {
        /// What is missing.
        what: String,
        /// The analysis that needs it.
        analysis: String,
        /// Where to give it.
        hint: String,
    },
    /// A link is given twice where each may appear once.
    #[error("link `{link}` is listed twice among the {role}")]
    RepeatedLink {
        /// The link.
        link: String,
        /// Where (e.g. `input links`).
        role: String,
    },
    /// More constraint rows than coordinates.
    #[error("{constraints} constraints on {coordinates} coordinates: over-constrained")]
    OverConstrained {
        /// Constraint rows (Willis and element rows).
        constraints: usize,
        /// Coordinates.
        coordinates: usize,
    },
    /// A quantity is not finite, or would overflow in the computation.
    #[error("{what} is not finite: {detail}")]
    NonFinite {
        /// The quantity.
        what: String,
        /// Why, in words.
        detail: String,
    },
    /// The reduced mass matrix has a negative direction.
    #[error(
        "the reduced mass matrix is indefinite (eigenvalue {low:.3e} against {top:.3e}); inertias and masses must be non-negative"
    )]
    IndefiniteMass {
        /// Its most negative eigenvalue.
        low: f64,
        /// Its largest eigenvalue.
        top: f64,
    },
    /// An iteration of a time integrator did not converge.
    #[error("{what} did not converge at t = {t:e}")]
    NotConverged {
        /// The iteration.
        what: String,
        /// The time.
        t: f64,
    },
    /// No consistent direction of power flow exists through the lossy meshes.
    #[error(
        "no consistent direction of power flow exists through the lossy meshes: the train self-locks under these loads (or the driving torque cannot overcome friction)"
    )]
    SelfLocking,
    /// The direction search did not settle and enumeration would be too large.
    #[error(
        "power-flow directions did not settle and {meshes} loaded lossy meshes are too many to enumerate (at most {limit})"
    )]
    DirectionsUndecided {
        /// Loaded lossy meshes.
        meshes: usize,
        /// The enumeration limit.
        limit: usize,
    },
    /// A train too large for an analysis that holds dense matrices (or exact
    /// rationals) of its size: refused before allocating.
    #[error(
        "{analysis} of a train of {links} links needs about {mib} MiB of dense matrices; the limit is {limit_mib} MiB, at most {most} links ({what})"
    )]
    TooLarge {
        /// The analysis refused.
        analysis: String,
        /// Links in the train.
        links: usize,
        /// Estimated MiB it would take.
        mib: usize,
        /// The limit in MiB.
        limit_mib: usize,
        /// The largest train within the limit.
        most: usize,
        /// What is still available for a train this large, in words.
        what: String,
    },
    /// Work past a documented budget (steps of a simulation, leaves of a
    /// search, rows of a grid), refused with the estimate and the flag or
    /// field that raises it; never taken for a singular system.
    #[error("{what}: {estimate} is past the budget of {limit}; {raise}")]
    Budget {
        /// The work refused, in words.
        what: String,
        /// The estimate or the count reached, in words.
        estimate: String,
        /// The budget, in words.
        limit: String,
        /// How to raise the budget (the flag or field).
        raise: String,
    },
    /// A solver could not allocate its working memory (reported instead of
    /// aborting; never taken for a singular system).
    #[error("{what} could not be computed: {detail}")]
    OutOfMemory {
        /// The solve.
        what: String,
        /// What failed, in the solver's words.
        detail: String,
    },
    /// The mass matrix varies with the configuration, which this analysis cannot follow.
    #[error(
        "{analysis} needs a constant mass matrix, but {} ride(s) on nested carriers whose arms do not balance, so [M] varies with the carrier angles; use the single-scenario dynamics with [analysis] angles",
        list(links)
    )]
    ConfigurationDependent {
        /// The floating links that couple the carriers.
        links: Vec<String>,
        /// The analysis.
        analysis: String,
    },
}

/// The largest tooth count accepted: far past any wheel, small enough that
/// products of many counts stay exact and fast.
pub const MAX_TEETH: i64 = 1_000_000;

/// Refuse results that overflowed: finite inputs whose results are not
/// finite (a speed or an inertia near the largest double) get a typed error
/// naming what overflowed, never an inf or NaN printed as a result.
///
/// # Errors
/// [`AnalysisError::NonFinite`] naming `what`.
pub fn finite_results<'a>(what: &str, values: impl IntoIterator<Item = &'a f64>) -> Result<()> {
    if values.into_iter().all(|v| v.is_finite()) {
        return Ok(());
    }
    Err(AnalysisError::NonFinite {
        what: what.to_string(),
        detail: "a result overflowed: the inputs exceed the range of double precision".into(),
    }
    .into())
}

impl AnalysisError {
    /// The stable code of [`Error::code`].
    pub fn code(&self) -> &'static str {
        match self {
            AnalysisError::WrongInputCount { .. } => "wrong_input_count",
            AnalysisError::FrameInput { .. } => "frame_input",
            AnalysisError::Underdetermined { .. } => "underdetermined",
            AnalysisError::Inconsistent { .. } => "inconsistent",
            AnalysisError::Singular { .. } => "singular",
            AnalysisError::IllConditioned { .. } => "ill_conditioned",
            AnalysisError::MissingData { .. } => "missing_data",
            AnalysisError::RepeatedLink { .. } => "repeated_link",
            AnalysisError::OverConstrained { .. } => "over_constrained",
            AnalysisError::NonFinite { .. } => "non_finite_result",
            AnalysisError::IndefiniteMass { .. } => "indefinite_mass",
            AnalysisError::NotConverged { .. } => "not_converged",
            AnalysisError::SelfLocking => "self_locking",
            AnalysisError::DirectionsUndecided { .. } => "directions_undecided",
            AnalysisError::ConfigurationDependent { .. } => "configuration_dependent",
            AnalysisError::TooLarge { .. } => "too_large",
            AnalysisError::OutOfMemory { .. } => "out_of_memory",
            AnalysisError::Budget { .. } => "budget",
        }
    }
}

/// A number as a person reads it: plain, or in exponent form when tiny or huge.
fn readable(v: f64) -> String {
    if v != 0.0 && !(1e-4..1e9).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// Names listed in one message at most; the rest are counted.
const LISTED_NAMES: usize = 12;

fn list(items: &[String]) -> String {
    let quoted: Vec<String> = items
        .iter()
        .take(LISTED_NAMES)
        .map(|s| format!("`{s}`"))
        .collect();
    let more = items.len().saturating_sub(LISTED_NAMES);
    if more > 0 {
        format!("{} and {more} more", quoted.join(", "))
    } else {
        quoted.join(", ")
    }
}

/// The declared name closest to `name`, if it is close enough to be a typo.
pub fn suggest<'a>(name: &str, candidates: impl IntoIterator<Item = &'a str>) -> Option<String> {
    let mut best: Option<(usize, &str)> = None;
    for c in candidates {
        let d = edit_distance(name, c);
        // A typo, not a different name: at most a third of the letters, never all of them.
        if d <= (name.len() / 3).max(1) && d < name.len() && best.is_none_or(|(bd, _)| d < bd) {
            best = Some((d, c));
        }
    }
    best.map(|(_, c)| c.to_string())
}

fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut cur = vec![i + 1; b.len() + 1];
        for (j, cb) in b.iter().enumerate() {
            cur[j + 1] = (prev[j] + usize::from(ca != *cb))
                .min(prev[j + 1] + 1)
                .min(cur[j] + 1);
        }
        prev = cur;
    }
    prev[b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn suggests_close_names_only() {
        assert_eq!(
            suggest("sunn", ["sun", "ring", "carrier"]),
            Some("sun".into())
        );
        assert_eq!(suggest("xyzzy", ["sun", "ring"]), None);
        assert_eq!(suggest("x", ["f", "sun"]), None);
        assert_eq!(
            suggest("carier", ["carrier", "sun"]),
            Some("carrier".into())
        );
    }
}

/// Why a gear state cannot be analysed as written. Every variant names the state.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum TransmissionError {
    /// The spec has no `[transmission]` section, or it lists no states.
    #[error(
        "no gear states: give `[transmission]` with `input`, `output` and `[transmission.states]`"
    )]
    NoStates,
    /// A state name that the spec does not define.
    #[error("unknown gear state `{state}`{}", suggestion.as_ref().map(|s| format!(" (did you mean `{s}`?)")).unwrap_or_default())]
    UnknownState {
        /// The name asked for.
        state: String,
        /// The closest defined name, if close.
        suggestion: Option<String>,
    },
    /// The engaged elements leave more than one DOF.
    #[error(
        "gear state `{state}` leaves {dof} degrees of freedom: with the input held, links {} can still turn; engage another element",
        list(free)
    )]
    Underconstrained {
        /// The state.
        state: String,
        /// Its DOF.
        dof: usize,
        /// Links not determined by the input speed.
        free: Vec<String>,
    },
    /// The engaged elements leave no DOF: the train is tied up.
    #[error(
        "gear state `{state}` locks the train (0 degrees of freedom): elements {} together tie it up",
        list(elements)
    )]
    Locked {
        /// The state.
        state: String,
        /// The engaged elements.
        elements: Vec<String>,
    },
    /// Some engaged elements impose constraints already imposed by the others
    /// (and by the gear pairs): their torques are statically indeterminate.
    #[error(
        "gear state `{state}`: elements {} are redundant: their constraints are linearly dependent{}, so their torques are statically indeterminate (the state has {dof} degree(s) of freedom)",
        list(elements),
        if gears.is_empty() { String::new() } else { format!(" together with gear pairs {}", list(gears)) }
    )]
    Redundant {
        /// The state.
        state: String,
        /// Engaged elements in a dependent set of rows.
        elements: Vec<String>,
        /// Gear pairs whose Willis rows are in the same dependent set.
        gears: Vec<String>,
        /// The state's DOF.
        dof: usize,
    },
    /// The state holds the input while other links turn.
    #[error(
        "gear state `{state}` holds the input `{input}` at rest (links {} move without it)",
        list(moving)
    )]
    InputHeld {
        /// The state.
        state: String,
        /// The input link.
        input: String,
        /// The links that move in the state's one free motion.
        moving: Vec<String>,
    },
    /// The state holds the output while the input turns: no finite ratio.
    #[error(
        "gear state `{state}` holds the output `{output}` at rest while the input turns: no finite ratio"
    )]
    OutputHeld {
        /// The state.
        state: String,
        /// The output link.
        output: String,
    },
    /// An analysis of a valid state failed.
    #[error("gear state `{state}`: {cause}")]
    InState {
        /// The state.
        state: String,
        /// What failed.
        cause: Box<Error>,
    },
}

impl TransmissionError {
    /// The stable code of [`crate::Error::code`].
    pub fn code(&self) -> &'static str {
        match self {
            TransmissionError::NoStates => "no_states",
            TransmissionError::UnknownState { .. } => "unknown_state",
            TransmissionError::Underconstrained { .. } => "underconstrained",
            TransmissionError::Locked { .. } => "locked_state",
            TransmissionError::Redundant { .. } => "redundant_elements",
            TransmissionError::InputHeld { .. } => "input_held",
            TransmissionError::OutputHeld { .. } => "output_held",
            TransmissionError::InState { cause, .. } => cause.code(),
            #[allow(unreachable_patterns)]
            _ => "transmission",
        }
    }
}

/// Why a search cannot run. Each variant names the offending field.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DesignError {
    /// `sets.<name>` is not a planetary set of the base train.
    #[error("sets.{0}: no simple planetary set of that name in the base train")]
    UnknownSet(String),
    /// `targets.ratios.<state>` is not a gear state of the base train.
    #[error("targets.ratios.{0}: no gear state of that name in the base train")]
    UnknownState(String),
    /// A field has an impossible value.
    #[error("{field}: {message}")]
    Invalid {
        /// The field.
        field: String,
        /// What is wrong.
        message: String,
    },
    /// The base train or a candidate failed egt's own analysis.
    #[error(transparent)]
    Egt(#[from] Error),
}

/// A design error as one of egt's typed errors (so the CLI's exit codes,
/// JSON error codes and Python's exceptions cover it): the base train's and
/// candidates' own errors as they are; a field, set or state of the search
/// spec as a spec error naming it (exit 2).
impl From<DesignError> for Error {
    fn from(e: DesignError) -> Self {
        match e {
            DesignError::Egt(e) => e,
            DesignError::UnknownSet(name) => Error::invalid(
                format!("sets.{name}"),
                "no simple planetary set of that name in the base train",
            ),
            DesignError::UnknownState(name) => Error::invalid(
                format!("targets.ratios.{name}"),
                "no gear state of that name in the base train",
            ),
            DesignError::Invalid { field, message } => Error::invalid(field, message),
        }
    }
}

//! Argument groups and parsers that several commands share (the spec and
//! output formats, loads, input speeds, torque curves, `LINK=VALUE` pairs), and their conversion into the
//! core's requests. The defaults themselves are decided in the core
//! (`DynamicsRequest::resolve`, `SimulationRequest::resolve`).

use std::path::PathBuf;

use anyhow::Context;
use clap::ValueEnum;
use egt_core::model::train::Curve;
use egt_core::numerics::exact::{self, Q};
use egt_core::{DynamicsRequest, LinkId, LoadOverrides, MassMatrix, SpeedInput, Train};

/// How results are printed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, ValueEnum)]
pub enum OutputFormat {
    /// Aligned, readable tables.
    #[default]
    Table,
    /// One JSON document (names, not ids; exact values as strings like "162/77").
    Json,
}

/// How the commands that integrate in time (`egt simulate`, `egt shift-sim`)
/// print their result.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, ValueEnum)]
pub enum SeriesFormat {
    /// A summary as a table (`egt simulate` adds a table of sampled steps).
    #[default]
    Table,
    /// The whole result as JSON, every stored sample included.
    Json,
    /// The time series as CSV, a row per stored sample: t, each moving link's
    /// speed, then `egt simulate`'s drift, energy, work and power, or `egt
    /// shift-sim`'s slip, torque and dissipated energy of each element, output
    /// torque, energy residual and DOF.
    Csv,
}

/// The text format of a spec.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SpecFormat {
    /// TOML.
    Toml,
    /// JSON.
    Json,
}

/// An output format flag: [`OutputFormat`], or a command's own choices.
pub trait FormatArg: ValueEnum + Default + Clone + Send + Sync + 'static {}
impl<F: ValueEnum + Default + Clone + Send + Sync + 'static> FormatArg for F {}

/// Arguments shared by every command that reads a spec: the spec, its
/// format, and the output format `F` (a table or JSON, or a command's own
/// choices, such as the CSV of `egt simulate` and `egt shift-sim`), whose
/// default is the table.
#[derive(Debug, Clone, clap::Args)]
pub struct SpecArgs<F: FormatArg = OutputFormat> {
    /// The spec file (TOML or JSON), or `-` for standard input.
    #[arg(value_name = "SPEC")]
    pub spec: PathBuf,
    /// Spec format; by default from the extension (`.json` is JSON), or sniffed on stdin.
    #[arg(long, value_enum, value_name = "FORMAT")]
    pub spec_format: Option<SpecFormat>,
    /// Output format.
    #[arg(long, value_enum, default_value_t)]
    pub format: F,
}

/// Loads, accelerations and driving links, from flags or the spec's `[analysis]`.
#[derive(Debug, Clone, clap::Args)]
pub struct LoadArgs {
    /// A known applied torque, `LINK=TORQUE` (positive along positive rotation;
    /// a resisting load is negative). Repeatable. Default: `[analysis] torques`.
    #[arg(long = "torque", value_name = "LINK=TORQUE", value_parser = parse_pair)]
    pub torques: Vec<(String, f64)>,
    /// A prescribed angular acceleration, `LINK=ACCEL`, one per DOF. Default:
    /// `[analysis] accelerations`; none means the static case.
    #[arg(long = "accel", value_name = "LINK=ACCEL", value_parser = parse_pair)]
    pub accelerations: Vec<(String, f64)>,
    /// A link whose driving torque is unknown, one per DOF. Default: `[analysis] driving`.
    #[arg(long = "driving", value_name = "LINK")]
    pub driving: Vec<String>,
}

pub fn parse_pair(s: &str) -> Result<(String, f64), String> {
    let (l, v) = s
        .split_once('=')
        .ok_or_else(|| format!("expected LINK=VALUE, got `{s}`"))?;
    let v: f64 = v
        .trim()
        .parse()
        .map_err(|_| format!("`{}` is not a number", v.trim()))?;
    if !v.is_finite() {
        return Err(format!("`{s}`: value must be finite"));
    }
    Ok((l.trim().to_string(), v))
}

/// The dynamics request from the flags, else the spec.
///
/// # Errors
/// Unknown link names (spec errors, with the flag named); no driving links.
pub fn load_request(train: &Train, a: &LoadArgs) -> anyhow::Result<DynamicsRequest> {
    let resolve = |name: &str, flag: &str| -> anyhow::Result<LinkId> {
        Ok(train.resolve(name, &format!("--{flag} {name}"))?)
    };
    let pairs =
        |given: &[(String, f64)], flag: &str| -> anyhow::Result<Option<Vec<(LinkId, f64)>>> {
            if given.is_empty() {
                return Ok(None);
            }
            let v = given
                .iter()
                .map(|(l, v)| Ok((resolve(l, flag)?, *v)))
                .collect::<anyhow::Result<_>>()?;
            Ok(Some(v))
        };
    let driving = if a.driving.is_empty() {
        None
    } else {
        Some(
            a.driving
                .iter()
                .map(|l| resolve(l, "driving"))
                .collect::<anyhow::Result<_>>()?,
        )
    };
    let over = LoadOverrides {
        torques: pairs(&a.torques, "torque")?,
        accelerations: pairs(&a.accelerations, "accel")?,
        driving,
        extras: Vec::new(),
    };
    DynamicsRequest::resolve(train, &over).map_err(|e| {
        e.with_hint("give `--driving LINK` or `[analysis] driving`")
            .into()
    })
}

/// The mass matrix, only when the request needs it (non-zero accelerations).
pub fn mass_if_needed(train: &Train, req: &DynamicsRequest) -> anyhow::Result<Option<MassMatrix>> {
    train
        .mass_for(req)
        .context("the mass matrix (needed because accelerations are prescribed)")
}

/// One `--input LINK=SPEED`.
#[derive(Debug, Clone)]
pub struct InputArg {
    /// Link name.
    pub link: String,
    /// Exact speed.
    pub speed: Q,
}

pub fn parse_input(s: &str) -> Result<InputArg, String> {
    let (link, speed) = s
        .split_once('=')
        .ok_or_else(|| format!("expected LINK=SPEED, got `{s}`"))?;
    let link = link.trim();
    if link.is_empty() {
        return Err(format!("no link name in `{s}`"));
    }
    let (speed, _) = exact::parse_finite(speed).map_err(|e| format!("`{}`: {e}", speed.trim()))?;
    Ok(InputArg {
        link: link.to_string(),
        speed,
    })
}

/// A spec and its input speeds: `egt kinematics` and `egt power`.
#[derive(Debug, Clone, clap::Args)]
pub struct SpeedArgs {
    #[command(flatten)]
    pub spec: SpecArgs,
    /// An input speed, `LINK=SPEED` (rad/s or any unit; SPEED may be a fraction
    /// `p/q` or a decimal, read exactly). Repeat once per DOF. Default: the
    /// spec's `[analysis] speeds`.
    #[arg(short, long = "input", value_name = "LINK=SPEED", value_parser = parse_input)]
    pub inputs: Vec<InputArg>,
}

/// Inputs from `--input`, else from the spec's `[analysis] speeds`.
pub fn speed_inputs(train: &Train, args: &SpeedArgs) -> anyhow::Result<Vec<SpeedInput>> {
    if !args.inputs.is_empty() {
        return args
            .inputs
            .iter()
            .map(|a| {
                let link = train.resolve(&a.link, &format!("--input {}", a.link))?;
                Ok(SpeedInput {
                    link,
                    speed: exact::to_f64(&a.speed),
                    exact: Some(a.speed.clone()),
                })
            })
            .collect();
    }
    let given = &train.analysis().speeds;
    if given.is_empty() && train.dof() > 0 {
        let e = egt_core::AnalysisError::WrongInputCount {
            dof: train.dof(),
            given: 0,
            what: "input speeds".into(),
        };
        return Err(anyhow::Error::new(egt_core::Error::from(e))
            .context("no input speeds: give `--input LINK=SPEED` once per DOF, or `[analysis] speeds` in the spec"));
    }
    Ok(given
        .iter()
        .map(|(link, speed, exact_speed)| SpeedInput {
            link: *link,
            speed: *speed,
            exact: exact_speed.clone(),
        })
        .collect())
}

/// Choices shared by `egt stability` and `egt simulate`.
#[derive(Debug, Clone, clap::Args)]
pub struct ModelArgs {
    /// Replace the slope dT/dw of the curves on a link, `LINK=SLOPE`
    /// (repeatable), e.g. to find where a train turns unstable.
    #[arg(long = "slope", value_name = "LINK=SLOPE", value_parser = parse_pair)]
    pub slopes: Vec<(String, f64)>,
}

/// The spec's curves with the `--slope` overrides applied.
///
/// # Errors
/// Unknown links; a link without a curve.
pub fn curves(train: &Train, a: &ModelArgs) -> anyhow::Result<Vec<Curve>> {
    let mut curves = train.analysis().curves.clone();
    for (name, slope) in &a.slopes {
        let l = train.resolve(name, &format!("--slope {name}"))?;
        let mut found = false;
        for c in curves.iter_mut().filter(|c| c.link == l) {
            c.slope = *slope;
            found = true;
        }
        if !found {
            return Err(anyhow::Error::new(egt_core::Error::invalid(
                format!("--slope {name}"),
                format!("link `{name}` carries no curve; add it to [[analysis.curves]]"),
            )));
        }
    }
    Ok(curves)
}

/// Resolve `LINK=VALUE` flags.
pub fn resolve_pairs(
    train: &Train,
    pairs: &[(String, f64)],
    flag: &str,
) -> anyhow::Result<Vec<(LinkId, f64)>> {
    pairs
        .iter()
        .map(|(l, v)| Ok((train.resolve(l, &format!("--{flag} {l}"))?, *v)))
        .collect()
}

/// `I/K`: partition I (0-based) of K disjoint parts of a search (`--part`).
///
/// # Errors
/// Not two integers separated by `/`: a usage error naming `--part` (exit 2).
pub fn parse_part(text: &str) -> Result<(usize, usize), egt_core::Error> {
    let bad = |what: &str| {
        egt_core::Error::spec(
            "--part",
            egt_core::SpecErrorKind::Invalid {
                message: format!("`{text}`: {what}; expected I/K with 0 <= I < K, e.g. 0/4"),
            },
        )
    };
    let (i, k) = text.split_once('/').ok_or_else(|| bad("no `/`"))?;
    let i = i
        .trim()
        .parse()
        .map_err(|_| bad("I is not a whole number"))?;
    let k = k
        .trim()
        .parse()
        .map_err(|_| bad("K is not a whole number"))?;
    Ok((i, k))
}

//! `egt simulate SPEC --t-end T`: forward dynamics in reduced coordinates
//! (eq. 12, 25) under the spec's linearised torque-speed curves, from given
//! initial speeds, with the explicit RK4 or the L-stable implicit SDIRK2
//! integrator. Prints a summary and a sampled table, the whole time series as
//! JSON or CSV, and optionally an SVG plot of the link speeds.

mod plot;

use std::io::Write;
use std::path::PathBuf;

use anyhow::Context;
use egt_core::{
    LinearCurves, Method, ReducedDynamics, SimulationOverrides, SimulationRequest, Train,
};
use egt_views::simulation::{MeshOut, Report, build, equilibrium};

use crate::args::{ModelArgs, curves, parse_pair, resolve_pairs};
use crate::args::{SeriesFormat, SpecArgs};
use crate::input;
use crate::report::{self, Table};

/// Integrators, as flags.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum MethodArg {
    /// Classical explicit Runge-Kutta, order 4 (stable for |lambda| dt <= 2.785).
    Rk4,
    /// Two-stage L-stable SDIRK, order 2, Newton on the analytic Jacobian (stiff trains).
    Implicit,
}

/// Arguments of `egt simulate`.
#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub spec: SpecArgs<SeriesFormat>,
    #[command(flatten)]
    pub model: ModelArgs,
    /// End time [s]. Default: `[analysis.simulate] t_end`.
    #[arg(long, value_name = "T")]
    pub t_end: Option<f64>,
    /// Fixed step [s]. Default: `[analysis.simulate] dt`, else t_end / 1000.
    #[arg(long, value_name = "DT")]
    pub dt: Option<f64>,
    /// Integrator. Default: `[analysis.simulate] method`, else rk4.
    #[arg(long, value_enum)]
    pub method: Option<MethodArg>,
    /// An initial speed, `LINK=SPEED`, one per DOF (any independent links).
    /// Default: `[analysis.simulate] initial`, else `[analysis] speeds`.
    #[arg(short, long = "initial", value_name = "LINK=SPEED", value_parser = parse_pair)]
    pub initial: Vec<(String, f64)>,
    /// Store every N-th step (default: about 2000 samples).
    #[arg(long, value_name = "N")]
    pub every: Option<usize>,
    /// Write an SVG plot of the link speeds against time to FILE.
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
    /// Also report the constraint (Willis multiplier) and mesh torques at the
    /// end time, by inverse dynamics on the simulated state (eq. 6-11).
    #[arg(long)]
    pub reactions: bool,
}
/// Run `egt simulate`.
///
/// # Errors
/// Reading or validating the spec; unknown links, a bad method or step
/// (exit 2); missing data, singular systems, a blown-up solution (exit 1,
/// after the series up to the blow-up has been written); I/O.
pub fn run(args: &Args, out: &mut dyn Write) -> anyhow::Result<()> {
    let loaded = input::load(&args.spec)?;
    let train = &loaded.train;
    let ctx = || format!("{}: simulate", loaded.source);
    let req = request(train, args)?;
    let curves = curves(train, &args.model)?;
    let torque = LinearCurves::new(train, &curves)?;
    let initial = train.initial_speeds(&req).with_context(ctx)?;
    let mut dynamics = ReducedDynamics::new(train, &torque).with_context(ctx)?;
    let sim = dynamics
        .simulate(&initial, &req.options)
        .with_context(ctx)?;

    let (equilibrium, observed_rate) = equilibrium(train, &curves, &sim);
    let reactions = if args.reactions {
        let last = sim.samples.last().context("no samples")?;
        let r = dynamics
            .reactions(last.t, &last.speed)
            .with_context(|| format!("{}: reactions at t = {}", loaded.source, last.t))?;
        Some(
            r.meshes
                .iter()
                .map(|m| MeshOut {
                    gear: train.gears()[m.gear.index()].name.clone(),
                    multiplier: m.multiplier,
                    torque_i: m.torque_i,
                    torque_j: m.torque_j,
                    torque_carrier: m.torque_carrier,
                })
                .collect(),
        )
    } else {
        None
    };
    let report = build(
        train,
        &loaded.source,
        &sim,
        req.options.t_end,
        equilibrium,
        observed_rate,
        reactions,
    );
    if let Some(path) = &args.plot {
        let svg = plot::speeds_svg(
            train,
            &report::title(train, &loaded.source),
            &report.links_plotted(train),
            &sim,
            report.equilibrium.as_deref(),
        );
        std::fs::write(path, svg).with_context(|| format!("writing {}", path.display()))?;
    }
    match args.spec.format {
        SeriesFormat::Json => report::json(out, &report)?,
        SeriesFormat::Csv => write_csv(out, train, &report)?,
        SeriesFormat::Table => write_table(out, train, &loaded.source, &report)?,
    }
    if let Some(d) = &sim.diverged {
        let hint = match (sim.method, sim.rk4_step_limit) {
            (Method::Rk4, Some(limit)) if sim.dt > limit => format!(
                "; dt = {} exceeds RK4's stability limit {} (2.785 / |lambda_min|): use --method implicit or a smaller --dt",
                report::sci(sim.dt),
                report::sci(limit)
            ),
            _ => String::new(),
        };
        anyhow::bail!(
            "{}: the solution blew up after t = {}: {}{hint}",
            loaded.source,
            report::sci(d.t),
            d.reason
        );
    }
    Ok(())
}

/// The simulation request: flags first, then `[analysis.simulate]`.
///
/// # Errors
/// No end time; an unknown method name in the spec; unknown links.
fn request(train: &Train, args: &Args) -> anyhow::Result<SimulationRequest> {
    let initial = resolve_pairs(train, &args.initial, "initial")?;
    let over = SimulationOverrides {
        t_end: args.t_end,
        dt: args.dt,
        method: args.method.map(|m| match m {
            MethodArg::Rk4 => Method::Rk4,
            MethodArg::Implicit => Method::Implicit,
        }),
        every: args.every,
        initial: (!initial.is_empty()).then_some(initial),
    };
    SimulationRequest::resolve(train, &over).map_err(|e| match e {
        egt_core::Error::Spec { ref path, .. } if path == "analysis.simulate.t_end" => {
            anyhow::Error::new(e).context("give `--t-end T` or `[analysis.simulate] t_end`")
        }
        e => anyhow::Error::new(e),
    })
}

fn write_csv(out: &mut dyn Write, train: &Train, r: &Report) -> anyhow::Result<()> {
    let moving = r.links_plotted(train);
    let mut header = vec!["t".to_string()];
    header.extend(
        moving
            .iter()
            .map(|&l| format!("w_{}", report::csv_name(&r.links[l.index()]))),
    );
    header.extend(["drift", "energy", "work", "power"].map(String::from));
    writeln!(out, "{}", header.join(","))?;
    for s in &r.samples {
        let mut row = vec![format!("{:e}", s.t)];
        row.extend(moving.iter().map(|l| format!("{:e}", s.speeds[l.index()])));
        row.extend([s.drift, s.energy, s.work, s.power].map(|v| format!("{v:e}")));
        writeln!(out, "{}", row.join(","))?;
    }
    Ok(())
}

/// Rows shown in the table: about 20, evenly spaced, the last always.
const TABLE_ROWS: usize = 20;

fn write_table(out: &mut dyn Write, train: &Train, source: &str, r: &Report) -> anyhow::Result<()> {
    writeln!(out, "{}: simulation", report::title(train, source))?;
    writeln!(
        out,
        "degree of freedom: {}; method: {}; dt = {}; t_end = {}; steps: {}",
        r.dof,
        r.method,
        report::sci(r.dt),
        report::sci(r.t_end),
        r.steps
    )?;
    let eig: Vec<String> = r.eigenvalues.iter().map(|&v| report::sci(v)).collect();
    writeln!(
        out,
        "eigenvalues at the start [1/s]: {}; RK4 step limit: {}",
        eig.join(", "),
        r.rk4_step_limit.map_or_else(|| "none".into(), report::sci)
    )?;
    let moving = r.links_plotted(train);
    let mut headers = vec!["t [s]".to_string()];
    headers.extend(moving.iter().map(|&l| format!("w {}", r.links[l.index()])));
    headers.extend(["energy", "Willis drift"].map(String::from));
    let hs: Vec<&str> = headers.iter().map(String::as_str).collect();
    let cols: Vec<usize> = (0..hs.len()).collect();
    let mut t = Table::new(&hs).right(&cols);
    let n = r.samples.len();
    let stride = n.div_ceil(TABLE_ROWS).max(1);
    for (k, s) in r.samples.iter().enumerate() {
        if k % stride != 0 && k + 1 != n {
            continue;
        }
        let mut row = vec![report::sci(s.t)];
        row.extend(moving.iter().map(|l| report::float(s.speeds[l.index()])));
        row.push(report::sci(s.energy));
        row.push(format!("{:.1e}", s.drift));
        t.row(row);
    }
    t.write(out, 2)?;
    if let Some(e) = &r.equilibrium {
        let eq: Vec<String> = moving
            .iter()
            .map(|&l| format!("{} {}", r.links[l.index()], report::float(e[l.index()])))
            .collect();
        writeln!(out, "equilibrium of the curves: {}", eq.join(", "))?;
    }
    if let Some(rate) = r.observed_rate {
        writeln!(
            out,
            "deviation from the equilibrium over the second half grows at {} 1/s (largest eigenvalue {})",
            report::sci(rate),
            r.eigenvalues
                .first()
                .map_or_else(|| "-".into(), |&v| report::sci(v))
        )?;
    }
    writeln!(
        out,
        "checks: max Willis drift {:.2e}; energy balance |E - E0 - W| / max {:.2e}{}",
        r.max_drift,
        r.energy_error,
        if r.newton_iterations > 0 {
            format!("; Newton iterations {}", r.newton_iterations)
        } else {
            String::new()
        }
    )?;
    if let Some(m) = &r.reactions {
        writeln!(
            out,
            "constraint torques at t = {} (inverse dynamics, eq. 6-11):",
            report::sci(r.samples.last().map_or(0.0, |s| s.t))
        )?;
        let mut t = Table::new(&[
            "gear pair",
            "lambda",
            "on gear i",
            "on gear j",
            "on carrier",
        ])
        .right(&[1, 2, 3, 4]);
        for x in m {
            t.row(vec![
                x.gear.clone(),
                report::sci(x.multiplier),
                report::sci(x.torque_i),
                report::sci(x.torque_j),
                report::sci(x.torque_carrier),
            ]);
        }
        t.write(out, 2)?;
    }
    for w in &r.warnings {
        writeln!(out, "warning: {w}")?;
    }
    Ok(())
}

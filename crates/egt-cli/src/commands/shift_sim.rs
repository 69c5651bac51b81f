//! `egt shift-sim SPEC --from 2 --to 3 ...`: a gear change in time
//! (egt_core::shift_dynamics::ShiftSim). The off-going elements' capacities
//! fall and the on-coming ones' rise (`--off-going`/`--on-coming` for a single
//! swap, `--ramp NAME=RAMP` for each element of any change). The report gives the mode changes,
//! the shift time, the output-torque range, each element's dissipated
//! energy, and the torque and inertia phases with the shift-quality measures
//! (dip, overshoot, oscillation after the lock, jerk, the largest step,
//! each element's peak power). `--format json` adds every sample,
//! `--format csv` gives the time series, and `--plot FILE` writes the shift
//! plot: link speeds, element torques and output torque against time, with
//! the phases shaded and the dip and the overshoot marked.

use std::io::Write;
use std::path::PathBuf;

use anyhow::Context;
use egt_core::Train;
use egt_core::shift_dynamics::{
    AtTime, Capacity, FrictionLaw, InputTorque, OutputShaft, ShiftMethod, ShiftResult, ShiftSim,
};

use crate::args::{SeriesFormat, SpecArgs};
use crate::input;
use crate::report::{self, Table};
use crate::svg::{
    Band, GAP, Line, Mark, PLOT_H, Panel, TOP, bands, legend, marks, panel, plain_lines,
};

/// The integrator, as on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum MethodArg {
    /// Explicit Bogacki–Shampine, implicit from where a stiff mode limits its steps.
    Auto,
    /// Explicit Bogacki–Shampine 3(2) throughout.
    Explicit,
    /// Extrapolated linearly implicit Euler throughout.
    Implicit,
}

/// Arguments of `egt shift-sim`.
#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub spec: SpecArgs<SeriesFormat>,
    /// Run the spec's `[[shift]]` of this name: its gears, operating point
    /// and ramps, instead of the flags that define a shift (`--from` to
    /// `--t-end`, which it excludes); the tolerances, `--method`,
    /// `--max-steps` and the outputs still apply.
    #[arg(long, value_name = "NAME")]
    pub shift: Option<String>,
    /// The gear before the shift (a state of `[transmission.states]`).
    #[arg(long, required_unless_present = "shift", conflicts_with = "shift")]
    pub from: Option<String>,
    /// The gear after the shift. The elements of `--from` not in `--to`
    /// release, those of `--to` not in `--from` apply (one or more each way:
    /// single swaps, skip shifts, double swaps); the others stay locked.
    #[arg(long, required_unless_present = "shift", conflicts_with = "shift")]
    pub to: Option<String>,
    /// Input speed at t = 0 [rad/s]; the train starts in the `--from` gear's steady motion.
    #[arg(
        long,
        value_name = "W",
        required_unless_present = "shift",
        conflicts_with = "shift"
    )]
    pub input_speed: Option<f64>,
    /// Constant input torque [N m].
    #[arg(
        long,
        value_name = "T",
        conflicts_with_all = ["torque_table", "shift"],
        required_unless_present_any = ["torque_table", "shift"]
    )]
    pub input_torque: Option<f64>,
    /// Input torque over input speed, `W:T,W:T,...` [rad/s : N m], linear between points.
    #[arg(long, value_name = "TABLE", value_parser = parse_table, conflicts_with = "shift")]
    pub torque_table: Option<TorqueTable>,
    /// Road load at the output, `C0,C1,C2`: c0 sgn(w) + c1 w + c2 w|w| [N m].
    #[arg(long, value_name = "C0,C1,C2", value_parser = parse_three, default_value = "0,0,0", conflicts_with = "shift")]
    pub road_load: [f64; 3],
    /// Vehicle inertia reflected to the output link [kg m^2].
    #[arg(
        long,
        value_name = "J",
        default_value_t = 0.0,
        conflicts_with = "shift"
    )]
    pub vehicle_inertia: f64,
    /// A compliant output shaft to the vehicle inertia, `K` or `K,C`:
    /// stiffness [N m/rad] and damping [N m s/rad], reduced to the output
    /// link (shows the shuffle after a lock-up); default: rigid.
    #[arg(long, value_name = "K[,C]", value_parser = parse_shaft, conflicts_with = "shift")]
    pub output_shaft: Option<OutputShaft>,
    /// Friction coefficients `STATIC,KINETIC` of both elements (typical wet clutch: 0.15,0.12).
    #[arg(long, value_name = "MU_S,MU_K", value_parser = parse_two, default_value = "0.15,0.12", conflicts_with = "shift")]
    pub mu: [f64; 2],
    /// Slip speed [rad/s] over which the coefficient falls from static to
    /// kinetic (exp(-|slip|/decay)); default: a step.
    #[arg(long, value_name = "W", conflicts_with = "shift")]
    pub mu_decay: Option<f64>,
    /// Off-going capacity [N m per unit friction coefficient]: `C` or a ramp
    /// `T0:T1:FROM:TO`. For a shift that releases one element; otherwise
    /// give each its `--ramp`.
    #[arg(long, value_name = "RAMP", value_parser = parse_capacity, conflicts_with = "shift")]
    pub off_going: Option<Capacity>,
    /// On-coming capacity, as `--off-going` (e.g. a pressure ramp
    /// `0.05:0.35:0:8000`), for a shift that applies one element.
    #[arg(long, value_name = "RAMP", value_parser = parse_capacity, conflicts_with = "shift")]
    pub on_coming: Option<Capacity>,
    /// One changing element's capacity, `NAME=RAMP` (RAMP as `--off-going`);
    /// repeat it for each element released or applied, e.g. the 8HP's 1-4
    /// double swap: `--ramp A=0.05:0.15:5000:0 --ramp C=0.05:0.15:5000:0
    /// --ramp D=0.05:0.3:0:9000 --ramp E=0.1:0.35:0:9000`. It comes before
    /// `--off-going`/`--on-coming`; every changing element needs a capacity
    /// (a missing one exits 2, naming it). For an element engaged in both
    /// gears it gives a capacity to hold by: it then slips if its torque
    /// exceeds it (without one it is held rigidly).
    #[arg(long = "ramp", value_name = "NAME=RAMP", value_parser = parse_ramp, conflicts_with = "shift")]
    pub ramps: Vec<(String, Capacity)>,
    /// End time [s].
    #[arg(
        long,
        value_name = "T",
        default_value_t = 1.0,
        conflicts_with = "shift"
    )]
    pub t_end: f64,
    /// Relative tolerance of the adaptive steps.
    #[arg(long, default_value_t = 1e-8)]
    pub rtol: f64,
    /// Absolute tolerance [rad/s, J].
    #[arg(long, default_value_t = 1e-8)]
    pub atol: f64,
    /// Integrator: `auto` (explicit until a stiff mode limits its steps, then
    /// implicit), `explicit` (reports a stiff mode, keeps going), `implicit`.
    #[arg(long, value_enum, default_value_t = MethodArg::Auto)]
    pub method: MethodArg,
    /// Steps (accepted and rejected) allowed before the run is refused
    /// (code `budget`). A step is at most 1 s, so `--t-end` past this many
    /// seconds is refused at once.
    #[arg(long, value_name = "N", default_value_t = egt_core::shift_dynamics::DEFAULT_MAX_STEPS)]
    pub max_steps: usize,
    /// Mesh losses: the gear pairs' `efficiency` (as `egt power` applies
    /// them) on the meshing forces; the meshes' loss is reported with the
    /// elements' energies. With `--shift`, as the shift's `losses = true`.
    #[arg(long)]
    pub losses: bool,
    /// Write the shift plot (SVG) to FILE.
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
}

fn numbers(s: &str, n: usize, sep: char) -> Result<Vec<f64>, String> {
    let v: Vec<f64> = s
        .split(sep)
        .map(|x| x.trim().parse::<f64>().map_err(|e| format!("`{x}`: {e}")))
        .collect::<Result<_, _>>()?;
    if v.len() == n {
        Ok(v)
    } else {
        Err(format!(
            "expected {n} numbers separated by `{sep}`, got {}",
            v.len()
        ))
    }
}

fn parse_three(s: &str) -> Result<[f64; 3], String> {
    let v = numbers(s, 3, ',')?;
    Ok([v[0], v[1], v[2]])
}

fn parse_two(s: &str) -> Result<[f64; 2], String> {
    let v = numbers(s, 2, ',')?;
    Ok([v[0], v[1]])
}

fn parse_capacity(s: &str) -> Result<Capacity, String> {
    if s.contains(':') {
        let v = numbers(s, 4, ':')?;
        Ok(Capacity::Ramp {
            t0: v[0],
            t1: v[1],
            from: v[2],
            to: v[3],
        })
    } else {
        Ok(Capacity::Constant(numbers(s, 1, ':')?[0]))
    }
}

fn parse_shaft(s: &str) -> Result<OutputShaft, String> {
    let v = if s.contains(',') {
        numbers(s, 2, ',')?
    } else {
        vec![numbers(s, 1, ',')?[0], 0.0]
    };
    Ok(OutputShaft {
        stiffness: v[0],
        damping: v[1],
    })
}

fn parse_ramp(s: &str) -> Result<(String, Capacity), String> {
    let (name, ramp) = s
        .split_once('=')
        .ok_or_else(|| format!("expected NAME=RAMP (e.g. `D=0.05:0.3:0:9000`), got `{s}`"))?;
    let name = name.trim();
    if name.is_empty() {
        return Err(format!("`{s}`: the element name is empty"));
    }
    Ok((name.to_string(), parse_capacity(ramp)?))
}

/// The points of `--torque-table`, one flag value. (A bare `Vec` here would
/// tell clap that the flag takes many values of one point each, and its
/// parser's `Vec` would then not be the type clap stores: a panic.)
#[derive(Debug, Clone, PartialEq)]
pub struct TorqueTable(pub Vec<(f64, f64)>);

fn parse_table(s: &str) -> Result<TorqueTable, String> {
    s.split(',')
        .map(|p| numbers(p, 2, ':').map(|v| (v[0], v[1])))
        .collect::<Result<_, _>>()
        .map(TorqueTable)
}

/// Runs `egt shift-sim`.
///
/// # Errors
/// The spec, a bad shift (named field), a failed run, or I/O.
pub fn run(args: &Args, out: &mut dyn Write) -> anyhow::Result<()> {
    let loaded = input::load(&args.spec)?;
    let train = &loaded.train;
    let method = match args.method {
        MethodArg::Auto => ShiftMethod::Auto,
        MethodArg::Explicit => ShiftMethod::Explicit,
        MethodArg::Implicit => ShiftMethod::Implicit,
    };
    let sim = match &args.shift {
        Some(name) => ShiftSim {
            rtol: args.rtol,
            atol: args.atol,
            method,
            max_steps: args.max_steps,
            ..ShiftSim::named(train, name)
                .map(|s| ShiftSim {
                    losses: s.losses || args.losses,
                    ..s
                })
                .map_err(|e| {
                    // An unknown name is the flag's; anything else the section's.
                    let context = if e.location().0 == Some("shift") {
                        format!("{} (flag `--shift`)", loaded.source)
                    } else {
                        format!("{}: [[shift]] `{name}`", loaded.source)
                    };
                    anyhow::Error::new(e).context(context)
                })?
        },
        None => ShiftSim {
            from: args.from.clone().unwrap_or_default(),
            to: args.to.clone().unwrap_or_default(),
            input_speed: args.input_speed.unwrap_or_default(),
            input_torque: match (&args.torque_table, args.input_torque) {
                (Some(t), _) => InputTorque::Table(t.0.clone()),
                (None, t) => InputTorque::Constant(t.unwrap_or_default()),
            },
            road_load: args.road_load,
            vehicle_inertia: args.vehicle_inertia,
            output_shaft: args.output_shaft,
            law: FrictionLaw {
                mu_static: args.mu[0],
                mu_kinetic: args.mu[1],
                decay: args.mu_decay,
            },
            off_going: args.off_going,
            on_coming: args.on_coming,
            ramps: args.ramps.clone(),
            t_end: args.t_end,
            rtol: args.rtol,
            atol: args.atol,
            method,
            max_steps: args.max_steps,
            losses: args.losses,
        },
    };
    let r = sim.run(train).map_err(|e| {
        // A refused field `shift.x_y` is this command's flag `--x-y`.
        let flag = e
            .location()
            .0
            .and_then(|p| p.strip_prefix("shift."))
            .map(|f| f.split(['.', '[']).next().unwrap_or(f).replace('_', "-"))
            .map(|f| if f == "ramps" { "ramp".into() } else { f });
        let context = match (&args.shift, flag) {
            // A shift the spec names: its field, not a flag.
            (Some(name), _) => format!("{}: [[shift]] `{name}`", loaded.source),
            (None, Some(f)) => format!("{} (flag `--{f}`)", loaded.source),
            (None, None) => loaded.source.clone(),
        };
        anyhow::Error::new(e).context(context)
    })?;
    if let Some(path) = &args.plot {
        std::fs::write(path, plot(train, &report::title(train, &loaded.source), &r))
            .with_context(|| format!("writing {}", path.display()))?;
    }
    match args.spec.format {
        SeriesFormat::Json => report::json(out, &r),
        SeriesFormat::Csv => csv(out, train, &r),
        SeriesFormat::Table => table(out, train, &loaded.source, &sim.from, &sim.to, &r),
    }
}

/// `` `A`, `C` ``.
fn quoted(names: &[String]) -> String {
    names
        .iter()
        .map(|n| format!("`{n}`"))
        .collect::<Vec<_>>()
        .join(", ")
}

fn opt(v: Option<f64>) -> String {
    v.map_or_else(|| "-".into(), report::float)
}

fn table(
    out: &mut dyn Write,
    train: &Train,
    source: &str,
    from: &str,
    to: &str,
    r: &ShiftResult,
) -> anyhow::Result<()> {
    writeln!(out, "{}", report::title(train, source))?;
    writeln!(
        out,
        "shift {from} -> {to}: off-going {}, on-coming {}; locked throughout: {}{}",
        quoted(&r.off_going),
        quoted(&r.on_coming),
        if r.kept.is_empty() {
            "none".to_string()
        } else {
            quoted(&r.kept)
        },
        if r.held.is_empty() {
            String::new()
        } else {
            format!("; held by a capacity: {}", quoted(&r.held))
        }
    )?;
    writeln!(out)?;
    writeln!(out, "mode changes:")?;
    let mut t = Table::new(&["t [s]", "element", "now", "DOF"]).right(&[0, 3]);
    for c in &r.changes {
        t.row(vec![
            report::float(c.t),
            c.element.clone(),
            c.now.clone(),
            c.dof.to_string(),
        ]);
    }
    t.write(out, 2)?;
    writeln!(out)?;
    writeln!(
        out,
        "torque phase starts (on-coming capacity > 0): {} s",
        opt(r.shift_start)
    )?;
    writeln!(
        out,
        "on-coming {}:                      {} s",
        if r.on_coming.len() == 1 {
            "element locks"
        } else {
            "elements lock"
        },
        opt(r.lock_time)
    )?;
    writeln!(
        out,
        "shift time:                                   {} s",
        opt(r.shift_time)
    )?;
    if let Some(t) = r.rest_time {
        writeln!(
            out,
            "at rest from:                                 {} s (every link stopped)",
            report::float(t)
        )?;
    }
    writeln!(
        out,
        "output torque: max {} N m, min {} N m",
        report::float(r.output_torque_range[0]),
        report::float(r.output_torque_range[1])
    )?;
    if !r.kept.is_empty() {
        writeln!(
            out,
            "torque of the elements locked throughout: {}",
            r.kept
                .iter()
                .zip(&r.kept_torque_range)
                .map(|(e, [hi, lo])| format!(
                    "`{e}` max {} N m, min {} N m",
                    report::float(*hi),
                    report::float(*lo)
                ))
                .collect::<Vec<_>>()
                .join("; ")
        )?;
    }
    writeln!(
        out,
        "energy dissipated: {}; at lock-ups {} J",
        r.elements
            .iter()
            .zip(&r.dissipated)
            .map(|(e, d)| format!("`{e}` {} J", report::float(*d)))
            .collect::<Vec<_>>()
            .join(", "),
        report::sci(r.lock_loss)
    )?;
    if let Some(m) = r.mesh_loss {
        writeln!(out, "mesh loss: {} J", report::float(m))?;
    }
    writeln!(
        out,
        "energy balance (W_in - dKE - E_friction - E_lock{}): largest residual {} J over {} steps ({})",
        if r.mesh_loss.is_some() {
            " - E_mesh"
        } else {
            ""
        },
        report::sci(r.max_energy_residual),
        r.steps,
        r.method
    )?;
    if let Some(s) = &r.stiff {
        writeln!(
            out,
            "stiff from t = {} s: decay rate {} 1/s holds explicit steps to {} s (2.5 / rate) whatever the tolerance{}",
            report::float(s.t),
            report::sci(s.rate),
            report::sci(s.h),
            if r.method == "explicit" {
                "; `--method auto` or `implicit` would take far fewer steps"
            } else if r.method == "implicit" {
                ""
            } else {
                "; continued with the implicit method"
            }
        )?;
    }
    quality(out, r)
}

/// `0.05 .. 0.133081 s`, or `none`.
fn phase(p: Option<[f64; 2]>) -> String {
    p.map_or_else(
        || "none".into(),
        |[a, b]| format!("{} .. {} s", report::float(a), report::float(b)),
    )
}

/// `-514.637615 N m at 0.133081 s`, or `-`.
fn at(v: Option<AtTime>, unit: &str) -> String {
    v.map_or_else(
        || "-".into(),
        |a| {
            format!(
                "{} {unit} at {} s",
                report::float(a.value),
                report::float(a.t)
            )
        },
    )
}

/// The phases and the shift-quality measures (docs/shift_dynamics.md,
/// "Phases and shift quality").
fn quality(out: &mut dyn Write, r: &ShiftResult) -> anyhow::Result<()> {
    let q = &r.quality;
    let reference = |v: Option<f64>| v.map_or_else(|| "-".into(), report::float);
    writeln!(out)?;
    writeln!(out, "phases:")?;
    writeln!(
        out,
        "  torque phase:  {} (on-coming capacity > 0, to the off-going release)",
        phase(q.torque_phase)
    )?;
    writeln!(
        out,
        "  inertia phase: {} (off-going release, to the on-coming lock)",
        phase(q.inertia_phase)
    )?;
    writeln!(out, "shift quality (output torque T_out to the vehicle):")?;
    let mut t = Table::new(&["measure", "value", "what"]);
    t.row(vec![
        "dip (torque phase)".into(),
        at(q.dip, "N m"),
        format!(
            "lowest T_out minus T_out(0), {} N m",
            reference(q.output_torque_start)
        ),
    ]);
    t.row(vec![
        "overshoot (inertia phase to lock)".into(),
        at(q.overshoot, "N m"),
        format!(
            "highest T_out minus the final T_out, {} N m",
            reference(q.output_torque_end)
        ),
    ]);
    t.row(vec![
        "oscillation after lock".into(),
        q.oscillation_after_lock
            .map_or_else(|| "-".into(), |v| format!("{} N m", report::float(v))),
        "peak to peak".into(),
    ]);
    t.row(vec![
        "jerk".into(),
        at(q.jerk, "rad/s^3"),
        "max |dT_out/dt| / vehicle inertia, steps at events excluded".into(),
    ]);
    t.row(vec![
        "largest step".into(),
        at(q.largest_step, "N m"),
        "jump of T_out at a mode change (right - left limit)".into(),
    ]);
    for e in &q.elements {
        t.row(vec![
            format!("`{}` peak power", e.element),
            at(e.peak_power, "W"),
            format!("max |T slip|; energy {} J", report::float(e.energy)),
        ]);
    }
    t.write(out, 2)?;
    Ok(())
}

fn csv(out: &mut dyn Write, train: &Train, r: &ShiftResult) -> anyhow::Result<()> {
    let moving: Vec<usize> = train.coordinates().iter().map(|l| l.index()).collect();
    let mut header = vec!["t".to_string()];
    header.extend(
        moving
            .iter()
            .map(|&l| format!("w_{}", report::csv_name(&train.links()[l].name))),
    );
    for e in &r.elements {
        header.push(format!("slip_{}", report::csv_name(e)));
        header.push(format!("torque_{}", report::csv_name(e)));
        header.push(format!("dissipated_{}", report::csv_name(e)));
    }
    header.extend(
        r.kept
            .iter()
            .map(|e| format!("torque_{}", report::csv_name(e))),
    );
    header.extend(["output_torque", "energy_residual", "dof"].map(String::from));
    if r.mesh_loss.is_some() {
        header.push("mesh_loss".into());
    }
    writeln!(out, "{}", header.join(","))?;
    for s in &r.samples {
        let mut row = vec![format!("{:e}", s.t)];
        row.extend(moving.iter().map(|&l| format!("{:e}", s.speed[l])));
        for i in 0..r.elements.len() {
            row.extend([s.slip[i], s.element_torque[i], s.dissipated[i]].map(|v| format!("{v:e}")));
        }
        row.extend(s.kept_torque.iter().map(|v| format!("{v:e}")));
        row.push(format!("{:e}", s.output_torque));
        row.push(format!("{:e}", s.energy_residual));
        row.push(s.dof.to_string());
        row.extend(s.mesh_loss.map(|m| format!("{m:e}")));
        writeln!(out, "{}", row.join(","))?;
    }
    Ok(())
}

/// The standard shift plot: link speeds; the two elements' torques; the
/// output torque. The torque and inertia phases are shaded on every panel,
/// the dip and the overshoot marked on the output torque's.
fn plot(train: &Train, title: &str, r: &ShiftResult) -> String {
    let s = &r.samples;
    let t_end = s.last().map_or(1.0, |x| x.t).max(f64::MIN_POSITIVE);
    let height = TOP + 3.0 * (PLOT_H + GAP) + 10.0;
    let mut svg = String::new();
    let subtitle = format!(
        "off-going {}, on-coming {}; shift time {} s; output torque {} .. {} N m",
        quoted(&r.off_going),
        quoted(&r.on_coming),
        opt(r.shift_time),
        report::float(r.output_torque_range[1]),
        report::float(r.output_torque_range[0]),
    );
    crate::svg::open_plot(&mut svg, height, title, &subtitle);
    let time = |i: usize| s[i].t;
    let q = &r.quality;
    let phases: Vec<Band<'_>> = [
        (q.torque_phase, "#E69F00", "torque phase"),
        (q.inertia_phase, "#56B4E9", "inertia phase"),
    ]
    .into_iter()
    .filter_map(|(p, colour, label)| p.map(|t| Band { t, colour, label }))
    .collect();
    for k in 0..3 {
        bands(&mut svg, TOP + k as f64 * (PLOT_H + GAP), t_end, &phases);
    }
    let links: Vec<usize> = train.coordinates().iter().map(|l| l.index()).collect();
    let speeds: Vec<Box<dyn Fn(usize) -> f64 + '_>> = links
        .iter()
        .map(|&l| Box::new(move |i: usize| s[i].speed[l]) as Box<dyn Fn(usize) -> f64>)
        .collect();
    let lines = plain_lines(&speeds);
    panel(
        &mut svg,
        &Panel {
            top: TOP,
            title: "link speeds",
            ylabel: "speed [rad/s]",
        },
        s.len(),
        &time,
        &lines,
        t_end,
    );
    let torques: Vec<Box<dyn Fn(usize) -> f64 + '_>> = (0..r.elements.len())
        .map(|e| Box::new(move |i: usize| s[i].element_torque[e]) as Box<dyn Fn(usize) -> f64>)
        .collect();
    let head = if r.elements.len() == 2 {
        format!(
            "element torques: blue `{}` (off-going), orange `{}` (on-coming)",
            r.elements[0], r.elements[1]
        )
    } else {
        format!(
            "element torques, in the colour order of the link speeds: off-going {}, on-coming {}",
            quoted(&r.off_going),
            quoted(&r.on_coming)
        )
    };
    panel(
        &mut svg,
        &Panel {
            top: TOP + PLOT_H + GAP,
            title: &head,
            ylabel: "torque [N m]",
        },
        s.len(),
        &time,
        &plain_lines(&torques),
        t_end,
    );
    let output = |i: usize| s[i].output_torque;
    panel(
        &mut svg,
        &Panel {
            top: TOP + 2.0 * (PLOT_H + GAP),
            title: "output torque (to the vehicle)",
            ylabel: "torque [N m]",
        },
        s.len(),
        &time,
        &[Line {
            value: &output,
            level: None,
        }],
        t_end,
    );
    let moments: Vec<Mark> = [(q.dip, "dip"), (q.overshoot, "overshoot")]
        .into_iter()
        .filter_map(|(m, what)| {
            m.map(|m| Mark {
                t: m.t,
                label: format!("{what} {} N m", report::float(m.value)),
            })
        })
        .collect();
    marks(&mut svg, TOP + 2.0 * (PLOT_H + GAP), t_end, &moments);
    let labels: Vec<String> = links
        .iter()
        .map(|&l| format!("link {}", train.links()[l].name))
        .collect();
    legend(&mut svg, &labels);
    svg.push_str("</svg>\n");
    svg
}

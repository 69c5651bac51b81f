//! `egt modes SPEC [--state G]`: natural frequencies and mass-normalised
//! mode shapes of the lumped torsional model (a spring along each mesh's
//! line of action, `[compliance]`; docs/vibration.md): the rigid-body modes
//! (the kinematics), the elastic modes with their multiplicities, and the
//! shares of strain energy per spring and of kinetic energy per coordinate.

use std::io::Write;
use std::path::PathBuf;

use anyhow::Context;
use egt_core::{ModesRequest, Train};
use egt_views::modes::{Report, build, statics};

use crate::args::{OutputFormat, SpecArgs};
use crate::input;
use crate::report::{self, Table};

mod campbell;

/// Arguments of `egt modes`.
#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub spec: SpecArgs,
    /// The gear state whose engaged elements hold (rigidly, or as springs
    /// where `[[compliance.elements]]` gives a stiffness). Default: the bare
    /// train, no element engaged.
    #[arg(long = "state", value_name = "NAME")]
    pub state: Option<String>,
    /// Also list the Campbell diagram's crossings: the input speeds at which
    /// a mesh's tooth-pass frequency equals a natural frequency (needs one
    /// rigid-body mode: a gear state, or a train of one DOF).
    #[arg(long = "campbell")]
    pub campbell: bool,
    /// The input speed range of `--campbell`, `MIN:MAX` [rpm].
    #[arg(long = "speed", value_name = "MIN:MAX", default_value = "0:7000", value_parser = parse_range, requires = "campbell")]
    pub speed: [f64; 2],
    /// Write the Campbell diagram (SVG) to FILE: natural frequencies against
    /// the tooth-pass frequencies over the input speed, crossings circled.
    #[arg(long = "plot", value_name = "FILE", requires = "campbell")]
    pub plot: Option<PathBuf>,
    /// Also the static deflection under TORQUE [N m] on the transmission
    /// input, the output reacting it: each mesh's force and deflection beside
    /// the rigid model's eq. (11) mesh torque, and the held elements' torques.
    #[arg(
        long = "static",
        value_name = "TORQUE",
        requires = "state",
        allow_hyphen_values = true
    )]
    pub static_torque: Option<f64>,
}

/// `MIN:MAX` as two numbers.
fn parse_range(s: &str) -> Result<[f64; 2], String> {
    let (a, b) = s
        .split_once(':')
        .ok_or_else(|| format!("`{s}`: expected MIN:MAX, e.g. 0:7000"))?;
    let num = |x: &str| {
        x.trim()
            .parse::<f64>()
            .map_err(|e| format!("`{x}` in `{s}`: {e}"))
    };
    Ok([num(a)?, num(b)?])
}

/// Run `egt modes`.
///
/// # Errors
/// Reading or validating the spec; an unknown `--state` (exit 2); a gear
/// pair without a mesh stiffness, a link without an inertia, a gear pair
/// without a base radius (`missing_data`, exit 1); I/O.
pub fn run(args: &Args, out: &mut dyn Write) -> anyhow::Result<()> {
    let loaded = input::load(&args.spec)?;
    let train = &loaded.train;
    let req = ModesRequest {
        state: args.state.clone(),
        campbell: args.campbell.then_some(args.speed),
    };
    let modes = train
        .modes(&req)
        .with_context(|| format!("{}: modes", loaded.source))?;
    let mut report = build(train, &loaded.source, &modes);
    if let (Some(torque), Some(state)) = (args.static_torque, args.state.as_deref()) {
        if !torque.is_finite() {
            anyhow::bail!(egt_core::Error::invalid(
                "--static",
                format!("the input torque must be finite, not {torque}")
            ));
        }
        let check = train
            .static_check_in_gear(state, torque)
            .with_context(|| format!("{}: static deflection", loaded.source))?;
        report.static_load = Some(statics(train, &modes, &check, torque));
    }
    if let Some(path) = &args.plot {
        let title = format!("{}: Campbell diagram", report::title(train, &loaded.source));
        std::fs::write(path, campbell::svg(&title, &report))
            .with_context(|| format!("writing {}", path.display()))?;
    }
    match args.spec.format {
        OutputFormat::Json => report::json(out, &report),
        OutputFormat::Table => write_table(out, train, &loaded.source, &report),
    }
}

/// A percentage of energy for a table ("-" below 0.05 %).
fn share(v: f64) -> String {
    if v < 5e-4 {
        "-".into()
    } else {
        format!("{:.1}", 100.0 * v)
    }
}

fn write_table(out: &mut dyn Write, train: &Train, source: &str, r: &Report) -> anyhow::Result<()> {
    let state = r
        .state
        .as_ref()
        .map_or_else(String::new, |s| format!(" in gear state {s}"));
    writeln!(
        out,
        "{}: torsional modes{state}",
        report::title(train, source)
    )?;
    writeln!(
        out,
        "{} coordinates, {} springs{}; rigid-body modes (DOF): {}",
        r.coordinates.len(),
        r.springs.len(),
        if r.constraints.is_empty() {
            String::new()
        } else {
            format!("; held rigidly: {}", r.constraints.join(", "))
        },
        r.dof
    )?;
    writeln!(out, "natural frequencies:")?;
    let mut t = Table::new(&[
        "mode",
        "f [Hz]",
        "omega [rad/s]",
        "multiplicity",
        "damping ratio",
        "most strain energy",
        "most kinetic energy",
    ])
    .right(&[0, 1, 2, 3, 4]);
    for (k, m) in r.modes.iter().enumerate() {
        let top = |v: &[f64], names: &mut dyn Iterator<Item = String>| {
            names
                .zip(v)
                .max_by(|a, b| a.1.total_cmp(b.1))
                .filter(|x| *x.1 > 0.0)
                .map_or_else(|| "-".into(), |(n, v)| format!("{n} {}%", share(*v)))
        };
        t.row(vec![
            (k + 1).to_string(),
            report::sci(m.hertz),
            report::sci(m.omega),
            if m.rigid {
                "rigid".into()
            } else if m.multiplicity > 1 {
                format!("{} (degenerate)", m.multiplicity)
            } else {
                "1".into()
            },
            m.damping_ratio.map_or_else(|| "-".into(), report::sci),
            top(
                &m.strain_energy,
                &mut r.springs.iter().map(|s| s.name.clone()),
            ),
            top(
                &m.kinetic_energy,
                &mut r.coordinates.iter().map(|c| c.name.clone()),
            ),
        ]);
    }
    t.write(out, 2)?;
    let numbers: Vec<String> = (1..=r.modes.len()).map(|k| k.to_string()).collect();
    let cols: Vec<usize> = (1..=r.modes.len()).collect();
    writeln!(out, "mode shapes (phi^T M phi = 1) [rad / sqrt(kg m^2)]:")?;
    let mut headers = vec!["coordinate"];
    headers.extend(numbers.iter().map(String::as_str));
    let mut t = Table::new(&headers).right(&cols);
    for (c, coord) in r.coordinates.iter().enumerate() {
        let mut cells = vec![coord.name.clone()];
        cells.extend(
            r.modes
                .iter()
                .map(|m| report::sci(clean(m.shape[c], &m.shape))),
        );
        t.row(cells);
    }
    t.write(out, 2)?;
    writeln!(out, "strain energy per spring [% of the mode's]:")?;
    let mut headers = vec!["spring"];
    headers.extend(numbers.iter().map(String::as_str));
    let mut t = Table::new(&headers).right(&cols);
    for (s, spring) in r.springs.iter().enumerate() {
        let mut cells = vec![spring.name.clone()];
        cells.extend(r.modes.iter().map(|m| share(m.strain_energy[s])));
        t.row(cells);
    }
    t.write(out, 2)?;
    writeln!(out, "kinetic energy per coordinate [% of the mode's]:")?;
    let mut headers = vec!["coordinate"];
    headers.extend(numbers.iter().map(String::as_str));
    let mut t = Table::new(&headers).right(&cols);
    for (c, coord) in r.coordinates.iter().enumerate() {
        let mut cells = vec![coord.name.clone()];
        cells.extend(r.modes.iter().map(|m| share(m.kinetic_energy[c])));
        t.row(cells);
    }
    t.write(out, 2)?;
    if !r.damped.is_empty() {
        writeln!(
            out,
            "damped modes (eigenvalues sigma + i omega_d of the model with its damping):"
        )?;
        let mut t = Table::new(&[
            "",
            "sigma [1/s]",
            "omega_d [rad/s]",
            "f_d [Hz]",
            "damping ratio",
        ])
        .right(&[0, 1, 2, 3, 4]);
        for (k, d) in r.damped.iter().enumerate() {
            t.row(vec![
                (k + 1).to_string(),
                report::sci(d.sigma),
                report::sci(d.omega_d),
                report::sci(d.hertz_d),
                report::sci(d.damping_ratio),
            ]);
        }
        t.write(out, 2)?;
    }
    if let Some(st) = &r.static_load {
        write_static(out, st)?;
    }
    if let Some(m) = &r.meshing {
        writeln!(
            out,
            "mesh (tooth-pass) frequencies per unit input speed (input `{}`):",
            m.input
        )?;
        let mut t =
            Table::new(&["gear pair", "order [per input rev]", "Hz per rpm"]).right(&[1, 2]);
        for o in &m.orders {
            t.row(vec![
                o.gear.clone(),
                report::float(o.order),
                report::sci(o.hertz_per_rpm),
            ]);
        }
        t.write(out, 2)?;
        if let Some([lo, hi]) = m.range {
            writeln!(
                out,
                "Campbell crossings, input {} to {} rpm (tooth-pass frequency = natural frequency):",
                report::float(lo),
                report::float(hi)
            )?;
            if m.crossings.is_empty() {
                writeln!(out, "  none")?;
            } else {
                let mut t =
                    Table::new(&["input [rpm]", "gear pair", "mode", "f [Hz]"]).right(&[0, 2, 3]);
                for c in &m.crossings {
                    t.row(vec![
                        report::float(c.speed),
                        c.gear.clone(),
                        (c.mode + 1).to_string(),
                        report::sci(c.hertz),
                    ]);
                }
                t.write(out, 2)?;
            }
        }
    }
    Ok(())
}

/// A shape's component as 0 when it is round-off against the largest (so
/// that a coordinate at rest reads 0, not 1e-17).
fn clean(v: f64, shape: &[f64]) -> f64 {
    let big = shape.iter().fold(0.0_f64, |a, x| a.max(x.abs()));
    if v.abs() <= 1e-12 * big { 0.0 } else { v }
}

/// The static deflection under `--static`: mesh by mesh beside eq. (11).
fn write_static(out: &mut dyn Write, st: &egt_views::modes::StaticOut) -> anyhow::Result<()> {
    writeln!(
        out,
        "static deflection: {} N m on the input, {} N m on the output; mesh torques on gear i against the rigid model (eq. 11):",
        report::float(st.input_torque),
        report::float(st.output_torque)
    )?;
    let mut t = Table::new(&[
        "gear pair",
        "eq. (11) [N m]",
        "springs [N m]",
        "force per mesh [N]",
        "deflection [um]",
    ])
    .right(&[1, 2, 3, 4]);
    for m in &st.meshes {
        t.row(vec![
            m.gear.clone(),
            report::sci(m.rigid_torque),
            report::sci(m.compliant_torque),
            report::sci(m.force),
            report::sci(1e6 * m.deflection),
        ]);
    }
    t.write(out, 2)?;
    if !st.elements.is_empty() {
        let held: Vec<String> = st
            .elements
            .iter()
            .map(|e| format!("{} {} N m", e.name, report::sci(e.torque)))
            .collect();
        writeln!(out, "held elements' torques: {}", held.join(", "))?;
    }
    Ok(())
}

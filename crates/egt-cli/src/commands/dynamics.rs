//! `egt dynamics SPEC`: inverse dynamics (eq. 6-11) for any DOF: link
//! accelerations, solved driving torques, Lagrange multipliers, the torques
//! each gear pair carries and its tangential meshing forces (eq. 11), the
//! housing reaction, and the equivalent inertia (1 DOF) or reduced mass
//! matrix (several DOF). Without accelerations it is the static-force analysis.

use std::io::Write;

use anyhow::Context;
use egt_core::Train;
use egt_views::dynamics::{Report, build};

use crate::args::{LoadArgs, load_request, mass_if_needed};
use crate::args::{OutputFormat, SpecArgs};
use crate::input;
use crate::report::{self, Table};

/// Arguments of `egt dynamics`.
#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub spec: SpecArgs,
    #[command(flatten)]
    pub loads: LoadArgs,
    /// Require tangential meshing forces for every gear pair (needs pitch radii).
    #[arg(long)]
    pub forces: bool,
    /// Link to reduce the equivalent inertia to (1 DOF). Default: `[analysis]
    /// reduce_to`, else the first driving link.
    #[arg(long, value_name = "LINK")]
    pub reduce_to: Option<String>,
}
/// Run `egt dynamics`.
///
/// # Errors
/// Spec errors (exit 2); missing data, singular or ill-conditioned systems (exit 1).
pub fn run(args: &Args, out: &mut dyn Write) -> anyhow::Result<()> {
    let loaded = input::load(&args.spec)?;
    let train = &loaded.train;
    let req = load_request(train, &args.loads)?;
    let mass = mass_if_needed(train, &req)?;
    let r = train
        .inverse_dynamics(&req, mass.as_ref())
        .with_context(|| format!("{}: inverse dynamics", loaded.source))?;
    if args.forces
        && let Some(g) = train.gears().iter().find(|g| g.radii.is_none())
    {
        let e = egt_core::AnalysisError::MissingData {
            what: format!("the pitch radii of gear pair `{}`", g.name),
            analysis: "meshing forces (eq. 11)".into(),
            hint: format!("give `radii`, or `module` with `teeth`, at {}", g.path),
        };
        return Err(egt_core::Error::from(e).into());
    }
    let reduce_to = match &args.reduce_to {
        Some(n) => Some(train.resolve(n, &format!("--reduce-to {n}"))?),
        None => train.analysis().reduce_to,
    };
    let report = build(train, &loaded.source, &req, &r, reduce_to);
    match args.spec.format {
        OutputFormat::Json => report::json(out, &report),
        OutputFormat::Table => write_table(out, train, &loaded.source, &report),
    }
}
fn write_table(out: &mut dyn Write, train: &Train, source: &str, r: &Report) -> anyhow::Result<()> {
    let kind = if r.static_analysis {
        "static-force analysis"
    } else {
        "inverse dynamics"
    };
    writeln!(
        out,
        "{}: {kind} ({} DOF)",
        report::title(train, source),
        r.dof
    )?;
    let f = report::float;
    let mut t = Table::new(&["link", "role", "acceleration", "applied torque"]).right(&[2, 3]);
    for l in &r.links {
        t.row(vec![
            l.name.clone(),
            l.role.clone(),
            f(l.acceleration),
            f(l.torque),
        ]);
    }
    writeln!(
        out,
        "links (applied torque: known loads, solved driving torques, and the housing reaction):"
    )?;
    t.write(out, 2)?;
    let with_forces = r.meshes.iter().any(|m| m.force.is_some());
    let mut headers = vec![
        "pair",
        "i",
        "j",
        "carrier",
        "lambda",
        "T_i",
        "T_j",
        "T_carrier",
    ];
    if with_forces {
        headers.extend(["F_i", "F_j", "copies", "F per copy"]);
    }
    let mut t = Table::new(&headers).right(&[4, 5, 6, 7, 8, 9, 10, 11]);
    let dash = || "-".to_string();
    for m in &r.meshes {
        let mut row = vec![
            m.pair.clone(),
            m.gear_i.clone(),
            m.gear_j.clone(),
            m.carrier.clone(),
            f(m.multiplier),
            f(m.torque_i),
            f(m.torque_j),
            f(m.torque_carrier),
        ];
        if with_forces {
            row.push(m.force.map_or_else(dash, |x| f(x[0])));
            row.push(m.force.map_or_else(dash, |x| f(x[1])));
            row.push(m.copies.to_string());
            row.push(m.force_per_copy.map_or_else(dash, |x| f(x[0])));
        }
        t.row(row);
    }
    writeln!(
        out,
        "gear pairs (torques each member spends on the mesh, lambda psi_w; forces by eq. 11):"
    )?;
    t.write(out, 2)?;
    if let Some((l, j)) = &r.equivalent_inertia {
        writeln!(out, "equivalent inertia reduced to `{l}`: {}", f(*j))?;
    }
    if let Some((names, m)) = &r.reduced_mass_matrix {
        writeln!(out, "reduced mass matrix over [{}]:", names.join(", "))?;
        for row in m {
            writeln!(
                out,
                "  [{}]",
                row.iter().map(|x| f(*x)).collect::<Vec<_>>().join(", ")
            )?;
        }
    }
    writeln!(
        out,
        "condition numbers: [Psi_w] {}, force system {}",
        f(r.conditions[0]),
        f(r.conditions[1])
    )?;
    for w in &r.warnings {
        writeln!(out, "warning: {w}")?;
    }
    Ok(())
}

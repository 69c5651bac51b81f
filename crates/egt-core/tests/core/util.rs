//! Trains shared by the test modules.

use crate::lab::families;
use egt_core::batch::{BatchPlan, BatchSpec};
use egt_core::solve::prepared::Compute;
use egt_core::{DynamicsRequest, Format, PowerRequest, SpeedInput, Train};

/// Build a train from TOML, panicking with the error and the text.
pub fn train(text: &str) -> Train {
    Train::from_str(text, Format::Toml, "test").unwrap_or_else(|e| panic!("{e}\n{text}"))
}

/// A bundled example by file name.
pub fn example(name: &str) -> Train {
    let path = format!("{}/../../examples/{name}", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    train(&text)
}

/// 1-DOF trains with `[analysis]` data: examples and generated families.
pub fn one_dof_trains() -> Vec<(String, Train)> {
    let mut out = vec![
        ("fig3".to_string(), example("fig3_example61.toml")),
        ("gear pair".to_string(), train(&families::gear_pair())),
        ("chain 2".to_string(), train(&families::planetary_chain(2))),
        ("chain 5".to_string(), train(&families::planetary_chain(5))),
        ("nest 6".to_string(), train(&families::nest(6))),
        ("nest 12".to_string(), train(&families::nest(12))),
    ];
    for seed in 1..6 {
        out.push((
            format!("random {seed}"),
            train(&families::random_train(seed, 1 + seed as usize, 3.0)),
        ));
    }
    out
}

/// The dynamics request of a train's `[analysis]` section.
pub fn request(t: &Train) -> DynamicsRequest {
    let a = t.analysis();
    DynamicsRequest {
        torques: a.torques.clone(),
        accelerations: a.accelerations.clone(),
        driving: a.driving.clone(),
        extras: vec![],
    }
}

/// The power request of a train's `[analysis]` section.
pub fn power_request(t: &Train, losses: bool) -> PowerRequest {
    PowerRequest {
        speeds: t
            .analysis()
            .speeds
            .iter()
            .map(|&(l, v, _)| SpeedInput::from((l, v)))
            .collect(),
        dynamics: request(t),
        losses,
    }
}

/// A batch plan from the `[analysis]` section.
pub fn plan(t: &Train, compute: Compute) -> BatchPlan {
    let spec = BatchSpec::from_analysis(t, compute).unwrap_or_else(|e| panic!("{e}"));
    BatchPlan::new(t, &spec).unwrap_or_else(|e| panic!("{e}"))
}

/// |a - b| <= rel * max(|a|, |b|, floor).
pub fn close(a: f64, b: f64, rel: f64, floor: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()).max(floor)
}

/// Every link's speed (the frame's 0) and the condition estimate from the
/// float speed solver, [`PreparedTrain`] with [`Compute::Kinematics`],
/// factored sparsely or densely as asked.
pub fn prepared_speeds(
    t: &Train,
    links: &[egt_core::LinkId],
    speeds: &[f64],
    sparse: bool,
) -> egt_core::error::Result<(Vec<f64>, f64)> {
    use egt_core::solve::prepared::{PreparedTrain, Scenario};
    let plan = PreparedTrain::for_analysis(t, links, links, links, &[])?.with_sparse(sparse)?;
    let ratios = t.ratios()?;
    let mut ws = plan.workspace();
    plan.solve(
        &mut ws,
        &Scenario::kinematic(&ratios, speeds),
        Compute::Kinematics,
    )?;
    let mut w = vec![0.0; t.links().len()];
    for (&l, &v) in t.coordinates().iter().zip(ws.speeds()) {
        w[l.index()] = v;
    }
    Ok((w, ws.conditions()[0]))
}

//! The batch API against the single-scenario analyses: every output column of
//! a row equals what `Train::kinematics`, `Train::inverse_dynamics` and
//! `Train::power_flow` give for a train written with that row's values;
//! parallel runs equal row-by-row runs; bad rows are reported and the rest go on.

use egt_core::batch::{BatchPlan, Executor, Layout, Threads};
use egt_core::solve::prepared::Compute;
use egt_core::{AnalysisError, Error, LinkId, Train};
use proptest::prelude::*;

use crate::util::{close, one_dof_trains, plan, power_request, request, train};

const REL: f64 = 1e-11;

/// Compare a plan's row for `t`'s own values with the single-scenario analyses of `t`.
fn check_against_single(name: &str, t: &Train, p: &BatchPlan, row: &[f64]) {
    let mut out = vec![0.0; p.outputs().len()];
    p.worker()
        .eval(row, &mut out)
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    let col = |s: String| {
        p.output(&s)
            .unwrap_or_else(|| panic!("{name}: no column {s}"))
    };
    let link = |l: LinkId| t.link_name(l).to_string();
    let tol = |a: f64, b: f64, what: &str| {
        assert!(
            close(a, b, REL, 1e-9),
            "{name}: {what}: batch {a} vs single {b}"
        );
    };

    let mass = t.mass_matrix().unwrap_or_else(|e| panic!("{e}"));
    let pf = t
        .power_flow(
            &power_request(t, p.compute() == Compute::Power),
            Some(&mass),
        )
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    for &l in t.coordinates() {
        if t.link(l).sized {
            tol(
                out[col(format!("speed.{}", link(l)))],
                pf.speeds.speed[l.index()],
                "speed",
            );
        }
    }
    if p.compute() == Compute::Kinematics {
        return;
    }
    let d = &pf.dynamics;
    for &l in t.coordinates() {
        if t.link(l).sized {
            tol(
                out[col(format!("accel.{}", link(l)))],
                d.acceleration[l.index()],
                "accel",
            );
        }
    }
    // Multipliers: compared relative to the largest one (a mesh may carry ~0).
    let scale = d.multipliers.iter().fold(1e-300_f64, |m, v| m.max(v.abs()));
    for (m, (g, lam)) in t.gears().iter().zip(&d.multipliers).enumerate() {
        let b = out[col(format!("lambda.{}", g.name))];
        assert!(
            (b - lam).abs() <= REL * scale,
            "{name}: lambda {}: {b} vs {lam}",
            g.name
        );
        // eq. (11) with the plan's pitch radius (radii are fixed when a plan is prepared).
        if let Some(c) = p.output(&format!("force.{}", g.name)) {
            let r = p.prepared().radii()[m].unwrap_or(f64::NAN);
            assert!((out[c] - lam / r).abs() <= REL * scale / r, "{name}: force");
        }
    }
    for &(l, td) in &d.driving_torques {
        tol(
            out[col(format!("driving_torque.{}", link(l)))],
            td,
            "driving torque",
        );
    }
    let single = t
        .inverse_dynamics(&request(t), Some(&mass))
        .unwrap_or_else(|e| panic!("{e}"));
    // Same matrix, same LU, same estimator: the condition of eq. (8) is identical
    // (the single analysis skips eq. 8 when every acceleration is zero).
    if t.analysis().accelerations.iter().any(|a| a.1 != 0.0) {
        assert_eq!(
            out[col("cond.accelerations".into())],
            single.conditions[0],
            "{name}"
        );
    }
    if p.compute() == Compute::Power {
        let (input, output) = (pf.totals.input_power, pf.totals.output_power);
        let scale = input.abs().max(output.abs()).max(1e-9);
        for (c, v) in [
            ("power.input", input),
            ("power.output", output),
            ("power.loss", pf.totals.loss),
            ("power.kinetic_rate", pf.totals.kinetic_rate),
        ] {
            assert!(
                (out[col(c.into())] - v).abs() <= REL * scale,
                "{name}: {c}: {} vs {v}",
                out[col(c.into())]
            );
        }
    }
}

#[test]
fn base_rows_equal_single_scenario_analyses() {
    for (name, t) in one_dof_trains() {
        for compute in [Compute::Kinematics, Compute::Dynamics, Compute::Power] {
            let p = plan(&t, compute);
            check_against_single(&format!("{name} {compute:?}"), &t, &p, p.base());
        }
    }
}

/// The paper's Fig. 3 train with the given values (as in tests of issue 3).
#[allow(clippy::too_many_arguments)]
fn fig3(
    r11: f64,
    r31: f64,
    r32: f64,
    i: [f64; 3],
    m: [f64; 3],
    eta: f64,
    w: f64,
    a: f64,
    tr: f64,
) -> String {
    let r42 = r11 + r31 - r32;
    let (t1, t2) = (-r31 / r11, -r42 / r32);
    format!(
        r#"
        frame = "1"
        links = [{{ name = "2", inertia = {:e}, mass = {:e} }},
                 {{ name = "3", inertia = {:e}, mass = {:e}, copies = 3, wheels = 2 }},
                 {{ name = "4", inertia = {:e}, mass = {:e} }}]
        revolutes = [{{ links = ["1", "2"], level = "a" }},
                     {{ links = ["2", "3"], level = "b" }},
                     {{ links = ["1", "4"], level = "a" }}]
        gears = [{{ links = ["1", "3"], ratio = {t1:e}, radii = [{r11:e}, {r31:e}], efficiency = {eta} }},
                 {{ links = ["3", "4"], ratio = {t2:e}, radii = [{r32:e}, {r42:e}], efficiency = {eta} }}]
        [analysis]
        speeds = {{ "2" = {w:e} }}
        accelerations = {{ "2" = {a:e} }}
        torques = {{ "4" = {tr:e} }}
        driving = ["2"]
        "#,
        i[0], m[0], i[1], m[1], i[2], m[2]
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// A plan prepared on one Fig. 3 train, fed another train's values by
    /// column name, gives that other train's single-scenario results: the
    /// parameter columns map to the right slots.
    #[test]
    fn overridden_rows_equal_single_calls_on_the_train_they_describe(
        r11 in 0.02..0.08f64, r31 in 0.01..0.05f64, frac in 0.2..0.8f64,
        i in prop::array::uniform3(1e-4..1.0f64), m in prop::array::uniform3(0.05..5.0f64),
        eta in 0.9..1.0f64, w in -300.0..300.0f64, a in -50.0..50.0f64, tr in -200.0..200.0f64,
        lossy in any::<bool>(),
    ) {
        let target = train(&fig3(r11, r31, frac * (r11 + r31), i, m, eta, w, a, tr));
        let compute = if lossy { Compute::Power } else { Compute::Dynamics };
        // Prepared on a train with other values (same offsets: the radii of pair 1 fix delta_ab).
        let other = train(&fig3(r11, r31, 0.5 * (r11 + r31), [0.1; 3], [1.0; 3], 0.95, 10.0, 1.0, 5.0));
        let p = plan(&other, compute);
        let truth = plan(&target, compute);
        let row: Vec<f64> = p.parameters().iter().map(|name| {
            truth.base()[truth.parameter(name).unwrap_or_else(|| panic!("{name}"))]
        }).collect();
        check_against_single("fig3", &target, &p, &row);
    }
}

#[test]
fn parallel_run_equals_row_by_row_and_reports_bad_rows() {
    let t = train(&crate::lab::families::planetary_chain(2));
    let p = plan(&t, Compute::Power);
    let np = p.parameters().len();
    let nq = p.outputs().len();
    let ratio = p
        .parameter("ratio.P1/sun-planet")
        .unwrap_or_else(|| panic!("{:?}", p.parameters()));
    let inertia = p
        .parameter("inertia.c1")
        .unwrap_or_else(|| panic!("{:?}", p.parameters()));
    let rows = 3000;
    let mut params = Vec::with_capacity(rows * np);
    for r in 0..rows {
        let mut row = p.base().to_vec();
        row[ratio] *= 1.0 + 0.5 * (r as f64 / rows as f64);
        params.extend(row);
    }
    // Bad rows: a NaN, a negative inertia, a zero ratio.
    params[17 * np + ratio] = f64::NAN;
    params[1234 * np + inertia] = -1.0;
    params[2999 * np + ratio] = 0.0;
    let mut out = vec![0.0; rows * nq];
    let errors = p.run(Layout::Rows(&params), &mut out, Threads::Pool).errors;
    let bad: Vec<usize> = errors.iter().map(|e| e.row).collect();
    assert_eq!(bad, vec![17, 1234, 2999]);
    assert!(errors.iter().all(|e| matches!(e.error, Error::Spec { .. })));
    // On a pool of one thread the tasks run one after another on the
    // calling thread: the same numbers and errors, in the same order.
    let one_thread = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap_or_else(|e| panic!("{e}"));
    let mut serial = vec![0.0; rows * nq];
    let serial_errors = one_thread.install(|| {
        p.run(Layout::Rows(&params), &mut serial, Threads::Pool)
            .errors
    });
    assert_eq!(show(&errors), show(&serial_errors));
    assert!(
        out.iter()
            .zip(&serial)
            .all(|(a, b)| a.to_bits() == b.to_bits())
    );
    one_thread.install(|| assert_columns_agree("one thread", &p, &params, &out, &errors));
    assert_columns_agree("pool", &p, &params, &out, &errors);
    // On the calling thread only, from outside any pool: the same again.
    let mut here = vec![0.0; rows * nq];
    let here_errors = p
        .run(Layout::Rows(&params), &mut here, Threads::Calling)
        .errors;
    assert_eq!(show(&errors), show(&here_errors));
    assert!(
        out.iter()
            .zip(&here)
            .all(|(a, b)| a.to_bits() == b.to_bits())
    );
    let mut w = p.worker();
    let mut one = vec![0.0; nq];
    for r in 0..rows {
        let res = w.eval(&params[r * np..(r + 1) * np], &mut one);
        assert_eq!(res.is_err(), bad.contains(&r));
        for (a, b) in one.iter().zip(&out[r * nq..(r + 1) * nq]) {
            assert!(a == b || (a.is_nan() && b.is_nan()), "row {r}: {a} vs {b}");
        }
    }
}

#[test]
fn ill_conditioned_rows_are_refused_not_returned() {
    // Fig. 3 near lock: tau_1 tau_2 -> 1 makes [Psi_w] singular.
    let t = train(&crate::lab::families::near_locked(0.1));
    let p = plan(&t, Compute::Dynamics);
    let c2 = p
        .parameter("ratio.G2")
        .unwrap_or_else(|| panic!("{:?}", p.parameters()));
    let t1 = p.base()[p.parameter("ratio.G1").unwrap_or(0)];
    let mut out = vec![0.0; p.outputs().len()];
    let mut w = p.worker();
    let mut refused = 0;
    for eps in [1e-3, 1e-6, 1e-9, 1e-12, 1e-14, 1e-15] {
        let mut row = p.base().to_vec();
        row[c2] = (1.0 + eps) / t1;
        match w.eval(&row, &mut out) {
            Ok(()) => {
                let cond = out[p.output("cond.speeds").unwrap_or(0)];
                assert!(
                    cond <= egt_core::numerics::linalg::COND_REFUSE,
                    "eps {eps}: returned at cond {cond}"
                );
                assert!(out.iter().all(|v| v.is_finite()));
            }
            Err(Error::Analysis(AnalysisError::IllConditioned { condition, .. })) => {
                assert!(condition > egt_core::numerics::linalg::COND_REFUSE);
                assert!(
                    out.iter().all(|v| v.is_nan()),
                    "refused rows carry no numbers"
                );
                refused += 1;
            }
            Err(Error::Analysis(AnalysisError::Singular { .. })) => refused += 1,
            Err(e) => panic!("eps {eps}: {e}"),
        }
    }
    assert!(refused >= 2, "near-lock rows must be refused");
}

#[test]
fn reused_factorisations_give_the_numbers_of_a_fresh_worker() {
    // Rows that share ratios reuse the previous factorisations; interleave
    // equal and different ratios, a refused row and lossy rows, and compare
    // every row with a worker that has seen nothing before.
    for compute in [Compute::Kinematics, Compute::Dynamics, Compute::Power] {
        for t in [
            crate::util::example("fig3_example61.toml"),
            train(&crate::lab::families::planetary_chain(3)),
        ] {
            let p = plan(&t, compute);
            let ratio = 0;
            let load = p
                .parameters()
                .iter()
                .position(|n| n.starts_with("torque.") || n.starts_with("speed."))
                .unwrap_or_else(|| panic!("{:?}", p.parameters()));
            let mut rows = Vec::new();
            for k in 0..12 {
                let mut row = p.base().to_vec();
                row[ratio] *= [1.0, 1.0, 1.1, 1.1, 1.0, 0.0][k % 6];
                row[load] += k as f64;
                rows.push(row);
            }
            let mut w = p.worker();
            let mut a = vec![0.0; p.outputs().len()];
            let mut b = vec![0.0; p.outputs().len()];
            for (k, row) in rows.iter().enumerate() {
                let ra = w.eval(row, &mut a);
                let rb = p.worker().eval(row, &mut b);
                assert_eq!(ra.is_ok(), rb.is_ok(), "row {k}");
                assert_eq!(ra.is_ok(), k % 6 != 5, "row {k}: the zero ratio is refused");
                for (x, y) in a.iter().zip(&b) {
                    assert!(
                        x == y || (x.is_nan() && y.is_nan()),
                        "{compute:?} row {k}: {x} vs {y}"
                    );
                }
            }
        }
    }
}

/// The linear block path (a block whose ratios, inertias and masses are
/// shared, with speeds, accelerations and torques varying) gives what a
/// worker solving each row gives, to round-off: every output column, the
/// conditions of rows with and without prescribed accelerations, and the
/// rows refused for a bad value. Trains: a nest (bodies on carriers on
/// carriers), a planetary chain and the paper's Fig. 3, kinematics and dynamics.
#[test]
fn linear_blocks_equal_row_by_row_solves() {
    for t in [
        train(&crate::lab::families::nest(6)),
        train(&crate::lab::families::planetary_chain(3)),
        crate::util::example("fig3_example61.toml"),
    ] {
        for compute in [Compute::Kinematics, Compute::Dynamics] {
            let p = plan(&t, compute);
            let (np, nq) = (p.parameters().len(), p.outputs().len());
            let linear: Vec<usize> = p
                .parameters()
                .iter()
                .enumerate()
                .filter(|(_, n)| {
                    ["speed.", "accel.", "torque."]
                        .iter()
                        .any(|k| n.starts_with(k))
                })
                .map(|(c, _)| c)
                .collect();
            assert!(!linear.is_empty());
            let rows = 700;
            let mut params = Vec::with_capacity(rows * np);
            for r in 0..rows {
                let mut row = p.base().to_vec();
                for (k, &c) in linear.iter().enumerate() {
                    // Every linear column varies; accelerations are zero in
                    // every third row (no eq. (8) there).
                    let name = &p.parameters()[c];
                    row[c] = if name.starts_with("accel.") && r % 3 == 0 {
                        0.0
                    } else {
                        (r as f64 * 0.37 + k as f64).sin() * 100.0
                    };
                }
                params.extend(row);
            }
            params[5 * np + linear[0]] = f64::NAN;
            // Two bad values in a row: the first in column order is named.
            let last = linear[linear.len() - 1];
            params[300 * np + last] = f64::INFINITY;
            params[300 * np + linear[0]] = f64::NEG_INFINITY;
            // The path under test: every block of 256 rows is a linear one.
            for block in params.chunks(256 * np) {
                assert!(p.is_linear_block(block));
            }
            let mut mixed = params[..16 * np].to_vec();
            mixed[3 * np] *= 1.5; // a ratio differs: solved row by row
            assert!(!p.is_linear_block(&mixed));
            let mut out = vec![0.0; rows * nq];
            let errors = p.run(Layout::Rows(&params), &mut out, Threads::Pool).errors;
            assert_eq!(errors.iter().map(|e| e.row).collect::<Vec<_>>(), [5, 300]);
            let first = &p.parameters()[linear[0]];
            assert!(
                errors[1].error.to_string().contains(first.as_str()),
                "{}",
                errors[1].error
            );
            // Column-major, the linear path goes column by column, every
            // output or only the chosen: the same numbers bit for bit.
            assert_columns_agree(&format!("linear {compute:?}"), &p, &params, &out, &errors);
            assert_choice_agrees(&format!("linear {compute:?}"), &p, &params, &out, &errors);
            let mut one = vec![0.0; nq];
            for r in 0..rows {
                let res = p.worker().eval(&params[r * np..(r + 1) * np], &mut one);
                assert_eq!(res.is_err(), r == 5 || r == 300);
                let got = &out[r * nq..(r + 1) * nq];
                let scale = one
                    .iter()
                    .filter(|v| v.is_finite())
                    .fold(1.0_f64, |m, v| m.max(v.abs()));
                for (c, (a, b)) in one.iter().zip(got).enumerate() {
                    assert!(
                        (a.is_nan() && b.is_nan()) || (a - b).abs() <= 1e-13 * scale,
                        "{compute:?} row {r} {}: {a} vs {b}",
                        p.outputs()[c]
                    );
                }
            }
        }
    }
}

/// The batch's test trains (see `runs_equal_fresh_row_by_row_solves_bit_for_bit`).
fn test_plans() -> Vec<(String, BatchPlan)> {
    use egt_core::batch::BatchSpec;
    let fig5 = crate::util::example("fig5_example62.toml");
    let id = |t: &Train, n: &str| t.link_id(n).unwrap_or_else(|| panic!("no link {n}"));
    let apart = BatchSpec {
        inputs: vec![id(&fig5, "2"), id(&fig5, "4")],
        accelerated: vec![id(&fig5, "3"), id(&fig5, "4")],
        driving: vec![id(&fig5, "6"), id(&fig5, "2")],
        extras: Vec::new(),
        compute: Compute::Dynamics,
    };
    let zf = crate::util::example("zf_8hp70.toml");
    let mut plans: Vec<(String, BatchPlan)> = Vec::new();
    for (name, t) in [
        ("nest", train(&crate::lab::families::nest(6))),
        ("chain", train(&crate::lab::families::planetary_chain(3))),
        ("fig3", crate::util::example("fig3_example61.toml")),
        ("fig5", fig5.clone()),
    ] {
        for compute in [Compute::Kinematics, Compute::Dynamics] {
            plans.push((format!("{name} {compute:?}"), plan(&t, compute)));
        }
    }
    plans.push((
        "fig5 apart".into(),
        BatchPlan::new(&fig5, &apart).unwrap_or_else(|e| panic!("{e}")),
    ));
    for s in &zf
        .checked_transmission()
        .unwrap_or_else(|e| panic!("{e}"))
        .states
    {
        let spec = BatchSpec::for_gear_state(&zf, &s.name, Compute::Dynamics)
            .unwrap_or_else(|e| panic!("{e}"));
        plans.push((
            format!("8HP {}", s.name),
            BatchPlan::new(&zf, &spec).unwrap_or_else(|e| panic!("{e}")),
        ));
    }
    plans
}

/// Rows of `sweep_rows` with a bad value in the last column of a group.
const BAD_ROWS: [(usize, &str); 6] = [
    (17, "ratio."),
    (23, "speed."),
    (29, "accel."),
    (31, "torque."),
    (37, "inertia."),
    (41, "mass."),
];

/// 613 rows, none linear: every row its own ratios, every 50th far off
/// (another pivot order), row 5 with a NaN, row 11 singular in most trains,
/// the rows of `BAD_ROWS` with a bad value.
fn sweep_rows(p: &BatchPlan) -> Vec<f64> {
    let (np, rows) = (p.parameters().len(), 613);
    let mut params = Vec::with_capacity(rows * np);
    for r in 0..rows {
        let mut row = p.base().to_vec();
        for (c, v) in row.iter_mut().enumerate() {
            let col = &p.parameters()[c];
            let wave = (r as f64 * 0.37 + c as f64).sin();
            if col.starts_with("ratio.") {
                // Every row its own ratios; every 50th far off (another pivot order).
                *v *= if r % 50 == 7 {
                    -3.0 + wave
                } else {
                    1.0 + 0.2 * wave
                };
            } else if col.starts_with("accel.") && r % 3 == 0 {
                *v = 0.0;
            } else if v.is_finite() && !col.starts_with("inertia.") && !col.starts_with("mass.") {
                *v = 100.0 * wave;
            } else if col.starts_with("inertia.") || col.starts_with("mass.") {
                *v *= 1.0 + 0.5 * wave.abs();
            }
        }
        params.extend(row);
    }
    params[5 * np] = f64::NAN;
    params[11 * np] = 1.0; // a singular row in most trains
    // A bad value in each other group of columns that has one.
    for ((r, prefix), v) in
        BAD_ROWS
            .into_iter()
            .zip([0.0, f64::INFINITY, f64::NAN, f64::NEG_INFINITY, -1e-3, -0.5])
    {
        if let Some(c) = p.parameters().iter().rposition(|n| n.starts_with(prefix)) {
            params[r * np + c] = v;
        }
    }
    params
}

/// Row errors as comparable text: the row and the message.
fn show(errors: &[egt_core::batch::RowError]) -> Vec<String> {
    errors
        .iter()
        .map(|e| format!("{} {}", e.row, e.error))
        .collect()
}

/// `Layout::Columns` on `params` (row-major here, transposed for
/// it) gives `out` and `errors` of `run` bit for bit.
fn assert_columns_agree(
    name: &str,
    p: &BatchPlan,
    params: &[f64],
    out: &[f64],
    errors: &[egt_core::batch::RowError],
) {
    let (np, nq) = (p.parameters().len(), p.outputs().len());
    let rows = params.len() / np;
    let columns: Vec<f64> = (0..np)
        .flat_map(|k| params[k..].iter().step_by(np).copied())
        .collect();
    for threads in [Threads::Pool, Threads::Calling] {
        let mut by_columns = vec![0.0; rows * nq];
        let column_errors = p
            .run(Layout::Columns(&columns), &mut by_columns, threads)
            .errors;
        assert_eq!(
            show(errors),
            show(&column_errors),
            "{name}: column-major, {threads:?}"
        );
        for r in 0..rows {
            for o in 0..nq {
                let (a, b) = (out[r * nq + o], by_columns[o * rows + r]);
                assert!(
                    a.to_bits() == b.to_bits(),
                    "{name} row {r} {}: {a} by rows, {b} by columns ({threads:?})",
                    p.outputs()[o]
                );
            }
        }
    }
}

/// `BatchPlan::with_outputs` (a few columns, out of order, a condition
/// among them) gives the chosen columns of `out` and the same `errors`,
/// bit for bit, row-major and column-major; its program is shorter.
fn assert_choice_agrees(
    name: &str,
    p: &BatchPlan,
    params: &[f64],
    out: &[f64],
    errors: &[egt_core::batch::RowError],
) {
    let nq = p.outputs().len();
    let rows = out.len() / nq;
    // Every third output from the last, so a condition leads.
    let picks: Vec<usize> = (0..nq).rev().step_by(3).collect();
    let names: Vec<&str> = picks.iter().map(|&o| p.outputs()[o].as_str()).collect();
    let c = p
        .clone()
        .with_outputs(&names)
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    assert_eq!(c.outputs(), names.as_slice(), "{name}");
    let conds: Vec<usize> = (picks.iter().enumerate())
        .filter(|(_, o)| p.condition_columns().contains(o))
        .map(|(k, _)| k)
        .collect();
    assert_eq!(c.condition_columns(), conds.as_slice(), "{name}");
    if let (Some(all), Some(some)) = (p.program_operations(), c.program_operations()) {
        assert!(some < all, "{name}: {some} operations chosen, {all} in all");
    }
    let mut chosen = vec![0.0; rows * picks.len()];
    let chosen_errors = c
        .run(Layout::Rows(params), &mut chosen, Threads::Pool)
        .errors;
    assert_eq!(show(errors), show(&chosen_errors), "{name}: chosen outputs");
    for r in 0..rows {
        for (k, &o) in picks.iter().enumerate() {
            let (a, b) = (out[r * nq + o], chosen[r * picks.len() + k]);
            assert!(
                a.to_bits() == b.to_bits(),
                "{name} row {r} {}: {a} of all, {b} chosen",
                names[k]
            );
        }
    }
    assert_columns_agree(name, &c, params, &chosen, &chosen_errors);
}

/// Power flow (row by row) gives the chosen columns too; a bad choice is
/// refused, naming it.
#[test]
fn chosen_outputs_of_power_flow_and_bad_choices() {
    let t = crate::util::example("fig3_example61.toml");
    let p = plan(&t, Compute::Power);
    let np = p.parameters().len();
    let mut params = Vec::new();
    for r in 0..300 {
        params.extend(p.base().iter().enumerate().map(|(c, &v)| {
            let wave = (r as f64 * 0.37 + c as f64).sin();
            if p.parameters()[c].starts_with("efficiency.") {
                v
            } else {
                v * (1.0 + 0.1 * wave)
            }
        }));
    }
    params[7 * np] = f64::NAN;
    let mut out = vec![0.0; params.len() / np * p.outputs().len()];
    let errors = p.run(Layout::Rows(&params), &mut out, Threads::Pool).errors;
    assert_eq!(
        errors.len(),
        1,
        "{:?}",
        errors.first().map(|e| e.error.to_string())
    );
    assert_choice_agrees("fig3 power", &p, &params, &out, &errors);
    let refused = |names: &[&str]| match p.clone().with_outputs(names) {
        Ok(_) => panic!("{names:?} accepted"),
        Err(e) => e.to_string(),
    };
    let e = refused(&["power.loss", "speed.nowhere"]);
    assert!(
        e.contains("outputs") && e.contains("`speed.nowhere`"),
        "{e}"
    );
    let e = refused(&["power.loss", "power.loss"]);
    assert!(e.contains("`power.loss` chosen twice"), "{e}");
    let e = refused(&[]);
    assert!(e.contains("no output column"), "{e}");
}

/// `BatchPlan::run` without condition bounds (rows whose ratios differ, so
/// no linear block and no program) gives what a fresh worker gives for each
/// row alone, bit for bit:
/// every output column, the conditions included, with rows that pivot
/// differently from their group, singular rows (a ratio of 1 locks a
/// planetary set's sun to its carrier) and rows with a bad value in among
/// them (and `Layout::Columns` gives the same, bit for bit). Trains: a nest, a chain, Fig. 3, the two-motor Fig. 5 with
/// accelerations prescribed on other links than the speeds (eq. 8 factored
/// apart) and torques solved on a third pair (eq. 10 apart), and every gear
/// state of the 8HP70 (engaged elements as extra rows, output torque solved).
#[test]
fn runs_equal_fresh_row_by_row_solves_bit_for_bit() {
    for (name, p) in &test_plans() {
        let (np, nq) = (p.parameters().len(), p.outputs().len());
        let rows = 613;
        let params = sweep_rows(p);
        for block in params.chunks(256 * np) {
            assert!(
                !p.is_linear_block(block) && !p.program_applies(block),
                "{name}"
            );
        }
        let mut out = vec![0.0; rows * nq];
        let errors = p.run(Layout::Rows(&params), &mut out, Threads::Pool).errors;
        assert_columns_agree(name, p, &params, &out, &errors);
        assert_choice_agrees(name, p, &params, &out, &errors);
        let mut failed = Vec::new();
        let mut one = vec![0.0; nq];
        for r in 0..rows {
            let res = p.worker().eval(&params[r * np..(r + 1) * np], &mut one);
            if res.is_err() {
                failed.push(r);
            }
            for (c, (a, b)) in one.iter().zip(&out[r * nq..(r + 1) * nq]).enumerate() {
                assert!(
                    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()),
                    "{name} row {r} {}: {a} alone vs {b} in the batch",
                    p.outputs()[c]
                );
            }
        }
        assert_eq!(
            errors.iter().map(|e| e.row).collect::<Vec<_>>(),
            failed,
            "{name}"
        );
        assert!(failed.contains(&5), "{name}");
        for (r, prefix) in BAD_ROWS {
            let has = p.parameters().iter().any(|n| n.starts_with(prefix));
            assert!(
                !has || failed.contains(&r),
                "{name}: row {r} ({prefix}) {failed:?}"
            );
        }
    }
}

/// The sparse engine of large trains (faer's sparse LU for the three
/// systems, [M] as a list of terms) gives the dense engine's numbers to
/// round-off on every test train: kinematics, inverse dynamics and power
/// flow with mesh losses (the same direction search), base rows and rows
/// with every parameter moved; a row the dense engine refuses is refused.
/// The condition estimates are of the same matrices by different
/// factorisations, so they are compared within the estimator's factor of 3.
#[test]
fn the_sparse_engine_gives_the_dense_numbers() {
    for (name, t) in one_dof_trains() {
        for compute in [Compute::Kinematics, Compute::Dynamics, Compute::Power] {
            let dense = plan(&t, compute)
                .with_sparse(false)
                .unwrap_or_else(|e| panic!("{e}"));
            let sparse = plan(&t, compute)
                .with_sparse(true)
                .unwrap_or_else(|e| panic!("{e}"));
            assert!(sparse.prepared().is_sparse() && !dense.prepared().is_sparse());
            let conds = dense.condition_columns();
            let q = dense.outputs().len();
            let (mut a, mut b) = (vec![0.0; q], vec![0.0; q]);
            let (mut wd, mut ws) = (dense.worker(), sparse.worker());
            for k in 0..6 {
                let row: Vec<f64> = dense
                    .base()
                    .iter()
                    .enumerate()
                    .map(|(c, &v)| {
                        let f = 1.0 + 0.02 * (((k * 5 + c * 3) % 7) as f64 - 3.0) / 3.0;
                        if k == 0 { v } else { v * f }
                    })
                    .collect();
                let (ra, rb) = (wd.eval(&row, &mut a), ws.eval(&row, &mut b));
                assert_eq!(
                    ra.is_ok(),
                    rb.is_ok(),
                    "{name} {compute:?} row {k}: {ra:?} {rb:?}"
                );
                if ra.is_err() {
                    continue;
                }
                let scale = a.iter().map(|v| v.abs()).fold(1e-300, f64::max);
                for (c, (x, y)) in a.iter().zip(&b).enumerate() {
                    if conds.contains(&c) {
                        assert!(
                            x / y <= 3.0 && y / x <= 3.0,
                            "{name} {compute:?} row {k} {}: {x} vs {y}",
                            dense.outputs()[c]
                        );
                    } else {
                        assert!(
                            (x - y).abs() <= 1e-12 * scale,
                            "{name} {compute:?} row {k} {}: {x} vs {y}",
                            dense.outputs()[c]
                        );
                    }
                }
            }
        }
    }
}

/// With condition bounds (`with_condition_bounds`) the batch refuses the same
/// rows, with the same messages, and give every other output bit for bit as
/// without; a `cond.*` value differs only where it is an upper bound of the
/// estimate at most COND_WARN / 2, so every warning is kept. On the batch's
/// test trains and Fig. 3 near its lock, where every fifth row takes
/// tau_2 = (1 + eps) / tau_1 with eps from 10^-1 to 10^-16 (conditions from
/// 10 to past the refusal): the bounds, the estimates past COND_WARN and
/// the refusals all occur.
#[test]
fn condition_bounds_change_only_small_conditions() {
    use egt_core::numerics::linalg::COND_WARN;
    let near = train(&crate::lab::families::near_locked(0.1));
    let plans = || {
        let mut v = test_plans();
        for compute in [Compute::Kinematics, Compute::Dynamics] {
            v.push((format!("near-locked {compute:?}"), plan(&near, compute)));
        }
        v
    };
    let (mut bounded, mut warned, mut refused, mut rounded) = (0, 0, 0, 0);
    for ((name, p), (_, b)) in plans().iter().zip(plans()) {
        let b = b.with_condition_bounds(true);
        assert!(b.has_program(), "{name}: no straight-line program");
        let (np, nq) = (p.parameters().len(), p.outputs().len());
        let mut params = sweep_rows(p);
        let rows = params.len() / np;
        if let (Some(g1), Some(g2)) = (p.parameter("ratio.G1"), p.parameter("ratio.G2")) {
            let t1 = p.base()[g1];
            for r in (2..rows).step_by(5) {
                let eps = 10f64.powi(-((r / 5 % 16) as i32 + 1));
                params[r * np + g1] = t1;
                params[r * np + g2] = (1.0 + eps) / t1;
            }
        }
        let (mut full, mut fast) = (vec![0.0; rows * nq], vec![0.0; rows * nq]);
        let errors = p
            .run(Layout::Rows(&params), &mut full, Threads::Pool)
            .errors;
        let errors_bounded = b
            .run(Layout::Rows(&params), &mut fast, Threads::Pool)
            .errors;
        assert_eq!(show(&errors), show(&errors_bounded), "{name}");
        // Column-major, the program reads and writes whole columns.
        assert_columns_agree(name, &b, &params, &fast, &errors_bounded);
        assert_choice_agrees(name, &b, &params, &fast, &errors_bounded);
        refused += errors
            .iter()
            .filter(|e| {
                matches!(
                    e.error,
                    Error::Analysis(AnalysisError::IllConditioned { .. })
                )
            })
            .count();
        let conds = p.condition_columns();
        assert_eq!(conds, b.condition_columns());
        for r in 0..rows {
            let (a, z) = (&full[r * nq..(r + 1) * nq], &fast[r * nq..(r + 1) * nq]);
            // The program's numbers differ by rounding: within 1e-12 of the
            // row's largest (non-condition) output.
            let scale = (0..nq)
                .filter(|c| !conds.contains(c))
                .map(|c| a[c].abs())
                .fold(0.0, f64::max);
            let mut differs = false;
            for c in 0..nq {
                let (x, y) = (a[c], z[c]);
                if x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan()) {
                    if conds.contains(&c) && x > COND_WARN && x.is_finite() {
                        warned += 1;
                    }
                    continue;
                }
                if conds.contains(&c) {
                    assert!(
                        y >= x * (1.0 - 1e-12) && y <= 0.5 * COND_WARN,
                        "{name} row {r} {}: {x} estimated, {y} with bounds",
                        p.outputs()[c]
                    );
                    bounded += 1;
                } else {
                    assert!(
                        (x - y).abs() <= 1e-12 * scale,
                        "{name} row {r} {}: {x} row by row, {y} with bounds",
                        p.outputs()[c]
                    );
                    differs = true;
                }
            }
            rounded += usize::from(differs);
        }
    }
    // Rows that differ by rounding were solved by the program (the others
    // are the row-by-row solve's numbers bit for bit).
    assert!(rounded > 500, "{rounded} rows solved by the program");
    assert!(
        bounded > 1000 && warned > 10 && refused > 10,
        "{bounded} bounds, {warned} warnings, {refused} refusals"
    );
}

/// The straight-line program runs compiled (`Executor::Auto`, with the
/// `jit` feature on a machine with AVX-512 or AVX2) or interpreted, with the
/// same bits and the same refused rows; a plan without a program takes
/// either executor and has no compiled program.
#[test]
fn the_program_runs_compiled_or_interpreted_with_the_same_bits() {
    let t = train(&crate::lab::families::planetary_chain(3));
    let p = plan(&t, Compute::Dynamics).with_condition_bounds(true);
    let (np, nq) = (p.parameters().len(), p.outputs().len());
    let ratio = p
        .parameter("ratio.P1/sun-planet")
        .unwrap_or_else(|| panic!("{:?}", p.parameters()));
    let rows = 200;
    let mut columns: Vec<f64> = (0..np)
        .flat_map(|c| std::iter::repeat_n(p.base()[c], rows))
        .collect();
    for r in 0..rows {
        columns[ratio * rows + r] = -0.5 - 0.4 * (r as f64 / rows as f64);
    }
    columns[ratio * rows + 17] = 0.0;
    // Compiled where the build has the JIT and the machine runs its code.
    #[cfg(all(feature = "jit", target_arch = "x86_64"))]
    let compiles = std::env::var("EGT_JIT").as_deref() != Ok("0")
        && (std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("bmi2")
            && std::arch::is_x86_feature_detected!("fma")
            || std::arch::is_x86_feature_detected!("avx512f")
                && std::arch::is_x86_feature_detected!("avx512dq"));
    #[cfg(not(all(feature = "jit", target_arch = "x86_64")))]
    let compiles = false;
    let mut results: Vec<(Executor, Vec<f64>, Vec<usize>)> = Vec::new();
    for executor in [Executor::Interpreted, Executor::Auto] {
        let q = p.clone().with_executor(executor);
        assert!(q.has_program(), "{executor:?}");
        assert_eq!(
            q.program_compiled(),
            executor == Executor::Auto && compiles,
            "{executor:?}"
        );
        let mut out = vec![0.0; rows * nq];
        let failed = q
            .run(Layout::Columns(&columns), &mut out, Threads::Pool)
            .errors
            .iter()
            .map(|e| e.row)
            .collect();
        results.push((executor, out, failed));
    }
    let (_, first, failed) = &results[0];
    assert_eq!(failed, &vec![17], "the zero ratio's row refused");
    for (executor, out, f) in &results[1..] {
        assert_eq!(f, failed, "{executor:?}");
        for (i, (a, b)) in out.iter().zip(first).enumerate() {
            assert!(
                a.to_bits() == b.to_bits(),
                "{executor:?} cell {i}: {a} against {b}"
            );
        }
    }
    // Back and forth: the executor is the plan's, kept through the outputs'
    // choice and the bounds.
    let back = p
        .clone()
        .with_executor(Executor::Interpreted)
        .with_condition_bounds(false)
        .with_condition_bounds(true);
    assert!(back.has_program() && !back.program_compiled());
    let none = plan(&t, Compute::Dynamics).with_executor(Executor::Interpreted);
    assert!(!none.has_program() && !none.program_compiled());
}

/// `Layout::ColumnSet` with some columns given as one value for
/// every row gives `Layout::Columns` on the same columns written out, bit for
/// bit, with the same errors: on the program (condition bounds), row by
/// row (no bounds), the linear path (only loads vary) and the transposed row-by-row path;
/// with nothing varied; with a bad value in a fixed column (every row
/// refused) and in varied ones; on the pool and the calling thread.
#[test]
fn fixed_columns_give_the_numbers_of_the_columns_written_out() {
    use egt_core::batch::Column;
    for (name, p) in &test_plans() {
        for p in [p.clone(), p.clone().with_condition_bounds(true)] {
            let (np, nq) = (p.parameters().len(), p.outputs().len());
            let rows = 613;
            let full = sweep_rows(&p);
            let group = |prefix: &str| -> Vec<usize> {
                (0..np)
                    .filter(|&c| p.parameters()[c].starts_with(prefix))
                    .collect()
            };
            let odd: Vec<usize> = (0..np).filter(|c| c % 2 == 1).collect();
            // A NaN in the last column that is not a ratio (fixed below).
            let mut bad_fixed = p.base().to_vec();
            let last = (0..np).rposition(|c| !p.parameters()[c].starts_with("ratio."));
            bad_fixed[last.unwrap_or_else(|| panic!("{name}: only ratios"))] = f64::NAN;
            for (what, varied, base) in [
                ("ratios", group("ratio."), p.base().to_vec()),
                ("loads", group("torque."), p.base().to_vec()),
                ("odd columns", odd, p.base().to_vec()),
                ("nothing", Vec::new(), p.base().to_vec()),
                ("a NaN fixed", group("ratio."), bad_fixed),
            ] {
                let label = format!("{name} {what} (program {})", p.has_program());
                // The full matrix: varied columns from `sweep_rows`, the others `base`.
                let columns: Vec<f64> = (0..np)
                    .flat_map(|k| {
                        let from_rows = varied.contains(&k);
                        (0..rows).map(move |r| (from_rows, r, k))
                    })
                    .map(|(from_rows, r, k)| if from_rows { full[r * np + k] } else { base[k] })
                    .collect();
                let mut expected = vec![0.0; rows * nq];
                let expected_errors = p
                    .run(Layout::Columns(&columns), &mut expected, Threads::Pool)
                    .errors;
                let set: Vec<Column<'_>> = (0..np)
                    .map(|k| {
                        if varied.contains(&k) {
                            Column::Rows(&columns[k * rows..(k + 1) * rows])
                        } else {
                            Column::Every(base[k])
                        }
                    })
                    .collect();
                for threads in [Threads::Pool, Threads::Calling] {
                    let mut out = vec![0.0; rows * nq];
                    let errors = p
                        .run(
                            Layout::ColumnSet {
                                columns: &set,
                                rows,
                            },
                            &mut out,
                            threads,
                        )
                        .errors;
                    assert_eq!(show(&expected_errors), show(&errors), "{label} {threads:?}");
                    for (i, (a, b)) in out.iter().zip(&expected).enumerate() {
                        assert!(
                            a.to_bits() == b.to_bits(),
                            "{label} {threads:?} {} row {}: {a} with fixed columns, {b} written out",
                            p.outputs()[i / rows],
                            i % rows
                        );
                    }
                }
                if what == "a NaN fixed" {
                    assert_eq!(expected_errors.len(), rows, "{label}");
                } else if what == "nothing" {
                    // Every row the base row: all solved or all refused.
                    let n = expected_errors.len();
                    assert!(n == 0 || n == rows, "{label}: {n} rows refused");
                }
            }
        }
    }
}

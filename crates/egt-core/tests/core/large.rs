//! Large trains: the sparse Willis solve against the dense one, against exact
//! rationals and against the product of the stage ratios of a 10 000-link
//! chain; refusals where the sparse LU meets a (nearly) singular system; the
//! dense analyses refused by name past their memory limit; a train with
//! thousands of degrees of freedom checked in about linear memory.

use egt_core::numerics::exact;
use egt_core::solve::kinematics::willis_residual;
use egt_core::{LinkId, SpeedInput, Train};

use crate::lab::families;
use crate::util::{self, one_dof_trains};

fn input_of(t: &Train) -> (Vec<LinkId>, Vec<f64>) {
    (
        t.analysis().speeds.iter().map(|s| s.0).collect(),
        t.analysis().speeds.iter().map(|s| s.1).collect(),
    )
}

fn speed_inputs(t: &Train) -> Vec<SpeedInput> {
    let (links, speeds) = input_of(t);
    links
        .iter()
        .zip(&speeds)
        .map(|(&l, &v)| (l, v).into())
        .collect()
}

fn solve(t: &Train, sparse: bool) -> egt_core::error::Result<(Vec<f64>, f64)> {
    let (links, speeds) = input_of(t);
    util::prepared_speeds(t, &links, &speeds, sparse)
}

#[test]
fn sparse_and_dense_willis_solves_agree_on_every_test_train() {
    let mut trains = one_dof_trains();
    trains.push(("zigzag 40".into(), util::train(&families::zigzag_chain(40))));
    trains.push((
        "chain 40".into(),
        util::train(&families::planetary_chain(40)),
    ));
    for (name, t) in trains {
        let (d, cd) = solve(&t, false).unwrap_or_else(|e| panic!("{name}: {e}"));
        let (s, cs) = solve(&t, true).unwrap_or_else(|e| panic!("{name}: {e}"));
        let scale = d.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        for (k, (a, b)) in d.iter().zip(&s).enumerate() {
            assert!(
                (a - b).abs() <= 1e-13 * scale,
                "{name}: link {k}: dense {a} against sparse {b}"
            );
        }
        // Two estimates of one condition number, from different factors.
        assert!(
            cs <= 3.0 * cd && cd <= 3.0 * cs,
            "{name}: condition {cd} against {cs}"
        );
    }
}

#[test]
fn sparse_solve_of_a_500_link_chain_is_within_1e_13_of_exact() {
    let t = util::train(&families::zigzag_chain(249));
    assert!(t.coordinates().len() >= egt_core::solve::prepared::PREPARED_SPARSE_FROM);
    let (w, cond) = solve(&t, true).unwrap_or_else(|e| panic!("{e}"));
    // A disturbance of one stage reaches every later one: the condition
    // grows like the number of links, not faster.
    assert!(cond < 10.0 * t.links().len() as f64, "condition {cond}");
    let inputs = speed_inputs(&t);
    let k = t.kinematics(&inputs).unwrap_or_else(|e| panic!("{e}"));
    let ex = k
        .exact
        .unwrap_or_else(|| panic!("tooth counts give exact speeds"));
    for (l, (f, q)) in w.iter().zip(&ex).enumerate() {
        let e = exact::to_f64(q);
        assert!(
            (f - e).abs() <= 1e-13 * e.abs().max(1e-300),
            "link {l}: {f} against exact {e}"
        );
    }
}

/// The speed of every stage's output of a zigzag chain, from its teeth
/// alone: a sun-in set turns its carrier at z_s / (z_s + z_r) of the sun's
/// speed, a carrier-in set its sun at (z_s + z_r) / z_s of the carrier's.
fn stage_speeds(k: usize, input: f64) -> Vec<f64> {
    let mut w = vec![input];
    for i in 1..=k {
        let zs = (21 + (7 * i as i64) % 13) as f64;
        let zp = (17 + (5 * i as i64) % 11) as f64;
        let zr = zs + 2.0 * zp;
        let last = w[i - 1];
        w.push(if i % 2 == 1 {
            last * zs / (zs + zr)
        } else {
            last * (zs + zr) / zs
        });
    }
    w
}

#[test]
fn a_10000_link_chain_checks_and_solves_to_the_product_of_its_stage_ratios() {
    let k = 4999;
    let t = util::train(&families::zigzag_chain(k));
    assert_eq!(t.links().len(), 10_000);
    let (_, speeds) = input_of(&t);
    let inputs = speed_inputs(&t);
    let s = t.kinematics(&inputs).unwrap_or_else(|e| panic!("{e}"));
    // No exact speeds this large, and the answer says so.
    assert!(s.exact.is_none());
    assert!(
        s.warnings.iter().any(|w| w.contains("no exact speeds")),
        "{:?}",
        s.warnings
    );
    let expected = stage_speeds(k, speeds[0]);
    for (i, e) in expected.iter().enumerate() {
        let l = t
            .link_id(&format!("m{i}"))
            .unwrap_or_else(|| panic!("m{i}"));
        let w = s.speed[l.index()];
        assert!((w - e).abs() <= 1e-12 * e.abs(), "m{i}: {w} against {e}");
    }
    let ratios = t.ratios().unwrap_or_else(|e| panic!("{e}"));
    let residual = willis_residual(&t, &ratios, &s.speed);
    assert!(residual < 1e-14, "residual {residual}");
    assert!(
        s.condition < 20.0 * t.links().len() as f64,
        "condition {}",
        s.condition
    );
}

#[test]
fn the_sparse_solve_refuses_singular_and_nearly_singular_systems() {
    for (name, text) in [
        ("locked Fig. 3", families::near_locked(0.0)),
        ("near-locked Fig. 3", families::near_locked(1e-15)),
    ] {
        let t = util::train(&text);
        for sparse in [false, true] {
            match solve(&t, sparse) {
                Ok((w, c)) => panic!("{name} (sparse {sparse}): speeds {w:?}, condition {c}"),
                Err(e) => assert!(
                    matches!(e.code(), "singular" | "ill_conditioned"),
                    "{name} (sparse {sparse}): {e}"
                ),
            }
        }
    }
}

#[test]
fn dense_analyses_of_a_train_past_the_limit_are_refused_by_name() {
    let t = util::train(&families::zigzag_chain(600));
    // [M] itself is held sparse; its dense copy is refused like the rest.
    let mass = t.mass_matrix().unwrap_or_else(|e| panic!("{e}"));
    for e in [t.willis_jacobian().err(), mass.matrix().err()] {
        let e = e.unwrap_or_else(|| panic!("a 1202-link train's dense analysis ran"));
        assert_eq!(e.code(), "too_large", "{e}");
        let msg = e.to_string();
        assert!(
            msg.contains("1202 links") && msg.contains("at most 1024 links"),
            "{msg}"
        );
    }
    assert!(t.willis_jacobian_exact().is_none());
}

#[test]
fn speeds_that_underflow_double_precision_are_flagged() {
    // 600 reducing sets: the last carriers turn below 1e-308 of the input.
    let t = util::train(&families::planetary_chain(600));
    let s = t
        .kinematics(&speed_inputs(&t))
        .unwrap_or_else(|e| panic!("{e}"));
    let tiny = s
        .speed
        .iter()
        .filter(|w| w.abs() < f64::MIN_POSITIVE)
        .count();
    assert!(tiny > 0, "the chain was meant to underflow");
    assert!(
        s.warnings.iter().any(|w| w.contains("below 2.2e-308")),
        "{:?}",
        s.warnings
    );
    // A chain whose speeds stay of order one gets no such warning.
    let t = util::train(&families::zigzag_chain(600));
    let s = t
        .kinematics(&speed_inputs(&t))
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(
        !s.warnings.iter().any(|w| w.contains("below 2.2e-308")),
        "{:?}",
        s.warnings
    );
}

/// The mobility check asks of the null space of the Willis equations which
/// turning pairs can move; a basis has one dense vector per freedom, which
/// for a train with 2 501 DOF and 7 502 links is 150 MB and grows as the
/// square (a 25 000-set chain would need 15 GB and abort). Two generic null
/// vectors answer the same: the mobile chain checks with its DOF, and the
/// same chain with a locked last stage is refused naming exactly that stage.
#[test]
fn a_train_with_thousands_of_freedoms_is_checked_and_its_locked_stage_found() {
    let k = 2500;
    let spec = egt_core::spec::parse::parse_spec(
        &families::free_ring_chain(k, false),
        egt_core::Format::Toml,
        "free rings",
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let (peak, t) = crate::alloc::peak_bytes(|| Train::from_spec(&spec));
    let t = t.unwrap_or_else(|e| panic!("{e}"));
    // A basis of the null space alone would hold 2 501 x 7 501 x 8 bytes.
    assert!(peak < 64 << 20, "checking held {peak} bytes at once");
    assert_eq!(t.links().len(), 3 * k + 2);
    assert_eq!(t.dof(), k + 1);
    let err = Train::from_str(
        &families::free_ring_chain(k, true),
        egt_core::Format::Toml,
        "locked end",
    )
    .err()
    .unwrap_or_else(|| panic!("a locked last stage was accepted"));
    let text = err.to_string();
    assert!(text.contains("locked sub-chain"), "{text}");
    let named = format!("`m{}`, `m{k}`, `P{k}.planet`, `Q.planet`", k - 1);
    assert!(text.contains(&named), "{text}");
    assert!(!text.contains(&format!("`m{}`", k - 2)), "{text}");
}

/// Inverse dynamics and power flow of a 10 000-link chain (sparse LUs, [M]
/// as terms), against relations of their own: the driving torque of the
/// static case is the output load times the product of the stage ratios
/// from the teeth; with inertia, the power of all torques at any admissible
/// speeds equals w^T M w' (eq. 6 times w, as Psi w = 0); the power flow
/// with mesh losses balances input, output, loss and kinetic rate.
#[test]
fn a_10000_link_chain_balances_its_inverse_dynamics_and_power_flow() {
    let k = 4999;
    let t = util::train(&families::zigzag_chain(k));
    let out = t
        .link_id(&format!("m{k}"))
        .unwrap_or_else(|| panic!("m{k}"));
    let input = t.link_id("m0").unwrap_or_else(|| panic!("m0"));
    let w_ratio = stage_speeds(k, 1.0)[k];

    let mut req = util::request(&t);
    req.accelerations.clear();
    let statics = t
        .inverse_dynamics(&req, None)
        .unwrap_or_else(|e| panic!("{e}"));
    let load = req.torques.iter().find(|q| q.0 == out).map_or(0.0, |q| q.1);
    let expected = -load * w_ratio;
    let got = statics.driving_torques[0].1;
    assert!(
        (got - expected).abs() <= 1e-12 * expected.abs(),
        "{got} against {expected}"
    );

    let req = util::request(&t);
    let mass = t
        .mass_for(&req)
        .unwrap_or_else(|e| panic!("{e}"))
        .unwrap_or_else(|| panic!("the request accelerates"));
    let d = t
        .inverse_dynamics(&req, Some(&mass))
        .unwrap_or_else(|e| panic!("{e}"));
    let speeds = t
        .kinematics(&speed_inputs(&t))
        .unwrap_or_else(|e| panic!("{e}"));
    let coords = t.coordinates();
    let w: Vec<f64> = coords.iter().map(|l| speeds.speed[l.index()]).collect();
    let wd: Vec<f64> = coords.iter().map(|l| d.acceleration[l.index()]).collect();
    let kinetic_rate: f64 = w.iter().zip(mass.mul_vec(&wd)).map(|(a, b)| a * b).sum();
    let powers: Vec<f64> = coords
        .iter()
        .map(|l| d.torque[l.index()] * speeds.speed[l.index()])
        .collect();
    let power: f64 = powers.iter().sum();
    let scale: f64 = powers.iter().map(|p| p.abs()).sum();
    assert!(
        (power - kinetic_rate).abs() <= 1e-11 * scale,
        "power {power}, w^T M w' {kinetic_rate}"
    );
    assert!(d.driving_torques[0].0 == input && d.driving_torques[0].1 > got);

    let flow = t
        .power_flow(&util::power_request(&t, true), Some(&mass))
        .unwrap_or_else(|e| panic!("{e}"));
    let balance = flow.totals.input_power
        - flow.totals.output_power
        - flow.totals.loss
        - flow.totals.kinetic_rate;
    assert!(
        balance.abs() <= 1e-9 * flow.totals.input_power,
        "input {} output {} loss {} kinetic {}",
        flow.totals.input_power,
        flow.totals.output_power,
        flow.totals.loss,
        flow.totals.kinetic_rate
    );
    // The same driving torque through the power-flow path (ideal meshes here).
    let driving = flow.dynamics.driving_torques[0].1;
    assert!(
        (driving - d.driving_torques[0].1).abs() <= 1e-12 * driving.abs(),
        "{driving} against {}",
        d.driving_torques[0].1
    );
    // [M] is held sparse; a dense copy of it is refused by name.
    let e = mass
        .matrix()
        .err()
        .unwrap_or_else(|| panic!("a dense 9 999 x 9 999 [M] was built"));
    assert_eq!(e.code(), "too_large", "{e}");
}

//! The accuracy study's claims: on well-conditioned trains every method is
//! within 1e-13 of the exact rational answer; egt's condition estimate is
//! within a factor of 10 of the true condition number (and never above it by
//! more than round-off); past COND_REFUSE egt refuses instead of returning
//! numbers, and below it its error stays within what the condition allows.

use crate::lab::accuracy::{Method, Problem, relative_error, residual, row_errors};
use crate::lab::families;
use egt_core::batch::{Layout, Threads};
use egt_core::numerics::linalg::{COND_REFUSE, COND_WARN};
use egt_core::{AnalysisError, Error, SpeedInput, Train};

use crate::util::train;

fn problem(t: &Train) -> Problem {
    Problem::from_train(t).unwrap_or_else(|e| panic!("{e}"))
}

/// Well-conditioned trains: generated families, random trains, Fig. 3.
fn well_conditioned() -> Vec<(String, Train)> {
    let mut out = vec![
        (
            "fig3".to_string(),
            crate::util::example("fig3_example61.toml"),
        ),
        ("chain 4".to_string(), train(&families::planetary_chain(4))),
        ("nest 8".to_string(), train(&families::nest(8))),
        ("gear pair".to_string(), train(&families::gear_pair())),
    ];
    for seed in 0..12 {
        out.push((
            format!("random {seed}"),
            train(&families::random_train(seed, 1 + seed as usize % 5, 2.0)),
        ));
    }
    out
}

#[test]
fn every_method_is_within_1e_13_of_exact_on_well_conditioned_trains() {
    for (name, t) in well_conditioned() {
        let p = problem(&t);
        let exact = p.exact().unwrap_or_else(|e| panic!("{name}: {e}"));
        let cond = p.true_conditions();
        assert!(
            cond.iter().all(|&c| c < 1e6),
            "{name}: not well-conditioned: {cond:?}"
        );
        for m in Method::ALL {
            let s = p
                .solve(m)
                .unwrap_or_else(|e| panic!("{name} {}: {e}", m.name()));
            let e = s.errors(&exact);
            assert!(e.max() <= 1e-13, "{name} {}: {e:?}", m.name());
            if m == Method::Exact {
                assert_eq!(e.max(), 0.0, "{name}: exact is exact");
            }
        }
    }
}

/// The batch's straight-line program (condition bounds on; 64 rows, the
/// ratio one ulp apart in every other row, so that no linear block forms) is
/// within 1e-13 of the exact speeds, accelerations, multipliers and driving
/// torques on every well-conditioned train, each group normwise.
#[test]
fn the_straight_line_program_is_within_1e_13_of_exact() {
    for (name, t) in well_conditioned() {
        let p = problem(&t);
        let exact = p.exact().unwrap_or_else(|e| panic!("{name}: {e}"));
        let plan = p.plan().clone().with_condition_bounds(true);
        assert!(plan.has_program(), "{name}: no program");
        let (np, nq) = (plan.parameters().len(), plan.outputs().len());
        let base = plan.base().to_vec();
        let mut params = Vec::with_capacity(64 * np);
        for r in 0..64 {
            let mut row = base.clone();
            if r % 2 == 1 {
                row[0] = f64::from_bits(row[0].to_bits() + 1);
            }
            params.extend(row);
        }
        let mut out = vec![0.0; 64 * nq];
        let errors = plan
            .run(Layout::Rows(&params), &mut out, Threads::Pool)
            .errors;
        assert!(errors.is_empty(), "{name}: {errors:?}");
        let e = row_errors(&plan, &t, &out[..nq], &exact);
        assert!(e.max() <= 1e-13, "{name}: {e:?}");
        // The odd rows are their own trains (a ratio one ulp off): they
        // agree with the even ones to rounding.
        let odd = row_errors(&plan, &t, &out[nq..2 * nq], &exact);
        assert!(odd.max() <= 1e-13, "{name} (odd row): {odd:?}");
    }
}

/// The float speed solver (`PreparedTrain`, which `Train::kinematics` and
/// the CLI use) factors the speed system by the dense LU below
/// `PREPARED_SPARSE_FROM` coordinates and by the sparse LU above: both,
/// forced on every well-conditioned train, are within 1e-13 of the exact
/// speeds.
#[test]
fn both_willis_factorisations_are_within_1e_13_of_exact_speeds() {
    let mut trains = well_conditioned();
    trains.push(("zigzag 30".into(), train(&families::zigzag_chain(30))));
    for (name, t) in trains {
        let (links, speeds): (Vec<_>, Vec<f64>) =
            t.analysis().speeds.iter().map(|s| (s.0, s.1)).unzip();
        let inputs: Vec<SpeedInput> = links
            .iter()
            .zip(&speeds)
            .map(|(&l, &v)| (l, v).into())
            .collect();
        let k = t
            .kinematics(&inputs)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        let exact: Vec<f64> = k
            .exact
            .unwrap_or_else(|| panic!("{name}: no exact speeds"))
            .iter()
            .map(egt_core::numerics::exact::to_f64)
            .collect();
        for sparse in [false, true] {
            let (w, _) = crate::util::prepared_speeds(&t, &links, &speeds, sparse)
                .unwrap_or_else(|e| panic!("{name}: {e}"));
            let e = relative_error(&w, &exact);
            assert!(e <= 1e-13, "{name} (sparse {sparse}): {e:e}");
        }
    }
}

#[test]
fn condition_estimate_is_within_a_factor_of_10_of_the_true_value() {
    let mut trains = well_conditioned();
    for eps in [1e-2, 1e-4, 1e-6, 1e-8, 1e-10] {
        trains.push((
            format!("near-locked {eps:e}"),
            train(&families::near_locked(eps)),
        ));
        trains.push((
            format!("stationary planet {eps:e}"),
            train(&families::stationary_planet(eps)),
        ));
    }
    for seed in 0..6 {
        trains.push((
            format!("random {seed}, inertias over 12 decades"),
            train(&families::random_train(100 + seed, 4, 12.0)),
        ));
    }
    for (name, t) in trains {
        let p = problem(&t);
        let truth = p.true_conditions();
        let est = match p.solve(Method::Egt) {
            Ok(s) => s.conditions.unwrap_or_default(),
            Err(e) => panic!("{name}: {e} (true conditions {truth:?})"),
        };
        for (k, (e, c)) in est.iter().zip(truth).enumerate() {
            assert!(
                *e <= c * (1.0 + 1e-6),
                "{name} [{k}]: estimate {e:e} above the true {c:e}"
            );
            assert!(
                *e >= c / 10.0,
                "{name} [{k}]: estimate {e:e} below a tenth of the true {c:e}"
            );
        }
    }
}

#[test]
fn egt_refuses_past_the_threshold_and_is_accurate_below_it() {
    let mut refused = 0;
    for k in 1..=16 {
        let eps = 10f64.powi(-k);
        for (name, t) in [
            ("near-locked", train(&families::near_locked(eps))),
            (
                "stationary planet",
                train(&families::stationary_planet(eps)),
            ),
        ] {
            let p = problem(&t);
            let truth = p.true_conditions().into_iter().fold(0.0, f64::max);
            match p.solve(Method::Egt) {
                Ok(s) => {
                    let est = s
                        .conditions
                        .unwrap_or_default()
                        .into_iter()
                        .fold(0.0, f64::max);
                    assert!(
                        est <= COND_REFUSE,
                        "{name} {eps:e}: returned past the threshold"
                    );
                    // Forward error bounded by what the condition allows (with margin).
                    let exact = p.exact().unwrap_or_else(|e| panic!("{e}"));
                    let err = s.errors(&exact).max();
                    assert!(
                        err <= 1e3 * f64::EPSILON * truth.max(1.0),
                        "{name} {eps:e}: error {err:e} at condition {truth:e}"
                    );
                }
                Err(Error::Analysis(AnalysisError::IllConditioned {
                    condition,
                    threshold,
                    ..
                })) => {
                    assert_eq!(threshold, COND_REFUSE);
                    assert!(condition > COND_REFUSE);
                    // The refusal is justified: the true condition is past the threshold's tenth.
                    assert!(
                        truth > COND_REFUSE / 10.0,
                        "{name} {eps:e}: refused at true condition {truth:e}"
                    );
                    refused += 1;
                }
                Err(Error::Analysis(AnalysisError::Singular { .. })) => refused += 1,
                Err(e) => panic!("{name} {eps:e}: {e}"),
            }
        }
    }
    assert!(
        refused >= 6,
        "the nearly locked trains must be refused ({refused})"
    );
}

#[test]
fn refinement_beats_plain_lu_when_conditioning_costs_digits() {
    // Near lock at condition ~1e9: plain LU loses about 9 digits somewhere;
    // one refinement step with a doubled-precision residual recovers them.
    let p = problem(&train(&families::near_locked(1e-9)));
    let exact = p.exact().unwrap_or_else(|e| panic!("{e}"));
    let plain = p
        .solve(Method::NalgebraLu)
        .unwrap_or_else(|e| panic!("{e}"))
        .errors(&exact)
        .max();
    let refined = p
        .solve(Method::EgtRefined)
        .unwrap_or_else(|e| panic!("{e}"))
        .errors(&exact)
        .max();
    assert!(
        refined < plain / 10.0,
        "refined {refined:e} vs plain {plain:e}"
    );
}

#[test]
fn kinematics_warns_between_the_thresholds() {
    // The single-scenario kinematics reports a warning (not a refusal) when
    // COND_WARN < condition <= COND_REFUSE, and none when well-conditioned.
    let mut warned = false;
    for k in 1..=11 {
        let t = train(&families::near_locked(10f64.powi(-k)));
        let input = t.link_id("4").unwrap_or_else(|| panic!("no link 4"));
        match t.kinematics(&[SpeedInput::from((input, 1.0))]) {
            Ok(s) if s.condition > COND_WARN => {
                assert!(
                    !s.warnings.is_empty(),
                    "no warning at condition {:e}",
                    s.condition
                );
                warned = true;
            }
            Ok(s) => assert!(s.warnings.is_empty(), "{:?}", s.warnings),
            Err(_) => {}
        }
    }
    assert!(warned);
}

#[test]
fn relative_error_is_normwise() {
    assert_eq!(relative_error(&[1.0, 2.0], &[1.0, 2.0]), 0.0);
    assert_eq!(relative_error(&[1.0, 2.5], &[1.0, 2.0]), 0.25);
    assert!(relative_error(&[f64::NAN], &[1.0]).is_infinite());
}

#[test]
fn dot2_residual_recovers_what_plain_arithmetic_loses() {
    // (1 + 2^-30)(1 - 2^-30) - 1 = -2^-60 exactly; plain f64 gives 0.
    let e = 2f64.powi(-30);
    let r = residual(&[1.0 + e], &[1.0 - e], 1.0);
    assert_eq!(r, 2f64.powi(-60));
}

#[test]
fn families_are_valid_one_dof_trains_of_the_stated_size() {
    assert_eq!(train(&families::gear_pair()).links().len(), 3);
    for k in 1..=14 {
        let t = train(&families::planetary_chain(k));
        assert_eq!((t.links().len(), t.dof()), (2 + 2 * k, 1), "chain {k}");
    }
    for l in 3..=30 {
        let t = train(&families::nest(l));
        assert_eq!((t.links().len(), t.dof()), (l, 1), "nest {l}");
    }
    for seed in 0..40 {
        let t = train(&families::random_train(seed, 1 + (seed as usize % 6), 4.0));
        assert_eq!(t.dof(), 1, "seed {seed}");
    }
    assert_eq!(train(&families::near_locked(1e-6)).dof(), 1);
    assert_eq!(train(&families::stationary_planet(1e-6)).dof(), 1);
}

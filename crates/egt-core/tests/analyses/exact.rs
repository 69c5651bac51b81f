//! Exact rational kinematics: the closed forms printed in examples 6.1 and 6.2
//! checked with BigRational equality, and the gear ratios of the Ford AOD and
//! C4 transmissions derived from their tooth counts (each gear state realised
//! as inputs: the held link at speed 0, the clutched links at the input's speed)
//! and compared with the published ratios to their printed precision.

use egt_core::numerics::exact::{self, Q};
use egt_core::spec::ElementKind;
use egt_core::{SpeedInput, Train};
use num_traits::{One, Zero};
use proptest::prelude::*;

use crate::paper::{fig3, fig5};
use crate::util::{exact_speed, example, fr, id, input};

fn ratio() -> impl Strategy<Value = Q> {
    (-60i64..60, 1i64..25).prop_filter_map("tau is never 0 or 1", |(p, q)| {
        let t = fr(p, q);
        (!t.is_zero() && !t.is_one()).then_some(t)
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 32, ..ProptestConfig::default() })]

    /// 6.1: w_2 = tau_1 tau_2/(tau_1 tau_2 - 1) w_4 and w_3 = (tau_1 - 1) tau_2/(tau_1 tau_2 - 1) w_4.
    #[test]
    fn example_61_closed_forms(t1 in ratio(), t2 in ratio(), w4 in (-50i64..50).prop_filter("moving", |w| *w != 0)) {
        let one = exact::q(1);
        let p = &t1 * &t2;
        prop_assume!(p != one);
        let train = fig3(&t1, &t2);
        let w4 = exact::q(w4);
        let s = train.kinematics(&[input(&train, "4", w4.clone())]).expect("regular");
        prop_assert_eq!(exact_speed(&train, &s, "2"), &p / (&p - &one) * &w4);
        prop_assert_eq!(exact_speed(&train, &s, "3"), (&t1 - &one) * &t2 / (&p - &one) * &w4);
    }

    /// 6.2: w_3 = w_2/tau_1, w_5 = (1 - tau_2)/tau_1 w_2 + tau_2 w_4,
    /// w_6 = (tau_3 - tau_2)/(tau_1 tau_3) w_2 + tau_2/tau_3 w_4.
    #[test]
    fn example_62_closed_forms(t1 in ratio(), t2 in ratio(), t3 in ratio(), w2 in -50i64..50, w4 in -50i64..50) {
        let one = exact::q(1);
        let train = fig5(&t1, &t2, &t3);
        let (w2, w4) = (exact::q(w2), exact::q(w4));
        let s = train.kinematics(&[input(&train, "2", w2.clone()), input(&train, "4", w4.clone())]).expect("regular");
        prop_assert_eq!(exact_speed(&train, &s, "3"), &w2 / &t1);
        prop_assert_eq!(exact_speed(&train, &s, "5"), (&one - &t2) / &t1 * &w2 + &t2 * &w4);
        prop_assert_eq!(exact_speed(&train, &s, "6"), (&t3 - &t2) / (&t1 * &t3) * &w2 + &t2 / &t3 * &w4);
    }
}

/// The example file: carrier 2 at 100 drives the output at w_2 (tau_1 tau_2 - 1)/(tau_1 tau_2),
/// exactly, with the teeth 30/20 and 18/32.
#[test]
fn example_61_file_is_exact() {
    let train = example("fig3_example61.toml");
    let s = train
        .kinematics(&[input(&train, "2", exact::q(100))])
        .expect("regular");
    let t1 = fr(-20, 30);
    let t2 = fr(-32, 18);
    let p = &t1 * &t2;
    assert_eq!(
        exact_speed(&train, &s, "4"),
        exact::q(100) * (&p - exact::q(1)) / &p
    );
    assert_eq!(
        exact::display(&(exact::q(100) / exact_speed(&train, &s, "4"))),
        "32/5"
    );
}

/// Inputs that realise a gear state: the transmission input at speed 1, every
/// link clutched to it at 1, every held link at 0 (one-way brakes hold too).
fn state_inputs(train: &Train, state: &str) -> Vec<SpeedInput> {
    let t = train.transmission().expect("transmission");
    let st = t.states.iter().find(|s| s.name == state).expect("state");
    let mut inputs = vec![SpeedInput {
        link: t.input,
        speed: 1.0,
        exact: Some(exact::q(1)),
    }];
    for e in &st.engaged {
        let el = &train.elements()[e.index()];
        match el.kind {
            ElementKind::Brake | ElementKind::OneWayBrake => {
                inputs.push(SpeedInput {
                    link: el.links[0],
                    speed: 0.0,
                    exact: Some(Q::zero()),
                });
            }
            ElementKind::Clutch | ElementKind::OneWayClutch => {
                let other = if el.links[0] == t.input {
                    el.links[1]
                } else {
                    el.links[0]
                };
                assert!(
                    el.links.contains(&t.input),
                    "clutch `{}` does not touch the input",
                    el.name
                );
                inputs.push(SpeedInput {
                    link: other,
                    speed: 1.0,
                    exact: Some(exact::q(1)),
                });
            }
        }
    }
    assert_eq!(
        inputs.len(),
        train.dof(),
        "state {state} fixes every DOF of the bare train"
    );
    inputs
}

/// Input/output ratio of a gear state, exactly, from the teeth in the spec.
fn state_ratio(train: &Train, state: &str) -> Q {
    let s = train
        .kinematics(&state_inputs(train, state))
        .expect("state determines the train");
    assert!(s.residual < 1e-12);
    let out = train.transmission().expect("transmission").output;
    exact::q(1) / s.exact.expect("exact")[out.index()].clone()
}

fn check_published(file: &str, published: &[(&str, &str)]) {
    let train = example(file);
    for (state, printed) in published {
        let r = state_ratio(&train, state);
        let decimals = printed.split('.').nth(1).map_or(0, str::len);
        assert_eq!(
            format!("{:.*}", decimals, exact::to_f64(&r)),
            *printed,
            "{file}: gear {state} = {}",
            exact::display(&r)
        );
    }
}

/// Ford AOD: forward sun 30, reverse sun 36, ring 72 give 2.40, 1.47, 1.00, 0.67, -2.00.
#[test]
fn ford_aod_ratios_from_teeth() {
    check_published(
        "ford_aod_ravigneaux.toml",
        &[
            ("1", "2.40"),
            ("2", "1.47"),
            ("3", "1.00"),
            ("4", "0.67"),
            ("R", "-2.00"),
        ],
    );
}

/// Ford C4: both sets sun 33, ring 72 give 2.46, 1.46, 1.00 and reverse -2.18.
#[test]
fn ford_c4_ratios_from_teeth() {
    check_published(
        "ford_c4_simpson.toml",
        &[("1", "2.46"), ("2", "1.46"), ("3", "1.00"), ("R", "-2.18")],
    );
}

/// The AOD's pinions have no tooth count: their speeds are unknown, the central
/// members' speeds exact; and a pinion cannot be an input.
#[test]
fn ford_aod_unsized_pinions() {
    let train = example("ford_aod_ravigneaux.toml");
    let s = train
        .kinematics(&state_inputs(&train, "2"))
        .expect("regular");
    for p in ["short_pinion", "long_pinion"] {
        assert!(!s.known[id(&train, p).index()], "{p} is unsized");
    }
    let mut inputs = state_inputs(&train, "2");
    inputs[2] = input(&train, "long_pinion", exact::q(1));
    let e = train.kinematics(&inputs).expect_err("unsized input");
    assert!(e.to_string().contains("long_pinion"), "{e}");
}

/// Ratios from tooth counts for a batch row follow the one rule the spec
/// uses: every bundled example's own teeth give back its ratios exactly, and
/// bad counts are refused naming the row and the gear pair.
#[test]
fn ratios_from_teeth_reproduce_the_spec() {
    let mut checked = 0;
    for name in [
        "zf_8hp70.toml",
        "ford_c4_simpson.toml",
        "ford_aod_ravigneaux.toml",
        "fig3_example61.toml",
    ] {
        let t = example(name);
        let Some(teeth) = t
            .gears()
            .iter()
            .map(|g| g.teeth.map(|z| [i64::from(z[0]), i64::from(z[1])]))
            .collect::<Option<Vec<_>>>()
        else {
            continue;
        };
        let mut out = vec![0.0; teeth.len()];
        t.ratios_from_teeth("row", &teeth, &mut out)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        for (g, v) in t.gears().iter().zip(&out) {
            assert_eq!(
                Some(*v),
                g.ratio.as_ref().map(|r| r.value),
                "{name} {}",
                g.name
            );
        }
        let mut bad = teeth.clone();
        bad[1] = [0, 20];
        let Err(e) = t.ratios_from_teeth("teeth[7]", &bad, &mut out) else {
            panic!("{name}: a zero tooth count was accepted");
        };
        assert_eq!(e.code(), "invalid_teeth");
        let text = e.to_string();
        assert!(
            text.contains("teeth[7][1]") && text.contains(&t.gears()[1].name),
            "{text}"
        );
        bad[1] = [20, egt_core::error::MAX_TEETH + 1];
        assert_eq!(
            t.ratios_from_teeth("r", &bad, &mut out)
                .map_err(|e| e.code())
                .err(),
            Some("invalid_teeth")
        );
        checked += 1;
    }
    assert!(checked >= 3, "{checked}");
}

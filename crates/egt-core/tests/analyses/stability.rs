//! Stability and forward dynamics (issue 4) against independent relations:
//! the printed matrices of example 6.2, the linearisation of the reduced
//! torque, invariance under the choice of driving links, simulation against
//! the eigenvalues (decay exactly when stable, growth at the largest
//! eigenvalue), the energy balance, and the edges where methods fail (a stiff
//! train, a nearly locked [Gamma_w], massless directions).
// A failed unwrap is a failed test that prints the error: what a test wants.
#![allow(clippy::unwrap_used)]

use egt_core::analysis::stability::RK4_REAL_LIMIT;
use egt_core::model::train::Curve;
use egt_core::motion::simulate::{DIVERGED_SPEED, ReducedDynamics};
use egt_core::{
    AnalysisError, Error, Format, LinearCurves, LinkId, Method, SimulationOptions,
    StabilityRequest, TorqueFn, Train, Verdict,
};
use proptest::prelude::*;

fn train(text: &str) -> Train {
    Train::from_str(text, Format::Toml, "test").unwrap_or_else(|e| panic!("{e}\n{text}"))
}

fn id(t: &Train, name: &str) -> LinkId {
    t.link_id(name).unwrap_or_else(|| panic!("no link {name}"))
}

fn curve(t: &Train, link: &str, torque: f64, slope: f64, speed: f64) -> Curve {
    Curve {
        link: id(t, link),
        torque,
        slope,
        speed,
    }
}

fn opts(t_end: f64, dt: f64, method: Method) -> SimulationOptions {
    SimulationOptions {
        t_end,
        dt,
        method,
        every: 0,
    }
}

/// Energy norm sqrt(dw^T M dw) of the deviation of link speeds `w` from `reference`.
fn energy_norm(t: &Train, w: &[f64], reference: &[f64]) -> f64 {
    let m = t.mass_matrix().expect("mass matrix");
    let dw: Vec<f64> = w.iter().zip(reference).map(|(a, b)| a - b).collect();
    (2.0 * t.kinetic_energy(&m, &dw)).sqrt()
}

/// The Fig. 5 drive built from Table 2 with Willis ratios tau, inertias
/// I2..I6, planet mass m5 at offset d_bc (one copy), as the paper has it.
fn fig5(tau: [f64; 3], inertia: [f64; 5], m5: f64, d_bc: f64) -> Train {
    let [i2, i3, i4, i5, i6] = inertia;
    train(&format!(
        r#"
        frame = "1"
        links = [{{ name = "2", inertia = {i2:e} }}, {{ name = "3", inertia = {i3:e} }},
                 {{ name = "4", inertia = {i4:e} }}, {{ name = "5", inertia = {i5:e}, mass = {m5:e} }},
                 {{ name = "6", inertia = {i6:e} }}]
        revolutes = [{{ links = ["1", "2"], level = "a" }}, {{ links = ["1", "3"], level = "b" }},
                     {{ links = ["3", "5"], level = "c" }}, {{ links = ["1", "4"], level = "b" }},
                     {{ links = ["1", "6"], level = "b" }}]
        gears = [{{ links = ["2", "3"], ratio = {:e} }}, {{ links = ["5", "4"], ratio = {:e} }},
                 {{ links = ["5", "6"], ratio = {:e} }}]
        offsets = [{{ levels = ["b", "c"], distance = {d_bc:e} }}]
        "#,
        tau[0], tau[1], tau[2]
    ))
}

fn close(a: f64, b: f64, scale: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * scale.max(a.abs()).max(b.abs()).max(1e-300)
}

/// |a - b| <= rel * (size of the terms of the entry) + 4 eps * (size of the
/// matrix): the second part is the rounding floor of entries that are exactly
/// zero in the printed form (e.g. K12 with K_r = 0).
fn entry(a: f64, b: f64, terms: f64, matrix: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * terms + 4.0 * f64::EPSILON * matrix
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]

    /// Example 6.2: [V] (eq. 23), [M] (eq. 25) and [K] (eq. 26-27) as printed,
    /// at random parameters, to 1e-12 relative to the size of their terms.
    #[test]
    fn example_6_2_printed_matrices(
        t1 in prop_oneof![-6.0..-0.2f64, 0.2..6.0f64],
        t2 in prop_oneof![-6.0..-0.2f64, 1.2..6.0f64],
        t3 in prop_oneof![-6.0..-0.2f64, 1.2..6.0f64],
        inertia in proptest::array::uniform5(0.0..2.0f64),
        m5 in 0.0..5.0f64, d in 0.01..0.5f64,
        kd1 in -3.0..3.0f64, kd2 in -3.0..3.0f64, kr in -3.0..3.0f64,
    ) {
        let t = fig5([t1, t2, t3], inertia, m5, d);
        let [i2, i3, i4, i5, i6] = inertia;
        let curves = vec![curve(&t, "2", 1.0, kd1, 10.0), curve(&t, "4", 2.0, kd2, 5.0), curve(&t, "6", -3.0, kr, 7.0)];
        let model = t.reduced_model(&[id(&t, "2"), id(&t, "4")], &curves).unwrap();
        prop_assert!(model.orthogonality < 1e-13, "eq. 24: {}", model.orthogonality);
        let v = |l: &str, c: usize| model.velocity[(id(&t, l).index(), c)];
        let printed_v = [("2", 1.0, 0.0), ("3", 1.0 / t1, 0.0), ("4", 0.0, 1.0),
            ("5", (1.0 - t2) / t1, t2), ("6", (t3 - t2) / (t1 * t3), t2 / t3)];
        for (l, a, b) in printed_v {
            prop_assert!(close(v(l, 0), a, 1.0, 1e-13) && close(v(l, 1), b, 1.0, 1e-13), "V row {l}: {} {}", v(l, 0), v(l, 1));
        }
        let a6 = (t2 - t3) / (t1 * t3);
        let m11 = [i2, (i3 + m5 * d * d) / (t1 * t1), ((t2 - 1.0) / t1).powi(2) * i5, a6 * a6 * i6];
        let m12 = [(1.0 - t2) * t2 / t1 * i5, (t3 - t2) * t2 / (t1 * t3 * t3) * i6];
        let m22 = [i4, i5 * t2 * t2, t2 * t2 / (t3 * t3) * i6];
        let sum = |x: &[f64]| x.iter().sum::<f64>();
        let size = |x: &[f64]| x.iter().map(|v| v.abs()).sum::<f64>();
        let m = &model.mass;
        let mn = size(&m11) + size(&m22);
        prop_assert!(entry(m[(0, 0)], sum(&m11), size(&m11), mn, 1e-12), "M11 {} vs {}", m[(0, 0)], sum(&m11));
        prop_assert!(entry(m[(0, 1)], sum(&m12), size(&m12), mn, 1e-12), "M12 {} vs {}", m[(0, 1)], sum(&m12));
        prop_assert!(entry(m[(1, 0)], sum(&m12), size(&m12), mn, 1e-12), "M21");
        prop_assert!(entry(m[(1, 1)], sum(&m22), size(&m22), mn, 1e-12), "M22");
        let k11 = [kd1, a6 * a6 * kr];
        let k12 = [t2 * (t3 - t2) / (t1 * t3 * t3) * kr];
        let k22 = [kd2, t2 * t2 / (t3 * t3) * kr];
        let k = &model.slope;
        let kn = size(&k11) + size(&k22);
        prop_assert!(entry(k[(0, 0)], sum(&k11), size(&k11), kn, 1e-12), "K11 {} vs {}", k[(0, 0)], sum(&k11));
        prop_assert!(entry(k[(0, 1)], sum(&k12), size(&k12), kn, 1e-12), "K12 {} vs {}", k[(0, 1)], sum(&k12));
        prop_assert!(k[(0, 1)] == k[(1, 0)], "[K] is exactly symmetric");
        prop_assert!(entry(k[(1, 1)], sum(&k22), size(&k22), kn, 1e-12), "K22");
    }

    /// [K] is the derivative of the reduced torque: V^T T(w0 + V d) - V^T T(w0) = [K] d
    /// for torques evaluated link by link (the paper's eq. 26 is this vector, not [K]).
    #[test]
    fn slope_matrix_linearises_the_reduced_torque(
        g in arb_train(), d in proptest::collection::vec(-5.0..5.0f64, 3),
    ) {
        let t = train(&g.toml);
        let (coords, _) = t.driving_coordinates(None).unwrap();
        let model = t.reduced_model(&coords, &t.analysis().curves).unwrap();
        let f = coords.len();
        let w0 = model.link_speeds(&vec![1.0; f]);
        let w1 = model.link_speeds(&d[..f].iter().map(|x| 1.0 + x).collect::<Vec<_>>());
        let (t0, t1) = (model.torques(&w0), model.torques(&w1));
        for a in 0..f {
            let lhs: f64 = (0..w0.len()).map(|l| model.velocity[(l, a)] * (t1[l] - t0[l])).sum();
            let rhs: f64 = (0..f).map(|b| model.slope[(a, b)] * d[b]).sum();
            let scale: f64 = (0..w0.len()).map(|l| (model.velocity[(l, a)] * (t1[l] - t0[l])).abs()).sum();
            prop_assert!(close(lhs, rhs, scale, 1e-11), "{lhs} vs {rhs}");
        }
    }

    /// The eigenvalues are a property of the train, not of the driving links
    /// chosen: [V] changes by an invertible map, the pencil by a congruence.
    #[test]
    fn eigenvalues_do_not_depend_on_the_driving_links(g in arb_train(), pick in 0usize..1000) {
        let t = train(&g.toml);
        let curves = t.analysis().curves.clone();
        let (coords, _) = t.driving_coordinates(None).unwrap();
        let auto = t.reduced_model(&coords, &curves).unwrap().stability().unwrap();
        // Another independent set: the first in a rotation of the link list that gives a regular [Gamma_w].
        let n = t.coordinates().len();
        let f = t.dof();
        let mut other = None;
        for shift in 0..n {
            let cand: Vec<LinkId> = (0..f).map(|k| t.coordinates()[(pick + shift + 2 * k) % n]).collect();
            let mut uniq = cand.clone();
            uniq.sort();
            uniq.dedup();
            if uniq.len() < f { continue; }
            if let Ok(m) = t.reduced_model(&cand, &curves)
                && m.gamma_condition < 1e6 { other = Some(m.stability().unwrap()); break; }
        }
        prop_assume!(other.is_some());
        let other = other.unwrap();
        let scale = auto.eigenvalues.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        for (a, b) in auto.eigenvalues.iter().zip(&other.eigenvalues) {
            prop_assert!(close(*a, *b, scale, 1e-8), "{a} vs {b}");
        }
        prop_assert!(auto.residual < 1e-10 && other.residual < 1e-10, "{} {}", auto.residual, other.residual);
    }
}

/// A random chain of simple planetary sets (2 or 3 DOF): teeth, module (so
/// the planet offsets follow from the radii), inertias, planet masses, and a
/// curve of random slope on every central member (falling with probability
/// 3/4, so that stable and unstable trains both come up often).
#[derive(Debug, Clone)]
struct RandomTrain {
    toml: String,
}

fn arb_train() -> impl Strategy<Value = RandomTrain> {
    (
        2usize..=3,
        proptest::array::uniform2((15i64..40, 12i64..30)),
        proptest::array::uniform7(0.2..2.0f64),
        proptest::array::uniform5((0.05..2.0f64, proptest::bool::weighted(0.75), -10.0..10.0f64, -100.0..100.0f64)),
        0usize..3,
        0usize..3,
    )
        .prop_map(|(dof, teeth, inertia, curves, i, j)| {
            let mut sets = vec![["s1", "r1", "c1"].map(String::from)];
            if dof == 3 {
                let mut s2 = ["s2", "r2", "c2"].map(String::from);
                s2[j] = sets[0][i].clone();
                sets.push(s2);
            }
            let mut central: Vec<String> = Vec::new();
            let mut text = String::from("frame = \"0\"\n");
            for (k, s) in sets.iter().enumerate() {
                let (zs, zp) = teeth[k];
                text += &format!(
                    "[[planetary]]\nname = \"P{k}\"\nsun = \"{}\"\nring = \"{}\"\ncarrier = \"{}\"\nmodule = 0.002\nteeth = {{ sun = {zs}, planet = {zp}, ring = {} }}\n",
                    s[0], s[1], s[2], zs + 2 * zp
                );
                for c in s {
                    if !central.contains(c) {
                        central.push(c.clone());
                    }
                }
            }
            let mut links: Vec<String> = central.clone();
            for k in 0..sets.len() {
                links.push(format!("P{k}.planet"));
            }
            for (k, l) in links.iter().enumerate() {
                let planet = l.contains("planet");
                text += &format!(
                    "[[links]]\nname = \"{l}\"\ninertia = {:e}\n{}",
                    inertia[k] * if planet { 1e-3 } else { 1e-2 },
                    if planet { "mass = 0.2\ncopies = 3\n" } else { "" }
                );
            }
            text += "[analysis]\n";
            for (k, l) in central.iter().enumerate() {
                let (mag, neg, torque, speed) = curves[k];
                let slope = if neg { -mag } else { mag };
                text += &format!(
                    "[[analysis.curves]]\nlink = \"{l}\"\ntorque = {torque:e}\nslope = {:e}\nspeed = {speed:e}\n",
                    slope * 1e-2
                );
            }
            RandomTrain { toml: text }
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// A small perturbation of the equilibrium decays in simulation exactly
    /// when every eigenvalue is negative, and grows otherwise; and the
    /// simulated growth rate of the linearised (deviation) dynamics is the
    /// largest eigenvalue.
    #[test]
    fn simulation_decays_exactly_when_stable_and_grows_at_the_largest_eigenvalue(
        g in arb_train(), p in proptest::collection::vec(-1.0..1.0f64, 3),
    ) {
        let t = train(&g.toml);
        let rep = t.stability(&StabilityRequest::default());
        prop_assume!(rep.is_ok());
        let rep = rep.unwrap();
        let st = &rep.stability;
        let lam = &st.eigenvalues;
        let big = lam.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let l1 = lam[0];
        prop_assume!(l1.abs() > 1e-3 * big);
        let gap = if lam.len() > 1 { l1 - lam[1] } else { big };
        prop_assume!(gap > 0.05 * l1.abs());
        prop_assume!(rep.operating.equilibrium_condition.is_some_and(|c| c < 1e8));
        prop_assert_eq!(st.verdict, if l1 > 0.0 { Verdict::Unstable } else { Verdict::Stable });
        let coords = rep.model.coordinates.clone();
        let f = coords.len();
        let eq = rep.operating.equilibrium.clone().unwrap();

        // 1. Around the true equilibrium with the spec's curves: decays iff stable.
        let span = 10.0 / l1.abs();
        let dt = (0.25 * st.rk4_step_limit.unwrap_or(f64::INFINITY)).min(span / 200.0);
        prop_assume!(span / dt < 100_000.0);
        let amp = 1e-3 * (1.0 + eq.iter().fold(0.0_f64, |m, v| m.max(v.abs())));
        let initial: Vec<(LinkId, f64)> = coords.iter().zip(&p).map(|(&l, d)| (l, eq[l.index()] + amp * d)).collect();
        let torque = LinearCurves::from_model(&rep.model);
        let mut dynamics = ReducedDynamics::new(&t, &torque).unwrap();
        let sim = dynamics.simulate(&initial, &opts(span, dt, Method::Rk4)).unwrap();
        prop_assert!(sim.diverged.is_none() || l1 > 0.0);
        let d0 = energy_norm(&t, &sim.samples[0].speed, &eq);
        let d1 = energy_norm(&t, &sim.samples.last().unwrap().speed, &eq);
        prop_assert_eq!(d1 < d0, st.verdict == Verdict::Stable, "d0 {} d1 {} lambda {:?}", d0, d1, lam);
        prop_assert!(sim.max_drift < 1e-12, "Willis drift {}", sim.max_drift);

        // 2. The deviation dynamics (the same slopes, no offsets): rate = largest eigenvalue.
        let homogeneous: Vec<Curve> = t.analysis().curves.iter().map(|c| Curve { torque: 0.0, speed: 0.0, ..c.clone() }).collect();
        let torque = LinearCurves::new(&t, &homogeneous).unwrap();
        let mut dynamics = ReducedDynamics::new(&t, &torque).unwrap();
        let settle = if f > 1 { 20.0 / gap } else { 0.0 };
        let end = settle + 5.0 / l1.abs();
        let dt = (0.05 / big).min(end / 400.0);
        prop_assume!(end / dt < 200_000.0);
        // Linear and homogeneous: any amplitude will do; start small enough that a
        // growing solution stays far from overflow.
        prop_assume!(l1 * end < 600.0);
        let amp = (-(l1 * end).max(0.0)).exp();
        let start: Vec<(LinkId, f64)> = coords.iter().zip(&p).map(|(&l, d)| (l, amp * (1.0 + d))).collect();
        let sim = dynamics.simulate(&start, &opts(end, dt, Method::Rk4)).unwrap();
        prop_assert!(sim.diverged.is_none());
        let m = t.mass_matrix().unwrap();
        let zero = vec![0.0; t.links().len()];
        let rate = sim.growth_rate(&t, &m, &zero, settle).unwrap();
        prop_assert!(close(rate, l1, 0.0, 1e-6), "simulated rate {} vs eigenvalue {} ({:?})", rate, l1, lam);
    }

    /// Kinetic energy: dE/dt = w . T along a trajectory under nonlinear torques
    /// (motors with quadratic curves, a fan load T = -c w |w|): by the work
    /// integrated with the state, and pointwise by differences of the samples.
    #[test]
    fn kinetic_energy_rate_is_the_power_of_the_applied_torques(g in arb_train(), c in 1e-5..1e-3f64) {
        let t = train(&g.toml);
        let (coords, _) = t.driving_coordinates(None).unwrap();
        let loaded = coords[0].index();
        let model = t.reduced_model(&coords, &t.analysis().curves).unwrap();
        let (slope, offset) = (model.link_slope.clone(), model.link_offset.clone());
        let law = TorqueFn(move |_t: f64, w: &[f64], out: &mut [f64]| {
            for (l, o) in out.iter_mut().enumerate() {
                *o = offset[l] + slope[l] * w[l] - 1e-4 * slope[l].abs() * w[l] * w[l];
            }
            out[loaded] -= c * w[loaded] * w[loaded].abs();
        });
        let start: Vec<(LinkId, f64)> = coords.iter().enumerate().map(|(k, &l)| (l, 20.0 * (k as f64 + 1.0))).collect();
        let mut dynamics = ReducedDynamics::new(&t, &law).unwrap();
        let sim = dynamics.simulate(&start, &SimulationOptions { t_end: 0.5, dt: 2e-4, method: Method::Rk4, every: 1 }).unwrap();
        prop_assume!(sim.diverged.is_none());
        prop_assert!(sim.energy_error < 1e-9, "RK4 energy balance {}", sim.energy_error);
        // Independently of the integrator's own quadrature: Simpson's rule on the sampled power.
        let s = &sim.samples;
        let scale = s.iter().fold(0.0_f64, |m, x| m.max(x.energy).max(x.work.abs()));
        let mut simpson = 0.0;
        for k in (2..s.len()).step_by(2) {
            let h = s[k].t - s[k - 1].t;
            simpson += h / 3.0 * (s[k - 2].power + 4.0 * s[k - 1].power + s[k].power);
            prop_assert!((s[k].energy - s[0].energy - simpson).abs() <= 1e-8 * scale,
                "E - E0 = {} vs Simpson of w.T = {} at t = {}", s[k].energy - s[0].energy, simpson, s[k].t);
        }
        let mut dynamics = ReducedDynamics::new(&t, &law).unwrap();
        let sim = dynamics.simulate(&start, &SimulationOptions { t_end: 0.5, dt: 1e-3, method: Method::Implicit, every: 1 }).unwrap();
        prop_assume!(sim.diverged.is_none());
        prop_assert!(sim.energy_error < 1e-4, "implicit energy balance {}", sim.energy_error);
    }
}

/// The sign convention: with applied torque T = T0 + K (w - w0) on a single
/// flywheel (a 1-DOF train), lambda = K / I. A motor whose torque falls as it
/// speeds up (K < 0) is stable, and simulation agrees; the paper's eq. (18),
/// (lambda M + K) X = 0, would say the opposite.
#[test]
fn falling_torque_motor_is_stabilising() {
    let t = train(
        r#"
        frame = "0"
        links = [{ name = "m", inertia = 0.5 }, { name = "o", inertia = 0.3 }]
        revolutes = [{ links = ["0", "m"], level = "a" }, { links = ["0", "o"], level = "b" }]
        gears = [{ links = ["m", "o"], ratio = -2.0 }]
        "#,
    );
    // Reflected inertia at m: 0.5 + 0.3 / 4 = 0.575; slope at m: K.
    for k in [-0.8, 0.8] {
        let curves = vec![curve(&t, "m", 1.0, k, 100.0)];
        let req = StabilityRequest {
            curves: Some(curves.clone()),
            speeds: Some(vec![(id(&t, "m"), 100.0)]),
            ..Default::default()
        };
        let rep = t.stability(&req).unwrap();
        let lam = rep.stability.eigenvalues[0];
        assert!(close(lam, k / 0.575, 0.0, 1e-13), "{lam}");
        let want = if k < 0.0 {
            Verdict::Stable
        } else {
            Verdict::Unstable
        };
        assert_eq!(rep.stability.verdict, want);
        let torque = LinearCurves::new(&t, &curves).unwrap();
        let m = id(&t, "m");
        let mut dynamics = ReducedDynamics::new(&t, &torque).unwrap();
        let sim = dynamics
            .simulate(&[(m, 101.0)], &opts(2.0, 1e-3, Method::Rk4))
            .unwrap();
        let eq = rep.operating.equilibrium.clone().unwrap();
        let d0 = (sim.samples[0].speed[m.index()] - eq[m.index()]).abs();
        let d1 = (sim.samples.last().unwrap().speed[m.index()] - eq[m.index()]).abs();
        assert!(close(d1 / d0, (lam * 2.0).exp(), 0.0, 1e-9), "{d0} {d1}");
    }
}

/// No slopes: every eigenvalue is zero (marginal); the train coasts and the
/// energy is conserved.
#[test]
fn no_slopes_is_marginal_and_conserves_energy() {
    let t = fig5(
        [-3.0, -1.5, 3.5],
        [5e-4, 8e-3, 6e-4, 3e-5, 4e-3],
        0.1,
        0.0375,
    );
    let curves = vec![curve(&t, "2", 0.0, 0.0, 0.0)];
    let rep = t
        .stability(&StabilityRequest {
            curves: Some(curves.clone()),
            speeds: Some(vec![(id(&t, "2"), 300.0), (id(&t, "4"), 100.0)]),
            ..Default::default()
        })
        .unwrap();
    assert_eq!(rep.stability.verdict, Verdict::Marginal);
    assert!(rep.stability.eigenvalues.iter().all(|&l| l == 0.0));
    let torque = LinearCurves::new(&t, &curves).unwrap();
    let coords = rep.model.coordinates.clone();
    let mut dynamics = ReducedDynamics::new(&t, &torque).unwrap();
    let start = [(coords[0], 300.0), (coords[1], 100.0)];
    let sim = dynamics
        .simulate(&start, &opts(1.0, 1e-2, Method::Implicit))
        .unwrap();
    let e0 = sim.samples[0].energy;
    assert!(sim.samples.iter().all(|s| close(s.energy, e0, 0.0, 1e-13)));
}

/// The stiff edge: small inertias and steep curves. RK4 is stable exactly up
/// to |lambda_min| dt = 2.785: just below, it follows the fine-step reference;
/// just above, it blows up; the implicit method at 20x that step stays on
/// the reference.
#[test]
fn stiff_train_rk4_step_limit_is_predicted_and_implicit_stays_accurate() {
    let t = fig5([-3.0, -1.5, 3.5], [1e-6, 1e-5, 6e-4, 1e-7, 4e-3], 0.0, 0.03);
    let curves = vec![
        curve(&t, "2", 1.0, -50.0, 300.0),
        curve(&t, "4", 2.0, -0.02, 100.0),
        curve(&t, "6", 0.0, -0.05, -185.0),
    ];
    let coords = [id(&t, "2"), id(&t, "4")];
    let model = t.reduced_model(&coords, &curves).unwrap();
    let st = model.stability().unwrap();
    assert_eq!(st.verdict, Verdict::Stable);
    let limit = st.rk4_step_limit.unwrap();
    let lmin = *st.eigenvalues.last().unwrap();
    assert!(close(limit, RK4_REAL_LIMIT / -lmin, 0.0, 1e-15));
    assert!(st.stiffness.unwrap() > 1e3, "stiffness {:?}", st.stiffness);
    let (eq, _) = model.equilibrium().unwrap();
    let torque = LinearCurves::from_model(&model);
    let start = [
        (coords[0], eq[coords[0].index()] + 50.0),
        (coords[1], eq[coords[1].index()] - 20.0),
    ];
    let t_end = 3.0 / -st.eigenvalues[0];
    let run = |dt: f64, method: Method| {
        let mut d = ReducedDynamics::new(&t, &torque).unwrap();
        d.simulate(&start, &opts(t_end, dt, method)).unwrap()
    };
    let reference = run(limit / 50.0, Method::Rk4);
    let dev0 = energy_norm(&t, &reference.samples[0].speed, &eq);
    let err = |s: &egt_core::Simulation| {
        energy_norm(
            &t,
            &s.samples.last().unwrap().speed,
            &reference.samples.last().unwrap().speed,
        ) / dev0
    };
    // Just below the limit: stable and accurate.
    let below = run(0.95 * limit, Method::Rk4);
    assert!(below.diverged.is_none());
    assert!(err(&below) < 1e-3, "RK4 below the limit: {}", err(&below));
    // Stable, but the fast transient is not resolved (R(z) = 0.81 per step
    // where e^z = 0.07): the energy balance says so.
    assert!(!below.warnings.iter().any(|w| w.contains("stability limit")));
    assert!(below.energy_error > 1e-2, "{}", below.energy_error);
    // Just above: the fast mode is amplified every step.
    let above = run(1.05 * limit, Method::Rk4);
    let grown = above.diverged.is_some()
        || energy_norm(&t, &above.samples.last().unwrap().speed, &eq) > 1e6 * dev0;
    assert!(grown, "RK4 above the limit did not blow up");
    assert!(above.warnings.iter().any(|w| w.contains("stability limit")));
    // The implicit method at 20x the limit: no blow-up, on the reference.
    let implicit = run(20.0 * limit, Method::Implicit);
    assert!(implicit.diverged.is_none());
    assert!(err(&implicit) < 1e-3, "implicit: {}", err(&implicit));
    assert!(implicit.samples.iter().all(|s| {
        s.speed
            .iter()
            .all(|v| v.is_finite() && v.abs() < DIVERGED_SPEED)
    }));
}

/// Nearly locked: with the sun 4 and ring 6 as driving links and tau_3 -> tau_2
/// (4 and 6 forced to turn together), [Gamma_w] nears singularity. egt warns
/// with the condition number (and the eigenvalues, which do not depend on the
/// driving links, still agree with a well-posed choice to the digits left),
/// then refuses.
#[test]
fn nearly_locked_gamma_warns_then_refuses() {
    let inertia = [5e-4, 8e-3, 6e-4, 3e-5, 4e-3];
    let mut last_cond = 0.0;
    for (eps, expect) in [(1e-3, "ok"), (1e-10, "warn"), (1e-14, "refuse")] {
        let t = fig5([-3.0, -1.5, -1.5 * (1.0 + eps)], inertia, 0.1, 0.0375);
        let curves = vec![
            curve(&t, "2", 1.0, -0.05, 300.0),
            curve(&t, "4", 1.0, -0.08, 100.0),
            curve(&t, "6", 1.0, -0.2, 50.0),
        ];
        let bad = [id(&t, "4"), id(&t, "6")];
        let good = [id(&t, "2"), id(&t, "4")];
        let r = t.reduced_model(&bad, &curves);
        match expect {
            "refuse" => match r {
                Err(Error::Analysis(AnalysisError::IllConditioned {
                    condition,
                    threshold,
                    ..
                })) => {
                    assert!(condition > threshold && condition > last_cond);
                }
                other => panic!("expected a refusal, got {other:?}"),
            },
            _ => {
                let m = r.unwrap();
                assert!(m.gamma_condition > last_cond);
                last_cond = m.gamma_condition;
                let warned = m.warnings.iter().any(|w| w.contains("ill-conditioned"));
                assert_eq!(
                    warned,
                    expect == "warn",
                    "{:?} {}",
                    m.warnings,
                    m.gamma_condition
                );
                assert!(m.mass.iter().chain(m.slope.iter()).all(|v| v.is_finite()));
                let reference = t
                    .reduced_model(&good, &curves)
                    .unwrap()
                    .stability()
                    .unwrap();
                let st = m.stability().unwrap();
                let digits = 1e3 * f64::EPSILON * m.gamma_condition;
                for (a, b) in st.eigenvalues.iter().zip(&reference.eigenvalues) {
                    assert!(
                        close(*a, *b, 0.0, digits.max(1e-10)),
                        "{a} vs {b} at cond {:e}",
                        m.gamma_condition
                    );
                }
            }
        }
    }
    // The automatic choice avoids the near-lock.
    let t = fig5([-3.0, -1.5, -1.5 * (1.0 + 1e-14)], inertia, 0.1, 0.0375);
    let (coords, _) = t.driving_coordinates(None).unwrap();
    let m = t.reduced_model(&coords, &[]).unwrap();
    assert!(
        m.gamma_condition < 1e3,
        "{:?} {}",
        coords,
        m.gamma_condition
    );
}

/// Massless links. (a) A planet without inertia or mass: [M] is singular but
/// V^T M V is not. (b) Links 2, 3, 4, 5 massless: one direction of the driving
/// coordinates has no inertia; it is eliminated as a torque balance, the
/// remaining eigenvalue is the limit of the slow one as their inertia -> 0,
/// and both integrators follow the reduced motion. (c) The same direction with
/// a rising torque is unstable; (d) without any slope it is undetermined.
#[test]
fn massless_links_are_handled_by_the_reduced_model() {
    let tau = [-3.0, -1.5, 3.5];
    // (a)
    let t = fig5(tau, [5e-4, 8e-3, 6e-4, 0.0, 4e-3], 0.0, 0.03);
    let curves = vec![
        curve(&t, "2", 1.0, -0.05, 300.0),
        curve(&t, "6", 1.0, -0.2, 50.0),
    ];
    let model = t
        .reduced_model(&[id(&t, "2"), id(&t, "4")], &curves)
        .unwrap();
    assert!(model.full_mass.determinant().abs() < 1e-300);
    let st = model.stability().unwrap();
    assert!(st.massless.is_empty());
    assert_eq!(st.eigenvalues.len(), 2);

    // (b)
    let motors = |t: &Train, k2: f64| {
        vec![
            curve(t, "2", 1.0, k2, 300.0),
            curve(t, "4", 2.0, -0.08, 100.0),
            curve(t, "6", 1.0, -0.2, -50.0),
        ]
    };
    let t = fig5(tau, [0.0, 0.0, 0.0, 0.0, 4e-3], 0.0, 0.03);
    let coords = [id(&t, "2"), id(&t, "4")];
    let model = t.reduced_model(&coords, &motors(&t, -0.05)).unwrap();
    let st = model.stability().unwrap();
    assert_eq!(st.massless.len(), 1);
    assert!(st.massless[0].slope < 0.0);
    let moving: Vec<&str> = st.massless[0]
        .links
        .iter()
        .map(|&l| t.link_name(l))
        .collect();
    assert!(!moving.contains(&"6"), "{moving:?}");
    assert_eq!(st.eigenvalues.len(), 1);
    assert_eq!(st.verdict, Verdict::Stable);
    // The singular-perturbation limit: tiny inertias on 2..5.
    for eps in [1e-7, 1e-9] {
        let te = fig5(tau, [eps, eps, eps, eps, 4e-3], 0.0, 0.03);
        let me = te.reduced_model(&coords, &motors(&te, -0.05)).unwrap();
        let se = me.stability().unwrap();
        assert_eq!(se.eigenvalues.len(), 2);
        assert!(se.massless.is_empty());
        assert!(
            close(se.eigenvalues[0], st.eigenvalues[0], 0.0, 1e3 * eps / 4e-3),
            "{eps}: {} vs {}",
            se.eigenvalues[0],
            st.eigenvalues[0]
        );
        assert!(se.eigenvalues[1] < -1e2 * st.eigenvalues[0].abs());
    }
    // Both integrators on the DAE agree, keep the balance and the Willis equations.
    let torque = LinearCurves::from_model(&model);
    let (eq, _) = model.equilibrium().unwrap();
    let start = [
        (coords[0], eq[coords[0].index()] + 30.0),
        (coords[1], eq[coords[1].index()] - 10.0),
    ];
    let t_end = 3.0 / -st.eigenvalues[0];
    let mut a = ReducedDynamics::new(&t, &torque).unwrap();
    assert_eq!(a.massless(), 1);
    let ra = a
        .simulate(&start, &opts(t_end, t_end / 2000.0, Method::Rk4))
        .unwrap();
    let mut b = ReducedDynamics::new(&t, &torque).unwrap();
    let rb = b
        .simulate(&start, &opts(t_end, t_end / 2000.0, Method::Implicit))
        .unwrap();
    assert!(
        ra.warnings.iter().any(|w| w.contains("torque balance")),
        "{:?}",
        ra.warnings
    );
    let dev0 = energy_norm(&t, &ra.samples[0].speed, &eq);
    let last = |s: &egt_core::Simulation| s.samples.last().unwrap().speed.clone();
    assert!(energy_norm(&t, &last(&ra), &last(&rb)) < 1e-5 * dev0);
    // Exact decay of the one dynamic mode.
    let d1 = energy_norm(&t, &last(&ra), &eq);
    assert!(
        close(d1 / dev0, (st.eigenvalues[0] * t_end).exp(), 0.0, 1e-8),
        "{}",
        d1 / dev0
    );
    assert!(ra.max_drift < 1e-13 && rb.max_drift < 1e-13);
    assert!(
        ra.energy_error < 1e-9 && rb.energy_error < 1e-5,
        "{} {}",
        ra.energy_error,
        rb.energy_error
    );
    // The accelerations on the massless direction balance the torques: reactions leave nothing over.
    let s = &ra.samples[ra.samples.len() / 3];
    let r = a.reactions(s.t, &s.speed).unwrap();
    let applied = r.torque.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    assert!(
        r.driving_torques
            .iter()
            .all(|(_, v)| v.abs() < 1e-9 * applied),
        "{:?}",
        r.driving_torques
    );

    // (c) Rising torque along the massless direction.
    let model = t.reduced_model(&coords, &motors(&t, 0.4)).unwrap();
    let st = model.stability().unwrap();
    assert_eq!(st.verdict, Verdict::Unstable);
    assert!(st.reason.contains("massless"), "{}", st.reason);

    // (d) No slope along it: undetermined, and the error names the links.
    let flat = vec![curve(&t, "6", 1.0, -0.2, -50.0)];
    let e = t
        .reduced_model(&coords, &flat)
        .unwrap()
        .stability()
        .unwrap_err();
    let msg = e.to_string();
    assert!(
        matches!(e, Error::Analysis(AnalysisError::Singular { .. })) && msg.contains("`2`"),
        "{msg}"
    );
}

/// The operating point of the bundled example is a steady state; shifting a
/// torque makes V^T T non-zero and is reported, with the equilibrium.
#[test]
fn fig5_example_operating_point_and_verdict() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/fig5_stability.toml"
    );
    let text = std::fs::read_to_string(path).unwrap();
    let t = Train::from_str(&text, Format::Toml, "fig5_stability.toml").unwrap();
    let rep = t.stability(&StabilityRequest::default()).unwrap();
    assert!(rep.operating.steady, "{}", rep.operating.residual);
    assert_eq!(rep.stability.verdict, Verdict::Stable);
    let eq = rep.operating.equilibrium.clone().unwrap();
    for (a, b) in eq.iter().zip(&rep.operating.speed) {
        assert!(close(*a, *b, 300.0, 1e-12));
    }
    let mut curves = t.analysis().curves.clone();
    curves[0].torque += 0.5;
    let rep = t
        .stability(&StabilityRequest {
            curves: Some(curves),
            ..Default::default()
        })
        .unwrap();
    assert!(!rep.operating.steady);
    assert!(close(rep.operating.reduced_torque[0], 0.5, 0.0, 1e-12));
    assert!(
        rep.warnings
            .iter()
            .any(|w| w.contains("not a steady state"))
    );

    // Constraint torques along the trajectory: the forward accelerations leave
    // no unbalanced driving torque, and the ring's mesh carries the load.
    let req = egt_core::SimulationRequest::from_spec(&t).unwrap();
    let sim = t.simulate(&req).unwrap();
    assert!(sim.diverged.is_none() && sim.max_drift < 1e-13);
    let torque = LinearCurves::new(&t, &t.analysis().curves).unwrap();
    let mut d = ReducedDynamics::new(&t, &torque).unwrap();
    for s in sim.samples.iter().step_by(400) {
        let r = d.reactions(s.t, &s.speed).unwrap();
        assert!(
            r.driving_torques.iter().all(|(_, v)| v.abs() < 1e-10),
            "{:?}",
            r.driving_torques
        );
        assert!(r.meshes.iter().all(|m| m.multiplier.is_finite()));
    }
}

/// A power split (a planetary differential: sun and carrier driven by motors
/// with falling curves, the ring loaded with `ring_slope`) whose sun, carrier
/// and planet have inertia `small` against a ring of `ring`.
fn power_split(small: f64, ring: f64, ring_slope: f64) -> (Train, Vec<Curve>) {
    let t = train(&format!(
        r#"
        frame = "case"
        links = [{{ name = "sun", inertia = {small:e} }}, {{ name = "carrier", inertia = {small:e} }},
                 {{ name = "ring", inertia = {ring:e} }}, {{ name = "P.planet", inertia = {small:e}, copies = 1 }}]
        [[planetary]]
        name = "P"
        sun = "sun"
        ring = "ring"
        carrier = "carrier"
        teeth = {{ sun = 30, ring = 72, planet = 21 }}
        "#
    ));
    let curves = vec![
        curve(&t, "sun", 0.0, -1.0, 0.0),
        curve(&t, "carrier", 0.0, -0.5, 0.0),
        curve(&t, "ring", 0.0, ring_slope, 0.0),
    ];
    (t, curves)
}

/// The verdict from the exact pencil: det(K - lambda M) = a lambda^2 + b lambda + c
/// with [M] and [K] reduced exactly on an exact null-space basis of the Willis
/// equations, and the sign of its largest root read off a, b and c (Vieta).
fn exact_pencil_verdict(t: &Train, inertia: &[(&str, f64)], curves: &[Curve]) -> Verdict {
    use egt_core::numerics::exact::{self, Q};
    use num_traits::{Signed, Zero};
    let psi = t.willis_jacobian_exact().unwrap();
    let n = t.coordinates().len();
    let basis = exact::nullspace(&psi, n);
    assert_eq!(basis.len(), 2);
    let diag = |values: &dyn Fn(LinkId) -> f64| -> Vec<Q> {
        t.coordinates()
            .iter()
            .map(|&l| exact::from_f64(values(l)).unwrap())
            .collect()
    };
    let m = diag(&|l| {
        inertia
            .iter()
            .find(|(name, _)| id(t, name) == l)
            .map_or(0.0, |p| p.1)
    });
    let k = diag(&|l| curves.iter().filter(|c| c.link == l).map(|c| c.slope).sum());
    let reduce = |d: &[Q]| -> [[Q; 2]; 2] {
        let e =
            |a: usize, b: usize| -> Q { (0..n).map(|c| &basis[a][c] * &basis[b][c] * &d[c]).sum() };
        [[e(0, 0), e(0, 1)], [e(1, 0), e(1, 1)]]
    };
    let (mr, kr) = (reduce(&m), reduce(&k));
    let a = &mr[0][0] * &mr[1][1] - &mr[0][1] * &mr[0][1];
    let b = -(&kr[0][0] * &mr[1][1] + &kr[1][1] * &mr[0][0] - exact::q(2) * &kr[0][1] * &mr[0][1]);
    let c = &kr[0][0] * &kr[1][1] - &kr[0][1] * &kr[0][1];
    assert!(a.is_positive());
    if c.is_negative() || (!c.is_negative() && (-&b).is_positive()) {
        Verdict::Unstable
    } else if c.is_zero() || b.is_zero() {
        Verdict::Marginal
    } else {
        Verdict::Stable
    }
}

/// Issue 11, class 3: verdicts on badly scaled trains. Inertia ratios from
/// 1e-12 to 1e12 (and the reported case, 1e-9 against 1e3), rising, falling
/// and absent ring slopes: the verdict equals the sign of the largest root of
/// the exact pencil, and a simulation with the L-stable implicit method
/// grows exactly when the verdict is unstable.
#[test]
fn badly_scaled_verdicts_equal_the_exact_pencil_and_simulation() {
    let mut cases: Vec<(f64, f64)> = (-12..=12).map(|k| (10f64.powi(k), 1.0)).collect();
    cases.extend([(1e-9, 1e3), (2e-10, 1e3), (1e-8, 1e3)]);
    for &(small, ring) in &cases {
        for ring_slope in [2.5, -2.5, 0.0] {
            let (t, curves) = power_split(small, ring, ring_slope);
            let rep = t
                .stability(&StabilityRequest {
                    curves: Some(curves.clone()),
                    speeds: Some(vec![(id(&t, "sun"), 100.0), (id(&t, "carrier"), 40.0)]),
                    ..Default::default()
                })
                .unwrap();
            let inertia = [
                ("sun", small),
                ("carrier", small),
                ("P.planet", small),
                ("ring", ring),
            ];
            let expected = exact_pencil_verdict(&t, &inertia, &curves);
            let st = &rep.stability;
            assert_eq!(
                st.verdict, expected,
                "small {small:e}, ring {ring:e}, slope {ring_slope}: {}",
                st.reason
            );
            if expected == Verdict::Marginal {
                continue;
            }
            // The deviation dynamics over five slow time constants.
            let slow = st
                .eigenvalues
                .iter()
                .fold(f64::INFINITY, |m, l| m.min(l.abs()));
            let end = 5.0 / slow;
            let torque = LinearCurves::new(&t, &curves).unwrap();
            let mut dynamics = ReducedDynamics::new(&t, &torque).unwrap();
            let coords = rep.model.coordinates.clone();
            let start = [(coords[0], 1.0), (coords[1], 0.3)];
            let sim = dynamics
                .simulate(&start, &opts(end, end / 2000.0, Method::Implicit))
                .unwrap();
            let zero = vec![0.0; t.links().len()];
            let d0 = energy_norm(&t, &sim.samples[0].speed, &zero);
            let d1 = energy_norm(&t, &sim.samples.last().unwrap().speed, &zero);
            assert_eq!(
                d1 > d0,
                expected == Verdict::Unstable,
                "small {small:e}, ring {ring:e}, slope {ring_slope}: energy norm {d0:e} -> {d1:e}"
            );
        }
    }
}

/// The simulation request a front end resolves: each setting from the
/// override, else `[analysis.simulate]`, else the default (dt = t_end / 1000,
/// rk4); no end time anywhere is refused naming `t_end`.
#[test]
fn simulation_requests_resolve_overrides_over_the_spec() {
    use egt_core::{SimulationOverrides, SimulationRequest};
    let t = crate::util::example("fig5_stability.toml");
    let spec = SimulationRequest::from_spec(&t).unwrap();
    assert_eq!((spec.options.t_end, spec.options.dt), (1.0, 1.0e-3));
    assert_eq!(spec.options.method, Method::Rk4);
    assert_eq!(spec.initial.len(), 2);
    let over = SimulationOverrides {
        t_end: Some(4.0),
        method: Some(Method::Implicit),
        initial: Some(vec![(id(&t, "2"), 300.0), (id(&t, "4"), 70.0)]),
        ..SimulationOverrides::default()
    };
    let r = SimulationRequest::resolve(&t, &over).unwrap();
    assert_eq!((r.options.t_end, r.options.dt), (4.0, 1.0e-3));
    assert_eq!(r.options.method, Method::Implicit);
    assert_eq!(r.initial[0], (id(&t, "2"), 300.0));
    let bare = crate::util::example("fig5_example62.toml");
    match SimulationRequest::from_spec(&bare) {
        Err(Error::Spec { path, .. }) => assert_eq!(path, "analysis.simulate.t_end"),
        other => panic!("expected a missing t_end, got {other:?}"),
    }
    let over = SimulationOverrides {
        t_end: Some(2.0),
        ..SimulationOverrides::default()
    };
    let r = SimulationRequest::resolve(&bare, &over).unwrap();
    assert_eq!(r.options.dt, 2.0 / 1000.0);
}

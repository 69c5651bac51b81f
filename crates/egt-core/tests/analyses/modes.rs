//! Issue 43: the lumped torsional model's natural frequencies and modes
//! against models written out by hand from the textbook formulas (Lin &
//! Parker 1999, purely torsional), closed forms, and the kinematics.

// A failed unwrap is a failed test that prints the error: what a test wants.
#![allow(clippy::unwrap_used)]

use egt_core::{AnalysisError, Error, ModesRequest, NaturalModes, SpeedInput, Train};
use nalgebra::{DMatrix, DVector, SymmetricEigen};

use crate::util::{id, toml};

/// Module, tooth counts, inertias and stiffnesses of the test planetary set.
const MODULE: f64 = 1.5e-3;
const ZS: f64 = 30.0;
const ZP: f64 = 21.0;
const ZR: f64 = 72.0;
const JS: f64 = 2.0e-4;
const JR: f64 = 6.0e-3;
const JC: f64 = 3.5e-3;
const JP: f64 = 1.5e-5;
const MP: f64 = 0.08;
const KSP: f64 = 4.0e8;
const KRP: f64 = 6.0e8;

fn modes(train: &Train, state: Option<&str>) -> NaturalModes {
    train
        .modes(&ModesRequest {
            state: state.map(String::from),
            ..ModesRequest::default()
        })
        .unwrap_or_else(|e| panic!("{e}"))
}

fn elastic(m: &NaturalModes) -> Vec<f64> {
    m.modes
        .iter()
        .filter(|m| !m.rigid)
        .map(|m| m.omega)
        .collect()
}

/// A simple planetary set with `n` planets; the ring is the frame when
/// `ring_held`. `extra` is appended (elements, states, compliance changes).
fn planetary(n: u32, ring_held: bool, scale: f64, extra: &str) -> String {
    let ring = if ring_held { "H" } else { "ring" };
    let ring_link = if ring_held {
        String::new()
    } else {
        format!("[[links]]\nname = \"ring\"\ninertia = {JR:e}\n")
    };
    format!(
        r#"
frame = "H"
[[planetary]]
name = "P"
sun = "sun"
ring = "{ring}"
carrier = "carrier"
teeth = {{ sun = {ZS}, planet = {ZP}, ring = {ZR} }}
module = {MODULE:e}
[[links]]
name = "sun"
inertia = {JS:e}
[[links]]
name = "carrier"
inertia = {JC:e}
[[links]]
name = "P.planet"
inertia = {JP:e}
mass = {MP:e}
copies = {n}
{ring_link}
[[compliance.meshes]]
gear = "P/sun-planet"
stiffness = {ksp:e}
[[compliance.meshes]]
gear = "P/planet-ring"
stiffness = {krp:e}
{extra}
"#,
        ksp = KSP * scale,
        krp = KRP * scale,
    )
}

/// Generalised eigenvalues of (K, M) by a Cholesky reduction, ascending.
fn generalised(k: &DMatrix<f64>, m: &DMatrix<f64>) -> Vec<f64> {
    let l = m.clone().cholesky().unwrap().l();
    let li = l.try_inverse().unwrap();
    let a = &li * k * li.transpose();
    let mut v: Vec<f64> = SymmetricEigen::new((&a + a.transpose()) * 0.5)
        .eigenvalues
        .iter()
        .copied()
        .collect();
    v.sort_by(f64::total_cmp);
    v
}

/// The purely torsional model written out by hand: coordinates
/// [sun, carrier, planets..., ring (when free)], absolute rotations;
/// delta_sp = r_bs (th_s - th_c) + r_bp (th_p - th_c) (external mesh),
/// delta_rp = r_br (th_r - th_c) - r_bp (th_p - th_c) (internal mesh).
fn hand_model(n: usize, ring_free: bool) -> (DMatrix<f64>, DMatrix<f64>) {
    let cos = 20f64.to_radians().cos();
    let rb = |z: f64| MODULE * z / 2.0 * cos;
    let (rbs, rbp, rbr) = (rb(ZS), rb(ZP), rb(ZR));
    let d = MODULE * (ZS + ZP) / 2.0; // the carrier arm: r_s + r_p
    let size = 2 + n + usize::from(ring_free);
    let (s, c) = (0, 1);
    let r = 2 + n;
    let mut k = DMatrix::zeros(size, size);
    let mut mass = vec![JS, JC + n as f64 * MP * d * d];
    mass.extend(std::iter::repeat_n(JP, n));
    if ring_free {
        mass.push(JR);
    }
    for p in 0..n {
        let mut g = DVector::zeros(size);
        g[s] += rbs;
        g[2 + p] += rbp;
        g[c] -= rbs + rbp;
        k += KSP * &g * g.transpose();
        let mut h = DVector::zeros(size);
        if ring_free {
            h[r] += rbr;
        }
        h[2 + p] -= rbp;
        h[c] -= rbr - rbp;
        k += KRP * &h * h.transpose();
    }
    (k, DMatrix::from_diagonal(&DVector::from_vec(mass)))
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs())
}

#[test]
fn two_inertias_on_one_spring_have_the_closed_form_frequency() {
    // A mesh of ratio -1 on equal base radii is a torsional spring of
    // stiffness k r_b^2 between the two rotations (one of them reversed).
    let (j1, j2, k, rb): (f64, f64, f64, f64) = (0.37, 2.9, 3.3e8, 0.021);
    let t = toml(&format!(
        r#"
frame = "0"
adjacency = "0-1:a 0-2:b 1-2:G=-1"
links = [{{ name = "1", inertia = {j1} }}, {{ name = "2", inertia = {j2} }}]
[compliance]
meshes = [{{ gear = "G1", stiffness = {k:e}, base_radii = [{rb}, {rb}] }}]
"#
    ));
    let m = modes(&t, None);
    assert_eq!(m.dof, 1);
    let f = (k * rb * rb * (1.0 / j1 + 1.0 / j2)).sqrt() / std::f64::consts::TAU;
    let got = m.modes[1].hertz;
    assert!(close(got, f, 1e-12), "{got} vs {f}");
    assert!(close(m.modes[1].omega, f * std::f64::consts::TAU, 1e-12));
    // All the strain energy is in the one mesh; the kinetic energy splits
    // inversely to the inertias.
    assert!(close(m.modes[1].strain_energy[0], 1.0, 1e-12));
    let ke = &m.modes[1].kinetic_energy;
    let (e1, e2) = (
        ke[t.coordinate(id(&t, "1")).unwrap()],
        ke[t.coordinate(id(&t, "2")).unwrap()],
    );
    assert!(close(e1 / e2, j2 / j1, 1e-10));
}

#[test]
fn a_torsional_spring_to_a_vehicle_inertia_gives_the_two_inertia_frequency() {
    // Ring held, the carrier joined to a vehicle inertia by a shaft (a
    // shaft joined to the train by a clutch only is allowed to turn freely);
    // written by hand: the shaft's row added to the hand model.
    let extra = r#"
[[links]]
name = "vehicle"
inertia = 0.8
[[revolutes]]
links = ["H", "vehicle"]
level = "v"
[[elements]]
name = "C"
kind = "clutch"
links = ["carrier", "vehicle"]
[[compliance.springs]]
name = "shaft"
links = ["carrier", "vehicle"]
stiffness = 2.5e3
"#;
    let t = toml(&planetary(3, true, 1.0, extra));
    let m = modes(&t, None);
    assert_eq!(m.dof, 1);
    let (k, mass) = hand_model(3, false);
    let n = k.nrows();
    let mut k2 = DMatrix::zeros(n + 1, n + 1);
    k2.view_mut((0, 0), (n, n)).copy_from(&k);
    let mut g = DVector::zeros(n + 1);
    g[1] = 1.0;
    g[n] = -1.0;
    k2 += 2.5e3 * &g * g.transpose();
    let mut m2 = DMatrix::zeros(n + 1, n + 1);
    m2.view_mut((0, 0), (n, n)).copy_from(&mass);
    m2[(n, n)] = 0.8;
    let hand = generalised(&k2, &m2);
    let ours = elastic(&m);
    assert_eq!(ours.len(), hand.len() - 1);
    for (a, b) in ours.iter().zip(&hand[1..]) {
        assert!(close(a * a, *b, 1e-10), "{} vs {b}", a * a);
    }
    // The spring's mode holds nearly all its strain energy in the shaft.
    let shaft = m
        .model
        .elastic
        .iter()
        .position(|e| e.name == "shaft")
        .unwrap();
    assert!(m.modes[1].strain_energy[shaft] > 0.99);
}

#[test]
fn planet_modes_have_multiplicity_n_minus_1_and_the_hand_models_frequencies() {
    for n in [3u32, 4, 5] {
        for ring_held in [true, false] {
            let t = toml(&planetary(n, ring_held, 1.0, ""));
            let m = modes(&t, None);
            let (k, mass) = hand_model(n as usize, !ring_held);
            let hand = generalised(&k, &mass);
            let zeros = if ring_held { 1 } else { 2 };
            assert_eq!(m.dof, zeros, "n = {n}, ring held {ring_held}");
            assert!(
                hand[..zeros]
                    .iter()
                    .all(|&l| l.abs() < 1e-6 * hand[hand.len() - 1])
            );
            let ours = elastic(&m);
            assert_eq!(ours.len(), hand.len() - zeros);
            for (a, b) in ours.iter().zip(&hand[zeros..]) {
                assert!(close(a * a, *b, 1e-10), "n = {n}: {} vs {b}", a * a);
            }
            // The planet modes: sun, ring and carrier at rest, N - 1 of them,
            // at omega^2 = (k_sp + k_rp) r_bp^2 / J_p (Lin & Parker 1999).
            let rbp = MODULE * ZP / 2.0 * 20f64.to_radians().cos();
            let w2 = (KSP + KRP) * rbp * rbp / JP;
            let planet: Vec<_> = m
                .modes
                .iter()
                .filter(|x| close(x.omega * x.omega, w2, 1e-10))
                .collect();
            assert_eq!(planet.len(), n as usize - 1, "n = {n}");
            let central: Vec<usize> = ["sun", "carrier", "ring"]
                .iter()
                .filter_map(|l| t.link_id(l))
                .filter_map(|l| m.model.coordinates.iter().position(|c| c.link == l))
                .collect();
            for p in &planet {
                assert_eq!(p.multiplicity, n as usize - 1);
                let big = p.shape.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
                for &c in &central {
                    assert!(p.shape[c].abs() < 1e-9 * big, "n = {n}: {:?}", p.shape);
                }
            }
            // Every other elastic mode is simple here.
            assert!(
                m.modes
                    .iter()
                    .filter(|x| !x.rigid && x.multiplicity == 1)
                    .count()
                    == ours.len() - (n as usize - 1)
            );
        }
    }
}

#[test]
fn shapes_are_mass_normalised_and_the_energies_are_shares() {
    let t = toml(&planetary(4, false, 1.0, ""));
    let m = modes(&t, None);
    for x in &m.modes {
        let norm: f64 = x
            .shape
            .iter()
            .zip(&m.model.mass)
            .map(|(p, j)| j * p * p)
            .sum();
        assert!(close(norm, 1.0, 1e-10));
        assert!(close(x.kinetic_energy.iter().sum(), 1.0, 1e-12));
        if !x.rigid {
            assert!(close(x.strain_energy.iter().sum(), 1.0, 1e-12));
        }
    }
    // M-orthogonality between distinct modes.
    for a in &m.modes {
        for b in &m.modes {
            if std::ptr::eq(a, b) {
                continue;
            }
            let dot: f64 = a
                .shape
                .iter()
                .zip(&b.shape)
                .zip(&m.model.mass)
                .map(|((x, y), j)| j * x * y)
                .sum();
            assert!(dot.abs() < 1e-8, "{dot}");
        }
    }
}

/// The kinematics of the bare train for `inputs`, over the model's coordinates.
fn expanded_speeds(t: &Train, m: &NaturalModes, inputs: &[(&str, f64)]) -> DVector<f64> {
    let inputs: Vec<SpeedInput> = inputs.iter().map(|&(l, w)| (id(t, l), w).into()).collect();
    let s = t.kinematics(&inputs).unwrap();
    DVector::from_iterator(
        m.model.coordinates.len(),
        m.model.coordinates.iter().map(|c| s.speed[c.link.index()]),
    )
}

/// The part of `v` outside the span of the rigid-body shapes, relative to |v|.
fn outside_rigid(m: &NaturalModes, v: &DVector<f64>) -> f64 {
    let cols: Vec<DVector<f64>> = m
        .modes
        .iter()
        .filter(|x| x.rigid)
        .map(|x| DVector::from_column_slice(&x.shape))
        .collect();
    let r = DMatrix::from_columns(&cols);
    let q = r.qr().q();
    let rest = v - &q * (q.transpose() * v);
    rest.norm() / v.norm()
}

const STATES: &str = r#"
[[elements]]
name = "B"
kind = "brake"
links = ["ring"]
[[elements]]
name = "C"
kind = "clutch"
links = ["sun", "carrier"]
[transmission]
input = "sun"
output = "carrier"
states = { low = ["B"], direct = ["C"] }
"#;

#[test]
fn the_rigid_body_modes_span_the_kinematics_bare_and_in_each_state() {
    let t = toml(&planetary(3, false, 1.0, STATES));
    let bare = modes(&t, None);
    assert_eq!(bare.dof, t.dof());
    for inputs in [[("sun", 1.0), ("ring", 0.0)], [("sun", 0.0), ("ring", 1.0)]] {
        let v = expanded_speeds(&t, &bare, &inputs);
        assert!(outside_rigid(&bare, &v) < 1e-10);
    }
    let low = modes(&t, Some("low"));
    assert_eq!(low.dof, 1);
    let v = expanded_speeds(&t, &low, &[("sun", 1.0), ("ring", 0.0)]);
    assert!(outside_rigid(&low, &v) < 1e-10);
    // Low: the ring held is the ring-held set's model.
    let (k, mass) = hand_model(3, false);
    let hand = generalised(&k, &mass);
    assert_eq!(elastic(&low).len(), hand.len() - 1);
    for (a, b) in elastic(&low).iter().zip(&hand[1..]) {
        assert!(close(a * a, *b, 1e-10), "{:?} vs {hand:?}", elastic(&low));
    }
    let direct = modes(&t, Some("direct"));
    assert_eq!(direct.dof, 1);
    let v = expanded_speeds(&t, &direct, &[("sun", 1.0), ("ring", 1.0)]);
    assert!(outside_rigid(&direct, &v) < 1e-10);
}

#[test]
fn an_element_given_a_stiffness_is_a_spring_not_a_constraint() {
    let extra = format!("{STATES}\n[[compliance.elements]]\nelement = \"B\"\nstiffness = 1.0e4\n");
    let t = toml(&planetary(3, false, 1.0, &extra));
    let low = modes(&t, Some("low"));
    // The spring to the frame takes away the bare train's second DOF only.
    assert_eq!(low.dof, 1);
    assert!(low.model.constraint_names.is_empty());
    let (k, mass) = hand_model(3, true);
    let r = k.nrows() - 1;
    let mut k2 = k.clone();
    k2[(r, r)] += 1.0e4;
    let hand = generalised(&k2, &mass);
    let ours = elastic(&low);
    assert_eq!(ours.len(), hand.len() - 1);
    for (a, b) in ours.iter().zip(&hand[1..]) {
        assert!(close(a * a, *b, 1e-10), "{} vs {b}", a * a);
    }
}

#[test]
fn frequencies_grow_as_the_square_root_of_the_stiffnesses() {
    let base = elastic(&modes(&toml(&planetary(4, true, 1.0, "")), None));
    for k in [2, 4, -2] {
        let t = toml(&planetary(4, true, 10f64.powi(k), ""));
        let m = modes(&t, None);
        assert_eq!(m.dof, 1);
        for (a, b) in elastic(&m).iter().zip(&base) {
            assert!(close(*a, b * 10f64.powf(f64::from(k) / 2.0), 1e-10));
        }
    }
}

#[test]
fn missing_compliance_is_refused_naming_what_is_missing() {
    let plain = r#"
frame = "H"
links = [{ name = "sun", inertia = 1e-4 }, { name = "carrier", inertia = 1e-3 }, { name = "P.planet", inertia = 1e-5 }]
[[planetary]]
name = "P"
sun = "sun"
ring = "H"
carrier = "carrier"
teeth = { sun = 30, planet = 21, ring = 72 }
module = 1.5e-3
"#;
    let e = toml(plain).modes(&ModesRequest::default()).unwrap_err();
    assert_eq!(e.code(), "missing_data");
    let text = e.to_string();
    assert!(
        text.contains("`P/sun-planet`") && text.contains("`P/planet-ring`"),
        "{text}"
    );

    // An inertia missing: named.
    let t = toml(&planetary(3, false, 1.0, "").replace("inertia = 6e-3", ""));
    let e = t.modes(&ModesRequest::default()).unwrap_err();
    assert!(
        matches!(&e, Error::Analysis(AnalysisError::MissingData { what, .. }) if what.contains("`ring`")),
        "{e}"
    );

    // A base radius: no module, no radii.
    let t = toml(
        r#"
frame = "0"
adjacency = "0-1:a 0-2:b 1-2:G=-2"
links = [{ name = "1", inertia = 1.0 }, { name = "2", inertia = 1.0 }]
compliance = { meshes = [{ gear = "G1", stiffness = 1e8 }] }
"#,
    );
    let e = t.modes(&ModesRequest::default()).unwrap_err();
    assert_eq!(e.code(), "missing_data");
    assert!(
        e.to_string().contains("base radius of gear pair `G1`"),
        "{e}"
    );
}

#[test]
fn bad_compliance_fields_are_spec_errors_with_their_path() {
    let bad = |from: &str, to: &str| {
        let text = planetary(3, true, 1.0, "").replacen(from, to, 1);
        Train::from_str(&text, egt_core::Format::Toml, "t.toml").unwrap_err()
    };
    let e = bad("gear = \"P/sun-planet\"", "gear = \"P/sun-planett\"");
    assert!(e.to_string().contains("P/sun-planet`?"), "{e}");
    let e = bad("stiffness = 4e8", "stiffness = -4e8");
    assert_eq!(e.code(), "out_of_range");
    let e = bad(
        "[[compliance.meshes]]",
        "[compliance]\npressure_angle = 95\n[[compliance.meshes]]",
    );
    assert_eq!(e.code(), "out_of_range");
    let e = bad("gear = \"P/planet-ring\"", "gear = \"P/sun-planet\"");
    assert_eq!(e.code(), "duplicate");
}

#[test]
fn mesh_orders_are_the_textbook_tooth_pass_frequencies_and_cross_the_modes() {
    let t = toml(&planetary(3, false, 1.0, STATES));
    let ask = |state: &str, campbell: Option<[f64; 2]>| {
        t.modes(&ModesRequest {
            state: Some(state.into()),
            campbell,
        })
    };
    // Low (ring held, sun in): both meshes pass z_r w_c = z_s z_r / (z_s + z_r)
    // teeth per sun revolution.
    let low = ask("low", Some([0.0, 1.0e5])).unwrap();
    let m = low.meshing.as_ref().unwrap();
    let want = ZS * ZR / (ZS + ZR);
    for o in &m.orders {
        assert!(close(o.order, want, 1e-12), "{}: {}", o.gear, o.order);
        assert!(close(o.hertz_per_rpm, want / 60.0, 1e-12));
    }
    // Each distinct elastic frequency is crossed once per mesh at 60 f / order.
    let distinct: Vec<f64> = low
        .modes
        .iter()
        .enumerate()
        .filter(|(k, x)| !x.rigid && x.group == *k)
        .map(|(_, x)| x.hertz)
        .collect();
    let inside: Vec<f64> = distinct
        .iter()
        .map(|f| 60.0 * f / want)
        .filter(|&s| s <= 1.0e5)
        .collect();
    assert_eq!(m.crossings.len(), 2 * inside.len());
    for c in &m.crossings {
        assert!(close(c.speed, 60.0 * c.hertz / want, 1e-12));
        assert!(c.speed <= 1.0e5);
    }
    assert!(m.crossings.windows(2).all(|w| w[0].speed <= w[1].speed));
    // Direct: the set turns as one body, no tooth passes, no crossings.
    let direct = ask("direct", Some([0.0, 1.0e5])).unwrap();
    let m = direct.meshing.as_ref().unwrap();
    assert!(m.orders.iter().all(|o| o.order.abs() < 1e-9));
    assert!(m.crossings.is_empty());
    // The bare train has two DOF: no mesh orders; asked for, a missing_data.
    let bare = t.modes(&ModesRequest::default()).unwrap();
    assert!(bare.meshing.is_none());
    let e = t
        .modes(&ModesRequest {
            state: None,
            campbell: Some([0.0, 7000.0]),
        })
        .unwrap_err();
    assert_eq!(e.code(), "missing_data");
    assert!(e.to_string().contains("one rigid-body mode"), "{e}");
    let e = ask("low", Some([100.0, 10.0])).unwrap_err();
    assert_eq!(e.code(), "invalid");
}

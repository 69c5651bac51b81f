//! Issue 43: the damped modes (complex eigenvalues) of the torsional model
//! against the closed form of two inertias on one damped mesh: the relative
//! motion u = theta_1 + theta_2 (a mesh of ratio -1) obeys
//! u'' + (1/J1 + 1/J2) r_b^2 (c u' + k u) = 0, so
//! lambda = -zeta omega_n +- i omega_n sqrt(1 - zeta^2) with
//! omega_n^2 = k r_b^2 (1/J1 + 1/J2), 2 zeta omega_n = c r_b^2 (1/J1 + 1/J2).

// A failed unwrap is a failed test that prints the error: what a test wants.
#![allow(clippy::unwrap_used)]

use egt_core::{ModesRequest, Train};

use crate::util::toml;

fn two_inertias(j1: f64, j2: f64, k: f64, c: f64, rb: f64) -> Train {
    toml(&format!(
        r#"
frame = "0"
adjacency = "0-1:a 0-2:b 1-2:G=-1"
links = [{{ name = "1", inertia = {j1} }}, {{ name = "2", inertia = {j2} }}]
[compliance]
meshes = [{{ gear = "G1", stiffness = {k:e}, damping = {c:e}, base_radii = [{rb}, {rb}] }}]
"#
    ))
}

#[test]
fn an_underdamped_mesh_has_the_closed_form_complex_eigenvalue() {
    let (j1, j2, k, c, rb): (f64, f64, f64, f64, f64) = (0.37, 2.9, 3.3e8, 2.0e4, 0.021);
    let m = two_inertias(j1, j2, k, c, rb)
        .modes(&ModesRequest::default())
        .unwrap();
    let s = 1.0 / j1 + 1.0 / j2;
    let wn = (k * rb * rb * s).sqrt();
    let zeta = c * rb * rb * s / (2.0 * wn);
    assert!(
        zeta > 0.01 && zeta < 1.0,
        "zeta {zeta}: underdamped, and not trivially small"
    );
    // The rigid-body motion (a double zero) is left out: one pair, once.
    assert_eq!(m.damped.len(), 1, "{:?}", m.damped);
    let d = &m.damped[0];
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-10 * b.abs();
    assert!(close(d.sigma, -zeta * wn), "{} vs {}", d.sigma, -zeta * wn);
    assert!(close(d.omega_d, wn * (1.0 - zeta * zeta).sqrt()));
    assert!(close(d.omega_n, wn) && close(d.damping_ratio, zeta));
    assert!(close(d.hertz_d * std::f64::consts::TAU, d.omega_d));
    // The undamped mode's modal damping ratio is the same here (one mode).
    assert!(close(m.modes[1].damping_ratio.unwrap(), zeta));
}

#[test]
fn an_overdamped_mesh_has_two_real_decay_rates() {
    let (j1, j2, k, rb): (f64, f64, f64, f64) = (0.5, 2.0, 1.0e6, 0.01);
    let s = 1.0 / j1 + 1.0 / j2;
    let wn = (k * rb * rb * s).sqrt();
    // zeta = 3: lambda = -wn (zeta +- sqrt(zeta^2 - 1)).
    let c = 2.0 * 3.0 * wn / (rb * rb * s);
    let m = two_inertias(j1, j2, k, c, rb)
        .modes(&ModesRequest::default())
        .unwrap();
    let mut rates: Vec<f64> = m.damped.iter().map(|d| d.sigma).collect();
    rates.sort_by(f64::total_cmp);
    let expect = [-wn * (3.0 + 8f64.sqrt()), -wn * (3.0 - 8f64.sqrt())];
    assert_eq!(rates.len(), 2, "{:?}", m.damped);
    for (a, b) in rates.iter().zip(expect) {
        assert!((a - b).abs() <= 1e-9 * b.abs(), "{a} vs {b}");
    }
    assert!(
        m.damped
            .iter()
            .all(|d| d.omega_d == 0.0 && (d.damping_ratio - 1.0).abs() < 1e-12)
    );
}

#[test]
fn no_damping_no_damped_modes() {
    let m = two_inertias(0.5, 2.0, 1.0e6, 0.0, 0.01)
        .modes(&ModesRequest::default())
        .unwrap();
    assert!(m.damped.is_empty());
}

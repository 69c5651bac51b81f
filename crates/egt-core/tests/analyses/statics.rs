//! Issue 43: the compliant model under a steady load is the rigid model at a
//! finer resolution: its mesh forces are eq. (11)'s meshing forces, its rigid
//! elements carry the rigid model's element torques, and every coordinate is
//! in equilibrium, on the paper's Fig. 3 train and the 8HP70 in two gears.

// A failed unwrap is a failed test that prints the error: what a test wants.
#![allow(clippy::unwrap_used)]

use egt_core::{DynamicsRequest, Extra, StaticCheck, Train};

use crate::util::{example, example_path, id, toml};

/// Relative difference against the larger of the two.
fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / a.abs().max(b.abs())
}

/// Every mesh's torque from the springs against eq. (11)'s, to `tol` of the
/// largest (a set locked by a clutch carries none); and eq. (11)'s tangential
/// forces (pitch radii) from the line-of-action force: F_t r = F r_b with
/// r_b = r cos(alpha), summed over the copies.
fn assert_meshes_agree(train: &Train, check: &StaticCheck, tol: f64) {
    let top = check
        .meshes
        .iter()
        .fold(0.0_f64, |a, m| a.max(m.rigid_torque.abs()));
    assert!(top > 1.0, "no mesh carries a load: a test that cannot fail");
    for m in &check.meshes {
        assert!(
            (m.compliant_torque - m.rigid_torque).abs() < tol * top,
            "{}: springs {} against eq. (11) {}",
            m.gear,
            m.compliant_torque,
            m.rigid_torque
        );
    }
    for (g, m) in train.gears().iter().zip(&check.meshes) {
        let Some([ri, _]) = g.radii else { continue };
        let copies = check
            .deflection
            .springs
            .iter()
            .filter(|s| s.name == g.name || s.name.starts_with(&format!("{}#", g.name)))
            .count() as f64;
        let tangential = m.force * 20f64.to_radians().cos() * copies;
        assert!(
            (tangential - m.rigid_torque / ri).abs() < tol * top / ri,
            "{}: tangential force {tangential} against eq. (11) {}",
            g.name,
            m.rigid_torque / ri
        );
    }
}

/// Equilibrium of every coordinate, written out here: the springs' torques
/// (-k delta times the row) and the rigid elements' reactions balance the load.
fn assert_equilibrium(train: &Train, state: Option<&str>, check: &StaticCheck) {
    let model = train.torsional_model(state).unwrap();
    let n = model.coordinates.len();
    let scale = check.torque.iter().fold(0.0_f64, |a, t| a.max(t.abs()));
    for k in 0..n {
        let link = model.coordinates[k].link;
        let copies = f64::from(train.link(link).copies.max(1));
        let mut sum = check.torque[link.index()] / copies;
        for (e, s) in model.elastic.iter().zip(&check.deflection.springs) {
            sum -= s.force * e.row[k];
        }
        for (r, mu) in check.deflection.element_torques.iter().enumerate() {
            sum -= mu * model.constraints[(r, k)];
        }
        assert!(
            sum.abs() < 1e-9 * scale,
            "{}: unbalanced by {sum}",
            model.coordinates[k].name
        );
    }
}

#[test]
fn fig3_mesh_forces_are_eq_11s_under_a_steady_load() {
    let text = std::fs::read_to_string(example_path("fig3_example61.toml")).unwrap();
    let train = toml(&format!(
        "{text}\n[[compliance.meshes]]\ngear = \"G1\"\nstiffness = 3.0e8\n\n[[compliance.meshes]]\ngear = \"G2\"\nstiffness = 2.5e8\n"
    ));
    // The output loaded with -50 N m, the input carrier balancing it.
    let req = DynamicsRequest {
        torques: vec![(id(&train, "4"), -50.0)],
        driving: vec![id(&train, "2")],
        ..DynamicsRequest::default()
    };
    let check = train.static_check(None, &req).unwrap();
    assert_meshes_agree(&train, &check, 1e-10);
    assert_equilibrium(&train, None, &check);
    // Three planets share each mesh alike.
    let g1: Vec<f64> = check
        .deflection
        .springs
        .iter()
        .filter(|s| s.name.starts_with("G1#"))
        .map(|s| s.force)
        .collect();
    assert_eq!(g1.len(), 3);
    assert!(g1.iter().all(|f| rel(*f, g1[0]) < 1e-10));
}

#[test]
fn the_8hp_in_two_gears_carries_eq_11s_mesh_forces_and_element_torques() {
    let train = example("zf_8hp70_compliant.toml");
    for state in ["3", "7"] {
        let req = DynamicsRequest {
            torques: vec![(id(&train, "input"), 300.0)],
            driving: vec![id(&train, "output")],
            ..DynamicsRequest::default()
        };
        let check = train.static_check(Some(state), &req).unwrap();
        assert_meshes_agree(&train, &check, 1e-10);
        assert_equilibrium(&train, Some(state), &check);
        // The elements held rigidly carry the rigid model's torques.
        let mut rigid = req.clone();
        let t = train.transmission().unwrap();
        let s = t.states.iter().find(|s| s.name == state).unwrap();
        rigid.extras = s
            .engaged
            .iter()
            .map(|&e| match train.elements()[e.index()].links.as_slice() {
                [l] => Extra::Hold(*l),
                [a, b] => Extra::Join(*a, *b),
                other => panic!("an element of {} links", other.len()),
            })
            .collect();
        let dynamics = train.inverse_dynamics(&rigid, None).unwrap();
        assert_eq!(dynamics.element_torques.len(), 3);
        for (a, b) in check
            .deflection
            .element_torques
            .iter()
            .zip(&dynamics.element_torques)
        {
            assert!(
                rel(*a, *b) < 1e-10,
                "gear {state}: element torque {a} against {b}"
            );
        }
    }
}

#[test]
fn an_unbalanced_load_is_refused_not_deflected() {
    let train = example("zf_8hp70_compliant.toml");
    let model = train.torsional_model(Some("3")).unwrap();
    let mut f = vec![0.0; model.coordinates.len()];
    f[0] = 300.0; // the input alone: the train would accelerate
    let e = model.static_deflection(&f).unwrap_err();
    assert!(e.to_string().contains("not balanced"), "{e}");
}

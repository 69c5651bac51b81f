//! Time of one simulated clutch engagement (divan): a 2-3-like inertia phase
//! with a pressure ramp, Stribeck friction, drive torque and road load, from
//! release to lock-up and on to the end time. Numbers in docs/performance.md (history: git log -p -- docs/benchmarks.md).

use std::hint::black_box;

use egt_core::motion::shift_dynamics::{Capacity, Engagement, FrictionLaw};

fn main() {
    divan::main();
}

fn ramped() -> Engagement {
    Engagement {
        j1: 0.25,
        j2: 1.5,
        speed: [300.0, 120.0],
        t1: 120.0,
        t2: -10.0,
        damping: 0.4,
        law: FrictionLaw {
            mu_static: 0.14,
            mu_kinetic: 0.1,
            decay: Some(5.0),
        },
        capacity: Capacity::Ramp {
            t0: 0.05,
            t1: 0.4,
            from: 0.0,
            to: 4000.0,
        },
        one_way: false,
        t_end: 2.0,
        rtol: 1e-8,
        atol: 1e-8,
    }
}

#[divan::bench]
fn one_engagement_rtol_1e8() -> usize {
    let e = ramped();
    black_box(&e).simulate().map(|r| r.steps).unwrap_or(0)
}

fn zf_2_3() -> (egt_core::Train, egt_core::shift_dynamics::ShiftSim) {
    use egt_core::shift_dynamics::{InputTorque, ShiftSim};
    let text = include_str!(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/zf_8hp70.toml"
    ));
    let train = egt_core::Train::from_str(text, egt_core::Format::Toml, "zf_8hp70.toml")
        .expect("example parses");
    let sim = ShiftSim {
        from: "2".into(),
        to: "3".into(),
        input_speed: 250.0,
        input_torque: InputTorque::Constant(300.0),
        road_load: [20.0, 0.2, 0.002],
        vehicle_inertia: 12.0,
        law: FrictionLaw {
            mu_static: 0.15,
            mu_kinetic: 0.12,
            decay: None,
        },
        off_going: Some(Capacity::Ramp {
            t0: 0.05,
            t1: 0.15,
            from: 5000.0,
            to: 0.0,
        }),
        on_coming: Some(Capacity::Ramp {
            t0: 0.05,
            t1: 0.3,
            from: 0.0,
            to: 9000.0,
        }),
        t_end: 1.0,
        rtol: 1e-8,
        atol: 1e-8,
        method: egt_core::shift_dynamics::ShiftMethod::Auto,
        max_steps: egt_core::shift_dynamics::DEFAULT_MAX_STEPS,
        ramps: Vec::new(),
    };
    (train, sim)
}

/// One whole-train shift: the 8HP70's 2-3 upshift (13 links, modes of 1-2
/// DOF), release of brake A to lock-up of clutch C and on to t = 1 s.
#[divan::bench]
fn zf_8hp_2_3_upshift(bencher: divan::Bencher) {
    let (train, sim) = zf_2_3();
    bencher.bench_local(|| {
        black_box(&sim)
            .run(black_box(&train))
            .map(|r| r.steps)
            .unwrap_or(0)
    });
}

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
    use egt_core::shift_dynamics::ShiftSim;
    let text = include_str!(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/zf_8hp70.toml"
    ));
    let train = egt_core::Train::from_str(text, egt_core::Format::Toml, "zf_8hp70.toml")
        .expect("example parses");
    // The example's [[shift]] "2-3": the upshift of docs/shift_dynamics.md.
    let sim = ShiftSim::named(&train, "2-3").expect("the example names it");
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

/// The 8HP70's 2-3 upshift stepped as an FMU steps it: 1000 pieces of 1 ms
/// (`ShiftStepper::advance`), the capacities of docs/fmu.md's ramps (`A`
/// 5000 -> 0 over 0.05..0.15 s, `C` 0 -> 9000 over 0.05..0.3 s) sent as a
/// value and a rate per piece. The time per piece is this over 1000.
#[divan::bench(sample_count = 20)]
fn zf_8hp_2_3_stepped_1000_pieces_of_1ms(bencher: divan::Bencher) {
    use egt_core::shift_dynamics::{ShiftStepper, StepInputs};
    let (train, sim) = zf_2_3();
    let ramp = |t: f64, t0: f64, t1: f64, c0: f64, c1: f64| {
        let cap = Capacity::Ramp {
            t0,
            t1,
            from: c0,
            to: c1,
        };
        let rate = if t >= t0 && t < t1 {
            (c1 - c0) / (t1 - t0)
        } else {
            0.0
        };
        (cap.at(t), rate)
    };
    let inputs = |t: f64| {
        let (a, ra) = ramp(t, 0.05, 0.15, 5000.0, 0.0);
        let (c, rc) = ramp(t, 0.05, 0.3, 0.0, 9000.0);
        StepInputs {
            input_torque: 300.0,
            load_torque: 0.0,
            capacity: vec![a, 1e7, c, 0.0, 1e7],
            capacity_rate: vec![ra, 0.0, rc, 0.0, 0.0],
        }
    };
    let start = ShiftStepper::new(&train, &sim, &inputs(0.0)).expect("second gear holds");
    let all: Vec<StepInputs> = (0..1000).map(|k| inputs(f64::from(k) * 1e-3)).collect();
    bencher.bench_local(|| {
        let mut s = start.clone();
        for i in &all {
            s.advance(i, 1e-3).expect("the shift steps");
        }
        black_box(s.lock_time(2))
    });
}

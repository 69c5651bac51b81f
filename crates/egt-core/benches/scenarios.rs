//! Timings by phase and by train size (divan): parsing; validation with the
//! topology checks; the topology checks and circuit table alone; preparing a
//! batch plan; and one scenario on a prepared train (kinematics, inverse
//! dynamics with meshing forces, power flow with mesh losses; the stability
//! eigenvalues of Fig. 5's two-motor train); plus batch throughput on all cores. Sizes run from 3 to 30 links over two generated
//! families (planetary chains, nests) and the bundled examples.
//!
//! `make bench` runs this with short settings; docs/performance.md (history: git log -p -- docs/benchmarks.md) has the numbers.
//! A row of the scenario benches is the one the spec's `[analysis]` describes.

use std::hint::black_box;

use divan::Bencher;
use divan::counter::ItemsCount;
use egt_core::batch::{BatchPlan, BatchSpec, Executor, Layout, Threads};
use egt_core::solve::prepared::Compute;
use egt_core::{Format, Train, parse_spec};

#[path = "../lab/mod.rs"]
mod lab;
use lab::families;

fn main() {
    divan::main();
}

/// Train sizes in links: a planetary chain of k sets has 2 + 2k links.
const CHAIN_LINKS: &[usize] = &[4, 6, 10, 16, 22, 30];
/// A nest of n links (n - 1 nested stages).
const NEST_LINKS: &[usize] = &[3, 6, 10, 16, 22, 30];
/// Bundled examples with an `[analysis]` section that names inputs.
const EXAMPLES: &[&str] = &[
    "fig3_example61.toml",
    "fig5_example62.toml",
    "simple_planetary.toml",
];

fn chain(links: usize) -> String {
    families::planetary_chain((links - 2) / 2)
}

fn example(name: &str) -> String {
    let path = format!("{}/../../examples/{name}", env!("CARGO_MANIFEST_DIR"));
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

fn build(text: &str) -> Train {
    Train::from_str(text, Format::Toml, "bench").unwrap_or_else(|e| panic!("{e}"))
}

fn plan(t: &Train, compute: Compute) -> BatchPlan {
    let spec = BatchSpec::from_analysis(t, compute).unwrap_or_else(|e| panic!("{e}"));
    BatchPlan::new(t, &spec).unwrap_or_else(|e| panic!("{e}"))
}

/// Two rows that differ in a ratio by one ulp: alternating them, every
/// scenario factors its matrices afresh (a worker reuses the factorisations
/// of the previous row when the ratios are equal).
fn rows(p: &BatchPlan) -> [Vec<f64>; 2] {
    let a = p.base().to_vec();
    let mut b = a.clone();
    b[0] = f64::from_bits(b[0].to_bits() + 1);
    [a, b]
}

/// One scenario on a prepared plan, factorisations included.
fn scenario(b: Bencher, t: &Train, compute: Compute) {
    scenario_on(b, plan(t, compute));
}

/// [`scenario`] on a given plan.
fn scenario_on(b: Bencher, p: BatchPlan) {
    let rows = rows(&p);
    let mut out = vec![0.0; p.outputs().len()];
    let mut w = p.worker();
    let mut k = 0;
    b.bench_local(|| {
        k ^= 1;
        w.eval(black_box(&rows[k]), black_box(&mut out))
            .unwrap_or_else(|e| panic!("{e}"))
    });
}

/// One scenario whose ratios equal the previous row's: the factorisations
/// and condition estimates are reused, only the substitutions remain.
fn scenario_same_ratios(b: Bencher, t: &Train, compute: Compute) {
    let p = plan(t, compute);
    let row = p.base().to_vec();
    let mut out = vec![0.0; p.outputs().len()];
    let mut w = p.worker();
    b.bench_local(|| {
        w.eval(black_box(&row), black_box(&mut out))
            .unwrap_or_else(|e| panic!("{e}"))
    });
}

/// Rows of a sweep: the spec's row with the input speed, the prescribed
/// accelerations and the applied torques varied row by row (a load sweep);
/// with `ratio_ulps`, the first ratio also moves by one ulp every other row,
/// so that every row is a different train (the rows the linear path cannot take).
fn sweep_rows(p: &BatchPlan, rows: usize, ratio_ulps: bool) -> Vec<f64> {
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
    let mut out = Vec::with_capacity(rows * p.parameters().len());
    for r in 0..rows {
        let mut row = p.base().to_vec();
        for (k, &c) in linear.iter().enumerate() {
            row[c] += ((r * 7 + k * 3) % 101) as f64 * 0.25;
        }
        if ratio_ulps && r % 2 == 1 {
            row[0] = f64::from_bits(row[0].to_bits() + 1);
        }
        out.extend(row);
    }
    out
}

/// 10 000 rows of a sweep through `BatchPlan::run` on one thread, per row
/// (with `bounds`, condition estimates only where bounds cannot show a row
/// well-conditioned).
fn sweep(b: Bencher, t: &Train, ratio_ulps: bool, bounds: bool) {
    sweep_layout(b, t, ratio_ulps, bounds, false, Executor::Auto);
}

/// [`sweep`] with the matrices column-major or not (`Layout::Columns`),
/// the straight-line program (with bounds) run by `executor`.
fn sweep_layout(
    b: Bencher,
    t: &Train,
    ratio_ulps: bool,
    bounds: bool,
    columns: bool,
    executor: Executor,
) {
    const ROWS: usize = 10_000;
    let p = plan(t, Compute::Dynamics)
        .with_condition_bounds(bounds)
        .with_executor(executor);
    let mut params = sweep_rows(&p, ROWS, ratio_ulps);
    let np = p.parameters().len();
    if columns {
        params = (0..np)
            .flat_map(|k| params[k..].iter().step_by(np).copied().collect::<Vec<_>>())
            .collect();
    }
    let mut out = vec![0.0; ROWS * p.outputs().len()];
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap_or_else(|e| panic!("{e}"));
    b.counter(ItemsCount::new(ROWS)).bench_local(|| {
        pool.install(|| {
            if columns {
                p.run(
                    Layout::Columns(black_box(&params)),
                    black_box(&mut out),
                    Threads::Pool,
                )
                .errors
            } else {
                p.run(
                    Layout::Rows(black_box(&params)),
                    black_box(&mut out),
                    Threads::Pool,
                )
                .errors
            }
        })
    });
}

macro_rules! phases {
    ($module:ident, $sizes:expr, $make:expr) => {
        mod $module {
            use super::*;

            #[divan::bench(args = $sizes)]
            fn parse(b: Bencher, links: usize) {
                let text = $make(links);
                b.bench(|| {
                    parse_spec(black_box(&text), Format::Toml, "bench").map(|s| s.frame.len())
                });
            }

            #[divan::bench(args = $sizes)]
            fn validate(b: Bencher, links: usize) {
                let spec = parse_spec(&$make(links), Format::Toml, "bench")
                    .unwrap_or_else(|e| panic!("{e}"));
                b.bench(|| Train::from_spec(black_box(&spec)).map(|t| t.dof()));
            }

            #[divan::bench(args = $sizes)]
            fn topology(b: Bencher, links: usize) {
                let t = build(&$make(links));
                b.bench(|| black_box(&t).reanalyse_topology());
            }

            #[divan::bench(args = $sizes)]
            fn prepare(b: Bencher, links: usize) {
                let t = build(&$make(links));
                b.bench(|| plan(black_box(&t), Compute::Power).outputs().len());
            }

            #[divan::bench(args = $sizes)]
            fn kinematics(b: Bencher, links: usize) {
                scenario(b, &build(&$make(links)), Compute::Kinematics);
            }

            #[divan::bench(args = $sizes)]
            fn inverse_dynamics(b: Bencher, links: usize) {
                scenario(b, &build(&$make(links)), Compute::Dynamics);
            }

            #[divan::bench(args = $sizes)]
            fn power_lossy(b: Bencher, links: usize) {
                scenario(b, &build(&$make(links)), Compute::Power);
            }

            #[divan::bench(args = $sizes)]
            fn inverse_dynamics_same_ratios(b: Bencher, links: usize) {
                scenario_same_ratios(b, &build(&$make(links)), Compute::Dynamics);
            }

            /// A load sweep (ratios fixed): the linear blocks of `run`, one core.
            #[divan::bench(args = $sizes)]
            fn sweep_loads(b: Bencher, links: usize) {
                sweep(b, &build(&$make(links)), false, false);
            }

            /// The same sweep with the ratio moving by one ulp every other
            /// row: every row solved, one core.
            #[divan::bench(args = $sizes)]
            fn sweep_loads_and_ratios(b: Bencher, links: usize) {
                sweep(b, &build(&$make(links)), true, false);
            }

            /// The same with condition bounds (`with_condition_bounds`): the
            /// `cond.*` columns not wanted for themselves.
            #[divan::bench(args = $sizes)]
            fn sweep_bounded_ratios(b: Bencher, links: usize) {
                sweep(b, &build(&$make(links)), true, true);
            }

            /// The same, column-major (`Layout::Columns`): the
            /// straight-line program compiled (with the `jit` feature, where
            /// the machine runs the code).
            #[divan::bench(args = $sizes)]
            fn sweep_bounded_ratios_columns(b: Bencher, links: usize) {
                let t = build(&$make(links));
                sweep_layout(b, &t, true, true, true, Executor::Auto);
            }

            /// The same with the program interpreted (`Executor::Interpreted`).
            #[divan::bench(args = $sizes)]
            fn sweep_bounded_ratios_columns_interpreted(b: Bencher, links: usize) {
                let t = build(&$make(links));
                sweep_layout(b, &t, true, true, true, Executor::Interpreted);
            }
        }
    };
}

phases!(chain, CHAIN_LINKS, chain);
phases!(nest, NEST_LINKS, families::nest);

/// Large trains (zigzag chains, speeds of order one): one kinematic solve
/// (new ratios each time, so a factorisation) with the dense and with the
/// sparse LU, and reading plus checking the spec.
mod large {
    use super::*;
    use egt_core::solve::prepared::{PreparedTrain, Scenario};

    const SIZES: &[usize] = &[6, 10, 16, 22, 34, 66, 130, 258, 514, 1026];

    fn solve(b: Bencher, links: usize, sparse: bool) {
        let t = build(&families::zigzag_chain((links - 2) / 2));
        let input = t.link_id("m0").unwrap_or_else(|| panic!("no m0"));
        let plan = PreparedTrain::for_analysis(&t, &[input], &[input], &[input], &[])
            .and_then(|p| p.with_sparse(sparse))
            .unwrap_or_else(|e| panic!("{e}"));
        let mut ws = plan.workspace();
        let ratios = t.ratios().unwrap_or_else(|e| panic!("{e}"));
        let nudged: Vec<f64> = ratios.iter().map(|r| r * (1.0 + 1e-12)).collect();
        let mut flip = false;
        b.bench_local(|| {
            flip = !flip;
            let r = if flip { &ratios } else { &nudged };
            let s = Scenario::kinematic(black_box(r), &[157.0]);
            plan.solve(&mut ws, &s, Compute::Kinematics)
                .unwrap_or_else(|e| panic!("{e}"))
        });
    }

    #[divan::bench(args = SIZES)]
    fn kinematics_dense(b: Bencher, links: usize) {
        solve(b, links, false);
    }

    #[divan::bench(args = SIZES)]
    fn kinematics_sparse(b: Bencher, links: usize) {
        solve(b, links, true);
    }

    /// One inverse-dynamics scenario (a new factorisation of each system,
    /// as `chain::inverse_dynamics`) with the dense and with the sparse
    /// engine of `PreparedTrain`; `PREPARED_SPARSE_FROM` in
    /// `solve/prepared.rs` sits where they cross.
    fn dynamics(b: Bencher, links: usize, sparse: bool) {
        let t = build(&families::zigzag_chain((links - 2) / 2));
        let p = plan(&t, Compute::Dynamics)
            .with_sparse(sparse)
            .unwrap_or_else(|e| panic!("{e}"));
        scenario_on(b, p);
    }

    #[divan::bench(args = [6, 10, 16, 22, 34, 66, 130, 258])]
    fn dynamics_dense(b: Bencher, links: usize) {
        dynamics(b, links, false);
    }

    #[divan::bench(args = [6, 10, 16, 22, 34, 66, 130, 258, 1026, 10_002])]
    fn dynamics_sparse(b: Bencher, links: usize) {
        dynamics(b, links, true);
    }

    #[divan::bench(args = [1002, 10_002, 100_002], sample_count = 5)]
    fn read_and_check(b: Bencher, links: usize) {
        let text = families::zigzag_chain((links - 2) / 2);
        b.bench(|| build(black_box(&text)).dof());
    }
}

mod examples {
    use super::*;

    #[divan::bench(args = EXAMPLES)]
    fn parse_validate(b: Bencher, name: &str) {
        let text = example(name);
        b.bench(|| Train::from_str(black_box(&text), Format::Toml, "bench").map(|t| t.dof()));
    }

    #[divan::bench(args = EXAMPLES)]
    fn inverse_dynamics(b: Bencher, name: &str) {
        scenario(b, &build(&example(name)), Compute::Dynamics);
    }

    #[divan::bench(args = EXAMPLES)]
    fn power_lossy(b: Bencher, name: &str) {
        scenario(b, &build(&example(name)), Compute::Power);
    }

    /// Stability of the Fig. 5 two-motor train (eq. 19-27): the eigenvalues of
    /// a prepared reduced model (V, V^T M V, V^T K V built once), and the
    /// whole analysis from the train (model, operating point, eigenvalues).
    #[divan::bench]
    fn stability_eigenvalues(b: Bencher) {
        let t = build(&example("fig5_stability.toml"));
        let (coords, _) = t
            .driving_coordinates(None)
            .unwrap_or_else(|e| panic!("{e}"));
        let model = t
            .reduced_model(&coords, &t.analysis().curves)
            .unwrap_or_else(|e| panic!("{e}"));
        b.bench_local(|| model.stability().map(|s| s.eigenvalues.len()));
    }

    #[divan::bench]
    fn stability_whole(b: Bencher) {
        let t = build(&example("fig5_stability.toml"));
        let req = egt_core::StabilityRequest::default();
        b.bench_local(|| {
            t.stability(black_box(&req))
                .map(|r| r.stability.eigenvalues.len())
        });
    }

    /// Every gear state of the ZF 8HP70 shift table, one scenario each (static:
    /// input speed and torque, no acceleration).
    #[divan::bench]
    fn zf_8hp_shift_table(b: Bencher) {
        let t = build(&example("zf_8hp70.toml"));
        let states = shift_table(&t, Compute::Power);
        // Alternate two rows one ulp apart in a ratio: every scenario factors.
        let mut work: Vec<_> = states
            .iter()
            .map(|(p, row)| {
                let mut other = row.clone();
                other[0] = f64::from_bits(other[0].to_bits() + 1);
                (
                    p.worker(),
                    [row.clone(), other],
                    vec![0.0; p.outputs().len()],
                )
            })
            .collect();
        let mut k = 0;
        b.counter(ItemsCount::new(work.len())).bench_local(|| {
            k ^= 1;
            for (w, rows, out) in &mut work {
                w.eval(black_box(&rows[k]), out)
                    .unwrap_or_else(|e| panic!("{e}"));
            }
        });
    }
}

/// A plan and a row per gear state: input at 200 rad/s with 300 N m.
fn shift_table(t: &Train, compute: Compute) -> Vec<(BatchPlan, Vec<f64>)> {
    let tr = t
        .transmission()
        .unwrap_or_else(|| panic!("no transmission"));
    let input = t.link_name(tr.input).to_string();
    tr.states
        .iter()
        .map(|s| {
            let spec =
                BatchSpec::for_gear_state(t, &s.name, compute).unwrap_or_else(|e| panic!("{e}"));
            let p = BatchPlan::new(t, &spec).unwrap_or_else(|e| panic!("{e}"));
            let mut row = p.base().to_vec();
            let set = |row: &mut Vec<f64>, name: &str, v: f64| {
                if let Some(c) = p.parameter(name) {
                    row[c] = v;
                }
            };
            set(&mut row, &format!("speed.{input}"), 200.0);
            set(&mut row, &format!("torque.{input}"), 300.0);
            (p, row)
        })
        .collect()
}

/// Batch throughput on all cores (rayon): scenarios per second.
mod batch {
    use super::*;

    const ROWS: usize = 200_000;

    fn run(b: Bencher, p: &BatchPlan, rows: &[f64]) {
        let n = rows.len() / p.parameters().len();
        let mut out = vec![0.0; n * p.outputs().len()];
        b.counter(ItemsCount::new(n)).bench_local(|| {
            let errors = p
                .run(Layout::Rows(black_box(rows)), &mut out, Threads::Pool)
                .errors;
            assert!(errors.is_empty());
        });
    }

    /// The 6-link 1-DOF chain: inverse dynamics, every row a different load
    /// (the ratios stay, so each worker factors once per run of equal ratios).
    #[divan::bench(sample_count = 10)]
    fn chain6_inverse_dynamics(b: Bencher) {
        let t = build(&chain(6));
        let p = plan(&t, Compute::Dynamics);
        let load = p
            .parameter("torque.c2")
            .unwrap_or_else(|| panic!("no load column"));
        let mut rows = Vec::with_capacity(ROWS * p.parameters().len());
        for r in 0..ROWS {
            let mut row = p.base().to_vec();
            row[load] = -40.0 - (r % 1000) as f64 * 0.1;
            rows.extend(row);
        }
        run(b, &p, &rows);
    }

    /// The same with a different ratio in every row: every scenario factors.
    #[divan::bench(sample_count = 10)]
    fn chain6_inverse_dynamics_new_ratios(b: Bencher) {
        new_ratios(b, false, &[]);
    }

    /// The same with condition bounds: the straight-line program.
    #[divan::bench(sample_count = 10)]
    fn chain6_inverse_dynamics_new_ratios_bounded(b: Bencher) {
        new_ratios(b, true, &[]);
    }

    /// The same, the input torque and the conditions chosen (as `egt batch
    /// --columns driving_torque.s1` chooses them).
    #[divan::bench(sample_count = 10)]
    fn chain6_inverse_dynamics_new_ratios_bounded_one_column(b: Bencher) {
        new_ratios(
            b,
            true,
            &[
                "driving_torque.s1",
                "cond.speeds",
                "cond.accelerations",
                "cond.forces",
            ],
        );
    }

    /// The same, column-major (`Layout::Columns`), as `egt batch`
    /// holds a Parquet or Arrow block: the in-process rate its end-to-end
    /// rate is compared with (docs/performance.md (history: git log -p -- docs/benchmarks.md)).
    #[divan::bench(sample_count = 10)]
    fn chain6_inverse_dynamics_new_ratios_bounded_one_column_by_columns(b: Bencher) {
        let (p, rows) = new_ratio_rows(
            true,
            &[
                "driving_torque.s1",
                "cond.speeds",
                "cond.accelerations",
                "cond.forces",
            ],
        );
        let np = p.parameters().len();
        let columns: Vec<f64> = (0..np)
            .flat_map(|k| rows[k..].iter().step_by(np).copied().collect::<Vec<_>>())
            .collect();
        let n = rows.len() / np;
        let mut out = vec![0.0; n * p.outputs().len()];
        b.counter(ItemsCount::new(n)).bench_local(|| {
            let errors = p
                .run(
                    Layout::Columns(black_box(&columns)),
                    &mut out,
                    Threads::Pool,
                )
                .errors;
            assert!(errors.is_empty());
        });
    }

    /// `egt batch`'s own job in process: the input torque alone chosen
    /// (`--columns driving_torque.s1`), the load and the ratio given row by
    /// row and every other parameter as one value (`Layout::ColumnSet`, as
    /// `egt batch` holds a grid's Parquet block; docs/performance.md (history: git log -p -- docs/benchmarks.md)).
    #[divan::bench(sample_count = 10)]
    fn chain6_inverse_dynamics_new_ratios_bounded_driving_torque_column_set(b: Bencher) {
        use egt_core::batch::Column;
        let (p, rows) = new_ratio_rows(true, &["driving_torque.s1"]);
        let np = p.parameters().len();
        let n = rows.len() / np;
        let load = p
            .parameter("torque.c2")
            .unwrap_or_else(|| panic!("no load column"));
        let varied: Vec<Vec<f64>> = [0, load]
            .iter()
            .map(|&k| rows[k..].iter().step_by(np).copied().collect())
            .collect();
        let columns: Vec<Column<'_>> = (0..np)
            .map(|k| match [0, load].iter().position(|&v| v == k) {
                Some(j) => Column::Rows(&varied[j]),
                None => Column::Every(p.base()[k]),
            })
            .collect();
        let mut out = vec![0.0; n * p.outputs().len()];
        b.counter(ItemsCount::new(n)).bench_local(|| {
            let errors = p
                .run(
                    Layout::ColumnSet {
                        columns: black_box(&columns),
                        rows: n,
                    },
                    &mut out,
                    Threads::Pool,
                )
                .errors;
            assert!(errors.is_empty());
        });
    }

    fn new_ratios(b: Bencher, bounds: bool, chosen: &[&str]) {
        let (p, rows) = new_ratio_rows(bounds, chosen);
        run(b, &p, &rows);
    }

    /// The 6-link chain's plan (condition bounds or not, the outputs
    /// `chosen` or all) and its rows: a new load and a new ratio every row.
    fn new_ratio_rows(bounds: bool, chosen: &[&str]) -> (BatchPlan, Vec<f64>) {
        let t = build(&chain(6));
        let mut p = plan(&t, Compute::Dynamics).with_condition_bounds(bounds);
        if !chosen.is_empty() {
            p = p.with_outputs(chosen).unwrap_or_else(|e| panic!("{e}"));
        }
        let load = p
            .parameter("torque.c2")
            .unwrap_or_else(|| panic!("no load column"));
        let mut rows = Vec::with_capacity(ROWS * p.parameters().len());
        for r in 0..ROWS {
            let mut row = p.base().to_vec();
            row[load] = -40.0 - (r % 1000) as f64 * 0.1;
            row[0] *= 1.0 + (r % 997) as f64 * 1e-4;
            rows.extend(row);
        }
        (p, rows)
    }

    /// The ZF 8HP70 shift table: rows cycle through the gear states.
    #[divan::bench(sample_count = 10)]
    fn zf_8hp_shift_table(b: Bencher) {
        let t = build(&example("zf_8hp70.toml"));
        let states = shift_table(&t, Compute::Dynamics);
        let per = ROWS / states.len();
        // Every row a different input torque; the ratios are the state's own.
        let input = t
            .transmission()
            .map(|tr| t.link_name(tr.input).to_string())
            .unwrap_or_default();
        let inputs: Vec<Vec<f64>> = states
            .iter()
            .map(|(p, row)| {
                let c = p
                    .parameter(&format!("torque.{input}"))
                    .unwrap_or_else(|| panic!("no input torque column"));
                let mut rows = Vec::with_capacity(per * row.len());
                for r in 0..per {
                    let mut x = row.clone();
                    x[c] = 300.0 + (r % 1000) as f64 * 0.1;
                    rows.extend(x);
                }
                rows
            })
            .collect();
        let mut outs: Vec<Vec<f64>> = states
            .iter()
            .map(|(p, _)| vec![0.0; per * p.outputs().len()])
            .collect();
        b.counter(ItemsCount::new(per * states.len()))
            .bench_local(|| {
                for ((p, _), (rows, out)) in states.iter().zip(inputs.iter().zip(&mut outs)) {
                    assert!(
                        p.run(Layout::Rows(black_box(rows)), out, Threads::Pool)
                            .errors
                            .is_empty()
                    );
                }
            });
    }
}

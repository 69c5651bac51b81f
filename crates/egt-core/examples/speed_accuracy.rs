//! The speed-accuracy study behind `docs/performance.md (history: git log -p -- docs/benchmarks.md)` and `docs/accuracy.md`
//! (run by `make chart`): for planetary chains of 4 to 30 links, the time per
//! scenario and the error against exact rationals of every Rust method; this
//! machine's flop rate (a dense matrix product) for the physical floor; the
//! accuracy sweeps on ill-conditioned trains; and the problems as JSON for the
//! SymPy and NumPy routes (`bench/routes.py`), which the chart puts beside these.
//!
//! Usage: `cargo run --release -p egt-core --features jit --example speed_accuracy -- OUT_DIR`
//! (without `--features jit` the batch program is interpreted)

use std::fmt::Write as _;
use std::hint::black_box;
use std::time::Instant;

#[path = "../lab/mod.rs"]
mod lab;
use egt_core::batch::{Layout, Threads};
use egt_core::numerics::linalg::COND_REFUSE;
use egt_core::{Format, Train};
use lab::accuracy::{Method, Problem};
use lab::families;
use serde_json::json;

/// Chain sizes, in links (a chain of k sets has 2 + 2k links).
const LINKS: [usize; 6] = [4, 6, 10, 16, 22, 30];

fn train(text: &str) -> Train {
    Train::from_str(text, Format::Toml, "study").unwrap_or_else(|e| panic!("{e}"))
}

/// Seconds per call: batches of at least `min` seconds, the fastest of five.
fn time(min: f64, mut f: impl FnMut()) -> f64 {
    f();
    let mut reps = 1usize;
    loop {
        let t = Instant::now();
        for _ in 0..reps {
            f();
        }
        if t.elapsed().as_secs_f64() >= min || reps >= 1 << 26 {
            break;
        }
        reps *= 2;
    }
    (0..5)
        .map(|_| {
            let t = Instant::now();
            for _ in 0..reps {
                f();
            }
            t.elapsed().as_secs_f64() / reps as f64
        })
        .fold(f64::INFINITY, f64::min)
}

/// This machine's double-precision rate on one core: a 384 x 384 matrix product.
fn flop_rate() -> f64 {
    let n = 384;
    let a = nalgebra::DMatrix::<f64>::from_fn(n, n, |i, j| ((i * 7 + j * 3) % 11) as f64 - 5.0);
    let b = a.transpose();
    let mut c = nalgebra::DMatrix::<f64>::zeros(n, n);
    let t = time(0.3, || {
        c.gemm(1.0, black_box(&a), black_box(&b), 0.0);
    });
    2.0 * (n * n * n) as f64 / t
}

/// Seconds per row of `plan.run` on one thread over 10 000 rows: the base
/// row and the base row one ulp off in its first ratio, alternating (so
/// every row is its own train). Also the two rows and the outputs.
fn batch_seconds(
    plan: &egt_core::batch::BatchPlan,
    columns: bool,
) -> (f64, [Vec<f64>; 2], Vec<f64>) {
    const ROWS: usize = 10_000;
    let a = plan.base().to_vec();
    let mut b = a.clone();
    b[0] = f64::from_bits(b[0].to_bits() + 1);
    let mut rows: Vec<f64> = (0..ROWS)
        .flat_map(|r| if r % 2 == 0 { a.clone() } else { b.clone() })
        .collect();
    let (p, q) = (plan.parameters().len(), plan.outputs().len());
    if columns {
        // Column-major (as NumPy's and SymPy's arrays, one per parameter).
        rows = (0..p)
            .flat_map(|k| rows[k..].iter().step_by(p).copied().collect::<Vec<_>>())
            .collect();
    }
    let mut out = vec![0.0; ROWS * q];
    // On the calling thread: the global pool has one thread (`main`).
    let seconds = time(0.2, || {
        if columns {
            black_box(
                plan.run(Layout::Columns(black_box(&rows)), &mut out, Threads::Pool)
                    .errors,
            );
        } else {
            black_box(
                plan.run(Layout::Rows(black_box(&rows)), &mut out, Threads::Pool)
                    .errors,
            );
        }
    }) / ROWS as f64;
    if columns {
        // Back to rows, for the callers' checks.
        out = (0..ROWS)
            .flat_map(|r| (0..q).map(move |o| (o, r)))
            .map(|(o, r)| out[o * ROWS + r])
            .collect();
    }
    (seconds, [a, b], out)
}

fn main() {
    // Every time here is on one core. A one-thread pool also lets
    // `BatchPlan::run` work on this thread, as a caller with
    // RAYON_NUM_THREADS=1 has it, with no hand-over to a pool thread.
    rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build_global()
        .unwrap_or_else(|e| panic!("{e}"));
    let dir = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "target/speed_accuracy".into());
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{dir}: {e}"));
    let rate = flop_rate();
    eprintln!("flop rate: {:.2} GFLOP/s", rate / 1e9);

    let mut sizes = Vec::new();
    let mut problems = Vec::new();
    for links in LINKS {
        let t = train(&families::planetary_chain((links - 2) / 2));
        let p = Problem::from_train(&t).unwrap_or_else(|e| panic!("{e}"));
        let n = p.n();
        let exact = p.exact().unwrap_or_else(|e| panic!("{e}"));
        let mut methods = Vec::new();
        for m in Method::ALL {
            let sol = p
                .solve(m)
                .unwrap_or_else(|e| panic!("{links} {}: {e}", m.name()));
            let errors = sol.errors(&exact);
            let seconds = match m {
                // egt as it runs in a batch: the prepared path, no allocation.
                Method::Egt => {
                    // Two rows one ulp apart in a ratio, alternated, so that
                    // every scenario factors afresh (a worker reuses the
                    // factorisations when the ratios repeat).
                    let plan = p.plan();
                    let a = plan.base().to_vec();
                    let mut b = a.clone();
                    b[0] = f64::from_bits(b[0].to_bits() + 1);
                    let rows = [a, b];
                    let mut out = vec![0.0; plan.outputs().len()];
                    let mut w = plan.worker();
                    let mut k = 0;
                    time(0.05, || {
                        k ^= 1;
                        let _ = w.eval(black_box(&rows[k]), &mut out);
                    })
                }
                Method::Exact => time(0.2, || {
                    let _ = black_box(p.exact());
                }),
                _ => time(0.05, || {
                    let _ = black_box(p.solve(m));
                }),
            };
            eprintln!(
                "{links:>2} links  {:<22} {:>10.3} us  error {:.1e}",
                m.name(),
                seconds * 1e6,
                errors.max()
            );
            methods.push(json!({
                "method": m.name(), "seconds": seconds, "error": errors.max(),
                "errors": {"speeds": errors.speeds, "accelerations": errors.accelerations,
                           "multipliers": errors.multipliers, "torques": errors.torques},
            }));
        }
        // egt's batch path: 10 000 rows through `BatchPlan::run` on one
        // thread, the same two rows alternating (every row factors, row by
        // row). Its rows are the worker's
        // numbers bit for bit (checked here), so its error is egt LU's.
        {
            let plan = p.plan();
            let (seconds, [a, b], out) = batch_seconds(plan, false);
            let q = plan.outputs().len();
            let mut one = vec![0.0; q];
            for (r, row) in [&a, &b].into_iter().enumerate() {
                plan.worker()
                    .eval(row, &mut one)
                    .unwrap_or_else(|e| panic!("{e}"));
                let same = one
                    .iter()
                    .zip(&out[r * q..(r + 1) * q])
                    .all(|(x, y)| x.to_bits() == y.to_bits());
                assert!(
                    same,
                    "{links} links: the batch row {r} differs from the worker's"
                );
            }
            let egt = &methods[0];
            assert_eq!(egt["method"], Method::Egt.name());
            eprintln!(
                "{links:>2} links  {:<22} {:>10.3} us",
                "egt batch",
                seconds * 1e6
            );
            methods.push(json!({
                "method": "egt batch", "seconds": seconds, "error": egt["error"],
                "errors": egt["errors"],
            }));
        }
        // egt's straight-line program: the same 10 000 rows with condition
        // bounds (the `cond.*` columns not wanted), each operation over 64
        // rows; row-major, and column-major as NumPy's arrays are. Its rows
        // differ from the worker's by rounding: their error against exact
        // rationals is measured here, on both rows (the two layouts give the
        // same numbers, checked).
        {
            let plan = p.plan().clone().with_condition_bounds(true);
            assert!(plan.has_program(), "{links} links: no program");
            // The outputs SymPy's and NumPy's routes compute: speeds,
            // accelerations, multipliers and driving torques (no meshing
            // forces, no conditions; the checks still run).
            let theirs: Vec<String> = (plan.outputs().iter())
                .filter(|o| !o.starts_with("force.") && !o.starts_with("cond."))
                .cloned()
                .collect();
            let like = plan
                .clone()
                .with_outputs(&theirs)
                .unwrap_or_else(|e| panic!("{e}"));
            let mut by_rows = Vec::new();
            for (route, plan, columns) in [
                ("egt program", &plan, false),
                ("egt columns", &plan, true),
                ("egt columns, their outputs", &like, true),
            ] {
                let q = plan.outputs().len();
                let (seconds, _, out) = batch_seconds(plan, columns);
                let errors = [&out[..q], &out[q..2 * q]]
                    .map(|row| lab::accuracy::row_errors(plan, &t, row, &exact));
                let worst = |f: fn(&lab::accuracy::Errors) -> f64| f(&errors[0]).max(f(&errors[1]));
                let max = errors[0].max().max(errors[1].max());
                eprintln!(
                    "{links:>2} links  {route:<22} {:>10.3} us  error {max:.1e}",
                    seconds * 1e6
                );
                methods.push(json!({
                    "method": route, "seconds": seconds, "error": max,
                    "operations": plan.program_operations(),
                    "compiled": plan.program_compiled(),
                    "errors": {"speeds": worst(|e| e.speeds), "accelerations": worst(|e| e.accelerations),
                               "multipliers": worst(|e| e.multipliers), "torques": worst(|e| e.torques)},
                }));
                if !columns {
                    by_rows = out;
                } else {
                    // The same numbers as the row-major program's columns, bit for bit.
                    let full = p.plan().outputs();
                    let all = full.len();
                    let same = (0..out.len() / q).all(|r| {
                        (plan.outputs().iter().enumerate()).all(|(k, name)| {
                            let o = full.iter().position(|f| f == name);
                            o.is_some_and(|o| {
                                out[r * q + k].to_bits() == by_rows[r * all + o].to_bits()
                            })
                        })
                    });
                    assert!(
                        same,
                        "{links} links: {route} differs from the row-major program"
                    );
                }
            }
        }
        // The floor: one LU (2n^3/3), two solves for speeds and accelerations,
        // [M]{w'} and the transposed solve (2n^2 each).
        let nf = n as f64;
        let flops = 2.0 * nf * nf * nf / 3.0 + 8.0 * nf * nf;
        sizes.push(json!({
            "links": links, "n": n, "floor_flops": flops, "floor_seconds": flops / rate,
            "conditions": p.true_conditions(), "methods": methods,
        }));
        let mut pj = p.to_json().unwrap_or_else(|e| panic!("{e}"));
        pj["links"] = json!(links);
        problems.push(pj);
    }
    let rust = json!({"flop_rate": rate, "sizes": sizes});
    write(
        &dir,
        "rust.json",
        &serde_json::to_string_pretty(&rust).unwrap_or_default(),
    );
    write(
        &dir,
        "problems.json",
        &serde_json::to_string(&problems).unwrap_or_default(),
    );
    write(&dir, "accuracy.md", &sweeps());
    write(
        &dir,
        "planetary_chain_6.toml",
        &families::planetary_chain(2),
    );
}

fn write(dir: &str, name: &str, text: &str) {
    let path = format!("{dir}/{name}");
    std::fs::write(&path, text).unwrap_or_else(|e| panic!("{path}: {e}"));
    eprintln!("wrote {path}");
}

/// Markdown tables of the ill-conditioned sweeps: per case the true condition
/// (max over the three systems), egt's estimate, and each method's largest
/// relative error (or egt's refusal).
fn sweeps() -> String {
    let mut md = String::new();
    let head = |md: &mut String, title: &str| {
        let _ = writeln!(md, "\n#### {title}\n");
        let _ = write!(md, "| case | true condition | egt estimate |");
        for m in Method::ALL.iter().filter(|m| **m != Method::Exact) {
            let _ = write!(md, " {} |", m.name());
        }
        let _ = write!(md, "\n|---|---|---|");
        for _ in 1..Method::ALL.len() {
            md.push_str("---|");
        }
        md.push('\n');
    };
    let row = |md: &mut String, case: String, t: &Train| {
        let p = Problem::from_train(t).unwrap_or_else(|e| panic!("{e}"));
        let truth = p.true_conditions().into_iter().fold(0.0, f64::max);
        let exact = p.exact();
        let mut cells = Vec::new();
        let mut est = String::from("-");
        for m in Method::ALL.iter().filter(|m| **m != Method::Exact) {
            cells.push(match (p.solve(*m), &exact) {
                (Ok(s), Ok(x)) => {
                    if let Some(c) = s.conditions {
                        est = format!("{:.1e}", c.into_iter().fold(0.0, f64::max));
                    }
                    format!("{:.0e}", s.errors(x).max())
                }
                (Err(e), _) if *m == Method::Egt => {
                    if let egt_core::Error::Analysis(egt_core::AnalysisError::IllConditioned {
                        condition,
                        ..
                    }) = e
                    {
                        est = format!("{condition:.1e}");
                    }
                    "refused".into()
                }
                (Err(_), _) | (_, Err(_)) => "singular".into(),
            });
        }
        let _ = writeln!(
            md,
            "| {case} | {truth:.1e} | {est} | {} |",
            cells.join(" | ")
        );
    };
    head(
        &mut md,
        "Near lock: Fig. 3 with tau_1 tau_2 = 1 + eps (eq. 8 and the speed system)",
    );
    for k in [2, 4, 6, 8, 10, 11, 12, 13, 14] {
        let eps = 10f64.powi(-k);
        row(
            &mut md,
            format!("eps = 1e-{k}"),
            &train(&families::near_locked(eps)),
        );
    }
    head(
        &mut md,
        "Nearly singular [Psi_w]: the planet prescribed while it barely turns (ratio 1 + eps)",
    );
    for k in [2, 4, 6, 8, 10, 12, 14] {
        let eps = 10f64.powi(-k);
        row(
            &mut md,
            format!("eps = 1e-{k}"),
            &train(&families::stationary_planet(eps)),
        );
    }
    head(
        &mut md,
        "Inertias and masses spread over 12 decades (random 4-set trains)",
    );
    for seed in 0..6 {
        row(
            &mut md,
            format!("seed {seed}"),
            &train(&families::random_train(100 + seed, 4, 12.0)),
        );
    }
    head(&mut md, "Random well-conditioned trains (1 to 6 sets)");
    for seed in 0..6 {
        row(
            &mut md,
            format!("seed {seed}, {} sets", 1 + seed % 6),
            &train(&families::random_train(seed, 1 + seed as usize % 6, 2.0)),
        );
    }
    let _ = writeln!(
        md,
        "\negt refuses past COND_REFUSE = {COND_REFUSE:.0e} (estimate of any of the three systems)."
    );
    md
}

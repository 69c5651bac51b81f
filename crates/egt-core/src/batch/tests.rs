//! The batch's unit tests (the numbers against solving each row alone are
//! in `tests/core/batch.rs`).

// The generated train families the core's other tests share (a file
// module, so that the path is from this folder).
#[allow(dead_code)]
#[path = "../../lab/families.rs"]
mod families;

use super::*;
#[cfg(feature = "jit")]
use crate::solve::prepared::{Isa, PROGRAM_BLOCK, Program};
use crate::{Format, Train};

/// The straight-line program solves a sweep's rows and leaves the bad,
/// the far-off and the ill-conditioned ones to the row-by-row solve, which
/// gives their error or estimate; its numbers are the row-by-row solve's
/// within rounding.
#[test]
fn the_program_solves_the_rows_it_can_vouch_for() {
    let text = include_str!("../../../../examples/fig3_example61.toml");
    let t = Train::from_str(text, Format::Toml, "fig3").unwrap_or_else(|e| panic!("{e}"));
    let p = BatchPlan::new(
        &t,
        &BatchSpec::from_analysis(&t, Compute::Dynamics).unwrap_or_else(|e| panic!("{e}")),
    )
    .unwrap_or_else(|e| panic!("{e}"))
    .with_condition_bounds(true);
    assert!(p.has_program());
    let (np, nq) = (p.parameters().len(), p.outputs().len());
    let rows = 300;
    let mut params = Vec::new();
    for r in 0..rows {
        let mut row = p.base().to_vec();
        row[0] *= 1.0 + 0.001 * r as f64;
        params.extend(row);
    }
    let col = |name: &str| p.parameter(name).unwrap_or_else(|| panic!("no {name}"));
    let (g1, g2) = (col("ratio.G1"), col("ratio.G2"));
    let t1 = p.base()[g1];
    params[3 * np + 1] = f64::NAN;
    // Far from the base ratio: other pivots.
    params[9 * np] *= -40.0;
    // Near the lock (tau_1 tau_2 = 1): past the warning.
    params[70 * np + g1] = t1;
    params[70 * np + g2] = (1.0 + 1e-10) / t1;
    let mut out = vec![0.0; rows * nq];
    let (mut w, mut blocks) = (p.worker(), p.blocks());
    let mut errors = Vec::new();
    let solved = w.eval_program(&mut blocks, &params, &mut out, 0, &mut errors);
    assert_eq!(solved, rows - 3);
    assert_eq!(errors.len(), 1);
    assert_eq!(errors[0].row, 3);
    let conds = p.condition_columns();
    let cond = (conds.iter())
        .map(|&c| out[70 * nq + c])
        .fold(0.0, f64::max);
    assert!(cond > crate::numerics::linalg::COND_WARN, "{cond}");
    let mut reference = vec![0.0; rows * nq];
    for (r, (row, o)) in params.chunks(np).zip(reference.chunks_mut(nq)).enumerate() {
        assert_eq!(w.eval(row, o).is_err(), r == 3, "row {r}");
    }
    for r in (0..rows).filter(|&r| r != 3) {
        let (a, b) = (&out[r * nq..][..nq], &reference[r * nq..][..nq]);
        let scale = a.iter().map(|v| v.abs()).fold(0.0, f64::max);
        for c in (0..nq).filter(|c| !conds.contains(c)) {
            assert!((a[c] - b[c]).abs() <= 1e-13 * scale, "row {r} column {c}");
        }
    }
}

/// `Solved::bounded` vouches for a block only when the program
/// solved every row, and then every row's `cond.*` is at most
/// `COND_WARN` / 2: a row near the lock of Fig. 3 (past the warning) in
/// the third task of the block makes it false, and so does a plan
/// without condition bounds (no program); on the calling thread and on
/// the pool alike, and in every [`Layout`] (the same verdict and bits).
#[test]
fn a_block_is_bounded_only_when_the_program_solved_every_row() {
    use crate::numerics::linalg::COND_WARN;
    let text = include_str!("../../../../examples/fig3_example61.toml");
    let t = Train::from_str(text, Format::Toml, "fig3").unwrap_or_else(|e| panic!("{e}"));
    let spec = BatchSpec::from_analysis(&t, Compute::Dynamics).unwrap_or_else(|e| panic!("{e}"));
    let plain = BatchPlan::new(&t, &spec).unwrap_or_else(|e| panic!("{e}"));
    let bounded = plain.clone().with_condition_bounds(true);
    assert!(bounded.has_program() && !plain.has_program());
    let col = |name: &str| plain.parameter(name).unwrap_or_else(|| panic!("no {name}"));
    let (g1, g2) = (col("ratio.G1"), col("ratio.G2"));
    let t1 = plain.base()[g1];
    let rows = 600;
    let ratios: Vec<f64> = (0..rows).map(|r| t1 * (1.0 + 0.001 * r as f64)).collect();
    let mut near = ratios.clone();
    near[550] = t1;
    let lock = (1.0 + 1e-10) / t1;
    for threads in [Threads::Calling, Threads::Pool] {
        for (p, g1s, at_550, vouched) in [
            (&bounded, &ratios, None, true),
            (&bounded, &near, Some(lock), false),
            (&plain, &ratios, None, false),
        ] {
            let g2s: Vec<f64> = (0..rows)
                .map(|r| match at_550 {
                    Some(v) if r == 550 => v,
                    _ => p.base()[g2],
                })
                .collect();
            let columns: Vec<Column<'_>> = (0..p.parameters().len())
                .map(|k| match k {
                    k if k == g1 => Column::Rows(g1s),
                    k if k == g2 => Column::Rows(&g2s),
                    k => Column::Every(p.base()[k]),
                })
                .collect();
            let mut out = vec![0.0; rows * p.outputs().len()];
            let solved = p.run(
                Layout::ColumnSet {
                    columns: &columns,
                    rows,
                },
                &mut out,
                threads,
            );
            let (errors, said) = (solved.errors, solved.bounded);
            assert!(errors.is_empty(), "{errors:?}");
            let locked = at_550.is_some();
            assert_eq!(said, vouched, "{threads:?}, near the lock: {locked}");
            let worst = |r: usize| {
                (p.condition_columns().iter())
                    .map(|&c| out[c * rows + r])
                    .fold(0.0, f64::max)
            };
            if said {
                assert!((0..rows).all(|r| worst(r) <= COND_WARN / 2.0));
            }
            if locked {
                assert!(worst(550) > COND_WARN, "{}", worst(550));
            }
            // The same rows written out, column- and row-major: the same
            // verdict and the same bits.
            let np = p.parameters().len();
            let matrix: Vec<f64> = (columns.iter())
                .flat_map(|c| match *c {
                    Column::Rows(v) => v.to_vec(),
                    Column::Every(v) => vec![v; rows],
                })
                .collect();
            let by_rows: Vec<f64> = (0..rows * np)
                .map(|i| matrix[(i % np) * rows + i / np])
                .collect();
            let mut c_out = vec![0.0; out.len()];
            let c = p.run(Layout::Columns(&matrix), &mut c_out, threads);
            let mut r_out = vec![0.0; out.len()];
            let r = p.run(Layout::Rows(&by_rows), &mut r_out, threads);
            assert!(c.errors.is_empty() && r.errors.is_empty());
            assert_eq!((c.bounded, r.bounded), (vouched, vouched), "{threads:?}");
            let q = p.outputs().len();
            for (k, (a, b)) in out.iter().zip(&c_out).enumerate() {
                assert_eq!(a.to_bits(), b.to_bits(), "column-major value {k}");
                let (o, row) = (k / rows, k % rows);
                let rv = r_out[row * q + o];
                assert_eq!(a.to_bits(), rv.to_bits(), "row-major row {row} output {o}");
            }
        }
    }
}

/// The program compiled to machine code gives the interpreter's numbers,
/// validity and errors bit for bit (a NaN's payload apart): row-major
/// and column-major, whole blocks (read and written in place) and a part
/// block, with rows the checks must refuse in among them. Trains: Fig. 3
/// and Fig. 5 (kinematics and dynamics, every output and a choice), and
/// every gear state of the 8HP70. On a machine without AVX-512 there is
/// no code, and the test says so by failing only where there should be.
/// (With the `jit` feature only: without it there is no code.)
#[cfg(feature = "jit")]
#[test]
fn compiled_and_interpreted_programs_agree_bit_for_bit() {
    // The instruction sets this machine runs, detected here rather than
    // asked of the compiler's own choice.
    let has = |features: &[&str]| {
        #[cfg(target_arch = "x86_64")]
        {
            features.iter().all(|f| match *f {
                "avx512f" => std::arch::is_x86_feature_detected!("avx512f"),
                "avx512dq" => std::arch::is_x86_feature_detected!("avx512dq"),
                "avx2" => std::arch::is_x86_feature_detected!("avx2"),
                "bmi2" => std::arch::is_x86_feature_detected!("bmi2"),
                "fma" => std::arch::is_x86_feature_detected!("fma"),
                other => panic!("no check for {other}"),
            })
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            let _ = features;
            false
        }
    };
    let isas = [
        (Isa::Avx512, has(&["avx512f", "avx512dq"])),
        (Isa::Avx2, has(&["avx2", "bmi2", "fma"])),
    ];
    let jit = std::env::var("EGT_JIT").unwrap_or_default();
    let default = match jit.as_str() {
        "0" => None,
        "avx2" => isas[1].1.then_some(Isa::Avx2),
        _ => isas.iter().find(|i| i.1).map(|i| i.0),
    };
    let example = |text: &str, name: &str| {
        Train::from_str(text, Format::Toml, name).unwrap_or_else(|e| panic!("{e}"))
    };
    let fig3 = example(
        include_str!("../../../../examples/fig3_example61.toml"),
        "fig3",
    );
    let fig5 = example(
        include_str!("../../../../examples/fig5_example62.toml"),
        "fig5",
    );
    let zf = example(include_str!("../../../../examples/zf_8hp70.toml"), "8hp");
    // Chains of 6 and 30 links: more values live than registers, so
    // values are spilled and reloaded (AVX2 has 14 registers for them).
    let chain6 = example(&families::planetary_chain(2), "chain 6");
    let chain30 = example(&families::planetary_chain(14), "chain 30");
    let mut plans: Vec<(String, BatchPlan)> = Vec::new();
    for (name, t) in [("chain6", &chain6), ("chain30", &chain30)] {
        let spec = BatchSpec::from_analysis(t, Compute::Dynamics).unwrap_or_else(|e| panic!("{e}"));
        let p = BatchPlan::new(t, &spec).unwrap_or_else(|e| panic!("{e}"));
        plans.push((name.to_string(), p.with_condition_bounds(true)));
    }
    for (name, t) in [("fig3", &fig3), ("fig5", &fig5)] {
        for compute in [Compute::Kinematics, Compute::Dynamics] {
            let spec = BatchSpec::from_analysis(t, compute).unwrap_or_else(|e| panic!("{e}"));
            let p = BatchPlan::new(t, &spec).unwrap_or_else(|e| panic!("{e}"));
            let p = p.with_condition_bounds(true);
            let some: Vec<String> = p.outputs().iter().step_by(3).cloned().collect();
            let chosen = p
                .clone()
                .with_outputs(&some)
                .unwrap_or_else(|e| panic!("{e}"));
            plans.push((format!("{name} {compute:?}"), p));
            plans.push((format!("{name} {compute:?} chosen"), chosen));
        }
    }
    let states = zf
        .checked_transmission()
        .unwrap_or_else(|e| panic!("{e}"))
        .states
        .clone();
    for s in &states {
        let spec = BatchSpec::for_gear_state(&zf, &s.name, Compute::Dynamics)
            .unwrap_or_else(|e| panic!("{e}"));
        let p = BatchPlan::new(&zf, &spec).unwrap_or_else(|e| panic!("{e}"));
        plans.push((format!("8HP {}", s.name), p.with_condition_bounds(true)));
    }
    for (name, p) in &plans {
        let program = p
            .program
            .as_ref()
            .unwrap_or_else(|| panic!("{name}: no program"));
        assert_eq!(program.isa(), default, "{name}: compiled where it runs");
        let mut interpreted = p.clone();
        interpreted.program = interpreted.program.take().map(|q| q.with_code(None));
        for &(isa, runs) in &isas {
            let mut p = p.clone();
            p.program = p.program.take().map(|q| q.with_code(Some(isa)));
            let got = p.program.as_ref().and_then(Program::isa);
            assert_eq!(
                got,
                runs.then_some(isa),
                "{name}: {isa:?} code where it runs"
            );
            if runs {
                compare(&format!("{name} {isa:?}"), &p, &interpreted);
            }
        }
    }
}

/// The rows of `plan` on its compiled program, and on `interpreted`: the
/// same bits, errors and valid rows.
#[cfg(feature = "jit")]
fn compare(name: &str, p: &BatchPlan, interpreted: &BatchPlan) {
    // 512 rows: the output columns start at one offset modulo 4 KiB, so
    // a plan of more than 12 outputs writes them through the slots.
    for rows in [300, 512] {
        let program = p
            .program
            .as_ref()
            .unwrap_or_else(|| panic!("{name}: no program"));
        let (np, nq) = (p.parameters().len(), p.outputs().len());
        let mut params = Vec::new();
        for r in 0..rows {
            params.extend(p.base().iter().enumerate().map(|(c, &v)| {
                let wave = (r as f64 * 0.37 + c as f64).sin();
                // The 8HP's base has no input speed (NaN): 1.
                let v = if v.is_nan() { 1.0 } else { v };
                if p.parameters()[c].starts_with("efficiency.") {
                    v
                } else {
                    v * (1.0 + 0.05 * wave)
                }
            }));
        }
        let col = |prefix: &str| p.parameters().iter().position(|n| n.starts_with(prefix));
        assert!(p.parameters()[0].starts_with("ratio."), "{name}");
        // Rows every check must refuse.
        let mut refused = vec![3, 70];
        params[3 * np] = f64::NAN;
        params[70 * np] = 0.0;
        for (row, prefix, value) in [
            (130, "torque.", f64::INFINITY),
            (131, "torque.", f64::NEG_INFINITY),
            (150, "inertia.", -1.0),
            (151, "mass.", f64::NAN),
            (152, "speed.", f64::INFINITY),
        ] {
            if let Some(c) = col(prefix) {
                params[row * np + c] = value;
                refused.push(row);
            }
        }
        // Far from the base ratio: other pivots.
        params[9 * np] *= -40.0;
        // Finite, but the parameters' sum may overflow; and a large load.
        let last = col("efficiency.").unwrap_or(np) - 1;
        params[200 * np + last] = f64::MAX;
        params[200 * np + last - 1] = f64::MAX;
        params[201 * np + last] = -f64::MAX;
        params[260 * np + last] = 1e300;
        if let Some(c) = col("accel") {
            params[270 * np + c] = 0.5;
        }
        let columns: Vec<f64> = (0..np)
            .flat_map(|k| params[k..].iter().step_by(np).copied())
            .collect();
        let same = |a: &[f64], b: &[f64], what: &str| {
            for (i, (x, y)) in a.iter().zip(b).enumerate() {
                assert!(
                    x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan()),
                    "{name} {what} cell {i}: {x} compiled vs {y} interpreted"
                );
            }
        };
        let errors = |e: &[RowError]| {
            e.iter()
                .map(|e| (e.row, e.error.to_string()))
                .collect::<Vec<_>>()
        };
        let mut a = vec![0.0; rows * nq];
        let mut b = vec![0.0; rows * nq];
        let (ea, eb) = (
            p.run(Layout::Rows(&params), &mut a, Threads::Pool).errors,
            interpreted
                .run(Layout::Rows(&params), &mut b, Threads::Pool)
                .errors,
        );
        same(&a, &b, "rows");
        assert_eq!(errors(&ea), errors(&eb), "{name}");
        assert!(ea.iter().any(|e| e.row == 3), "{name}: the NaN row refused");
        let (ea, eb) = (
            p.run(Layout::Columns(&columns), &mut a, Threads::Pool)
                .errors,
            interpreted
                .run(Layout::Columns(&columns), &mut b, Threads::Pool)
                .errors,
        );
        same(&a, &b, "columns");
        assert_eq!(errors(&ea), errors(&eb), "{name} columns");
        // Block by block: the same rows valid, the same outputs in them.
        let (pa, pb) = (
            program,
            interpreted.program.as_ref().unwrap_or_else(|| panic!()),
        );
        let (mut wa, mut wb) = (pa.workspace(), pb.workspace());
        let mut valid = 0;
        for (k, block) in params.chunks(np * PROGRAM_BLOCK).enumerate() {
            let n = block.len() / np;
            let (mut oa, mut ob) = (vec![0.0; n * nq], vec![0.0; n * nq]);
            pa.run(&mut wa, block, np);
            pb.run(&mut wb, block, np);
            assert_eq!(wa.valid, wb.valid, "{name}");
            pa.write(&wa, &mut oa);
            pb.write(&wb, &mut ob);
            for r in (0..n).filter(|&r| wa.valid[r]) {
                same(&oa[r * nq..][..nq], &ob[r * nq..][..nq], "block");
                valid += 1;
            }
            for r in (0..n).filter(|r| refused.contains(&(k * PROGRAM_BLOCK + r))) {
                assert!(!wa.valid[r], "{name}: row {} valid", k * PROGRAM_BLOCK + r);
            }
        }
        assert!(valid > rows / 2, "{name}: {valid} rows valid");
    }
}

/// Column-major runs give `run`'s numbers and errors bit for bit, on
/// every path: the program (with its left rows), the linear path (a
/// load sweep) and row by row (no bounds, and power flow).
#[test]
fn column_major_runs_give_the_row_major_numbers_bit_for_bit() {
    let text = include_str!("../../../../examples/fig3_example61.toml");
    let t = Train::from_str(text, Format::Toml, "fig3").unwrap_or_else(|e| panic!("{e}"));
    for compute in [Compute::Kinematics, Compute::Dynamics, Compute::Power] {
        for bounds in [false, true] {
            let spec = BatchSpec::from_analysis(&t, compute).unwrap_or_else(|e| panic!("{e}"));
            let p = BatchPlan::new(&t, &spec)
                .unwrap_or_else(|e| panic!("{e}"))
                .with_condition_bounds(bounds);
            assert_eq!(p.has_program(), bounds && compute != Compute::Power);
            let (np, nq) = (p.parameters().len(), p.outputs().len());
            let rows = 700;
            let g1 = p.parameter("ratio.G1").unwrap_or_else(|| panic!("no G1"));
            let speed = p.groups.speed;
            let mut params = Vec::new();
            for r in 0..rows {
                let mut row = p.base().to_vec();
                if (256..512).contains(&r) {
                    // A task of loads and speeds only: the linear path.
                    row[speed] *= 1.0 + 0.01 * r as f64;
                } else {
                    row[g1] *= 1.0 + 0.001 * r as f64;
                }
                params.extend(row);
            }
            params[3 * np + 1] = f64::NAN;
            params[9 * np] *= -40.0;
            params[600 * np + g1] = f64::INFINITY;
            let t1 = p.base()[g1];
            let g2 = p.parameter("ratio.G2").unwrap_or_else(|| panic!("no G2"));
            params[70 * np + g1] = t1;
            params[70 * np + g2] = (1.0 + 1e-10) / t1;
            params[71 * np + g1] = t1;
            params[71 * np + g2] = 1.0 / t1;
            let mut by_rows = vec![0.0; rows * nq];
            let errors = p
                .run(Layout::Rows(&params), &mut by_rows, Threads::Pool)
                .errors;
            assert!(errors.len() >= 2, "{compute:?} {errors:?}");
            let columns: Vec<f64> = (0..np)
                .flat_map(|k| params[k..].iter().step_by(np).copied())
                .collect();
            let mut by_columns = vec![0.0; rows * nq];
            let column_errors = p
                .run(Layout::Columns(&columns), &mut by_columns, Threads::Pool)
                .errors;
            // Debug forms: an error may hold the NaN it refused.
            assert_eq!(
                format!("{errors:?}"),
                format!("{column_errors:?}"),
                "{compute:?} bounds {bounds}"
            );
            for r in 0..rows {
                for o in 0..nq {
                    assert_eq!(
                        by_rows[r * nq + o].to_bits(),
                        by_columns[o * rows + r].to_bits(),
                        "{compute:?} bounds {bounds}: row {r}, {}",
                        p.outputs()[o]
                    );
                }
            }
        }
    }
}

/// Issue 42: a row whose results overflow (an inertia of 1e308 times an
/// acceleration) is a failed row naming the first output that did, with NaN
/// outputs, row- and column-major alike, as `Train::dynamics` refuses the
/// same inputs (`tests/bad_inputs.rs` runs both); it used to be written as
/// blank cells with no error. The rows around it are untouched.
#[test]
fn rows_whose_results_overflow_fail_by_name() {
    let text = include_str!("../../../../examples/fig3_example61.toml");
    let t = Train::from_str(text, Format::Toml, "fig3").unwrap_or_else(|e| panic!("{e}"));
    let p = BatchPlan::new(
        &t,
        &BatchSpec::from_analysis(&t, Compute::Dynamics).unwrap_or_else(|e| panic!("{e}")),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let (np, q) = (p.parameters().len(), p.outputs().len());
    let inertia = (p.parameters().iter().position(|n| n == "inertia.2"))
        .unwrap_or_else(|| panic!("no inertia.2 in {:?}", p.parameters()));
    let rows = 600;
    let mut params = Vec::new();
    for _ in 0..rows {
        params.extend(p.base());
    }
    for r in [1, 450] {
        params[r * np + inertia] = 1e308;
    }
    let mut out = vec![0.0; rows * q];
    let errors = p.run(Layout::Rows(&params), &mut out, Threads::Pool).errors;
    let failed: Vec<usize> = errors.iter().map(|e| e.row).collect();
    assert_eq!(failed, [1, 450]);
    assert_eq!(errors[0].error.code(), "non_finite_result");
    assert!(out[q..2 * q].iter().all(|v| v.is_nan()));
    assert!(
        out[..q]
            .iter()
            .chain(&out[2 * q..3 * q])
            .all(|v| v.is_finite())
    );
    // The same rows column by column.
    let mut columns = vec![0.0; rows * np];
    for r in 0..rows {
        for c in 0..np {
            columns[c * rows + r] = params[r * np + c];
        }
    }
    let mut col_out = vec![0.0; rows * q];
    let col_errors = p
        .run(Layout::Columns(&columns), &mut col_out, Threads::Pool)
        .errors;
    assert_eq!(
        col_errors.iter().map(|e| e.row).collect::<Vec<_>>(),
        [1, 450]
    );
}

//! The paper's printed results, reproduced: the Willis Jacobians [psi_w] of
//! examples 6.1 (Fig. 3) and 6.2 (Fig. 5) at random ratios, up to row order
//! and row sign, and the fundamental-circuit table of Fig. 5 (Table 2).

use egt_core::Train;
use egt_core::numerics::exact::{self, Q};
use num_traits::{One, Zero};
use proptest::prelude::*;

use crate::util::{example, fr, id, text, toml};

/// A printed Jacobian: named columns (links) and rows of entries.
struct Printed {
    columns: Vec<&'static str>,
    rows: Vec<Vec<Q>>,
}

/// Assert that the core's Jacobian (exact and float) equals the printed one,
/// up to the order of the rows and the sign of each row.
fn assert_same_jacobian(train: &Train, printed: &Printed) {
    let ncols = train.coordinates().len();
    assert_eq!(
        printed.columns.len(),
        ncols,
        "the printed matrix has one column per moving link"
    );
    // Put the printed columns where the core has them.
    let col: Vec<usize> = printed
        .columns
        .iter()
        .map(|n| train.coordinate(id(train, n)).expect("not the frame"))
        .collect();
    let expected: Vec<Vec<Q>> = printed
        .rows
        .iter()
        .map(|r| {
            let mut row = vec![Q::zero(); ncols];
            for (k, v) in r.iter().enumerate() {
                row[col[k]] = v.clone();
            }
            row
        })
        .collect();

    let exact_j = train.willis_jacobian_exact().expect("exact ratios");
    let float_j = train.willis_jacobian().expect("ratios");
    assert_eq!(exact_j.len(), expected.len());
    let mut used = vec![false; exact_j.len()];
    for e in &expected {
        let neg: Vec<Q> = e.iter().map(|v| -v.clone()).collect();
        let m = (0..exact_j.len())
            .find(|&m| !used[m] && (exact_j[m] == *e || exact_j[m] == neg))
            .unwrap_or_else(|| {
                panic!(
                    "printed row {:?} not among the core's rows {:?}",
                    show(e),
                    exact_j.iter().map(|r| show(r)).collect::<Vec<_>>()
                )
            });
        used[m] = true;
        let sign = if exact_j[m] == *e { 1.0 } else { -1.0 };
        for (k, v) in e.iter().enumerate() {
            let want = sign * exact::to_f64(v);
            assert!(
                (float_j[(m, k)] - want).abs() <= 1e-12 * want.abs().max(1.0),
                "float entry ({m}, {k})"
            );
        }
    }
}

fn show(r: &[Q]) -> Vec<String> {
    r.iter().map(text).collect()
}

/// A random Willis ratio p/q, never 0 or 1.
fn ratio() -> impl Strategy<Value = Q> {
    (-60i64..60, 1i64..25).prop_filter_map("tau is never 0 or 1", |(p, q)| {
        let t = fr(p, q);
        (!t.is_zero() && !t.is_one()).then_some(t)
    })
}

/// The Fig. 3 chain (example 6.1) with the given ratios, from its adjacency list.
pub fn fig3(t1: &Q, t2: &Q) -> Train {
    toml(&format!(
        "frame = \"1\"\nadjacency = \"1-2:a 2-3:b 1-4:a 1-3:G={} 3-4:G={}\"\n",
        text(t1),
        text(t2)
    ))
}

/// The Fig. 5 chain (example 6.2, Table 2) with the given ratios.
pub fn fig5(t1: &Q, t2: &Q, t3: &Q) -> Train {
    toml(&format!(
        "frame = \"1\"\nadjacency = \"1-2:a 1-3:b 3-5:c 1-4:b 1-6:b 2-3:G={} 5-4:G={} 5-6:G={}\"\n",
        text(t1),
        text(t2),
        text(t3)
    ))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 32, ..ProptestConfig::default() })]

    /// Example 6.1: psi_1 = tau_1 w_3 + (1 - tau_1) w_2, psi_2 = w_3 - tau_2 w_4 + (tau_2 - 1) w_2.
    /// The paper prints [psi_w] = [[tau_1, 1 - tau_1, 0], [1, tau_2 - 1, -tau_2]], whose
    /// columns are in the order w_3, w_2, w_4 (see docs/errata.md).
    #[test]
    fn example_61_jacobian_matches_the_paper(t1 in ratio(), t2 in ratio()) {
        let one = exact::q(1);
        let printed = Printed {
            columns: vec!["3", "2", "4"],
            rows: vec![
                vec![t1.clone(), &one - &t1, Q::zero()],
                vec![one.clone(), &t2 - &one, -t2.clone()],
            ],
        };
        assert_same_jacobian(&fig3(&t1, &t2), &printed);
    }

    /// Example 6.2: the 3 x 5 matrix printed under Table 2, columns w_2 .. w_6.
    #[test]
    fn example_62_jacobian_matches_the_paper(t1 in ratio(), t2 in ratio(), t3 in ratio()) {
        let (one, zero) = (exact::q(1), Q::zero());
        let printed = Printed {
            columns: vec!["2", "3", "4", "5", "6"],
            rows: vec![
                vec![one.clone(), -t1.clone(), zero.clone(), zero.clone(), zero.clone()],
                vec![zero.clone(), &t2 - &one, -t2.clone(), one.clone(), zero.clone()],
                vec![zero.clone(), &t3 - &one, zero.clone(), one.clone(), -t3.clone()],
            ],
        };
        assert_same_jacobian(&fig5(&t1, &t2, &t3), &printed);
    }
}

/// The 6.1 example file has the paper's structure too (ratios from its teeth).
#[test]
fn example_61_file_jacobian_matches_the_paper() {
    let train = example("fig3_example61.toml");
    let tau = |m: usize| {
        train.gears()[m]
            .ratio
            .as_ref()
            .and_then(|r| r.exact.clone())
            .expect("exact")
    };
    let (t1, t2) = (tau(0), tau(1));
    let one = exact::q(1);
    let printed = Printed {
        columns: vec!["3", "2", "4"],
        rows: vec![
            vec![t1.clone(), &one - &t1, Q::zero()],
            vec![one.clone(), &t2 - &one, -t2.clone()],
        ],
    };
    assert_same_jacobian(&train, &printed);
}

/// Table 2: gear i, gear j and transfer vertex k of each circuit of Fig. 5, in
/// the paper's order, and the levels of the turning pairs. (The paper prints
/// "a, c" for #3; its own equations need "b, c": docs/errata.md.)
#[test]
fn table_2_is_reproduced() {
    let train = example("fig5_example62.toml");
    let rows: Vec<(String, String, String, Vec<String>)> = train
        .circuits()
        .iter()
        .map(|c| {
            let mut levels = vec![
                train.level_name(c.level_i).to_string(),
                train.level_name(c.level_j).to_string(),
            ];
            levels.sort();
            (
                train.link_name(c.gear_i).to_string(),
                train.link_name(c.gear_j).to_string(),
                train.link_name(c.carrier).to_string(),
                levels,
            )
        })
        .collect();
    let want = |i: &str, j: &str, k: &str, l: [&str; 2]| {
        (
            i.to_string(),
            j.to_string(),
            k.to_string(),
            l.iter().map(|s| (*s).to_string()).collect::<Vec<_>>(),
        )
    };
    assert_eq!(
        rows,
        vec![
            want("2", "3", "1", ["a", "b"]),
            want("5", "4", "3", ["b", "c"]),
            want("5", "6", "3", ["b", "c"])
        ]
    );
    assert_eq!(train.dof(), 2);
}

/// Table 2 with the paper's printed levels for #3 ("a, c": 6 coaxial with 2)
/// is not a valid chain: the circuit of 5-6 then crosses three levels.
#[test]
fn table_2_as_printed_has_no_transfer_vertex_for_circuit_3() {
    let e = crate::util::toml_err(
        "frame = \"1\"\nadjacency = \"1-2:a 1-3:b 3-5:c 1-4:b 1-6:a 2-3:G 5-4:G 5-6:G\"\n",
    );
    match e {
        egt_core::Error::Topology(egt_core::TopologyError::NoTransferVertex { pair, levels }) => {
            assert_eq!(pair, "G3");
            assert_eq!(levels, vec!["c", "b", "a"]);
        }
        other => panic!("expected NoTransferVertex, got {other}"),
    }
}

//! Time of the torsional modes (divan, issue 43): one gear state of the
//! 8HP70 with compliant meshes (25 coordinates, 34 springs), and a chain of
//! gears of 250 to 1000 coordinates, where the dense eigensolver's cubic
//! cost shows. Numbers in docs/performance.md.

use std::fmt::Write as _;
use std::hint::black_box;

use egt_core::{Format, ModesRequest, Train};

fn main() {
    divan::main();
}

fn zf_8hp70() -> Train {
    let text = include_str!(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/zf_8hp70_compliant.toml"
    ));
    Train::from_str(text, Format::Toml, "zf_8hp70_compliant.toml").expect("example parses")
}

/// A chain of `n` gears, each on its own shaft in the housing (axes a and b
/// alternate), each meshing the next: n coordinates, n - 1 mesh springs,
/// one rigid-body mode.
fn gear_chain(n: usize) -> Train {
    let mut adjacency = String::new();
    let mut links = String::new();
    let mut meshes = String::new();
    for k in 1..=n {
        let level = if k % 2 == 1 { "a" } else { "b" };
        let _ = write!(adjacency, "0-{k}:{level} ");
        let _ = write!(
            links,
            "{{ name = \"{k}\", inertia = {:e} }}, ",
            1e-3 * (1.0 + 0.1 * (k % 7) as f64)
        );
    }
    for k in 1..n {
        let _ = write!(adjacency, "{k}-{}:G=-1 ", k + 1);
        let _ = writeln!(
            meshes,
            "[[compliance.meshes]]\ngear = \"G{k}\"\nstiffness = {:e}\nbase_radii = [0.03, 0.03]",
            3e8 * (1.0 + 0.05 * (k % 5) as f64)
        );
    }
    let text = format!("frame = \"0\"\nadjacency = \"{adjacency}\"\nlinks = [{links}]\n{meshes}");
    Train::from_str(&text, Format::Toml, "chain.toml").expect("the chain is a valid train")
}

/// All modes of one gear state of the 8HP70 (third gear), the Campbell
/// crossings from 0 to 7000 rpm included.
#[divan::bench]
fn zf_8hp70_one_state(bencher: divan::Bencher) {
    let train = zf_8hp70();
    let req = ModesRequest {
        state: Some("3".into()),
        campbell: Some([0.0, 7000.0]),
    };
    bencher.bench_local(|| {
        black_box(&train)
            .modes(black_box(&req))
            .map(|m| m.modes.len())
    });
}

/// The chain sizes: in a debug build (`cargo test --all-targets` runs each
/// benchmark once, unoptimised) a small one only, so that the test stays a
/// smoke test of seconds.
const SIZES: &[usize] = if cfg!(debug_assertions) {
    &[40]
} else {
    &[250, 500, 1000]
};

/// All modes of a gear chain of `n` coordinates.
#[divan::bench(args = SIZES, sample_count = 5, sample_size = 1)]
fn gear_chain_modes(bencher: divan::Bencher, n: usize) {
    let train = gear_chain(n);
    let req = ModesRequest::default();
    bencher.bench_local(|| {
        black_box(&train)
            .modes(black_box(&req))
            .map(|m| m.modes.len())
    });
}

//! Link the `egt` binary as a position-dependent executable on Linux.
//!
//! A position-independent `egt` carries about 25 700 relative relocations
//! (vtables and other pointers in its data), which the dynamic loader
//! applies at every start, touching about 340 KB of otherwise shared pages.
//! Linked with `-no-pie`, the linker resolves them once: `egt --version`
//! went from 1.81 to 1.35 ms and a one-row `egt batch` from 3.27 to 3.11 ms
//! (medians of 30 alternated runs, docs/benchmarks.md). The cost: the
//! binary's own code and data are not placed at a random address (its
//! libraries, stack and heap still are). Only the binaries are linked so;
//! the library, its tests and the Python module are untouched.

fn main() {
    let os = std::env::var("CARGO_CFG_TARGET_OS").unwrap_or_default();
    let env = std::env::var("CARGO_CFG_TARGET_ENV").unwrap_or_default();
    if os == "linux" && env == "gnu" {
        println!("cargo:rustc-link-arg-bins=-no-pie");
    }
    println!("cargo:rerun-if-changed=build.rs");
}

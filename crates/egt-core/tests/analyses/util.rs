//! Helpers shared by the integration tests.

use std::path::PathBuf;

use egt_core::numerics::exact::{self, Q};
use egt_core::{Format, LinkId, SpeedInput, Train};

/// The workspace root.
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Path of a bundled example.
pub fn example_path(name: &str) -> PathBuf {
    root().join("examples").join(name)
}

/// Load a bundled example.
pub fn example(name: &str) -> Train {
    let path = example_path(name);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    Train::from_str(&text, Format::from_path(name), name).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Build a train from TOML text, which must be valid.
pub fn toml(text: &str) -> Train {
    Train::from_str(text, Format::Toml, "test.toml").unwrap_or_else(|e| panic!("{e}\n{text}"))
}

/// Build from TOML text, expecting an error.
pub fn toml_err(text: &str) -> egt_core::Error {
    match Train::from_str(text, Format::Toml, "test.toml") {
        Ok(_) => panic!("expected an error for\n{text}"),
        Err(e) => e,
    }
}

/// A link id by name.
pub fn id(train: &Train, name: &str) -> LinkId {
    train
        .link_id(name)
        .unwrap_or_else(|| panic!("no link `{name}`"))
}

/// An exact input speed.
pub fn input(train: &Train, name: &str, speed: Q) -> SpeedInput {
    SpeedInput {
        link: id(train, name),
        speed: exact::to_f64(&speed),
        exact: Some(speed),
    }
}

/// The exact speed of a link from a solution.
pub fn exact_speed(train: &Train, speeds: &egt_core::Speeds, name: &str) -> Q {
    speeds.exact.as_ref().expect("exact solution")[id(train, name).index()].clone()
}

/// p/q.
pub fn fr(p: i64, q: i64) -> Q {
    exact::frac(p, q)
}

/// A rational as text for a spec (`p/q`).
pub fn text(q: &Q) -> String {
    exact::display(q)
}

//! Issue 44: `egt fmu SPEC -o FILE` packages a transmission, or a train
//! without shift elements, as an FMI 2.0 Co-Simulation unit; its contents (the importer's view) are tested by
//! FMPy in crates/egt-py/tests/test_fmu.py.

use std::path::PathBuf;

use crate::util::{egt, root};

/// egt-fmu's shared library as `cargo build` leaves it beside (or in `deps/`
/// beside) the `egt` under test.
pub fn library() -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_BIN_EXE_egt"));
    let dir = dir.parent().expect("egt's directory");
    [
        dir.join(egt_fmu::LIBRARY_FILE),
        dir.join("deps").join(egt_fmu::LIBRARY_FILE),
    ]
    .into_iter()
    .find(|p| p.is_file())
    .expect("cargo builds egt-fmu's cdylib with egt")
}

/// `name` in a fresh directory of this test's own (`egt fmu` names the
/// unit after the file's stem).
fn tmp(test: &str, name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("egt-fmu-{}-{test}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a temporary directory");
    dir.join(name)
}

#[test]
fn the_8hp_unit_holds_its_description_library_and_spec() {
    let out = tmp("zf", "zf.fmu");
    let o = out.to_string_lossy();
    let r = egt(&["fmu", "examples/zf_8hp70.toml", "-o", &o], None);
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(r.stdout.contains("model identifier `zf`"), "{}", r.stdout);
    let bytes = std::fs::read(&out).expect("the unit");
    std::fs::remove_file(&out).ok();
    assert_eq!(&bytes[..2], b"PK");
    // The zip's central directory names its entries uncompressed.
    let text = String::from_utf8_lossy(&bytes);
    for entry in [
        "modelDescription.xml",
        "binaries/linux64/zf.so",
        "resources/spec.toml",
    ] {
        assert!(text.contains(entry), "{entry}");
    }
    let lib = std::fs::read(library()).expect("the library");
    assert!(bytes.len() < lib.len(), "the library is deflated");
}

#[test]
fn a_train_without_elements_is_a_unit_and_elements_without_states_or_inertias_are_refused() {
    let out = tmp("refused", "x.fmu");
    let o = out.to_string_lossy();
    let r = egt(&["fmu", "examples/fig5_stability.toml", "-o", &o], None);
    assert_eq!(r.code, 0, "{}", r.stderr);
    std::fs::remove_file(&out).expect("the unit");
    // Shift elements without `[transmission]`: neither kind of unit.
    let zf = std::fs::read_to_string(root().join("examples/zf_8hp70.toml")).expect("the 8HP");
    let cut = tmp("refused", "cut.toml");
    std::fs::write(
        &cut,
        &zf[..zf.find("[transmission]").expect("a transmission")],
    )
    .expect("cut");
    let r = egt(&["fmu", &cut.to_string_lossy(), "-o", &o], None);
    assert_eq!(r.code, 1);
    assert!(
        r.stderr.contains("shift elements") && r.stderr.contains("gear states"),
        "{}",
        r.stderr
    );
    // A train without inertia cannot step: refused when packaged.
    let bare = tmp("refused", "bare.toml");
    std::fs::write(
        &bare,
        r#"frame = "0"
links = [{ name = "m" }, { name = "o" }]
revolutes = [{ links = ["0", "m"], level = "a" }, { links = ["0", "o"], level = "b" }]
gears = [{ links = ["m", "o"], ratio = -2.0 }]
"#,
    )
    .expect("bare");
    let r = egt(&["fmu", &bare.to_string_lossy(), "-o", &o], None);
    assert_eq!(r.code, 1);
    assert!(r.stderr.contains("inertia"), "{}", r.stderr);
    let missing = root().join("no-such-library.so");
    let m = missing.to_string_lossy();
    let r = egt(
        &["fmu", "examples/zf_8hp70.toml", "-o", &o, "--library", &m],
        None,
    );
    assert_ne!(r.code, 0);
    assert!(r.stderr.contains("no-such-library.so"), "{}", r.stderr);
    assert!(!out.exists());
}

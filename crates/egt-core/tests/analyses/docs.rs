//! The spec examples in `docs/spec.md` run: every complete TOML or JSON block
//! (one that names a `frame`) validates into a train.

use egt_core::{Format, Train};

use crate::util::root;

#[test]
fn spec_md_examples_validate() {
    let text = std::fs::read_to_string(root().join("docs/spec.md")).expect("docs/spec.md");
    let mut checked = 0;
    let mut lines = text.lines();
    while let Some(line) = lines.next() {
        let format = match line.trim() {
            "```toml" => Format::Toml,
            "```json" => Format::Json,
            _ => continue,
        };
        let block: Vec<&str> = lines.by_ref().take_while(|l| l.trim() != "```").collect();
        let block = block.join("\n");
        if !(block.contains("frame =") || block.contains("\"frame\"")) {
            continue; // a fragment of a larger spec
        }
        let train = Train::from_str(&block, format, "docs/spec.md")
            .unwrap_or_else(|e| panic!("{e}\n{block}"));
        assert!(train.dof() >= 1);
        checked += 1;
    }
    assert!(
        checked >= 3,
        "only {checked} complete examples found in docs/spec.md"
    );
}

/// Every stable error code of the core has a row in `docs/errors.md`.
#[test]
fn every_error_code_is_documented() {
    let source =
        std::fs::read_to_string(root().join("crates/egt-core/src/error.rs")).expect("error.rs");
    let doc = std::fs::read_to_string(root().join("docs/errors.md")).expect("docs/errors.md");
    let mut codes = 0;
    for line in source.lines().filter(|l| l.contains("=> \"")) {
        let code = line.split('"').nth(1).expect("a quoted code");
        assert!(
            doc.contains(&format!("| `{code}` |")),
            "error code `{code}` has no row in docs/errors.md"
        );
        codes += 1;
    }
    assert!(codes >= 40, "only {codes} codes found in error.rs");
}

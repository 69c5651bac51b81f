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

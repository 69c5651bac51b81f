//! `egt schema`: the JSON Schema of the spec format, for editors and generators.

use std::io::Write;

/// Arguments of `egt schema` (none).
#[derive(Debug, Clone, clap::Args)]
pub struct Args {}

/// Print the schema as pretty JSON.
///
/// # Errors
/// I/O errors.
pub fn run(_args: &Args, out: &mut dyn Write) -> anyhow::Result<()> {
    crate::report::json_document(out, &egt_core::spec_schema())
}

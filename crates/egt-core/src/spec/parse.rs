//! Reading specs from TOML or JSON text, with syntax and type errors located
//! by file, line, column and field path.

use crate::error::{Error, Result, SpecErrorKind, SyntaxError};
use crate::spec::Spec;

/// The text format of a spec.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// TOML.
    Toml,
    /// JSON.
    Json,
}

impl Format {
    /// Guess from a file name (`.json` is JSON, anything else TOML).
    pub fn from_path(path: &str) -> Format {
        if path.to_ascii_lowercase().ends_with(".json") {
            Format::Json
        } else {
            Format::Toml
        }
    }

    /// Guess from content: JSON documents start with `{` (after a UTF-8
    /// byte-order mark, if any).
    pub fn sniff(text: &str) -> Format {
        if strip_bom(text).trim_start().starts_with('{') {
            Format::Json
        } else {
            Format::Toml
        }
    }
}

/// The text without a leading UTF-8 byte-order mark.
fn strip_bom(text: &str) -> &str {
    text.strip_prefix('\u{feff}').unwrap_or(text)
}

/// The longest spec text read: 256 MiB, about 1.7 million links written as
/// planetary sets (past [`MAX_TRAIN_LINKS`](crate::model::train::MAX_TRAIN_LINKS)),
/// so a larger file is refused by its size before parsing, which takes
/// about 30 times the text in memory.
pub const MAX_SPEC_BYTES: usize = 256 << 20;

/// Refuse spec text longer than [`MAX_SPEC_BYTES`].
///
/// # Errors
/// A spec error on `source_name`, code `out_of_range`, with the limit.
pub fn check_spec_size(bytes: usize, source_name: &str) -> Result<()> {
    if bytes <= MAX_SPEC_BYTES {
        return Ok(());
    }
    #[allow(clippy::cast_precision_loss)]
    Err(Error::spec(
        source_name,
        SpecErrorKind::OutOfRange {
            value: bytes as f64,
            expected: format!(
                "a spec of at most {} MiB ({MAX_SPEC_BYTES} bytes); this one has more",
                MAX_SPEC_BYTES >> 20
            ),
        },
    ))
}

/// Parse a spec from text. `source_name` is used in error messages.
///
/// # Errors
/// [`Error::Syntax`] with line, column and (when known) the field path; a
/// text longer than [`MAX_SPEC_BYTES`].
pub fn parse_spec(text: &str, format: Format, source_name: &str) -> Result<Spec> {
    parse_document(text, format, source_name)
}

/// Parse any egt document (a train spec, a design-search spec) from text,
/// with the same located errors as [`parse_spec`].
///
/// # Errors
/// [`Error::Syntax`] with line, column and (when known) the field path.
pub fn parse_document<T: serde::de::DeserializeOwned>(
    text: &str,
    format: Format,
    source_name: &str,
) -> Result<T> {
    check_spec_size(text.len(), source_name)?;
    // A byte-order mark is no part of the document, in either format (the
    // positions of errors are then counted from the first character after it).
    let text = strip_bom(text);
    match format {
        Format::Json => {
            let mut de = serde_json::Deserializer::from_str(text);
            serde_path_to_error::deserialize(&mut de).map_err(|e| {
                let path = path_string(e.path());
                let inner = e.into_inner();
                Error::Syntax(SyntaxError {
                    source_name: source_name.to_string(),
                    line: inner.line(),
                    // serde_json counts 0 at the start of a line (e.g. at end of input).
                    column: inner.column().max(1),
                    path,
                    message: strip_position(&inner.to_string()),
                })
            })
        }
        Format::Toml => {
            let located = |e: toml::de::Error, path: Option<String>| {
                let (line, column) = e.span().map(|s| line_col(text, s.start)).unwrap_or((1, 1));
                Error::Syntax(SyntaxError {
                    source_name: source_name.to_string(),
                    line,
                    column,
                    path,
                    message: e.message().trim().to_string(),
                })
            };
            let de = toml::Deserializer::parse(text).map_err(|e| located(e, None))?;
            serde_path_to_error::deserialize(de).map_err(|e| {
                let path = path_string(e.path());
                located(e.into_inner(), path)
            })
        }
    }
}

fn path_string(p: &serde_path_to_error::Path) -> Option<String> {
    let s = p.to_string();
    (s != "." && !s.is_empty()).then_some(s)
}

/// serde_json appends " at line L column C"; we report those separately.
fn strip_position(msg: &str) -> String {
    match msg.rfind(" at line ") {
        Some(i) => msg[..i].to_string(),
        None => msg.to_string(),
    }
}

/// 1-based line and column (in characters) of a byte offset.
fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(text.len());
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, col)
}

/// The JSON Schema of the spec format.
pub fn spec_schema() -> serde_json::Value {
    let schema = schemars::schema_for!(Spec);
    serde_json::to_value(schema).unwrap_or(serde_json::Value::Null)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn toml_type_error_has_line_column_and_path() {
        let text = "frame = \"f\"\n[[gears]]\nlinks = [\"a\", \"b\"]\nteeth = [30, \"x\"]\n";
        let Err(Error::Syntax(e)) = parse_spec(text, Format::Toml, "t.toml") else {
            panic!("expected a syntax error")
        };
        assert_eq!(e.line, 4);
        assert!(e.path.as_deref().unwrap_or("").contains("gears"), "{e}");
    }

    #[test]
    fn json_syntax_error_has_line() {
        let text = "{\n \"frame\": \"f\",\n \"links\": [ }\n";
        let Err(Error::Syntax(e)) = parse_spec(text, Format::Json, "t.json") else {
            panic!("expected a syntax error")
        };
        assert_eq!(e.line, 3);
    }

    #[test]
    fn unknown_field_is_rejected_with_path() {
        let text = "frame = \"f\"\n[[links]]\nname = \"a\"\ninertai = 1.0\n";
        let Err(Error::Syntax(e)) = parse_spec(text, Format::Toml, "t.toml") else {
            panic!("expected a syntax error")
        };
        assert!(e.message.contains("inertai"), "{e}");
        assert_eq!(e.line, 4);
    }
}

//! Reading a spec: a path or `-` for standard input; TOML or JSON chosen by
//! `--spec-format`, else by the file extension, else (stdin) by sniffing.
//! The validated [`Train`] is built here, once, for every command.

use std::io::Read;
use std::path::Path;

use anyhow::Context;
use egt_core::{Format, Train};

use crate::cli::{SpecArgs, SpecFormat};

/// A validated train and the name its spec was read under.
#[derive(Debug)]
pub struct Loaded {
    /// The train.
    pub train: Train,
    /// File name, or `<stdin>`, as used in messages.
    pub source: String,
}

/// Read the spec named by `args` and validate it into a train.
///
/// # Errors
/// I/O errors (with the path), and the core's syntax, spec and topology errors.
/// Semantic errors carry the source name as context; syntax errors already
/// say `file:line:col`.
pub fn load(args: &SpecArgs) -> anyhow::Result<Loaded> {
    let (text, source) = read_text(&args.spec)?;
    let format = match args.spec_format {
        Some(SpecFormat::Toml) => Format::Toml,
        Some(SpecFormat::Json) => Format::Json,
        None if is_stdin(&args.spec) => Format::sniff(&text),
        None => Format::from_path(&source),
    };
    match Train::from_str(&text, format, &source) {
        Ok(train) => Ok(Loaded { train, source }),
        Err(e @ egt_core::Error::Syntax(_)) => Err(e.into()),
        Err(e) => Err(anyhow::Error::new(e).context(source)),
    }
}

/// Whether `path` means standard input (`-`).
pub fn is_stdin(path: &Path) -> bool {
    path.as_os_str() == "-"
}

/// The text of a file, or of standard input for `-`, and its name for messages.
///
/// # Errors
/// I/O errors, with the path.
pub fn read_text(path: &Path) -> anyhow::Result<(String, String)> {
    if is_stdin(path) {
        let mut text = String::new();
        std::io::stdin()
            .read_to_string(&mut text)
            .context("reading the spec from standard input")?;
        Ok((text, "<stdin>".to_string()))
    } else {
        let text =
            std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
        Ok((text, path.display().to_string()))
    }
}

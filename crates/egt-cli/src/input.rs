//! Reading a spec: a path or `-` for standard input; TOML or JSON chosen by
//! `--spec-format`, else by the file extension, else (stdin) by sniffing.
//! The validated [`Train`] is built here, once, for every command.

use std::io::Read;
use std::path::Path;

use anyhow::Context;
use egt_core::{Format, SpeedInput, Train};

use crate::args::{FormatArg, SpecArgs, SpecFormat, SpeedArgs, speed_inputs};

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
pub fn load<F: FormatArg>(args: &SpecArgs<F>) -> anyhow::Result<Loaded> {
    let (text, source, format) = read_spec(&args.spec, args.spec_format)?;
    match Train::from_str(&text, format, &source) {
        Ok(train) => Ok(Loaded { train, source }),
        Err(e @ egt_core::Error::Syntax(_)) => Err(e.into()),
        Err(e) => Err(anyhow::Error::new(e).context(source)),
    }
}

/// Read a spec ([`load`]) and its input speeds ([`speed_inputs`]).
///
/// # Errors
/// Those of [`load`]; unknown input links; no input speeds at all.
pub fn load_speeds(args: &SpeedArgs) -> anyhow::Result<(Loaded, Vec<SpeedInput>)> {
    let loaded = load(&args.spec)?;
    let speeds = speed_inputs(&loaded.train, args)?;
    Ok((loaded, speeds))
}

/// The text of a spec ([`read_text`]), its name for messages and its
/// format: `choice` (`--spec-format`) when given, else sniffed from the
/// text on standard input, else by the file extension.
///
/// # Errors
/// Those of [`read_text`].
pub fn read_spec(
    path: &Path,
    choice: Option<SpecFormat>,
) -> anyhow::Result<(String, String, Format)> {
    let (text, source) = read_text(path)?;
    let format = match choice {
        Some(SpecFormat::Toml) => Format::Toml,
        Some(SpecFormat::Json) => Format::Json,
        None if is_stdin(path) => Format::sniff(&text),
        None => Format::from_path(&source),
    };
    Ok((text, source, format))
}

/// Whether `path` means standard input (`-`).
pub fn is_stdin(path: &Path) -> bool {
    path.as_os_str() == "-"
}

/// The text of a file, or of standard input for `-`, and its name for messages.
/// At most [`MAX_SPEC_BYTES`](egt_core::spec::parse::MAX_SPEC_BYTES) are
/// read: a longer input is refused by its size, not loaded.
///
/// # Errors
/// I/O errors, with the path; text that is not UTF-8; an input past the limit.
pub fn read_text(path: &Path) -> anyhow::Result<(String, String)> {
    use egt_core::spec::parse::{MAX_SPEC_BYTES, check_spec_size};
    let limit = MAX_SPEC_BYTES as u64 + 1;
    let mut bytes = Vec::new();
    let name = if is_stdin(path) {
        std::io::stdin()
            .take(limit)
            .read_to_end(&mut bytes)
            .context("reading the spec from standard input")?;
        "<stdin>".to_string()
    } else {
        std::fs::File::open(path)
            .and_then(|f| f.take(limit).read_to_end(&mut bytes))
            .with_context(|| format!("reading {}", path.display()))?;
        path.display().to_string()
    };
    check_spec_size(bytes.len(), &name)?;
    let text = String::from_utf8(bytes)
        .map_err(|_| {
            std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                "stream did not contain valid UTF-8",
            )
        })
        .with_context(|| format!("reading {name}"))?;
    Ok((text, name))
}

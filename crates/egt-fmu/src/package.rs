//! The `.fmu` archive: `modelDescription.xml`, the platform's shared library
//! as `binaries/<platform>/<modelIdentifier>.<ext>`, and the spec as
//! `resources/spec.toml` (or `.json`), which each instance reads.

use std::io::Write;

use egt_core::Train;
use zip::write::SimpleFileOptions;

use crate::description::model_description;
use crate::variables::Variables;

/// The FMI 2.0 platform folder and library extension of this build.
pub const PLATFORM: (&str, &str) = if cfg!(target_os = "windows") {
    ("win64", "dll")
} else if cfg!(target_os = "macos") {
    ("darwin64", "dylib")
} else {
    ("linux64", "so")
};

/// The file name of the unit's shared library as cargo builds it
/// (`libegt_fmu.so` on Linux).
pub const LIBRARY_FILE: &str = if cfg!(target_os = "windows") {
    "egt_fmu.dll"
} else if cfg!(target_os = "macos") {
    "libegt_fmu.dylib"
} else {
    "libegt_fmu.so"
};

/// A model identifier (a C identifier, the library's file stem) from a name:
/// letters, digits and `_`, not starting with a digit.
pub fn model_identifier(name: &str) -> String {
    let mut id: String = name
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    if id.is_empty() || id.starts_with(|c: char| c.is_ascii_digit()) {
        id.insert_str(0, "egt_");
    }
    id
}

/// Why a unit could not be packaged.
#[derive(Debug)]
pub struct PackageError(pub String);

impl std::fmt::Display for PackageError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for PackageError {}

/// The `.fmu` of `train` (made from `spec`, whose format `json` says), named
/// `model_identifier`, with `library` (the bytes of this crate's cdylib).
///
/// # Errors
/// A spec that is not a transmission, or the writer's error.
pub fn package(
    train: &Train,
    spec: &str,
    json: bool,
    model_identifier: &str,
    library: &[u8],
) -> Result<Vec<u8>, PackageError> {
    let variables = Variables::of(train).map_err(|e| PackageError(e.0))?;
    let name = train.name().unwrap_or(model_identifier);
    let xml = model_description(&variables, name, model_identifier, spec)
        .map_err(|e| PackageError(format!("model description: {e}")))?;
    let (platform, ext) = PLATFORM;
    let mut zip = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let deflated =
        SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated);
    let library_options = deflated.unix_permissions(0o755);
    let files: [(String, &[u8], SimpleFileOptions); 3] = [
        ("modelDescription.xml".into(), xml.as_bytes(), deflated),
        (
            format!("binaries/{platform}/{model_identifier}.{ext}"),
            library,
            library_options,
        ),
        (
            format!("resources/spec.{}", if json { "json" } else { "toml" }),
            spec.as_bytes(),
            deflated,
        ),
    ];
    let io = |e: std::io::Error| PackageError(e.to_string());
    for (path, bytes, options) in files {
        zip.start_file(path, options)
            .map_err(|e| PackageError(e.to_string()))?;
        zip.write_all(bytes).map_err(io)?;
    }
    let cursor = zip.finish().map_err(|e| PackageError(e.to_string()))?;
    Ok(cursor.into_inner())
}

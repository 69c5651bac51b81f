//! `egt fmu SPEC -o train.fmu`: a transmission, or a train without shift
//! elements, as an FMI 2.0 Co-Simulation unit (egt-fmu's packager). The unit carries egt-fmu's shared library,
//! found by `--library`, else `EGT_FMU_LIBRARY`, else next to the running
//! `egt` (`target/<profile>/`, where `cargo build --workspace` puts both) or
//! in its `deps/` (where building egt alone leaves egt-fmu's cdylib).

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use egt_core::{Format, Train};

use crate::args::SpecFormat;
use crate::input;

/// Arguments of `egt fmu`.
#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    /// The spec file (TOML or JSON) of a transmission or of a train without
    /// shift elements (with inertias), or `-` for standard input.
    #[arg(value_name = "SPEC")]
    pub spec: PathBuf,
    /// Spec format; by default from the extension (`.json` is JSON), or sniffed on stdin.
    #[arg(long, value_enum, value_name = "FORMAT")]
    pub spec_format: Option<SpecFormat>,
    /// The `.fmu` to write.
    #[arg(short, long, value_name = "FILE")]
    pub output: PathBuf,
    /// The model identifier (the shared library's name in the unit); by
    /// default the output file's stem, made a C identifier.
    #[arg(long, value_name = "ID")]
    pub model_identifier: Option<String>,
    /// egt-fmu's shared library to package (default: `EGT_FMU_LIBRARY`, else
    /// `libegt_fmu.so` beside the egt executable).
    #[arg(long, value_name = "FILE")]
    pub library: Option<PathBuf>,
}

/// Where egt-fmu's shared library is: `--library`, `EGT_FMU_LIBRARY`, or
/// beside the running executable.
fn library(args: &Args) -> anyhow::Result<PathBuf> {
    if let Some(p) = &args.library {
        return Ok(p.clone());
    }
    if let Some(p) = std::env::var_os("EGT_FMU_LIBRARY") {
        return Ok(PathBuf::from(p));
    }
    let exe = std::env::current_exe().context("locating the egt executable")?;
    // `cargo build -p egt-fmu` puts it beside egt; building egt alone (a
    // dependency's cdylib) leaves it in `deps/`.
    let beside = exe.parent().and_then(|d| {
        [
            d.join(egt_fmu::LIBRARY_FILE),
            d.join("deps").join(egt_fmu::LIBRARY_FILE),
        ]
        .into_iter()
        .find(|p| p.is_file())
    });
    match beside {
        Some(p) => Ok(p),
        None => bail!(
            "no {} beside {} (build it with `cargo build -p egt-fmu`, which puts it beside egt, or give --library or EGT_FMU_LIBRARY)",
            egt_fmu::LIBRARY_FILE,
            exe.display()
        ),
    }
}

/// Run `egt fmu`.
///
/// # Errors
/// Reading or validating the spec, a spec without a transmission, a missing
/// shared library, I/O.
pub fn run(args: &Args, out: &mut dyn Write) -> anyhow::Result<()> {
    let (text, source, format) = input::read_spec(&args.spec, args.spec_format)?;
    let train = match Train::from_str(&text, format, &source) {
        Ok(train) => train,
        Err(e @ egt_core::Error::Syntax(_)) => return Err(e.into()),
        Err(e) => return Err(anyhow::Error::new(e).context(source)),
    };
    let id = args.model_identifier.clone().unwrap_or_else(|| {
        egt_fmu::model_identifier(
            &args
                .output
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default(),
        )
    });
    if id != egt_fmu::model_identifier(&id) {
        bail!("--model-identifier `{id}` is not a C identifier");
    }
    let lib = library(args)?;
    let bytes = std::fs::read(&lib).with_context(|| format!("reading {}", lib.display()))?;
    let fmu = egt_fmu::package(&train, &text, format == Format::Json, &id, &bytes)
        .map_err(|e| anyhow::anyhow!("{source}: {e}"))?;
    write(&args.output, &fmu)?;
    writeln!(
        out,
        "wrote {} ({} bytes): FMI 2.0 Co-Simulation, model identifier `{id}`, library {}",
        args.output.display(),
        fmu.len(),
        lib.display()
    )?;
    Ok(())
}

fn write(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    std::fs::write(path, bytes).with_context(|| format!("writing {}", path.display()))
}

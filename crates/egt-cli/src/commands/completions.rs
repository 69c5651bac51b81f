//! `egt completions SHELL` and `egt man`: shell completions and the man page,
//! generated from the same clap definitions as the parser (handed in by
//! `cli.rs`), so they never drift from the commands.

use std::io::Write;

use clap_complete::Shell;

/// Arguments of `egt completions`.
#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    /// The shell (bash, zsh, fish, elvish, powershell).
    #[arg(value_enum)]
    pub shell: Shell,
}

/// Arguments of `egt man` (none).
#[derive(Debug, Clone, clap::Args)]
pub struct ManArgs {}

/// Print the completion script, e.g. `egt completions bash > /etc/bash_completion.d/egt`.
///
/// # Errors
/// I/O errors.
pub fn run(args: &Args, cmd: &mut clap::Command, out: &mut dyn Write) -> anyhow::Result<()> {
    clap_complete::generate(args.shell, cmd, "egt", out);
    Ok(())
}

/// Print the man page (roff), e.g. `egt man > egt.1 && man ./egt.1`.
///
/// # Errors
/// I/O errors.
pub fn man(_args: &ManArgs, cmd: clap::Command, out: &mut dyn Write) -> anyhow::Result<()> {
    clap_mangen::Man::new(cmd).render(out)?;
    Ok(())
}

//! `egt enumerate --links N --dof F`: the atlas of non-isomorphic geared
//! kinematic chains (egt_core::synthesis), one train per line in the compact
//! adjacency form (readable back by every egt command as `adjacency = "..."`
//! with any frame), or JSON Lines with the classification. Streamed unit by
//! unit; `--part I/K` runs one of K disjoint partitions of the search.
//! `--identify SPEC` prints the member a given train is instead. Ctrl-C
//! stops it after the last whole tree: the lines written are every member of
//! the trees done (`--count` then prints nothing), and it exits with 130.
//! `--search levels` finds the same atlas levels first
//! (`egt_core::synthesis::hypertree`) and prints it at the end.

use std::io::Write;
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

use egt_core::synthesis::hypertree::{enumerate_by_levels_until, hypertrees};
use egt_core::synthesis::{
    AtlasMember, AtlasRequest, Fractionation, GraphLevel, enumerate_until, member, units,
};

use crate::args::parse_part;
use crate::args::{OutputFormat, SpecArgs};
use crate::input;
use crate::interrupt::{self, Interrupted};
use crate::progress::Progress;

/// Arguments of `egt enumerate`.
#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    /// Number of links (frame included).
    #[arg(long, required_unless_present = "identify")]
    pub links: Option<usize>,
    /// Print the member this train (a spec file) is, instead of the atlas;
    /// its links and DOF come from the spec.
    #[arg(long, value_name = "SPEC", conflicts_with_all = ["links", "part", "count"])]
    pub identify: Option<PathBuf>,
    /// Degree of freedom (Gruebler-Kutzbach).
    #[arg(long, default_value_t = 1)]
    pub dof: usize,
    /// Count rotation graphs (levels unlabelled) or displacement graphs (with axis levels).
    #[arg(long, value_enum, default_value_t = Level::Rotation)]
    pub level: Level,
    /// Print JSON Lines with the classification instead of adjacency lines.
    #[arg(long)]
    pub jsonl: bool,
    /// Only partition I of K (`I/K`, 0-based): disjoint parts that together make the atlas.
    #[arg(long)]
    pub part: Option<String>,
    /// Which chains count as fractionated: `layout` (as `egt check`, in some
    /// bearing layout) or `kinematic` (also a cut link in the rotation graph,
    /// Tsai & Lin's non-fractionated trains; stricter for two or more DOF).
    #[arg(long, value_enum, default_value_t = FractionationArg::Layout)]
    pub fractionation: FractionationArg,
    /// Print only the number of members (nothing when Ctrl-C stops the
    /// run: a count of part of the atlas is not its size).
    #[arg(long)]
    pub count: bool,
    /// The most links asked for without a refusal: 9 links take about 10 s
    /// on 2 cores; 10 take about 5 minutes with `--search levels` and many
    /// hours by trees (docs/atlas.md). Raise it to go further on purpose.
    #[arg(long, value_name = "N", default_value_t = DEFAULT_MAX_LINKS)]
    pub max_links: usize,
    /// Show a progress line on stderr (trees done / all, rate, members found)
    /// even when stderr is not a terminal (on a terminal it shows anyway).
    /// Ctrl-C stops the run after the last whole tree and exits with 130.
    #[arg(long)]
    pub progress: bool,
    /// The search: `trees` (bearing trees first, streamed tree by tree, with
    /// progress and Ctrl-C) or `levels` (hypertrees of axis levels first:
    /// the same atlas, far faster from 9 links on, held in memory until the
    /// end; `--part` splits it at the displacement level only).
    #[arg(long, value_enum, default_value_t = Search::Trees)]
    pub search: Search,
}

/// Which search finds the atlas (the same members either way).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Search {
    /// Bearing trees first (`egt_core::synthesis::enumerate_until`).
    Trees,
    /// Hypertrees of axis levels first (`egt_core::synthesis::hypertree`).
    Levels,
}

/// The default of `--max-links`: the largest atlas measured to finish.
pub const DEFAULT_MAX_LINKS: usize = 9;

/// The sense of fractionation, as on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum FractionationArg {
    /// As `egt check`, in the best bearing layout.
    Layout,
    /// Also no cut link in the rotation graph.
    Kinematic,
}

/// The graph level, as on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Level {
    /// Rotation graphs: axis levels unlabelled.
    Rotation,
    /// Displacement graphs: with the axis levels.
    Displacement,
}

/// Runs `egt enumerate`.
///
/// # Errors
/// A bad request (links, dof, part) or a failed write.
pub fn run(args: &Args, out: &mut dyn Write) -> anyhow::Result<()> {
    let level = match args.level {
        Level::Rotation => GraphLevel::Rotation,
        Level::Displacement => GraphLevel::Displacement,
    };
    if let Some(path) = &args.identify {
        let loaded = input::load(&SpecArgs {
            spec: path.clone(),
            spec_format: None,
            format: OutputFormat::Table,
        })?;
        let m = member(&loaded.train, level)
            .map_err(|e| anyhow::Error::new(e).context(loaded.source))?;
        writeln!(out, "{}", printed(m, args.jsonl)?)?;
        return Ok(());
    }
    let links = args.links.unwrap_or_default();
    if links > args.max_links {
        return Err(egt_core::Error::spec(
            "--links",
            egt_core::SpecErrorKind::Invalid {
                message: format!(
                    "{links} links is past the budget of {} (9 links take about 10 s on 2 cores, \
                     10 about 5 minutes with --search levels and many hours by trees); \
                     raise it with --max-links {links} if that is meant",
                    args.max_links
                ),
            },
        )
        .into());
    }
    let req = AtlasRequest {
        links,
        dof: args.dof,
        level,
        part: args.part.as_deref().map(parse_part).transpose()?,
        fractionation: match args.fractionation {
            FractionationArg::Layout => Fractionation::Layout,
            FractionationArg::Kinematic => Fractionation::Kinematic,
        },
    };
    if args.search == Search::Levels {
        let bar = Progress::new(
            args.progress,
            "hypertrees",
            Some(hypertrees(links.clamp(3, 12)).len() as u64),
        );
        let found = AtomicUsize::new(0);
        let members = enumerate_by_levels_until(&req, &interrupt::flag(), &|valid| {
            let total = found.fetch_add(valid, Ordering::Relaxed) + valid;
            bar.add(1);
            bar.note(format!("{total} displacement graphs"));
        })?;
        drop(bar);
        let Some(members) = members else {
            return Err(Interrupted(
                "the levels-first search stopped before the end; it prints only at the end, so nothing was written"
                    .to_string(),
            )
            .into());
        };
        if args.count {
            writeln!(out, "{}", members.len())?;
            return Ok(());
        }
        for m in members {
            writeln!(out, "{}", printed(m, args.jsonl)?)?;
        }
        return Ok(());
    }
    // The trees this run covers (a partition's share of them).
    let trees = units(links.clamp(3, 12));
    let trees = match req.part {
        Some((i, k)) if k > 0 => (i..trees).step_by(k).len(),
        _ => trees,
    };
    let bar = Progress::new(args.progress, "trees", Some(trees as u64));
    let (mut total, mut done) = (0usize, 0u64);
    let mut failed: Option<std::io::Error> = None;
    let whole = enumerate_until(&req, &interrupt::flag(), |_, members| {
        total += members.len();
        done += 1;
        bar.note(format!("{total} members"));
        bar.set(done);
        if args.count || failed.is_some() {
            return;
        }
        for m in members {
            let line = printed(m, args.jsonl).unwrap_or_default();
            if let Err(e) = writeln!(out, "{line}") {
                failed = Some(e);
                return;
            }
        }
    })?;
    drop(bar);
    if let Some(e) = failed {
        return Err(e.into());
    }
    if !whole {
        let written = if args.count {
            format!("{total} members counted, no count printed (it would be part of the atlas's)")
        } else {
            format!("{total} members written, every member of those trees")
        };
        return Err(Interrupted(format!("{done} of {trees} trees enumerated; {written}")).into());
    }
    if args.count {
        writeln!(out, "{total}")?;
    }
    Ok(())
}

/// A member as printed: its JSON line, or its adjacency line.
fn printed(m: AtlasMember, jsonl: bool) -> serde_json::Result<String> {
    if jsonl {
        serde_json::to_string(&m)
    } else {
        Ok(m.adjacency)
    }
}

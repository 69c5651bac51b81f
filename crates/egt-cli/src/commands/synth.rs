//! `egt synth SEARCH`: the design search of `egt_core::design`. Reads a search
//! spec (the base transmission, tooth ranges per unknown set, constraints,
//! target ratios; `docs/synth.md`), searches every admissible tooth count on
//! all cores, and prints the best candidates with their exact ratios.
//! `--part I/K` runs one of K disjoint partitions (for several machines);
//! `--write-specs DIR` writes each candidate as a train spec that every egt
//! command reads (e.g. `egt shift DIR/candidate-1.json`). Ctrl-C stops the
//! search: the candidates confirmed so far are printed as the report (marked
//! interrupted), and it exits with 130.

use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

use std::io::IsTerminal;

use anyhow::Context;
use egt_core::design::{Candidate, ConceptInfo, Stats, SynthSpec, Synthesis};
use egt_core::{Format, parse_spec};
use serde::Serialize;

/// Parts of a search run one after another to show progress on a terminal.
const PROGRESS_PARTS: usize = 32;

use crate::args::parse_part;
use crate::args::{OutputFormat, SpecFormat};
use crate::input::{is_stdin, read_spec};
use crate::interrupt::{self, Interrupted};
use crate::progress::Progress;
use crate::report::{self, Table};

/// Arguments of `egt synth`.
#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    /// The search spec (TOML or JSON; `docs/synth.md`), or `-` for standard input.
    #[arg(value_name = "SEARCH")]
    pub spec: PathBuf,
    /// Search-spec format; by default from the extension, or sniffed on stdin.
    #[arg(long, value_enum, value_name = "FORMAT")]
    pub spec_format: Option<SpecFormat>,
    /// Output format.
    #[arg(long, value_enum, default_value_t = OutputFormat::Table)]
    pub format: OutputFormat,
    /// Keep this many of the best candidates (default: the spec's `top`, else 20).
    #[arg(long, value_name = "N")]
    pub top: Option<usize>,
    /// Refuse the search (code `budget`) once the bound reaches more than N
    /// leaves in one run or partition, each confirmed exactly (default: the
    /// spec's `max_leaves`, else 10000).
    #[arg(long, value_name = "N")]
    pub max_leaves: Option<u64>,
    /// Only partition I of K (`I/K`, 0-based): disjoint parts whose candidates,
    /// merged and ranked, are the whole search's.
    #[arg(long, value_name = "I/K")]
    pub part: Option<String>,
    /// Write each candidate's train spec to DIR/candidate-<rank>.json.
    #[arg(long, value_name = "DIR")]
    pub write_specs: Option<PathBuf>,
    /// Give each candidate's whole gear table (`shift`: the document `egt
    /// shift --format json` prints for its train). JSON and `--stream` only.
    #[arg(long)]
    pub tables: bool,
    /// Stream JSON Lines: the best candidates so far after each part of the
    /// search (`{"event": "progress", "done", "of", "best"}`), then the whole
    /// report (`{"event": "done", ...}`).
    #[arg(long, conflicts_with = "part")]
    pub stream: bool,
    /// Show a progress line on stderr (parts searched / all, rate) even when
    /// stderr is not a terminal (on a terminal it shows anyway). The space is
    /// then searched in 32 parts one after another, each with its own
    /// `--max-leaves`. Ctrl-C stops the search: the candidates confirmed so
    /// far are printed (marked interrupted) and it exits with 130.
    #[arg(long, conflicts_with = "part")]
    pub progress: bool,
}

#[derive(Debug, Serialize)]
struct SetTeeth {
    set: String,
    /// The basic ratio k: ring/sun (the small sun of a Ravigneaux set), or
    /// ring planet/(sun planet2) for a stepped planet.
    basic: String,
    /// ring/large sun of a Ravigneaux set.
    #[serde(skip_serializing_if = "Option::is_none")]
    basic2: Option<String>,
    sun: i64,
    ring: i64,
    /// The planet meshing the sun (a Ravigneaux set's short pinion).
    planet: i64,
    #[serde(skip_serializing_if = "Option::is_none")]
    sun2: Option<i64>,
    /// A Ravigneaux set's long pinion, a double-pinion set's outer pinion,
    /// or a stepped planet's wheel on the ring.
    #[serde(skip_serializing_if = "Option::is_none")]
    planet2: Option<i64>,
    alternatives: usize,
}

#[derive(Debug, Serialize)]
struct RatioRow {
    state: String,
    ratio: f64,
    exact: String,
}

#[derive(Debug, Serialize)]
struct Row {
    rank: usize,
    score: f64,
    spread: Option<f64>,
    sets: Vec<SetTeeth>,
    /// The freed elements' links (`[layout]`), element -> links.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    layout: Vec<(String, Vec<String>)>,
    /// A concept search: the candidate's shafts, held members, input,
    /// output and the equivalent positions and layouts.
    #[serde(skip_serializing_if = "Option::is_none")]
    concept: Option<ConceptInfo>,
    /// Per set, every admissible tooth set with the same basic ratios.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    same_ratio_teeth: Vec<Vec<egt_core::design::Teeth>>,
    /// Lowest efficiency and largest element torque per unit input torque
    /// over the targeted states.
    #[serde(skip_serializing_if = "Option::is_none")]
    efficiency: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    element_torque: Option<f64>,
    /// Largest |mesh multiplier| per unit input torque.
    #[serde(skip_serializing_if = "Option::is_none")]
    mesh_torque: Option<f64>,
    /// Largest planet speed relative to its carrier per unit input speed.
    #[serde(skip_serializing_if = "Option::is_none")]
    planet_speed: Option<f64>,
    ratios: Vec<RatioRow>,
    spec: Option<String>,
    /// `--tables`: the candidate's `egt shift --format json` document.
    #[serde(skip_serializing_if = "Option::is_none")]
    shift: Option<serde_json::Value>,
}

#[derive(Debug, Serialize)]
struct Report {
    source: String,
    base: String,
    part: Option<[usize; 2]>,
    candidates: Vec<Row>,
    stats: Stats,
    seconds: f64,
}

/// Run `egt synth`.
///
/// # Errors
/// Syntax and field errors of the search spec (exit 2), the base train's own
/// errors, I/O.
pub fn run(args: &Args, out: &mut dyn Write) -> anyhow::Result<()> {
    let (text, source, format) = read_spec(&args.spec, args.spec_format)?;
    let mut spec = SynthSpec::from_str(&text, format, &source)?;
    if let Some(top) = args.top {
        spec.top = top;
    }
    if let Some(n) = args.max_leaves {
        spec.max_leaves = n;
    }
    let file = (!is_stdin(&args.spec)).then_some(args.spec.as_path());
    // A concept search builds its own trains: no base to read.
    let (base, base_name) = if Synthesis::is_concept(&spec) {
        (None, String::new())
    } else {
        let base_path = spec.base_path(file);
        let base_text = std::fs::read_to_string(&base_path).with_context(|| {
            format!(
                "{source}: base = {:?}: reading {}",
                spec.base,
                base_path.display()
            )
        })?;
        let base_name = base_path.display().to_string();
        let base = parse_spec(&base_text, Format::from_path(&base_name), &base_name)?;
        (Some(base), base_name)
    };
    let search = Synthesis::new(spec, base)
        .map_err(egt_core::Error::from)
        .with_context(|| source.clone())?
        .with_cancel(interrupt::flag());
    let part = args.part.as_deref().map(parse_part).transpose()?;
    let start = Instant::now();
    // Parts one after another, for a progress line (on a terminal or with
    // `--progress`) and for `--stream`; the result is the same as one run.
    // (`--part` is one run: no line.)
    // A concept search counts structures (part i holds structures i, i + K,
    // ...), a tooth search parts; both say the best score so far.
    let structures = search.structures();
    let bar = if part.is_none() {
        Progress::new(
            args.progress,
            if structures.is_some() {
                "structures"
            } else {
                "parts"
            },
            None,
        )
    } else {
        Progress::hidden()
    };
    let tick = |done: usize, of: usize, best: &[Candidate]| {
        match structures {
            Some(n) => {
                bar.total(n as u64);
                bar.set(structures_in_parts(n, done, of) as u64);
            }
            None => {
                bar.total(of as u64);
                bar.set(done as u64);
            }
        }
        if let Some(b) = best.first() {
            bar.note(format!("best score {:.3e}", b.score));
        }
    };
    let (found, stats) = match part {
        Some((i, k)) => search.run_partition(i, k),
        // JSON Lines: the best so far after each part, as it is found.
        None if args.stream => search.run_in_parts(PROGRESS_PARTS, |done, of, best| {
            tick(done, of, best);
            let best: Vec<Row> = best
                .iter()
                .enumerate()
                .map(|(k, c)| row(&search, c, k + 1, None))
                .collect();
            let line =
                serde_json::json!({"event": "progress", "done": done, "of": of, "best": best});
            // A closed pipe ends the stream at the final write.
            let _ = writeln!(out, "{line}").and_then(|()| out.flush());
        }),
        None if args.progress || std::io::stderr().is_terminal() => {
            search.run_in_parts(PROGRESS_PARTS, tick)
        }
        None => search.run(),
    }
    .map_err(egt_core::Error::from)?;
    drop(bar);
    let seconds = start.elapsed().as_secs_f64();
    let interrupted = stats.interrupted;
    let mut rows = Vec::with_capacity(found.len());
    for (k, c) in found.iter().enumerate() {
        let written = match &args.write_specs {
            Some(dir) => Some(write_spec(&search, c, dir, k + 1)?),
            None => None,
        };
        let mut r = row(&search, c, k + 1, written);
        if args.tables {
            let name = r
                .spec
                .clone()
                .unwrap_or_else(|| format!("candidate-{}", k + 1));
            let train = egt_core::Train::from_spec(
                &search.candidate_spec(c).map_err(egt_core::Error::from)?,
            )?;
            let table = train
                .shift_table()
                .with_context(|| format!("{name}: gear table"))?;
            r.shift = Some(egt_views::shift(&train, &name, &table)?);
        }
        rows.push(r);
    }
    let report = Report {
        source,
        base: base_name,
        part: part.map(|(i, k)| [i, k]),
        candidates: rows,
        stats,
        seconds,
    };
    let count = report.candidates.len();
    if args.stream {
        let mut done = report::value_of(&report)?;
        if let serde_json::Value::Object(map) = &mut done {
            let event = if interrupted { "interrupted" } else { "done" };
            map.insert("event".into(), event.into());
        }
        writeln!(out, "{done}")?;
    } else {
        match args.format {
            OutputFormat::Json => report::json(out, &report)?,
            OutputFormat::Table => write_table(out, &report)?,
        }
    }
    if interrupted {
        return Err(Interrupted(format!(
            "the search stopped before it covered the space ({} nodes, {} leaves); \
             the {count} candidates written are exact but the best of the part searched only",
            report.stats.nodes, report.stats.leaves
        ))
        .into());
    }
    Ok(())
}

fn row(search: &Synthesis, c: &Candidate, rank: usize, spec: Option<String>) -> Row {
    Row {
        rank,
        score: c.score,
        spread: c.spread,
        sets: search
            .set_names()
            .iter()
            .zip(&c.teeth)
            .zip(c.basic.iter().zip(&c.basic2))
            .zip(&c.alternatives)
            .map(|(((set, t), (basic, basic2)), &alternatives)| SetTeeth {
                set: set.clone(),
                basic: basic.clone(),
                basic2: basic2.clone(),
                sun: t.sun,
                ring: t.ring,
                planet: t.planet,
                sun2: t.sun2,
                planet2: t.planet2,
                alternatives,
            })
            .collect(),
        ratios: c
            .ratios
            .iter()
            .map(|(state, ratio, exact)| RatioRow {
                state: state.clone(),
                ratio: *ratio,
                exact: exact.clone(),
            })
            .collect(),
        layout: c.layout.clone(),
        concept: c.concept.clone(),
        same_ratio_teeth: c.same_ratio_teeth.clone(),
        efficiency: c.efficiency,
        element_torque: c.element_torque,
        mesh_torque: c.mesh_torque,
        planet_speed: c.planet_speed,
        spec,
        shift: None,
    }
}

/// The candidate's train spec as JSON, for every other egt command.
fn write_spec(
    search: &Synthesis,
    c: &Candidate,
    dir: &std::path::Path,
    rank: usize,
) -> anyhow::Result<String> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let path = dir.join(format!("candidate-{rank}.json"));
    let spec = search.candidate_spec(c).map_err(egt_core::Error::from)?;
    let text = serde_json::to_string_pretty(&spec)?;
    std::fs::write(&path, text + "\n").with_context(|| format!("writing {}", path.display()))?;
    Ok(path.display().to_string())
}

fn write_table(out: &mut dyn Write, r: &Report) -> anyhow::Result<()> {
    let over = match (r.part, r.stats.interrupted) {
        (Some([i, k]), false) => format!("partition {i} of {k}"),
        (Some([i, k]), true) => format!("part of partition {i} of {k} (interrupted)"),
        (None, false) => "the whole space".into(),
        (None, true) => "part of the space (interrupted)".into(),
    };
    if r.base.is_empty() {
        writeln!(out, "{}: concept search over {over}", r.source)?;
        writeln!(
            out,
            "{} structures, {} with layouts left after the gear states were checked over the whole box ({} state systems), {} element layouts searched",
            r.stats.structures,
            r.stats.structures_searched,
            r.stats.states_checked,
            r.stats.layouts
        )?;
    } else {
        writeln!(
            out,
            "{}: design search over {over} (base {})",
            r.source, r.base
        )?;
    }
    if !r.base.is_empty() && (r.stats.layouts > 1 || r.stats.skipped_layouts > 0) {
        writeln!(
            out,
            "{} element layouts searched, {} skipped (an element doubled, a state not one DOF or singular for any teeth)",
            r.stats.layouts, r.stats.skipped_layouts
        )?;
    }
    writeln!(
        out,
        "{:.3e} tooth combinations, {:.3e} distinct ratio combinations, {} nodes, {} leaves ({} failed the analysis targets), {:.2} s; {} candidates",
        r.stats.tooth_space,
        r.stats.ratio_space,
        r.stats.nodes,
        r.stats.leaves,
        r.stats.rejected,
        r.seconds,
        r.candidates.len()
    )?;
    let Some(first) = r.candidates.first() else {
        if r.base.is_empty() {
            writeln!(
                out,
                "no concept (structure, layout and teeth) meets the targets within the tolerance"
            )?;
        } else {
            writeln!(out, "no tooth counts meet the targets within the tolerance")?;
        }
        return Ok(());
    };
    let mut headers: Vec<String> = vec!["rank".into(), "score".into()];
    headers.extend(first.sets.iter().map(|s| {
        if s.sun2.is_some() {
            format!("{} sun/sun2/ring/planet/planet2 (k, k2)", s.set)
        } else if s.planet2.is_some() {
            format!("{} sun/ring/planet/planet2 (k)", s.set)
        } else {
            format!("{} sun/ring/planet (k)", s.set)
        }
    }));
    headers.extend(first.ratios.iter().map(|x| format!("i{}", x.state)));
    if !first.layout.is_empty() {
        headers.push("layout".into());
    }
    if first.concept.is_some() {
        headers.push("input, output, held; shafts".into());
    }
    let refs: Vec<&str> = headers.iter().map(String::as_str).collect();
    let mut t = Table::new(&refs).right(&[0, 1]);
    for c in &r.candidates {
        let mut cells = vec![c.rank.to_string(), format!("{:.2e}", c.score)];
        cells.extend(c.sets.iter().map(|s| {
            let alt = if s.alternatives > 1 {
                format!(" +{}", s.alternatives - 1)
            } else {
                String::new()
            };
            match (s.sun2, s.planet2, &s.basic2) {
                (Some(s2), Some(p2), Some(k2)) => format!(
                    "{}/{s2}/{}/{}/{p2} ({}, {k2}){alt}",
                    s.sun, s.ring, s.planet, s.basic
                ),
                (None, Some(p2), _) => {
                    format!("{}/{}/{}/{p2} ({}){alt}", s.sun, s.ring, s.planet, s.basic)
                }
                _ => format!("{}/{}/{} ({}){alt}", s.sun, s.ring, s.planet, s.basic),
            }
        }));
        cells.extend(c.ratios.iter().map(|x| format!("{:.4}", x.ratio)));
        if !c.layout.is_empty() {
            let placed: Vec<String> = c
                .layout
                .iter()
                .map(|(e, links)| format!("{e}={}", links.join("+")))
                .collect();
            cells.push(placed.join(" "));
        }
        if let Some(k) = &c.concept {
            let held = if k.held.is_empty() {
                "-".to_string()
            } else {
                k.held.join(" ")
            };
            cells.push(format!(
                "{}, {}, {held}; {}",
                k.input,
                k.output,
                k.shafts.join(" ")
            ));
        }
        t.row(cells);
    }
    t.write(out, 2)?;
    write_tooth_options(out, r)?;
    writeln!(
        out,
        "(k = ring/sun, ring planet/(sun planet2) for a stepped planet, k2 = ring/sun2; +N: N other tooth sets with the same k; ratios are exact, e.g. {} = {})",
        first.ratios.first().map_or("", |x| x.state.as_str()),
        first.ratios.first().map_or("", |x| x.exact.as_str()),
    )?;
    Ok(())
}

/// A concept search's other tooth sets per concept, a line each: the basic
/// ratios per set and the score.
fn write_tooth_options(out: &mut dyn Write, r: &Report) -> anyhow::Result<()> {
    let listed: Vec<(usize, &ConceptInfo)> = r
        .candidates
        .iter()
        .filter_map(|c| c.concept.as_ref().map(|k| (c.rank, k)))
        .filter(|(_, k)| !k.tooth_options.is_empty())
        .collect();
    if listed.is_empty() {
        return Ok(());
    }
    writeln!(
        out,
        "other tooth sets of each concept meeting the targets, best first (k per set, score):"
    )?;
    for (rank, k) in listed {
        let options: Vec<String> = k
            .tooth_options
            .iter()
            .map(|o| {
                let ks: Vec<String> = o
                    .basic
                    .iter()
                    .zip(&o.basic2)
                    .map(|(b, b2)| b2.as_ref().map_or(b.clone(), |b2| format!("{b},{b2}")))
                    .collect();
                format!("{} ({:.1e})", ks.join(" "), o.score)
            })
            .collect();
        let cut = if k.tooth_options_cut {
            " (search cut at concept.max_nodes: may miss some)"
        } else {
            ""
        };
        writeln!(out, "  {rank:>4}: {}{cut}", options.join("; "))?;
    }
    Ok(())
}

/// Structures in the first `done` of `parts` parts of `n` (structure i in
/// part i mod parts).
fn structures_in_parts(n: usize, done: usize, parts: usize) -> usize {
    (0..done.min(n)).map(|p| (n - p).div_ceil(parts)).sum()
}

#[cfg(test)]
mod tests {
    use super::structures_in_parts;

    #[test]
    fn parts_hold_structures_i_mod_k() {
        // 10 structures in 3 parts: {0, 3, 6, 9}, {1, 4, 7}, {2, 5, 8}.
        let counts: Vec<usize> = (0..=3).map(|d| structures_in_parts(10, d, 3)).collect();
        assert_eq!(counts, [0, 4, 7, 10]);
        // More parts than structures: one each, then none.
        assert_eq!(structures_in_parts(2, 5, 5), 2);
    }
}

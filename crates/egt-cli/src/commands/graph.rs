//! `egt graph SPEC`: the train's graph as Graphviz DOT (paper section 2,
//! Fig. 1): links are nodes (the frame a box; a transmission's input and output
//! double circles), turning pairs thin edges labelled with their axis level,
//! gear pairs bold coloured edges labelled with their name and Willis ratio,
//! and shift elements dashed edges (a brake to the frame, a clutch between its
//! two links). `--format json` gives the same nodes and edges as JSON. Render
//! with e.g. `egt graph spec.toml | dot -Tsvg -o graph.svg`.

use std::io::Write;

use egt_core::spec::ElementKind;
use egt_core::{Edge, LinkId, Train};
use serde::Serialize;

use crate::cli::{OutputFormat, SpecArgs};
use crate::input;
use crate::report;

/// Arguments of `egt graph`.
#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub spec: SpecArgs,
}

#[derive(Debug, Serialize)]
struct Graph {
    name: Option<String>,
    nodes: Vec<Node>,
    edges: Vec<GraphEdge>,
}

#[derive(Debug, Serialize)]
struct Node {
    link: String,
    /// `frame`, `input`, `output`, `planet` (unsized planet), or `link`.
    role: &'static str,
}

#[derive(Debug, Serialize)]
struct GraphEdge {
    /// `revolute`, `gear`, `brake`, `clutch`, `one_way_brake`, `one_way_clutch`.
    kind: &'static str,
    links: [String; 2],
    /// Axis level (revolute), gear pair name and ratio (gear), element name.
    label: String,
}

/// Run `egt graph`.
///
/// # Errors
/// Reading or validating the spec; I/O.
pub fn run(args: &Args, out: &mut dyn Write) -> anyhow::Result<()> {
    let loaded = input::load(&args.spec)?;
    let g = build(&loaded.train);
    match args.spec.format {
        OutputFormat::Json => report::json(out, &g),
        OutputFormat::Table => write_dot(out, &g),
    }
}

fn build(train: &Train) -> Graph {
    let (input, output) = train
        .transmission()
        .map_or((None, None), |t| (Some(t.input), Some(t.output)));
    let name = |l: LinkId| train.link_name(l).to_string();
    let nodes = train
        .links()
        .iter()
        .enumerate()
        .map(|(i, l)| {
            let id = LinkId::from_index(i);
            let role = if id == train.frame() {
                "frame"
            } else if Some(id) == input {
                "input"
            } else if Some(id) == output {
                "output"
            } else if !l.sized {
                "planet"
            } else {
                "link"
            };
            Node {
                link: l.name.clone(),
                role,
            }
        })
        .collect();
    let mut edges = Vec::new();
    for e in train.graph().edge_indices() {
        let Some((a, b)) = train.graph().edge_endpoints(e) else {
            continue;
        };
        let (a, b) = (train.graph()[a], train.graph()[b]);
        let (kind, label) = match train.graph()[e] {
            Edge::Revolute(r) => (
                "revolute",
                train
                    .level_name(train.revolutes()[r.index()].level)
                    .to_string(),
            ),
            Edge::Gear(g) => {
                let gp = &train.gears()[g.index()];
                let ratio = gp.ratio.as_ref().map_or_else(String::new, |r| {
                    r.exact
                        .as_ref()
                        .map_or_else(|| report::float(r.value), report::exact)
                });
                ("gear", format!("{} {ratio}", gp.name).trim().to_string())
            }
        };
        edges.push(GraphEdge {
            kind,
            links: [name(a), name(b)],
            label,
        });
    }
    for el in train.elements() {
        let kind = match el.kind {
            ElementKind::Brake => "brake",
            ElementKind::Clutch => "clutch",
            ElementKind::OneWayBrake => "one_way_brake",
            ElementKind::OneWayClutch => "one_way_clutch",
        };
        let other = el.links.get(1).copied().unwrap_or(train.frame());
        edges.push(GraphEdge {
            kind,
            links: [name(el.links[0]), name(other)],
            label: el.name.clone(),
        });
    }
    Graph {
        name: train.name().map(str::to_string),
        nodes,
        edges,
    }
}

/// A DOT identifier: always quoted, with quotes and backslashes escaped.
fn id(s: &str) -> String {
    format!("\"{}\"", s.replace('\\', "\\\\").replace('"', "\\\""))
}

fn write_dot(out: &mut dyn Write, g: &Graph) -> anyhow::Result<()> {
    writeln!(out, "graph {} {{", id(g.name.as_deref().unwrap_or("train")))?;
    writeln!(
        out,
        "  graph [fontname=\"Helvetica\", overlap=false, splines=true];"
    )?;
    writeln!(
        out,
        "  node [fontname=\"Helvetica\", shape=ellipse, style=filled, fillcolor=\"#f4f4f4\"];"
    )?;
    writeln!(out, "  edge [fontname=\"Helvetica\", fontsize=10];")?;
    for n in &g.nodes {
        let mut attrs = match n.role {
            "frame" => "shape=box, fillcolor=\"#cccccc\"",
            "input" => "shape=doublecircle, fillcolor=\"#cfe8ff\"",
            "output" => "shape=doublecircle, fillcolor=\"#ffe0c2\"",
            "planet" => "fillcolor=\"#ffffff\", style=\"filled,dotted\"",
            _ => "",
        }
        .to_string();
        // Name the role beside the node unless the link is already named so.
        if matches!(n.role, "input" | "output") && n.link != n.role {
            attrs.push_str(&format!(", xlabel={}", id(n.role)));
        }
        writeln!(out, "  {} [{attrs}];", id(&n.link))?;
    }
    for e in &g.edges {
        let style = match e.kind {
            "revolute" => "color=\"#555555\"",
            "gear" => "color=\"#0072B2\", penwidth=2.5, fontcolor=\"#0072B2\"",
            "brake" | "one_way_brake" => "style=dashed, color=\"#D55E00\", fontcolor=\"#D55E00\"",
            _ => "style=dashed, color=\"#009E73\", fontcolor=\"#009E73\"",
        };
        let label = match e.kind {
            "revolute" | "gear" => e.label.clone(),
            kind => format!(
                "{} ({})",
                e.label,
                kind.replace('_', " ").replace("one way", "one-way")
            ),
        };
        writeln!(
            out,
            "  {} -- {} [label={}, {style}];",
            id(&e.links[0]),
            id(&e.links[1]),
            id(&label)
        )?;
    }
    writeln!(out, "}}")?;
    Ok(())
}

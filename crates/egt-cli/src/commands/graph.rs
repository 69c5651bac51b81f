//! `egt graph SPEC`: the train's graph as Graphviz DOT (paper section 2,
//! Fig. 1): links are nodes (the frame a box; a transmission's input and output
//! double circles), turning pairs thin edges labelled with their axis level,
//! gear pairs bold coloured edges labelled with their name and Willis ratio,
//! and shift elements dashed edges (a brake to the frame, a clutch between its
//! two links). `--format json` gives the same nodes and edges as JSON. Render
//! with e.g. `egt graph spec.toml | dot -Tsvg -o graph.svg`, or `--svg` for a
//! self-contained drawing (links on a circle) where Graphviz is not installed.

use std::io::Write;

use egt_core::spec::ElementKind;
use egt_core::{Edge, LinkId, Train};
use serde::Serialize;

use crate::args::{OutputFormat, SpecArgs};
use crate::input;
use crate::report;

/// Arguments of `egt graph`.
#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub spec: SpecArgs,
    /// Write an SVG drawing (links on a circle) instead of DOT; needs no Graphviz.
    #[arg(long)]
    pub svg: bool,
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
    if args.svg {
        return write_svg(out, &g);
    }
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
        .links_with_ids()
        .map(|(id, l)| {
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

/// A self-contained SVG: links evenly on a circle (the frame at the top),
/// turning pairs thin grey lines with their level, gear pairs bold blue lines,
/// shift elements dashed.
fn write_svg(out: &mut dyn Write, g: &Graph) -> anyhow::Result<()> {
    use crate::svg::esc;
    let (w, h, r) = (420.0, 420.0, 150.0);
    let (cx, cy) = (w / 2.0, h / 2.0 + 10.0);
    let n = g.nodes.len().max(1) as f64;
    let at = |link: &str| {
        let i = g.nodes.iter().position(|x| x.link == link).unwrap_or(0) as f64;
        let t = std::f64::consts::TAU * i / n - std::f64::consts::FRAC_PI_2;
        (cx + r * t.cos(), cy + r * t.sin())
    };
    writeln!(
        out,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="Helvetica, Arial, sans-serif">"#
    )?;
    writeln!(
        out,
        r##"<rect width="100%" height="100%" fill="#ffffff"/>"##
    )?;
    if let Some(name) = &g.name {
        writeln!(
            out,
            r#"<text x="{cx}" y="18" text-anchor="middle" font-size="13">{}</text>"#,
            esc(name)
        )?;
    }
    for e in &g.edges {
        let ((x1, y1), (x2, y2)) = (at(&e.links[0]), at(&e.links[1]));
        let style = match e.kind {
            "revolute" => r##"stroke="#555555" stroke-width="1.2""##,
            "gear" => r##"stroke="#0072B2" stroke-width="4""##,
            "brake" | "one_way_brake" => {
                r##"stroke="#D55E00" stroke-width="1.5" stroke-dasharray="5,4""##
            }
            _ => r##"stroke="#009E73" stroke-width="1.5" stroke-dasharray="5,4""##,
        };
        writeln!(
            out,
            r#"<line x1="{x1:.1}" y1="{y1:.1}" x2="{x2:.1}" y2="{y2:.1}" {style}/>"#
        )?;
        let label = if e.kind == "gear" {
            "G".to_string()
        } else {
            e.label.clone()
        };
        let colour = if e.kind == "gear" {
            "#0072B2"
        } else {
            "#333333"
        };
        writeln!(
            out,
            r#"<text x="{:.1}" y="{:.1}" font-size="11" fill="{colour}" text-anchor="middle">{}</text>"#,
            0.5 * (x1 + x2),
            0.5 * (y1 + y2) - 3.0,
            esc(&label)
        )?;
    }
    for node in &g.nodes {
        let (x, y) = at(&node.link);
        let fill = match node.role {
            "frame" => "#cccccc",
            "input" => "#cfe8ff",
            "output" => "#ffe0c2",
            _ => "#f4f4f4",
        };
        writeln!(
            out,
            r##"<circle cx="{x:.1}" cy="{y:.1}" r="15" fill="{fill}" stroke="#333333"/>"##
        )?;
        writeln!(
            out,
            r#"<text x="{x:.1}" y="{:.1}" font-size="12" text-anchor="middle">{}</text>"#,
            y + 4.0,
            esc(&node.link)
        )?;
    }
    writeln!(out, "</svg>")?;
    Ok(())
}

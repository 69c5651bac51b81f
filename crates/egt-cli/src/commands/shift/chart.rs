//! The SVG chart of `egt shift --plot`: a speed ladder (every shaft's speed
//! per unit input speed, one column per gear state, one line per shaft, the
//! way lever-analogy speed charts are read: held shafts sit on the zero line,
//! the input on 1, the output at 1/ratio) above a bar chart of the engaged
//! elements' torques per unit input torque. Plain SVG, no dependencies.

use std::fmt::Write as _;

use crate::svg::{PALETTE, esc, fmt_tick, ticks};
use egt_views::shift::{GearRow, Report};

const WIDTH: f64 = 980.0;
const LEFT: f64 = 70.0;
const PLOT_W: f64 = 700.0;
const LEGEND_X: f64 = LEFT + PLOT_W + 30.0;
const SPEED_TOP: f64 = 80.0;
const SPEED_H: f64 = 380.0;
const TORQUE_TOP: f64 = SPEED_TOP + SPEED_H + 110.0;
const TORQUE_H: f64 = 260.0;
const HEIGHT: f64 = TORQUE_TOP + TORQUE_H + 70.0;

/// Axes, grid and gear columns for one panel; returns the y mapping.
fn panel(
    svg: &mut String,
    r: &Report,
    top: f64,
    height: f64,
    lo: f64,
    hi: f64,
    title: &str,
) -> impl Fn(f64) -> f64 + use<> {
    let (a, b, ts) = ticks(lo, hi);
    let y = move |v: f64| top + height - (v - a) / (b - a) * height;
    let _ = writeln!(
        svg,
        r#"<text x="{LEFT}" y="{:.1}" class="title">{}</text>"#,
        top - 18.0,
        esc(title)
    );
    for t in ts {
        let yy = y(t);
        let class = if t.abs() < 1e-12 { "zero" } else { "grid" };
        let _ = writeln!(
            svg,
            r#"<line x1="{LEFT}" y1="{yy:.1}" x2="{:.1}" y2="{yy:.1}" class="{class}"/><text x="{:.1}" y="{:.1}" class="tick" text-anchor="end">{}</text>"#,
            LEFT + PLOT_W,
            LEFT - 6.0,
            yy + 4.0,
            fmt_tick(t)
        );
    }
    let n = r.gears.len();
    for (k, g) in r.gears.iter().enumerate() {
        let x = column(k, n);
        let _ = writeln!(
            svg,
            r#"<line x1="{x:.1}" y1="{top:.1}" x2="{x:.1}" y2="{:.1}" class="col"/><text x="{x:.1}" y="{:.1}" class="gear" text-anchor="middle">{}</text><text x="{x:.1}" y="{:.1}" class="tick" text-anchor="middle">{:.3}</text>"#,
            top + height,
            top + height + 18.0,
            esc(&g.state),
            top + height + 33.0,
            g.ratio
        );
    }
    let _ = writeln!(
        svg,
        r#"<rect x="{LEFT}" y="{top:.1}" width="{PLOT_W}" height="{height:.1}" class="frame"/>"#
    );
    y
}

fn column(k: usize, n: usize) -> f64 {
    LEFT + PLOT_W * (k as f64 + 0.5) / n.max(1) as f64
}

fn legend(svg: &mut String, top: f64, entries: &[(String, &str)]) {
    for (i, (name, color)) in entries.iter().enumerate() {
        let y = top + 8.0 + 18.0 * i as f64;
        let _ = writeln!(
            svg,
            r#"<rect x="{LEGEND_X}" y="{:.1}" width="14" height="10" fill="{color}"/><text x="{:.1}" y="{:.1}" class="legend">{}</text>"#,
            y - 9.0,
            LEGEND_X + 20.0,
            y,
            esc(name)
        );
    }
}

/// The chart for a gear table.
pub fn svg(r: &Report) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH}" height="{HEIGHT}" viewBox="0 0 {WIDTH} {HEIGHT}" font-family="sans-serif">"#
    );
    s.push_str(
        "<style>.title{font-size:15px;font-weight:bold}.tick{font-size:11px;fill:#444}\
         .gear{font-size:13px;font-weight:bold}.legend{font-size:12px}\
         .grid{stroke:#ddd;stroke-width:1}.zero{stroke:#333;stroke-width:1.2}\
         .col{stroke:#eee;stroke-width:1}.frame{fill:none;stroke:#888}</style>\n",
    );
    s.push_str(r##"<rect width="100%" height="100%" fill="white"/>"##);
    s.push('\n');
    let name = r.name.clone().unwrap_or_else(|| r.source.clone());
    let _ = writeln!(
        s,
        r#"<text x="{LEFT}" y="24" class="title" font-size="17">{} — input `{}`, output `{}`</text>"#,
        esc(&name),
        esc(&r.input),
        esc(&r.output)
    );
    let n = r.gears.len();

    // Speed ladder: shafts only (planets spin about their own axes).
    let shafts: Vec<&str> = r
        .gears
        .first()
        .map(|g| {
            g.speeds
                .iter()
                .filter(|x| x.shaft)
                .map(|x| x.link.as_str())
                .collect()
        })
        .unwrap_or_default();
    let speed = |g: &GearRow, link: &str| {
        g.speeds
            .iter()
            .find(|x| x.link == link)
            .and_then(|x| x.speed)
    };
    let all: Vec<f64> = r
        .gears
        .iter()
        .flat_map(|g| shafts.iter().filter_map(move |l| speed(g, l)))
        .filter(|v| v.is_finite())
        .collect();
    let lo = all.iter().copied().fold(0.0_f64, f64::min);
    let hi = all.iter().copied().fold(1.0_f64, f64::max);
    let y = panel(
        &mut s,
        r,
        SPEED_TOP,
        SPEED_H,
        lo,
        hi,
        "Shaft speed per unit input speed, by gear",
    );
    let mut entries = Vec::new();
    for (i, link) in shafts.iter().enumerate() {
        let color = PALETTE[i % PALETTE.len()];
        let (dash, width) = if *link == r.input {
            ("6 3", 3.0)
        } else if *link == r.output {
            ("", 3.5)
        } else {
            ("", 1.8)
        };
        let pts: Vec<String> = r
            .gears
            .iter()
            .enumerate()
            .filter_map(|(k, g)| speed(g, link).map(|v| format!("{:.1},{:.1}", column(k, n), y(v))))
            .collect();
        let _ = writeln!(
            s,
            r#"<polyline points="{}" fill="none" stroke="{color}" stroke-width="{width}" stroke-dasharray="{dash}"/>"#,
            pts.join(" ")
        );
        for p in &pts {
            let (px, py) = p.split_once(',').unwrap_or(("0", "0"));
            let _ = writeln!(s, r#"<circle cx="{px}" cy="{py}" r="3.5" fill="{color}"/>"#);
        }
        let role = if *link == r.input {
            " (input)"
        } else if *link == r.output {
            " (output)"
        } else {
            ""
        };
        entries.push((format!("{link}{role}"), color));
    }
    legend(&mut s, SPEED_TOP, &entries);
    let _ = writeln!(
        s,
        r#"<text x="{:.1}" y="{:.1}" class="tick" text-anchor="middle">gear state (ratio input/output below)</text>"#,
        LEFT + PLOT_W / 2.0,
        SPEED_TOP + SPEED_H + 52.0
    );

    // Element torques: grouped bars, one colour per element.
    // Elements in the spec's order, those engaged in some gear.
    let elements: Vec<String> = r
        .elements
        .iter()
        .map(|e| e.name.clone())
        .filter(|e| {
            r.gears
                .iter()
                .any(|g| g.elements.iter().any(|x| &x.element == e))
        })
        .collect();
    let torques: Vec<f64> = r
        .gears
        .iter()
        .flat_map(|g| g.elements.iter().map(|e| e.torque))
        .filter(|v| v.is_finite())
        .collect();
    let lo = torques.iter().copied().fold(0.0_f64, f64::min);
    let hi = torques
        .iter()
        .copied()
        .fold(0.0_f64, f64::max)
        .max(lo + 1.0);
    let y = panel(
        &mut s,
        r,
        TORQUE_TOP,
        TORQUE_H,
        lo,
        hi,
        "Engaged element torque per unit input torque (on the element's first link)",
    );
    let slot = PLOT_W / n.max(1) as f64;
    for (k, g) in r.gears.iter().enumerate() {
        let m = g.elements.len().max(1) as f64;
        let bar = (slot * 0.7 / m).min(26.0);
        let x0 = column(k, n) - bar * m / 2.0;
        for (j, e) in g.elements.iter().enumerate() {
            if !e.torque.is_finite() {
                continue;
            }
            let i = elements.iter().position(|x| *x == e.element).unwrap_or(0);
            let color = PALETTE[(i + 3) % PALETTE.len()];
            let (y0, y1) = (y(0.0), y(e.torque));
            let _ = writeln!(
                s,
                r#"<rect x="{:.1}" y="{:.1}" width="{:.1}" height="{:.1}" fill="{color}"><title>{} in gear {}: {:.4}</title></rect>"#,
                x0 + bar * j as f64,
                y0.min(y1),
                bar * 0.9,
                (y0 - y1).abs().max(0.5),
                esc(&e.element),
                esc(&g.state),
                e.torque
            );
        }
    }
    let entries: Vec<(String, &str)> = elements
        .iter()
        .enumerate()
        .map(|(i, e)| (e.clone(), PALETTE[(i + 3) % PALETTE.len()]))
        .collect();
    legend(&mut s, TORQUE_TOP, &entries);
    s.push_str("</svg>\n");
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_cover_the_range_with_round_steps() {
        let (a, b, ts) = ticks(-3.3, 4.7);
        assert!(a <= -3.3 && b >= 4.7);
        assert!(ts.len() >= 4 && ts.len() <= 10);
        assert!(ts.iter().any(|t| t.abs() < 1e-12));
    }
}

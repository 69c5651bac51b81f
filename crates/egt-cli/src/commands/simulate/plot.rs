//! The SVG plot of `egt simulate --plot`: every link's speed against time,
//! one coloured line per link, with the equilibrium of the curves as dashed
//! lines of the same colour, and below it the deviation from that
//! equilibrium, so convergence (or divergence) reads at a glance.
//! Plain SVG, no dependencies.

use std::fmt::Write as _;

use crate::svg::{PALETTE, esc, fmt_tick, ticks};
use egt_core::{LinkId, Simulation, Train};

const WIDTH: f64 = 900.0;
const LEFT: f64 = 80.0;
const TOP: f64 = 95.0;
const PLOT_W: f64 = 660.0;
const PLOT_H: f64 = 330.0;
/// Space between panels (axis labels and the next panel's heading).
const GAP: f64 = 90.0;
/// At most this many points per line.
const MAX_POINTS: usize = 600;

/// One panel: axes, ticks, a line per link of `value(sample, link)`, and
/// optional dashed reference levels.
struct Panel<'a> {
    top: f64,
    title: &'a str,
    ylabel: &'a str,
}

#[allow(clippy::too_many_arguments)]
fn panel(
    svg: &mut String,
    p: &Panel<'_>,
    links: &[LinkId],
    sim: &Simulation,
    value: &dyn Fn(usize, LinkId) -> f64,
    levels: Option<&dyn Fn(LinkId) -> f64>,
    t_end: f64,
) {
    let samples = &sim.samples;
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for i in 0..samples.len() {
        for &l in links {
            lo = lo.min(value(i, l));
            hi = hi.max(value(i, l));
        }
    }
    if let Some(lv) = levels {
        for &l in links {
            lo = lo.min(lv(l));
            hi = hi.max(lv(l));
        }
    }
    if !lo.is_finite() || !hi.is_finite() {
        (lo, hi) = (-1.0, 1.0);
    }
    let (ya, yb, yt) = ticks(lo, hi);
    let (xa, xb, xt) = ticks(0.0, t_end);
    let top = p.top;
    let x = |t: f64| LEFT + (t - xa) / (xb - xa) * PLOT_W;
    let y = |v: f64| top + PLOT_H - (v - ya) / (yb - ya) * PLOT_H;
    let _ = writeln!(
        svg,
        r#"<text x="{LEFT}" y="{:.1}" class="head">{}</text>"#,
        top - 10.0,
        esc(p.title)
    );
    for &v in &yt {
        let class = if v.abs() < 1e-12 * (yb - ya) {
            "zero"
        } else {
            "grid"
        };
        let _ = writeln!(
            svg,
            r#"<line x1="{LEFT}" y1="{0:.1}" x2="{1:.1}" y2="{0:.1}" class="{class}"/><text x="{2:.1}" y="{3:.1}" class="tick" text-anchor="end">{4}</text>"#,
            y(v),
            LEFT + PLOT_W,
            LEFT - 6.0,
            y(v) + 4.0,
            fmt_tick(v)
        );
    }
    for &t in &xt {
        let _ = writeln!(
            svg,
            r#"<line x1="{0:.1}" y1="{top}" x2="{0:.1}" y2="{1:.1}" class="grid"/><text x="{0:.1}" y="{2:.1}" class="tick" text-anchor="middle">{3}</text>"#,
            x(t),
            top + PLOT_H,
            top + PLOT_H + 18.0,
            fmt_tick(t)
        );
    }
    let _ = writeln!(
        svg,
        r#"<rect x="{LEFT}" y="{top}" width="{PLOT_W}" height="{PLOT_H}" class="axis"/>"#
    );
    let _ = writeln!(
        svg,
        r#"<text x="{:.1}" y="{:.1}" class="label" text-anchor="middle">t [s]</text>"#,
        LEFT + PLOT_W / 2.0,
        top + PLOT_H + 38.0
    );
    let _ = writeln!(
        svg,
        r#"<text x="20" y="{0:.1}" class="label" text-anchor="middle" transform="rotate(-90 20 {0:.1})">{1}</text>"#,
        top + PLOT_H / 2.0,
        esc(p.ylabel)
    );
    let stride = samples.len().div_ceil(MAX_POINTS).max(1);
    for (k, &l) in links.iter().enumerate() {
        let colour = PALETTE[k % PALETTE.len()];
        if let Some(lv) = levels {
            let _ = writeln!(
                svg,
                r#"<line x1="{LEFT}" y1="{0:.2}" x2="{1:.1}" y2="{0:.2}" stroke="{colour}" stroke-width="1" stroke-dasharray="5 4"/>"#,
                y(lv(l)),
                LEFT + PLOT_W
            );
        }
        let mut pts = String::new();
        for (i, s) in samples.iter().enumerate() {
            if i % stride == 0 || i + 1 == samples.len() {
                let _ = write!(pts, "{:.2},{:.2} ", x(s.t), y(value(i, l)));
            }
        }
        let _ = writeln!(
            svg,
            r#"<polyline points="{}" fill="none" stroke="{colour}" stroke-width="1.8"/>"#,
            pts.trim_end()
        );
    }
}

/// The plot as an SVG document: the link speeds, and their deviation from
/// the equilibrium when there is one.
pub fn speeds_svg(
    train: &Train,
    title: &str,
    links: &[LinkId],
    sim: &Simulation,
    equilibrium: Option<&[f64]>,
) -> String {
    let samples = &sim.samples;
    let t_end = samples.last().map_or(1.0, |s| s.t).max(f64::MIN_POSITIVE);
    let panels = if equilibrium.is_some() { 2.0 } else { 1.0 };
    let height = TOP + panels * (PLOT_H + GAP) + 10.0;
    let mut svg = String::new();
    let _ = writeln!(
        svg,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH}" height="{height}" viewBox="0 0 {WIDTH} {height}" font-family="sans-serif">"#
    );
    svg.push_str(
        "<style>.grid{stroke:#ddd;stroke-width:1}.zero{stroke:#888;stroke-width:1}.axis{stroke:#333;stroke-width:1.2;fill:none}.tick{font-size:12px;fill:#333}.title{font-size:16px;font-weight:bold}.head{font-size:14px;font-weight:bold;fill:#222}.sub{font-size:12px;fill:#444}.label{font-size:13px}</style>\n",
    );
    let _ = writeln!(
        svg,
        r#"<rect width="{WIDTH}" height="{height}" fill="white"/>"#
    );
    let _ = writeln!(
        svg,
        r#"<text x="{LEFT}" y="28" class="title">{}</text>"#,
        esc(title)
    );
    let eig: Vec<String> = sim.eigenvalues.iter().map(|v| format!("{v:.4}")).collect();
    let _ = writeln!(
        svg,
        r#"<text x="{LEFT}" y="48" class="sub">{}, dt = {:e} s, {} steps; eigenvalues [1/s]: {}; max Willis drift {:.1e}; energy balance {:.1e}</text>"#,
        sim.method,
        sim.dt,
        sim.steps,
        esc(&eig.join(", ")),
        sim.max_drift,
        sim.energy_error
    );
    let speed = |i: usize, l: LinkId| samples[i].speed[l.index()];
    let eq_level = equilibrium.map(|e| move |l: LinkId| e[l.index()]);
    panel(
        &mut svg,
        &Panel {
            top: TOP,
            title: "link speeds (dashed: equilibrium of the curves)",
            ylabel: "speed [rad/s]",
        },
        links,
        sim,
        &speed,
        eq_level.as_ref().map(|f| f as &dyn Fn(LinkId) -> f64),
        t_end,
    );
    if let Some(e) = equilibrium {
        let dev = |i: usize, l: LinkId| samples[i].speed[l.index()] - e[l.index()];
        panel(
            &mut svg,
            &Panel {
                top: TOP + PLOT_H + GAP,
                title: "deviation from the equilibrium",
                ylabel: "speed - equilibrium [rad/s]",
            },
            links,
            sim,
            &dev,
            None,
            t_end,
        );
    }
    for (k, &l) in links.iter().enumerate() {
        let colour = PALETTE[k % PALETTE.len()];
        let ly = TOP + 14.0 + 22.0 * k as f64;
        let _ = writeln!(
            svg,
            r#"<line x1="{0:.1}" y1="{1:.1}" x2="{2:.1}" y2="{1:.1}" stroke="{colour}" stroke-width="2.5"/><text x="{3:.1}" y="{4:.1}" class="label">link {5}</text>"#,
            LEFT + PLOT_W + 20.0,
            ly,
            LEFT + PLOT_W + 44.0,
            LEFT + PLOT_W + 50.0,
            ly + 4.5,
            esc(train.link_name(l))
        );
    }
    if let Some(d) = &sim.diverged {
        let _ = writeln!(
            svg,
            r#"<text x="{:.1}" y="{:.1}" class="label" fill="firebrick">blew up after t = {:e}</text>"#,
            LEFT + 10.0,
            TOP + 20.0,
            d.t
        );
    }
    svg.push_str("</svg>\n");
    svg
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_cover_the_range_with_round_steps() {
        let (a, b, t) = ticks(-185.7, 330.0);
        assert!(a <= -185.7 && b >= 330.0);
        assert!(t.len() >= 3 && t.len() <= 10);
        let (a, b, _) = ticks(5.0, 5.0);
        assert!(a < 5.0 && b > 5.0);
    }
}

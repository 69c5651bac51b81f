//! The Campbell diagram of `egt modes --campbell --plot FILE` (SVG): the
//! elastic natural frequencies as horizontal lines, each mesh's tooth-pass
//! frequency as a ray from the origin over the input speed, and the
//! crossings circled and numbered by mode.

use std::fmt::Write as _;

use egt_views::modes::Report;

use crate::svg::{LEFT, PALETTE, PLOT_H, PLOT_W, TOP, axes, esc, fmt_tick, open_plot, ticks};

/// The diagram as an SVG document (`meshing` present with a range: the
/// caller asked for `--campbell`).
pub fn svg(title: &str, r: &Report) -> String {
    let Some(m) = &r.meshing else {
        return String::new();
    };
    let [lo, hi] = m.range.unwrap_or([0.0, 7000.0]);
    let top_mesh = m
        .orders
        .iter()
        .map(|o| o.hertz_per_rpm * hi)
        .fold(0.0_f64, f64::max);
    // The natural frequencies up to a little above the highest mesh frequency.
    let ceiling = 1.15 * top_mesh.max(f64::MIN_POSITIVE);
    let mut seen = Vec::new();
    let mut above = 0;
    for (k, mode) in r.modes.iter().enumerate() {
        if mode.rigid || mode.group != k {
            continue;
        }
        if mode.hertz <= ceiling {
            seen.push((k, mode.hertz, mode.multiplicity));
        } else {
            above += 1;
        }
    }
    let rows = m.orders.len().div_ceil(2) as f64;
    let height = TOP + PLOT_H + 70.0 + 20.0 * rows;
    let mut out = String::new();
    let subtitle = format!(
        "{} crossing(s) from {} to {} rpm; {} elastic frequency group(s) drawn, {above} above the highest mesh frequency",
        m.crossings.len(),
        fmt_tick(lo),
        fmt_tick(hi),
        seen.len()
    );
    open_plot(&mut out, height, title, &subtitle);
    let _ = writeln!(
        out,
        r#"<text x="{LEFT}" y="{:.1}" class="head">natural frequencies (grey) and tooth-pass frequencies (input `{}`)</text>"#,
        TOP - 10.0,
        esc(&m.input)
    );
    let (x, y) = axes(
        &mut out,
        TOP,
        ticks(lo, hi),
        ticks(0.0, ceiling),
        ["input speed [rpm]", "frequency [Hz]"],
    );
    for &(k, f, mult) in &seen {
        let label = if mult > 1 {
            format!("mode {} (x{mult})", k + 1)
        } else {
            format!("mode {}", k + 1)
        };
        let _ = writeln!(
            out,
            r##"<line x1="{LEFT}" y1="{0:.2}" x2="{1:.1}" y2="{0:.2}" stroke="#777" stroke-width="1.2"/><text x="{2:.1}" y="{3:.1}" class="tick" fill="#555">{4}</text>"##,
            y(f),
            LEFT + PLOT_W,
            LEFT + 4.0,
            y(f) - 3.0,
            esc(&label)
        );
    }
    for (k, o) in m.orders.iter().enumerate() {
        let colour = PALETTE[k % PALETTE.len()];
        let _ = writeln!(
            out,
            r#"<polyline points="{:.2},{:.2} {:.2},{:.2}" fill="none" stroke="{colour}" stroke-width="1.8"/>"#,
            x(lo),
            y(o.hertz_per_rpm * lo),
            x(hi),
            y(o.hertz_per_rpm * hi)
        );
    }
    for c in &m.crossings {
        let k = m.orders.iter().position(|o| o.gear == c.gear).unwrap_or(0);
        let _ = writeln!(
            out,
            r#"<circle cx="{:.2}" cy="{:.2}" r="4.5" fill="none" stroke="{}" stroke-width="2"/>"#,
            x(c.speed),
            y(c.hertz),
            PALETTE[k % PALETTE.len()]
        );
    }
    // The legend under the axis, two columns: the gear pairs' names are long.
    for (k, o) in m.orders.iter().enumerate() {
        let lx = LEFT + 340.0 * (k % 2) as f64;
        let ly = TOP + PLOT_H + 66.0 + 20.0 * (k / 2) as f64;
        let _ = writeln!(
            out,
            r#"<line x1="{lx:.1}" y1="{ly:.1}" x2="{:.1}" y2="{ly:.1}" stroke="{}" stroke-width="2.5"/><text x="{:.1}" y="{:.1}" class="label">{} (order {})</text>"#,
            lx + 24.0,
            PALETTE[k % PALETTE.len()],
            lx + 30.0,
            ly + 4.5,
            esc(&o.gear),
            fmt_tick(o.order)
        );
    }
    out.push_str("</svg>\n");
    out
}

//! The SVG pieces the plots share (`egt simulate --plot`, `egt shift --plot`,
//! `egt shift-sim --plot`): the palette, text escaping, round tick positions
//! and tick labels, and the time-series panel (with shaded stretches of
//! time and marked moments, e.g. a shift's phases and its dip).

use std::fmt::Write as _;

/// A colour-blind-friendly palette (Okabe-Ito and Tol), cycled.
pub const PALETTE: [&str; 12] = [
    "#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#882255", "#117733",
    "#332288", "#999933", "#AA4499", "#44AA99",
];

/// Text escaped for SVG content and attribute values.
pub fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Round tick positions covering [lo, hi].
pub fn ticks(lo: f64, hi: f64) -> (f64, f64, Vec<f64>) {
    let (lo, hi) = if hi - lo < 1e-12 * hi.abs().max(1.0) {
        (lo - 0.5 * lo.abs().max(1.0), hi + 0.5 * hi.abs().max(1.0))
    } else {
        (lo, hi)
    };
    let raw = (hi - lo) / 6.0;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 2.5, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| (hi - lo) / s <= 8.0)
        .unwrap_or(10.0 * mag);
    let (a, b) = ((lo / step).floor() * step, (hi / step).ceil() * step);
    let n = ((b - a) / step).round() as usize;
    (a, b, (0..=n).map(|i| a + i as f64 * step).collect())
}

/// A tick label: short fixed point, scientific outside [1e-3, 1e6).
pub fn fmt_tick(v: f64) -> String {
    if v != 0.0 && (v.abs() < 1e-3 || v.abs() >= 1e6) {
        return format!("{v:.1e}");
    }
    let s = format!("{v:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".into() } else { s.into() }
}

/// Width of a time-series plot.
pub const WIDTH: f64 = 900.0;
/// Left margin of a panel.
pub const LEFT: f64 = 80.0;
/// Top of the first panel.
pub const TOP: f64 = 95.0;
/// Panel width.
pub const PLOT_W: f64 = 660.0;
/// Panel height.
pub const PLOT_H: f64 = 330.0;
/// Space between panels (axis labels and the next panel's heading).
pub const GAP: f64 = 90.0;
/// At most this many points per line.
const MAX_POINTS: usize = 600;
/// The style sheet of the time-series plots.
pub const PLOT_STYLE: &str = "<style>.grid{stroke:#ddd;stroke-width:1}.zero{stroke:#888;stroke-width:1}.axis{stroke:#333;stroke-width:1.2;fill:none}.tick{font-size:12px;fill:#333}.title{font-size:16px;font-weight:bold}.head{font-size:14px;font-weight:bold;fill:#222}.sub{font-size:12px;fill:#444}.label{font-size:13px}</style>\n";

/// A panel's place and words.
pub struct Panel<'a> {
    /// Top edge.
    pub top: f64,
    /// Heading.
    pub title: &'a str,
    /// Y axis label.
    pub ylabel: &'a str,
}

/// One line of a panel: its value at sample `i`, and an optional dashed level.
pub struct Line<'a> {
    /// Value at sample `i`.
    pub value: &'a dyn Fn(usize) -> f64,
    /// A reference level drawn dashed in the line's colour.
    pub level: Option<f64>,
}

/// One line without a level for each of `series`.
pub fn plain_lines<'a>(series: &'a [Box<dyn Fn(usize) -> f64 + 'a>]) -> Vec<Line<'a>> {
    series
        .iter()
        .map(|f| Line {
            value: f.as_ref(),
            level: None,
        })
        .collect()
}

/// A panel's frame at `top`: the grid at the round ticks of x and y (as
/// [`ticks`] gives them), tick labels, the axes box and the axis labels
/// `[x, y]`; returns the maps from values to the panel's x and y.
pub fn axes(
    svg: &mut String,
    top: f64,
    (xa, xb, xt): (f64, f64, Vec<f64>),
    (ya, yb, yt): (f64, f64, Vec<f64>),
    [xlabel, ylabel]: [&str; 2],
) -> (impl Fn(f64) -> f64 + use<>, impl Fn(f64) -> f64 + use<>) {
    let x = move |t: f64| LEFT + (t - xa) / (xb - xa) * PLOT_W;
    let y = move |v: f64| top + PLOT_H - (v - ya) / (yb - ya) * PLOT_H;
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
        r#"<text x="{:.1}" y="{:.1}" class="label" text-anchor="middle">{}</text>"#,
        LEFT + PLOT_W / 2.0,
        top + PLOT_H + 38.0,
        esc(xlabel)
    );
    let _ = writeln!(
        svg,
        r#"<text x="20" y="{0:.1}" class="label" text-anchor="middle" transform="rotate(-90 20 {0:.1})">{1}</text>"#,
        top + PLOT_H / 2.0,
        esc(ylabel)
    );
    (x, y)
}

/// One panel: axes, ticks against time, a coloured line per `lines` entry
/// (colours in order of `PALETTE`), dashed levels.
pub fn panel(
    svg: &mut String,
    p: &Panel<'_>,
    samples: usize,
    time: &dyn Fn(usize) -> f64,
    lines: &[Line<'_>],
    t_end: f64,
) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for line in lines {
        for i in 0..samples {
            let v = (line.value)(i);
            if v.is_finite() {
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
        if let Some(l) = line.level {
            lo = lo.min(l);
            hi = hi.max(l);
        }
    }
    if !lo.is_finite() || !hi.is_finite() {
        (lo, hi) = (-1.0, 1.0);
    }
    let top = p.top;
    let (x, y) = axes(
        svg,
        top,
        ticks(0.0, t_end),
        ticks(lo, hi),
        ["t [s]", p.ylabel],
    );
    let _ = writeln!(
        svg,
        r#"<text x="{LEFT}" y="{:.1}" class="head">{}</text>"#,
        top - 10.0,
        esc(p.title)
    );
    let stride = samples.div_ceil(MAX_POINTS).max(1);
    for (k, line) in lines.iter().enumerate() {
        let colour = PALETTE[k % PALETTE.len()];
        if let Some(l) = line.level {
            let _ = writeln!(
                svg,
                r#"<line x1="{LEFT}" y1="{0:.2}" x2="{1:.1}" y2="{0:.2}" stroke="{colour}" stroke-width="1" stroke-dasharray="5 4"/>"#,
                y(l),
                LEFT + PLOT_W
            );
        }
        let mut pts = String::new();
        for i in 0..samples {
            if i % stride == 0 || i + 1 == samples {
                let _ = write!(pts, "{:.2},{:.2} ", x(time(i)), y((line.value)(i)));
            }
        }
        let _ = writeln!(
            svg,
            r#"<polyline points="{}" fill="none" stroke="{colour}" stroke-width="1.8"/>"#,
            pts.trim_end()
        );
    }
}

/// A stretch of time shaded across a panel (drawn before the panel, so its
/// lines lie on top), with its name at the top left of the stretch.
#[derive(Debug, Clone, Copy)]
pub struct Band<'a> {
    /// Start and end time.
    pub t: [f64; 2],
    /// Fill colour.
    pub colour: &'a str,
    /// Its name, written inside the band.
    pub label: &'a str,
}

/// A moment marked on a panel: a dashed vertical line and a label.
#[derive(Debug, Clone)]
pub struct Mark {
    /// Time.
    pub t: f64,
    /// Label, written beside the line near the panel's bottom.
    pub label: String,
}

/// The time axis's x of `t` on a panel ending at `t_end` (as `panel` draws it).
fn time_x(t: f64, t_end: f64) -> f64 {
    let (xa, xb, _) = ticks(0.0, t_end);
    LEFT + (t - xa) / (xb - xa) * PLOT_W
}

/// `bands` shaded over the panel at `top` whose time axis ends at `t_end`;
/// their names go on rows of their own (a short band's name overruns it).
pub fn bands(svg: &mut String, top: f64, t_end: f64, bands: &[Band<'_>]) {
    for (k, b) in bands.iter().enumerate() {
        let (x0, x1) = (time_x(b.t[0], t_end), time_x(b.t[1], t_end));
        let _ = writeln!(
            svg,
            r#"<rect x="{x0:.2}" y="{top}" width="{:.2}" height="{PLOT_H}" fill="{}" fill-opacity="0.14"/><text x="{:.1}" y="{:.1}" class="tick">{}</text>"#,
            (x1 - x0).max(0.5),
            b.colour,
            x0 + 3.0,
            top + 14.0 + 15.0 * k as f64,
            esc(b.label)
        );
    }
}

/// `marks` on the panel at `top` whose time axis ends at `t_end`, their
/// labels stacked from the bottom up.
pub fn marks(svg: &mut String, top: f64, t_end: f64, marks: &[Mark]) {
    for (k, m) in marks.iter().enumerate() {
        let x = time_x(m.t, t_end);
        let _ = writeln!(
            svg,
            r##"<line x1="{x:.2}" y1="{top}" x2="{x:.2}" y2="{:.1}" stroke="#333" stroke-width="1" stroke-dasharray="3 3"/><text x="{:.1}" y="{:.1}" class="tick">{}</text>"##,
            top + PLOT_H,
            x + 4.0,
            top + PLOT_H - 8.0 - 16.0 * k as f64,
            esc(&m.label)
        );
    }
}

/// A legend to the right of the panels: a colour swatch and a label per line.
pub fn legend(svg: &mut String, labels: &[String]) {
    for (k, label) in labels.iter().enumerate() {
        let colour = PALETTE[k % PALETTE.len()];
        let ly = TOP + 14.0 + 22.0 * k as f64;
        let _ = writeln!(
            svg,
            r#"<line x1="{0:.1}" y1="{1:.1}" x2="{2:.1}" y2="{1:.1}" stroke="{colour}" stroke-width="2.5"/><text x="{3:.1}" y="{4:.1}" class="label">{5}</text>"#,
            LEFT + PLOT_W + 20.0,
            ly,
            LEFT + PLOT_W + 44.0,
            LEFT + PLOT_W + 50.0,
            ly + 4.5,
            esc(label)
        );
    }
}

/// Opens a time-series plot document of `height`: the style sheet, a white
/// background, the title and a subtitle line.
pub fn open_plot(svg: &mut String, height: f64, title: &str, subtitle: &str) {
    let _ = writeln!(
        svg,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH}" height="{height}" viewBox="0 0 {WIDTH} {height}" font-family="sans-serif">"#
    );
    svg.push_str(PLOT_STYLE);
    let _ = writeln!(
        svg,
        r#"<rect width="{WIDTH}" height="{height}" fill="white"/>"#
    );
    let _ = writeln!(
        svg,
        r#"<text x="{LEFT}" y="28" class="title">{}</text>"#,
        esc(title)
    );
    let _ = writeln!(
        svg,
        r#"<text x="{LEFT}" y="48" class="sub">{}</text>"#,
        esc(subtitle)
    );
}

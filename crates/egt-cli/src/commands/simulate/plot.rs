//! The SVG plot of `egt simulate --plot`: every link's speed against time,
//! one coloured line per link, with the equilibrium of the curves as dashed
//! lines of the same colour, and below it the deviation from that
//! equilibrium, so convergence (or divergence) reads at a glance.
//! Plain SVG, no dependencies.

use std::fmt::Write as _;

use crate::svg::{GAP, LEFT, Line, PLOT_H, Panel, TOP, panel, plain_lines};
use egt_core::{LinkId, Simulation, Train};

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
    let eig: Vec<String> = sim.eigenvalues.iter().map(|v| format!("{v:.4}")).collect();
    let subtitle = format!(
        "{}, dt = {:e} s, {} steps; eigenvalues [1/s]: {}; max Willis drift {:.1e}; energy balance {:.1e}",
        sim.method,
        sim.dt,
        sim.steps,
        eig.join(", "),
        sim.max_drift,
        sim.energy_error
    );
    crate::svg::open_plot(&mut svg, height, title, &subtitle);
    let time = |i: usize| samples[i].t;
    let speeds: Vec<Box<dyn Fn(usize) -> f64 + '_>> = links
        .iter()
        .map(|&l| {
            Box::new(move |i: usize| samples[i].speed[l.index()]) as Box<dyn Fn(usize) -> f64>
        })
        .collect();
    let lines: Vec<Line<'_>> = links
        .iter()
        .zip(&speeds)
        .map(|(&l, f)| Line {
            value: f.as_ref(),
            level: equilibrium.map(|e| e[l.index()]),
        })
        .collect();
    panel(
        &mut svg,
        &Panel {
            top: TOP,
            title: "link speeds (dashed: equilibrium of the curves)",
            ylabel: "speed [rad/s]",
        },
        samples.len(),
        &time,
        &lines,
        t_end,
    );
    if let Some(e) = equilibrium {
        let devs: Vec<Box<dyn Fn(usize) -> f64 + '_>> = links
            .iter()
            .map(|&l| {
                Box::new(move |i: usize| samples[i].speed[l.index()] - e[l.index()])
                    as Box<dyn Fn(usize) -> f64>
            })
            .collect();
        let lines = plain_lines(&devs);
        panel(
            &mut svg,
            &Panel {
                top: TOP + PLOT_H + GAP,
                title: "deviation from the equilibrium",
                ylabel: "speed - equilibrium [rad/s]",
            },
            samples.len(),
            &time,
            &lines,
            t_end,
        );
    }
    let labels: Vec<String> = links
        .iter()
        .map(|&l| format!("link {}", train.link_name(l)))
        .collect();
    crate::svg::legend(&mut svg, &labels);
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
    use crate::svg::ticks;

    #[test]
    fn ticks_cover_the_range_with_round_steps() {
        let (a, b, t) = ticks(-185.7, 330.0);
        assert!(a <= -185.7 && b >= 330.0);
        assert!(t.len() >= 3 && t.len() <= 10);
        let (a, b, _) = ticks(5.0, 5.0);
        assert!(a < 5.0 && b > 5.0);
    }
}

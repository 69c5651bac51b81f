//! Where a spec's scenarios come from: `--set`, `--vary` and `--grid`
//! values parsed, and the design they make (a product of zipped arrays and
//! grid axes, or the lines of a `--rows` file), filled into blocks.

use std::path::PathBuf;

use anyhow::Context;
use egt_core::batch::BatchPlan;
use egt_core::{Error, SpecErrorKind};

use super::Args;
use super::order::size_global_pool;
use super::rows;

pub(super) fn parse_set(s: &str) -> Result<(String, f64), String> {
    let (name, v) = split(s)?;
    let v: f64 = v.parse().map_err(|_| format!("`{v}` is not a number"))?;
    Ok((name, v))
}

pub(super) fn split(s: &str) -> Result<(String, &str), String> {
    let (n, v) = s
        .split_once('=')
        .ok_or_else(|| format!("expected NAME=VALUE, got `{s}`"))?;
    if n.trim().is_empty() {
        return Err(format!("no parameter name in `{s}`"));
    }
    Ok((n.trim().to_string(), v.trim()))
}

/// Most values one `--vary` array or `--grid` axis may hold (80 MB of
/// doubles): a larger sweep is a product of axes, bounded by `--max-rows`.
pub(super) const MAX_AXIS_VALUES: usize = 10_000_000;

/// The default of `--max-rows`: the scenarios a design may make.
pub const DEFAULT_MAX_ROWS: u64 = 1_000_000_000;

pub(super) fn parse_values(s: &str) -> Result<(String, Vec<f64>), String> {
    let (name, v) = split(s)?;
    let num = |x: &str| -> Result<f64, String> {
        x.trim()
            .parse::<f64>()
            .map_err(|_| format!("`{}` is not a number", x.trim()))
    };
    let values = if v.contains(':') {
        let parts: Vec<&str> = v.split(':').collect();
        let [a, b, n] = parts[..] else {
            return Err(format!("expected START:STOP:COUNT, got `{v}`"));
        };
        let (a, b) = (num(a)?, num(b)?);
        let n: usize = n
            .trim()
            .parse()
            .ok()
            .filter(|&n| n >= 1)
            .ok_or_else(|| format!("COUNT must be a positive integer, got `{n}`"))?;
        if n > MAX_AXIS_VALUES {
            return Err(format!(
                "COUNT {n} is more than {MAX_AXIS_VALUES} values for one array or axis; \
                 make a larger sweep a product of --grid axes"
            ));
        }
        (0..n)
            .map(|i| {
                if n == 1 {
                    a
                } else {
                    a + (b - a) * i as f64 / (n - 1) as f64
                }
            })
            .collect()
    } else {
        v.split(',').map(num).collect::<Result<Vec<_>, _>>()?
    };
    if let Some(bad) = values.iter().find(|x| !x.is_finite()) {
        return Err(format!("`{bad}` for `{name}` is not a finite number"));
    }
    if values.is_empty() {
        return Err(format!("no values for `{name}`"));
    }
    Ok((name, values))
}

/// Where each scenario's overrides come from.
pub(super) struct Design {
    /// Parameter columns (in the plans' layout) that vary, in output order.
    pub(super) varied: Vec<(String, usize)>,
    /// Per scenario: overrides (column, value), or why the row is unreadable.
    pub(super) rows: Rows,
}

pub(super) enum Rows {
    /// Zipped arrays times grid axes: row i by mixed radix.
    Product {
        zipped: Vec<(usize, Vec<f64>)>,
        axes: Vec<(usize, Vec<f64>)>,
        count: usize,
    },
    /// Parsed lines of a `--rows` file.
    Listed(rows::Listed),
}

impl Rows {
    pub(super) fn count(&self) -> usize {
        match self {
            Rows::Product { count, .. } => *count,
            Rows::Listed(lines) => lines.len(),
        }
    }

    /// Apply row `i`'s overrides to `row`; Err for an unreadable line.
    pub(super) fn apply(&self, i: usize, row: &mut [f64]) -> Result<(), String> {
        self.set(i, |c, v| row[c] = v)
    }

    /// Row `i`'s values, `set(column, value)`.
    pub(super) fn set(&self, i: usize, mut set: impl FnMut(usize, f64)) -> Result<(), String> {
        match self {
            Rows::Product { zipped, axes, .. } => {
                let zl = zipped.first().map_or(1, |z| z.1.len());
                let mut r = i;
                for (c, vals) in axes.iter().rev() {
                    set(*c, vals[r % vals.len()]);
                    r /= vals.len();
                }
                for (c, vals) in zipped {
                    set(*c, vals[r % zl]);
                }
                Ok(())
            }
            Rows::Listed(lines) => match lines.line(i) {
                Ok(values) => {
                    for &(c, x) in values {
                        set(c, x);
                    }
                    Ok(())
                }
                Err(e) => Err(e.to_string()),
            },
        }
    }

    /// Rows `start..start + len` of a grid or zip into `params`, column-major
    /// (`len` rows a column) or row-major (`width` columns a row), as
    /// [`Rows::set`] gives them: each varied column is filled in runs of
    /// equal values, with no division per row (which cost about a tenth of
    /// a 10^6-row Parquet batch). False for a `--rows` file, which is set
    /// line by line.
    pub(super) fn fill(
        &self,
        (start, len): (usize, usize),
        params: &mut [f64],
        by: Layout<'_>,
    ) -> bool {
        let Rows::Product { zipped, axes, .. } = self else {
            return false;
        };
        let mut fill = |c: usize, vals: &[f64], stride: usize| {
            // (Every column a product sets is a varied one.)
            let (c, by) = match by {
                Layout::Varied(slot) => match slot[c] {
                    Some(j) => (j, Layout::Columns),
                    None => return,
                },
                by => (c, by),
            };
            if vals.is_empty() || stride == 0 {
                return;
            }
            if let (1, Layout::Columns) = (stride, by) {
                // The last axis: its values in turn, copied in runs.
                let column = &mut params[c * len..][..len];
                let (mut k, mut r) = (start % vals.len(), 0);
                while r < len {
                    let n = (vals.len() - k).min(len - r);
                    column[r..r + n].copy_from_slice(&vals[k..k + n]);
                    (r, k) = (r + n, 0);
                }
                return;
            }
            let mut k = (start / stride) % vals.len();
            let mut r = 0;
            let mut run = stride - start % stride;
            while r < len {
                let end = len.min(r + run);
                match by {
                    Layout::Columns | Layout::Varied(_) => params[c * len..][r..end].fill(vals[k]),
                    Layout::Rows(width) => (params[r * width + c..end * width].iter_mut())
                        .step_by(width)
                        .for_each(|x| *x = vals[k]),
                }
                (r, run) = (end, stride);
                k = if k + 1 == vals.len() { 0 } else { k + 1 };
            }
        };
        // Row i takes the last axis's value i % L, the one before's
        // (i / L) % L', and the zipped arrays' (i / all axes) % their length.
        let mut stride = 1usize;
        for (c, vals) in axes.iter().rev() {
            fill(*c, vals, stride);
            stride = stride.saturating_mul(vals.len());
        }
        for (c, vals) in zipped {
            fill(*c, vals, stride);
        }
        true
    }
}

/// How a block's parameters are laid out ([`Rows::fill`]).
#[derive(Clone, Copy)]
pub(super) enum Layout<'a> {
    /// Column-major, a column for each parameter.
    Columns,
    /// Column-major, a column for each varied parameter only: parameter
    /// `c`'s is column `slot[c]` (the others are the base row's values).
    Varied(&'a [Option<usize>]),
    /// Row-major, this many columns a row.
    Rows(usize),
}

pub(super) fn unknown(plan: &BatchPlan, name: &str, flag: &str) -> Error {
    let hint = egt_core::error::suggest(name, plan.parameters().iter().map(String::as_str))
        .map(|s| format!(" (did you mean `{s}`?)"))
        .unwrap_or_default();
    Error::spec(
        flag,
        SpecErrorKind::Invalid {
            message: format!(
                "unknown parameter `{name}`{hint}; `egt batch SPEC --list` lists them"
            ),
        },
    )
}

/// A usage error of `egt batch` naming its flag (exit 2).
fn refuse(flag: &str, message: String) -> Error {
    Error::spec(flag, SpecErrorKind::Invalid { message })
}

pub(super) fn design(args: &Args, plan: &BatchPlan) -> anyhow::Result<Design> {
    let col = |name: &str, flag: &str| {
        plan.parameter(name)
            .ok_or_else(|| unknown(plan, name, flag))
    };
    let mut varied: Vec<(String, usize)> = Vec::new();
    // A parameter is given once: a second `--vary`, `--grid` or `--set` of
    // it would silently win over the first.
    let mut given: Vec<(usize, &str)> = Vec::new();
    let mut once = |name: &str, c: usize, flag: &'static str| -> Result<(), Error> {
        if let Some((_, first)) = given.iter().find(|g| g.0 == c) {
            return Err(refuse(
                flag,
                format!(
                    "`{name}` is given twice (by {first} and by {flag}); give each parameter once"
                ),
            ));
        }
        given.push((c, flag));
        Ok(())
    };
    for (name, _) in &args.set {
        once(name, col(name, "--set")?, "--set")?;
    }
    let mut note = |name: &str, c: usize| {
        if !varied.iter().any(|v| v.1 == c) {
            varied.push((name.to_string(), c));
        }
    };
    if let Some(path) = &args.rows {
        let text = read(path)?;
        let lines: Vec<(usize, &str)> = text
            .lines()
            .enumerate()
            .filter(|(_, l)| !l.trim().is_empty())
            .collect();
        // Parsed in parallel; the varied columns noted in line order.
        size_global_pool(args.threads);
        let rows = rows::parse(&lines, plan, &path.display().to_string());
        for &(c, _) in rows.overrides() {
            note(&plan.parameters()[c], c);
        }
        return Ok(Design {
            varied,
            rows: Rows::Listed(rows),
        });
    }
    let mut zipped = Vec::new();
    for (name, vals) in &args.vary {
        let c = col(name, "--vary")?;
        once(name, c, "--vary")?;
        if let Some(first) = zipped.first().map(|z: &(usize, Vec<f64>)| z.1.len())
            && first != vals.len()
        {
            return Err(refuse(
                "--vary",
                format!(
                    "--vary arrays are zipped and must have equal lengths: `{name}` has {}, the first has {first}",
                    vals.len()
                ),
            )
            .into());
        }
        note(name, c);
        zipped.push((c, vals.clone()));
    }
    let mut axes = Vec::new();
    // Counted without overflow, and bounded before any row is made.
    let mut count: u128 = zipped.first().map_or(1, |z| z.1.len() as u128);
    for (name, vals) in &args.grid {
        let c = col(name, "--grid")?;
        once(name, c, "--grid")?;
        note(name, c);
        count = count.saturating_mul(vals.len() as u128);
        axes.push((c, vals.clone()));
    }
    if count > u128::from(args.max_rows) {
        return Err(refuse(
            "--grid",
            format!(
                "the design makes {count} scenarios, more than --max-rows {} allows; \
                 raise it with --max-rows if that many are meant",
                args.max_rows
            ),
        )
        .into());
    }
    let count = usize::try_from(count).map_err(|_| {
        refuse(
            "--max-rows",
            format!("{count} scenarios do not fit this machine's addresses"),
        )
    })?;
    Ok(Design {
        varied,
        rows: Rows::Product {
            zipped,
            axes,
            count,
        },
    })
}

pub(super) fn read(path: &PathBuf) -> anyhow::Result<String> {
    if path.as_os_str() == "-" {
        let mut s = String::new();
        std::io::Read::read_to_string(&mut std::io::stdin(), &mut s)
            .context("reading standard input")?;
        return Ok(s);
    }
    std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))
}

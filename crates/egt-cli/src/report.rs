//! Output helpers: aligned plain-text tables, number formatting (floats and
//! exact fractions) and JSON printing. Commands build named result structs
//! and choose table or JSON here; nothing else formats numbers.

use std::io::{self, Write};

use egt_core::Train;
use serde::Serialize;

pub use egt_views::format::{exact, float, sci, value_of};

/// Column alignment.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Align {
    Left,
    Right,
}

/// A plain-text table: a header line, a rule, then rows, columns padded to
/// the widest cell (numbers right-aligned).
#[derive(Debug, Clone)]
pub struct Table {
    headers: Vec<String>,
    align: Vec<Align>,
    rows: Vec<Vec<String>>,
}

impl Table {
    /// A table with these column headers, all left-aligned.
    pub fn new(headers: &[&str]) -> Self {
        Table {
            headers: headers.iter().map(|h| (*h).to_string()).collect(),
            align: vec![Align::Left; headers.len()],
            rows: Vec::new(),
        }
    }

    /// Right-align these columns (numbers).
    pub fn right(mut self, cols: &[usize]) -> Self {
        for &c in cols {
            if let Some(a) = self.align.get_mut(c) {
                *a = Align::Right;
            }
        }
        self
    }

    /// Append a row (missing cells print empty).
    pub fn row(&mut self, cells: Vec<String>) {
        self.rows.push(cells);
    }

    /// Write the table, each line indented by `indent` spaces.
    pub fn write(&self, out: &mut dyn Write, indent: usize) -> io::Result<()> {
        let n = self.headers.len();
        let mut width: Vec<usize> = self.headers.iter().map(|h| h.chars().count()).collect();
        for r in &self.rows {
            for (c, cell) in r.iter().enumerate().take(n) {
                width[c] = width[c].max(cell.chars().count());
            }
        }
        let pad = " ".repeat(indent);
        let line = |out: &mut dyn Write, cells: &[String]| -> io::Result<()> {
            let mut s = String::new();
            for (c, (w, align)) in width.iter().zip(&self.align).enumerate() {
                let cell = cells.get(c).map_or("", String::as_str);
                let fill = " ".repeat(w - cell.chars().count());
                if c > 0 {
                    s.push_str("  ");
                }
                match align {
                    Align::Left => {
                        s.push_str(cell);
                        s.push_str(&fill);
                    }
                    Align::Right => {
                        s.push_str(&fill);
                        s.push_str(cell);
                    }
                }
            }
            writeln!(out, "{pad}{}", s.trim_end())
        };
        line(out, &self.headers)?;
        let rule: Vec<String> = width.iter().map(|w| "-".repeat(*w)).collect();
        line(out, &rule)?;
        for r in &self.rows {
            line(out, r)?;
        }
        Ok(())
    }
}

/// Write `value` as pretty JSON followed by a newline.
///
/// # Errors
/// I/O errors (a closed pipe among them).
pub fn json(out: &mut dyn Write, value: &impl Serialize) -> anyhow::Result<()> {
    json_document(out, &value_of(value)?)
}

/// Pretty JSON of a document as it is (the JSON Schema, which carries no version field).
///
/// # Errors
/// I/O errors (a closed pipe included, recognised in `main`).
pub fn json_document(out: &mut dyn Write, value: &impl Serialize) -> anyhow::Result<()> {
    // An I/O failure inside serde_json becomes the io::Error again, so that a
    // closed pipe is recognised in `main`.
    serde_json::to_writer_pretty(&mut *out, value).map_err(|e| {
        if e.is_io() {
            anyhow::Error::from(std::io::Error::from(e))
        } else {
            e.into()
        }
    })?;
    writeln!(out)?;
    Ok(())
}

/// The train's name, or the source it came from.
pub fn title(train: &Train, source: &str) -> String {
    train
        .name()
        .map_or_else(|| source.to_string(), str::to_string)
}

/// A link name safe in a CSV header (quotes and commas replaced).
pub fn csv_name(n: &str) -> String {
    n.chars()
        .map(|c| {
            if c == ',' || c == '"' || c.is_whitespace() {
                '_'
            } else {
                c
            }
        })
        .collect()
}

/// Write the circuit table, indented by `indent`.
///
/// # Errors
/// I/O errors.
pub fn circuit_table(
    out: &mut dyn Write,
    rows: &[egt_views::circuits::CircuitRow],
    indent: usize,
) -> io::Result<()> {
    let mut t = Table::new(&[
        "#m",
        "gear pair",
        "gear i",
        "gear j",
        "transfer vertex k",
        "ratio tau",
        "exact",
        "levels i/j",
    ])
    .right(&[0, 5, 6]);
    for r in rows {
        t.row(vec![
            format!("#{}", r.m),
            r.gear_pair.clone(),
            r.gear_i.clone(),
            r.gear_j.clone(),
            r.carrier.clone(),
            match (&r.ratio_symbolic, r.ratio) {
                (Some(sym), _) => sym.clone(),
                (None, Some(x)) => float(x),
                (None, None) => "?".to_string(),
            },
            r.ratio_exact.clone().unwrap_or_else(|| "-".to_string()),
            format!("{}, {}", r.level_i, r.level_j),
        ]);
    }
    t.write(out, indent)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_pads_and_right_aligns() {
        let mut t = Table::new(&["name", "x"]).right(&[1]);
        t.row(vec!["a".into(), "1".into()]);
        t.row(vec!["long".into(), "10.5".into()]);
        let mut out = Vec::new();
        t.write(&mut out, 0).expect("write to a Vec");
        let s = String::from_utf8(out).expect("utf8");
        assert_eq!(s, "name     x\n----  ----\na        1\nlong  10.5\n");
    }
}

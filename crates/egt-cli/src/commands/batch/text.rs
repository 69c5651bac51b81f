//! JSON Lines and CSV: a block's rows formatted as text, numbers as the
//! shortest decimals that read back.

use std::fmt::Write as _;

use egt_core::batch::{BatchPlan, Threads};
use rayon::prelude::*;

use super::design::Design;
use super::warning;

/// Rows formatted per parallel task.
pub(super) const FORMAT_TASK: usize = 1024;

/// A JSON string literal.
pub(super) fn quoted(s: &str) -> String {
    serde_json::to_string(s).unwrap_or_else(|_| "\"?\"".into())
}

/// A CSV field (quoted when needed).
pub(super) fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// A number as JSON (null when not finite) or CSV (empty when not finite),
/// as `{v:?}` writes it: the shortest decimal that reads back as `v`.
pub(super) fn number(buf: &mut String, v: f64, json: bool) {
    if !v.is_finite() {
        if json {
            buf.push_str("null");
        }
    } else if v == 0.0 || (1e-4..1e16).contains(&v.abs()) {
        plain_decimal(buf, v);
    } else {
        let _ = write!(buf, "{v:?}");
    }
}

/// `{v:?}` of a number it writes as a plain decimal (zero, or 1e-4 <= |v| <
/// 1e16: most of a batch's numbers), written by zmij (dtolnay's Schubfach
/// port, which serde_json uses), several times faster. (Outside that range
/// zmij spells the exponent otherwise, "1e+16" and "0.00001" for 1e-5.)
///
/// The two differ only where two shortest decimals are equally near `v`:
/// zmij writes the one with an even last digit, `{v:?}` the one greater in
/// magnitude, and so does this. That happens when the lowest set bit of `v`
/// is one binary place below its last decimal place, so that `v` times ten
/// to the decimal places is an odd number of halves. (Tested on half a
/// million numbers; a release build of the same code agreed with `{v:?}` on
/// 156 million, docs/performance.md (history: git log -p -- docs/benchmarks.md).)
pub(super) fn plain_decimal(buf: &mut String, v: f64) {
    let mut digits = zmij::Buffer::new();
    let text = digits.format_finite(v);
    buf.push_str(text);
    // |v| = odd 2^exponent (normal: |v| >= 1e-4). A tie needs 1 to 21
    // decimal places (17 digits from 1e-4 on), so -22 <= exponent <= -2: a
    // computed number, with bits far below, is passed at once.
    let bits = v.abs().to_bits();
    let mantissa = (bits & ((1 << 52) - 1)) | (1 << 52);
    let shift = mantissa.trailing_zeros();
    let (odd, exponent) = (mantissa >> shift, (bits >> 52) as i32 - 1075 + shift as i32);
    if !(-22..=-2).contains(&exponent) {
        return;
    }
    let Some((_, fraction)) = text.split_once('.') else {
        return;
    };
    let places = fraction.len() as i32;
    if exponent != -(places + 1) {
        return;
    }
    // |v| 10^places = odd 5^places / 2: zmij wrote the lower of the two
    // when twice its digits fall short of that.
    let written =
        (text.bytes().filter(u8::is_ascii_digit)).fold(0u128, |n, d| n * 10 + u128::from(d - b'0'));
    if 2 * written < u128::from(odd) * 5u128.pow(places.unsigned_abs()) {
        // Its last digit is even (zmij's choice): one more carries nothing.
        if let Some(last) = buf.pop() {
            buf.push(char::from(last as u8 + 1));
        }
    }
}

/// What the text writers of one block share.
pub(super) struct TextBlock<'a> {
    pub(super) json: bool,
    pub(super) base_row: usize,
    pub(super) state: Option<&'a str>,
    pub(super) design: &'a Design,
    pub(super) keys: &'a [String],
    pub(super) okeys: &'a [String],
    pub(super) header_len: usize,
    /// The plan's CSV positions and its selected outputs.
    pub(super) positions: (&'a [usize], &'a [usize]),
}

/// A block as JSON Lines or CSV, in pieces of [`FORMAT_TASK`] rows, in
/// order: parallel tasks on rayon's global pool (`within` a pool: a lone
/// block), or on this thread (blocks run in parallel, or one thread).
pub(super) fn format_text(
    t: TextBlock<'_>,
    plan: &BatchPlan,
    (params, np): (&[f64], usize),
    (results, nq): (&[f64], usize),
    messages: &[Option<String>],
    within: Threads,
) -> Vec<String> {
    let sel = t.positions.1;
    let piece = |k: usize, res: &[f64], par: &[f64], msgs: &[Option<String>]| {
        let mut buf = String::with_capacity(res.len() * 24);
        for (r, ((o, p), m)) in res.chunks(nq).zip(par.chunks(np)).zip(msgs).enumerate() {
            let fmt = Row {
                row: t.base_row + k * FORMAT_TASK + r,
                state: t.state,
                varied: &t.design.varied,
                keys: t.keys,
                params: p,
            };
            if t.json {
                fmt.json(&mut buf, t.okeys, sel, plan, o, m.as_deref());
            } else {
                fmt.csv(&mut buf, t.header_len, t.positions, plan, o, m.as_deref());
            }
        }
        buf
    };
    match within {
        Threads::Pool => (results.par_chunks(nq * FORMAT_TASK))
            .zip(params.par_chunks(np * FORMAT_TASK))
            .zip(messages.par_chunks(FORMAT_TASK))
            .enumerate()
            .map(|(k, ((res, par), msgs))| piece(k, res, par, msgs))
            .collect(),
        Threads::Calling => (results.chunks(nq * FORMAT_TASK))
            .zip(params.chunks(np * FORMAT_TASK))
            .zip(messages.chunks(FORMAT_TASK))
            .enumerate()
            .map(|(k, ((res, par), msgs))| piece(k, res, par, msgs))
            .collect(),
    }
}

/// One output row's identity and inputs.
pub(super) struct Row<'a> {
    row: usize,
    state: Option<&'a str>,
    varied: &'a [(String, usize)],
    keys: &'a [String],
    params: &'a [f64],
}

impl Row<'_> {
    fn json(
        &self,
        buf: &mut String,
        okeys: &[String],
        sel: &[usize],
        plan: &BatchPlan,
        o: &[f64],
        error: Option<&str>,
    ) {
        let _ = write!(buf, "{{\"row\":{}", self.row);
        if let Some(s) = self.state {
            let _ = write!(buf, ",\"state\":{}", quoted(s));
        }
        for (k, (_, c)) in self.keys.iter().zip(self.varied) {
            let _ = write!(buf, ",{k}:");
            number(buf, self.params[*c], true);
        }
        match error {
            Some(e) => {
                let _ = write!(buf, ",\"error\":{}", quoted(e));
            }
            None => {
                for &i in sel {
                    let _ = write!(buf, ",{}:", okeys[i]);
                    number(buf, o[i], true);
                }
                if let Some(w) = warning(plan, o) {
                    let _ = write!(buf, ",\"warning\":{}", quoted(&w));
                }
            }
        }
        buf.push_str("}\n");
    }

    fn csv(
        &self,
        buf: &mut String,
        width: usize,
        cols: (&[usize], &[usize]),
        plan: &BatchPlan,
        o: &[f64],
        error: Option<&str>,
    ) {
        let (positions, sel) = cols;
        let _ = write!(buf, "{}", self.row);
        if let Some(s) = self.state {
            let _ = write!(buf, ",{}", csv_field(s));
        }
        for (_, c) in self.varied {
            buf.push(',');
            number(buf, self.params[*c], false);
        }
        let mut cells = vec![f64::NAN; width];
        if error.is_none() {
            for (&p, &i) in positions.iter().zip(sel) {
                cells[p] = o[i];
            }
        }
        for v in cells {
            buf.push(',');
            number(buf, v, false);
        }
        let w = if error.is_none() {
            warning(plan, o)
        } else {
            None
        };
        let _ = writeln!(
            buf,
            ",{},{}",
            csv_field(w.as_deref().unwrap_or("")),
            csv_field(error.unwrap_or(""))
        );
    }
}

//! The lines of a `--rows` file, parsed in parallel, [`TASK`] lines a task,
//! each task's into one flat list of (column, value) overrides.
//!
//! Each line is a JSON object of parameter values. It is read key by key
//! with the keys borrowed from the line where they have no escapes, into a
//! buffer each task reuses, and the task's overrides are appended to its
//! list: no map and no vector a line, and the lists are kept as the tasks
//! left them. (A map and a vector a line took about twice as long, much of
//! it the kernel clearing fresh pages; docs/performance.md (history: git log -p -- docs/benchmarks.md).)

use std::borrow::Cow;
use std::collections::BTreeMap;
use std::fmt;

use egt_core::batch::BatchPlan;
use rayon::prelude::*;
use serde::de::{DeserializeSeed, Deserializer, MapAccess, Visitor};

/// Lines parsed in one task.
const TASK: usize = 4096;

/// Parsed lines of a `--rows` file, as the tasks that parsed them left
/// them: line `i` is line `i % TASK` of part `i / TASK`.
pub(super) struct Listed {
    parts: Vec<Part>,
}

/// [`TASK`] lines (the last part fewer): line `j` sets
/// `values[starts[j]..starts[j + 1]]`, unless it is in `errors`.
struct Part {
    values: Vec<(usize, f64)>,
    starts: Vec<usize>,
    errors: BTreeMap<usize, String>,
}

impl Listed {
    /// No lines.
    #[cfg(test)]
    pub(super) fn empty() -> Self {
        Listed { parts: Vec::new() }
    }

    /// How many lines.
    pub(super) fn len(&self) -> usize {
        self.parts.iter().map(|p| p.starts.len() - 1).sum()
    }

    /// Line `i`'s overrides, or why it is unreadable.
    pub(super) fn line(&self, i: usize) -> Result<&[(usize, f64)], &str> {
        let (part, j) = (&self.parts[i / TASK], i % TASK);
        match part.errors.get(&j) {
            Some(e) => Err(e),
            None => Ok(&part.values[part.starts[j]..part.starts[j + 1]]),
        }
    }

    /// Every override of the readable lines, in line order.
    pub(super) fn overrides(&self) -> impl Iterator<Item = &(usize, f64)> {
        self.parts.iter().flat_map(|p| &p.values)
    }
}

/// Parses `lines` (each with its line number in `path`, from 0) against
/// `plan`'s parameters. A line that is not a JSON object, names a parameter
/// the plan does not have, or gives a value that is not a number is
/// unreadable, with a message naming the file, the line and the key.
pub(super) fn parse(lines: &[(usize, &str)], plan: &BatchPlan, path: &str) -> Listed {
    let parts = lines
        .par_chunks(TASK)
        .map(|chunk| {
            let mut part = Part {
                values: Vec::with_capacity(chunk.len() * 2),
                starts: Vec::with_capacity(chunk.len() + 1),
                errors: BTreeMap::new(),
            };
            part.starts.push(0);
            let mut entries = Vec::new();
            for (j, &(k, line)) in chunk.iter().enumerate() {
                let at = part.values.len();
                if let Err(e) = read_line(line, plan, &mut entries, &mut part.values) {
                    part.values.truncate(at);
                    part.errors.insert(j, format!("{path}:{}: {e}", k + 1));
                }
                part.starts.push(part.values.len());
            }
            part
        })
        .collect();
    Listed { parts }
}

/// Appends the overrides of one line to `values`. `entries` is a buffer
/// for the line's keys and values: the whole line is read first, so that a
/// syntax error anywhere is the one reported; a key given twice keeps its
/// first place and its last value (as a JSON object read into a map).
fn read_line<'a>(
    line: &'a str,
    plan: &BatchPlan,
    entries: &mut Vec<(Cow<'a, str>, serde_json::Value)>,
    values: &mut Vec<(usize, f64)>,
) -> Result<(), String> {
    entries.clear();
    let mut de = serde_json::Deserializer::from_str(line);
    Entries(entries)
        .deserialize(&mut de)
        .and_then(|()| de.end())
        .map_err(|e| e.to_string())?;
    keep_first_places_and_last_values(entries);
    for (name, v) in entries.iter() {
        let c = plan
            .parameter(name)
            .ok_or_else(|| super::design::unknown(plan, name, "--rows").to_string())?;
        let x = v
            .as_f64()
            .ok_or_else(|| format!("`{name}` is not a number"))?;
        values.push((c, x));
    }
    Ok(())
}

/// Reads a JSON object into a list of entries.
struct Entries<'b, 'a>(&'b mut Vec<(Cow<'a, str>, serde_json::Value)>);

impl<'de, 'b> DeserializeSeed<'de> for Entries<'b, 'de> {
    type Value = ();

    fn deserialize<D: Deserializer<'de>>(self, deserializer: D) -> Result<(), D::Error> {
        deserializer.deserialize_map(self)
    }
}

impl<'de, 'b> Visitor<'de> for Entries<'b, 'de> {
    type Value = ();

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a map")
    }

    fn visit_map<M: MapAccess<'de>>(self, mut map: M) -> Result<(), M::Error> {
        while let Some(Key(name)) = map.next_key()? {
            self.0.push((name, map.next_value()?));
        }
        Ok(())
    }
}

/// Of keys given more than once, keeps the first place and the last value,
/// as a JSON object read into a map does: by comparing names on a short
/// line, by a hash map of the first places on a long one (a large train's
/// line may set thousands of parameters).
fn keep_first_places_and_last_values(entries: &mut Vec<(Cow<'_, str>, serde_json::Value)>) {
    let short = entries.len() <= 16;
    let twice = |i: usize| (0..i).any(|j| entries[j].0 == entries[i].0);
    if short && !(1..entries.len()).any(twice) {
        return;
    }
    let first: Vec<usize> = if short {
        (0..entries.len())
            .map(|i| (0..i).find(|&j| entries[j].0 == entries[i].0).unwrap_or(i))
            .collect()
    } else {
        let mut seen = std::collections::HashMap::with_capacity(entries.len());
        (0..entries.len())
            .map(|i| *seen.entry(&*entries[i].0).or_insert(i))
            .collect()
    };
    if first.iter().enumerate().all(|(i, &f)| f == i) {
        return;
    }
    for (i, &f) in first.iter().enumerate() {
        if f != i {
            let value = std::mem::take(&mut entries[i].1);
            entries[f].1 = value;
        }
    }
    let mut i = 0;
    entries.retain(|_| {
        i += 1;
        first[i - 1] == i - 1
    });
}

/// A key, borrowed from the line when it has no escapes.
struct Key<'a>(Cow<'a, str>);

impl<'de> serde::Deserialize<'de> for Key<'de> {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Text;
        impl<'de> Visitor<'de> for Text {
            type Value = Key<'de>;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a string")
            }
            fn visit_borrowed_str<E>(self, v: &'de str) -> Result<Key<'de>, E> {
                Ok(Key(Cow::Borrowed(v)))
            }
            fn visit_str<E>(self, v: &str) -> Result<Key<'de>, E> {
                Ok(Key(Cow::Owned(v.to_string())))
            }
            fn visit_string<E>(self, v: String) -> Result<Key<'de>, E> {
                Ok(Key(Cow::Owned(v)))
            }
        }
        deserializer.deserialize_str(Text)
    }
}

#[cfg(test)]
mod tests {
    use egt_core::solve::prepared::Compute;
    use egt_core::{Format, Train};
    use proptest::prelude::*;

    use super::*;

    /// Fig. 3's plan for dynamics.
    fn fig3_plan() -> BatchPlan {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../examples/fig3_example61.toml"
        );
        let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{e}"));
        let train = Train::from_str(&text, Format::Toml, "fig3").unwrap_or_else(|e| panic!("{e}"));
        let spec = egt_core::batch::BatchSpec::from_analysis(&train, Compute::Dynamics)
            .unwrap_or_else(|e| panic!("{e}"));
        BatchPlan::new(&train, &spec).unwrap_or_else(|e| panic!("{e}"))
    }

    /// The reading of a line before this module: the whole line into a map
    /// (serde_json's, keeping first places), then key by key.
    fn read_as_a_map(line: &str, plan: &BatchPlan, at: &str) -> Result<Vec<(usize, f64)>, String> {
        let map: serde_json::Map<String, serde_json::Value> =
            serde_json::from_str(line).map_err(|e| format!("{at}: {e}"))?;
        map.iter()
            .map(|(name, v)| {
                let c = plan.parameter(name).ok_or_else(|| {
                    format!(
                        "{at}: {}",
                        super::super::design::unknown(plan, name, "--rows")
                    )
                })?;
                let x = v
                    .as_f64()
                    .ok_or_else(|| format!("{at}: `{name}` is not a number"))?;
                Ok((c, x))
            })
            .collect()
    }

    /// A line: an object of keys (known, unknown, escaped, repeated) and
    /// values (numbers, and what is not one), or something else, with or
    /// without trailing text.
    fn line() -> impl Strategy<Value = String> {
        let key = prop::sample::select(vec![
            "\"torque.4\"",
            "\"ratio.G2\"",
            "\"torque.9\"",
            "\"torque\\u002e4\"",
            "\"\"",
        ]);
        let value = prop_oneof![
            (-1e3..1e3f64).prop_map(|x| format!("{x:?}")),
            (-100i64..100).prop_map(|x| x.to_string()),
            prop::sample::select(vec!["\"x\"", "null", "true", "[1]", "{}", "1e400", "-0"])
                .prop_map(str::to_string),
        ];
        let object = prop::collection::vec((key, value), 0..24).prop_map(|entries| {
            let inner: Vec<String> = entries.iter().map(|(k, v)| format!("{k}: {v}")).collect();
            format!("{{{}}}", inner.join(", "))
        });
        let tail = prop::sample::select(vec!["", "", "", " ", " x", ",", "}"]);
        prop_oneof![
            8 => (object, tail).prop_map(|(o, t)| format!("{o}{t}")),
            1 => prop::sample::select(vec!["[1]", "3", "not json", "\"s\"", "{", "{\"torque.4\" -1}"])
                .prop_map(str::to_string),
        ]
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        /// Every line reads as it read into a map: the same overrides in the
        /// same order, or the same message.
        #[test]
        fn lines_read_as_they_did_into_a_map(lines in prop::collection::vec(line(), 1..300)) {
            let plan = fig3_plan();
            let numbered: Vec<(usize, &str)> = lines.iter().map(String::as_str).enumerate().collect();
            let listed = parse(&numbered, &plan, "rows.jsonl");
            prop_assert_eq!(listed.len(), lines.len());
            for (i, l) in lines.iter().enumerate() {
                let want = read_as_a_map(l, &plan, &format!("rows.jsonl:{}", i + 1));
                let got = listed.line(i).map(<[_]>::to_vec).map_err(str::to_string);
                prop_assert_eq!(got, want, "line {}: {}", i + 1, l);
            }
        }
    }

    /// Lines over three tasks (parts), each setting its own load, with unreadable
    /// ones among them: every line's overrides or message lands on its own
    /// row; a key given twice keeps its first place and its last value; an
    /// escaped key is read; the syntax error of a line wins over its
    /// unknown key; a line that fails after a good key leaves nothing.
    #[test]
    fn lines_keep_their_rows_across_tasks() {
        let plan = fig3_plan();
        let (load, ratio) = (
            plan.parameter("torque.4")
                .unwrap_or_else(|| panic!("torque.4")),
            plan.parameter("ratio.G2")
                .unwrap_or_else(|| panic!("ratio.G2")),
        );
        let n = 2 * TASK + 100;
        let special = |i: usize| match i {
            7 => Some("not json".to_string()),
            4097 => Some("{\"torque.9\": 1, \"torque.4\": }".to_string()),
            5000 => Some("{\"torque.9\": 1}".to_string()),
            6000 => Some("{\"ratio.G2\": \"x\"}".to_string()),
            6001 => Some("{\"torque.4\": -1, \"ratio.G2\": -1.4, \"torque.4\": -2}".to_string()),
            6002 => Some("{\"torque\\u002e4\": -3}".to_string()),
            6003 => Some("[1]".to_string()),
            6004 => Some("{\"torque.4\": -5, \"ratio.G2\": \"x\"}".to_string()),
            6005 => Some("{\"torque.4\": -6} x".to_string()),
            // Twenty keys, two of them ten times each (the long line's way).
            6006 => Some(format!(
                "{{{}}}",
                (1..=10)
                    .map(|k| format!("\"ratio.G2\": -1.{k}, \"torque.4\": -{k}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            )),
            _ => None,
        };
        let owned: Vec<String> = (0..n)
            .map(|i| special(i).unwrap_or_else(|| format!("{{\"torque.4\": {}}}", -(i as f64))))
            .collect();
        // Line numbers as in a file with a blank line after every tenth.
        let lines: Vec<(usize, &str)> = owned
            .iter()
            .enumerate()
            .map(|(i, l)| (i + i / 10, l.as_str()))
            .collect();
        let listed = parse(&lines, &plan, "rows.jsonl");
        assert_eq!(listed.len(), n);
        let message = |i: usize| match listed.line(i) {
            Err(e) => e.to_string(),
            Ok(v) => panic!("line {i} read as {v:?}"),
        };
        for (i, part) in [
            (7, "rows.jsonl:8: expected ident"),
            (4097, "rows.jsonl:4507: expected value"),
            (5000, "torque.9"),
            (6000, "`ratio.G2` is not a number"),
            (6003, "expected a map"),
            (6004, "`ratio.G2` is not a number"),
            (6005, "trailing characters"),
        ] {
            assert!(message(i).contains(part), "line {i}: {}", message(i));
        }
        let read = |i: usize| {
            listed
                .line(i)
                .unwrap_or_else(|e| panic!("line {i}: {e}"))
                .to_vec()
        };
        assert_eq!(read(6001), vec![(load, -2.0), (ratio, -1.4)]);
        assert_eq!(read(6002), vec![(load, -3.0)]);
        assert_eq!(read(6006), vec![(ratio, -1.1), (load, -10.0)]);
        for i in (0..n).filter(|&i| special(i).is_none()) {
            assert_eq!(read(i), vec![(load, -(i as f64))], "line {i}");
        }
        let good = (0..n).filter(|&i| listed.line(i).is_ok()).count();
        assert_eq!(good, n - 7);
        assert_eq!(listed.overrides().count(), good + 2);
    }
}

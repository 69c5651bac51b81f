//! The typed ids (links, gear pairs, turning pairs, levels, elements) and the
//! named view in which they serialize as names ([`Train::named`]).

use super::*;

/// The names ids serialize as inside [`Train::named`] (by kind: links, gear
/// pairs, turning pairs, levels, elements); outside it, ids serialize as
/// their indices.
#[derive(Debug, Default)]
struct NameTable([Vec<String>; 5]);

thread_local! {
    static NAMES: std::cell::RefCell<Option<NameTable>> = const { std::cell::RefCell::new(None) };
}

macro_rules! id_type {
    ($(#[$m:meta])* $name:ident, $kind:expr) => {
        $(#[$m])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub struct $name(pub(crate) u32);

        impl $name {
            /// The index of this id in its table.
            #[inline]
            pub fn index(self) -> usize {
                self.0 as usize
            }

            /// The id with index `i` (for iteration; ids are dense from 0).
            #[inline]
            pub fn from_index(i: usize) -> Self {
                Self(u32::try_from(i).unwrap_or(u32::MAX))
            }
        }

        /// The index, or inside [`Train::named`] the name.
        impl Serialize for $name {
            fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
                let name = NAMES.with(|n| {
                    n.borrow()
                        .as_ref()
                        .and_then(|t| t.0[$kind].get(self.index()).cloned())
                });
                match name {
                    Some(name) => s.serialize_str(&name),
                    None => s.serialize_u32(self.0),
                }
            }
        }
    };
}

id_type!(
    /// A link (vertex of the graph).
    LinkId,
    0
);
id_type!(
    /// A gear pair (geared edge); gear pair m is fundamental circuit m.
    GearId,
    1
);
id_type!(
    /// A turning (revolute) pair.
    RevoluteId,
    2
);
id_type!(
    /// An axis level (a, b, c, ...).
    LevelId,
    3
);
id_type!(
    /// A shift element.
    ElementId,
    4
);

impl Train {
    /// `value` (any result of this train) as JSON with every id replaced by
    /// its name: links, gear pairs and elements by name, levels by letter,
    /// turning pairs as `a-b`. The named view for serde output; outside this
    /// call ids serialize as indices (what the Python conversion reads).
    ///
    /// # Errors
    /// A value that does not serialize (it never happens for egt's results).
    pub fn named<T: Serialize>(&self, value: &T) -> Result<serde_json::Value> {
        let table = NameTable([
            self.links().iter().map(|l| l.name.clone()).collect(),
            self.gears().iter().map(|g| g.name.clone()).collect(),
            self.revolutes()
                .iter()
                .map(|r| {
                    format!(
                        "{}-{}",
                        self.link_name(r.links[0]),
                        self.link_name(r.links[1])
                    )
                })
                .collect(),
            self.levels().to_vec(),
            self.elements().iter().map(|e| e.name.clone()).collect(),
        ]);
        let previous = NAMES.with(|n| n.borrow_mut().replace(table));
        let out = serde_json::to_value(value);
        NAMES.with(|n| *n.borrow_mut() = previous);
        out.map_err(|e| Error::invalid("named view", e.to_string()))
    }
}

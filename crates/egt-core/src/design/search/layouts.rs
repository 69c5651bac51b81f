//! The element layouts: the freed shift elements' placements, listed and
//! written into the base spec.

use crate::design::spec::SynthSpec;
use crate::error::DesignError;
use crate::spec::{ElementKind, Spec};

use super::Search;

/// The freed shift elements and where each may sit (`[layout]`). A layout
/// is one pick per freed element (empty: the base train's layout).
#[derive(Debug, Clone, Default)]
pub(super) struct Layouts {
    pub(super) names: Vec<String>,
    pub(super) choices: Vec<Vec<Vec<String>>>,
}

impl Layouts {
    pub(super) fn count(&self) -> usize {
        self.choices.iter().map(Vec::len).product()
    }

    /// The `i`-th layout (mixed radix over the freed elements).
    pub(super) fn pick(&self, mut i: usize) -> Vec<u32> {
        self.choices
            .iter()
            .map(|c| {
                let k = i % c.len();
                i /= c.len();
                u32::try_from(k).unwrap_or(u32::MAX)
            })
            .collect()
    }

    /// Element -> links of a layout, as a candidate reports it.
    pub(super) fn named(&self, pick: &[u32]) -> Vec<(String, Vec<String>)> {
        self.names
            .iter()
            .zip(&self.choices)
            .zip(pick)
            .map(|((n, c), &k)| (n.clone(), c[k as usize].clone()))
            .collect()
    }
}

/// Most element layouts one search may list.
pub const MAX_LAYOUTS: usize = 1_000_000;

/// The element layouts to search: the base layout alone without
/// `[layout]`; else every combination of the freed elements' placements.
/// `links`: the sets' central links (the columns so far).
pub(super) fn layouts(
    spec: &SynthSpec,
    base: &Spec,
    links: &[String],
) -> Result<Layouts, DesignError> {
    use crate::spec::ElementKind;
    let tx = base.transmission.as_ref();
    let (input, output) = tx.map_or((None, None), |t| (Some(&t.input), Some(&t.output)));
    // Central links: the sets' members and every link an element or the
    // transmission names (the input shaft may reach the sets only through clutches).
    let mut central: Vec<String> = links.to_vec();
    for name in base
        .elements
        .iter()
        .flat_map(|e| e.links.iter())
        .chain(input)
        .chain(output)
    {
        if !central.contains(name) {
            central.push(name.clone());
        }
    }
    let mut out = Layouts::default();
    for (name, placement) in &spec.layout {
        let field = format!("layout.{name}");
        let e = base
            .elements
            .iter()
            .find(|e| &e.name == name)
            .ok_or_else(|| DesignError::Invalid {
                field: field.clone(),
                message: "no shift element of that name in the base train".into(),
            })?;
        let brake = matches!(e.kind, ElementKind::Brake | ElementKind::OneWayBrake);
        let choices: Vec<Vec<String>> = match placement {
            crate::design::Placement::Any(word) if word == "any" => {
                let free: Vec<&String> = central.iter().filter(|l| **l != base.frame).collect();
                if brake {
                    free.into_iter()
                        .filter(|l| Some(*l) != input && Some(*l) != output)
                        .map(|l| vec![l.clone()])
                        .collect()
                } else {
                    let mut pairs = Vec::new();
                    for (i, a) in free.iter().enumerate() {
                        for b in &free[i + 1..] {
                            pairs.push(vec![(*a).clone(), (*b).clone()]);
                        }
                    }
                    pairs
                }
            }
            crate::design::Placement::Any(word) => {
                return Err(DesignError::Invalid {
                    field,
                    message: format!("`{word}`: give \"any\" or a list of link lists"),
                });
            }
            crate::design::Placement::Choices(list) => {
                for (k, c) in list.iter().enumerate() {
                    let want = if brake { 1 } else { 2 };
                    if c.len() != want {
                        return Err(DesignError::Invalid {
                            field: format!("{field}[{k}]"),
                            message: format!(
                                "a {} joins {want} link(s), got {}",
                                if brake { "brake" } else { "clutch" },
                                c.len()
                            ),
                        });
                    }
                    if let Some(l) = c.iter().find(|l| !central.contains(l)) {
                        return Err(DesignError::Invalid {
                            field: format!("{field}[{k}]"),
                            message: format!("`{l}` is not a central link of the base train"),
                        });
                    }
                    if c.contains(&base.frame) {
                        return Err(DesignError::Invalid {
                            field: format!("{field}[{k}]"),
                            message: "name the held link; the frame is implied for a brake".into(),
                        });
                    }
                    if c.len() == 2 && c[0] == c[1] {
                        return Err(DesignError::Invalid {
                            field: format!("{field}[{k}]"),
                            message: format!("a clutch joins two links, `{}` twice", c[0]),
                        });
                    }
                }
                list.clone()
            }
        };
        if choices.is_empty() {
            return Err(DesignError::Invalid {
                field,
                message: "no placement to try".into(),
            });
        }
        if out.count().saturating_mul(choices.len()) > MAX_LAYOUTS {
            return Err(DesignError::Invalid {
                field: "layout".into(),
                message: format!("more than {MAX_LAYOUTS} element layouts; free fewer elements"),
            });
        }
        out.names.push(name.clone());
        out.choices.push(choices);
    }
    Ok(out)
}

/// The base spec with a layout's elements moved.
pub(super) fn place(base: &Spec, layout: &[(String, Vec<String>)]) -> Spec {
    let mut spec = base.clone();
    for (name, links) in layout {
        if let Some(e) = spec.elements.iter_mut().find(|e| &e.name == name) {
            e.links.clone_from(links);
        }
    }
    spec
}

/// Two elements of one way-ness on the same links (a layout that wastes
/// one). A one-way element beside a friction element on the same member is
/// not doubled: that is how automatics hold a member for drive (the one-way
/// brake) and for coast (the brake), e.g. the NAG1's reverse-and-first
/// brake beside its freewheel.
pub(super) fn doubled(elements: &[Placed<'_>]) -> bool {
    let mut seen: Vec<(Vec<&String>, bool)> = Vec::new();
    for e in elements {
        let mut k: Vec<&String> = e.links.iter().collect();
        k.sort();
        let key = (k, e.one_way);
        if seen.contains(&key) {
            return true;
        }
        seen.push(key);
    }
    false
}

/// An element as a layout places it.
#[derive(Debug, Clone, Copy)]
pub(super) struct Placed<'a> {
    /// Its name.
    pub name: &'a str,
    /// The links it acts on in this layout.
    pub links: &'a [String],
    /// A one-way brake or clutch.
    pub one_way: bool,
}

impl Search {
    /// Every element's name, links and way-ness in a layout.
    pub(super) fn elements(&self, pick: &[u32]) -> Vec<Placed<'_>> {
        self.base
            .elements
            .iter()
            .map(|e| {
                let placed = self
                    .layouts
                    .names
                    .iter()
                    .position(|n| n == &e.name)
                    .and_then(|f| {
                        pick.get(f)
                            .map(|&k| self.layouts.choices[f][k as usize].as_slice())
                    });
                Placed {
                    name: e.name.as_str(),
                    links: placed.unwrap_or(e.links.as_slice()),
                    one_way: matches!(e.kind, ElementKind::OneWayBrake | ElementKind::OneWayClutch),
                }
            })
            .collect()
    }
}

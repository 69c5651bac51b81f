//! Expansion of the spec's three ways of writing a graph (explicit pairs, the
//! planetary-set shorthand and the compact adjacency list) into one flat list
//! of links, turning pairs and gear pairs, each remembering where it was written.

use indexmap::IndexMap;

use crate::error::{Error, Result, SpecErrorKind, suggest};
use crate::spec::{GearSpec, LinkSpec, MeshKind, PlanetaryKind, PlanetarySpec, RatioSpec, Spec};

/// A link after expansion.
#[derive(Debug, Clone)]
pub(crate) struct DraftLink {
    pub data: LinkSpec,
    /// False for a planet created by the shorthand without a tooth count: its
    /// own speed is then unknown (only its carrier's motion is).
    pub sized: bool,
}

/// A turning pair after expansion.
#[derive(Debug, Clone)]
pub(crate) struct DraftRevolute {
    pub links: [String; 2],
    pub level: String,
    pub path: String,
}

/// A gear pair after expansion.
#[derive(Debug, Clone)]
pub(crate) struct DraftGear {
    pub name: String,
    pub spec: GearSpec,
    pub path: String,
}

/// The flat graph a spec describes.
#[derive(Debug, Clone, Default)]
pub(crate) struct Draft {
    /// Links in first-appearance order, the frame first.
    pub links: IndexMap<String, DraftLink>,
    pub revolutes: Vec<DraftRevolute>,
    pub gears: Vec<DraftGear>,
    /// Index in `revolutes` of each central member's mount on the frame (so a
    /// set mounting a link already mounted finds it without a scan).
    mounts: std::collections::HashMap<String, usize>,
}

impl Draft {
    /// Declare a link if it is new (data from an explicit entry wins).
    fn declare(&mut self, name: &str) {
        self.links
            .entry(name.to_string())
            .or_insert_with(|| DraftLink {
                data: LinkSpec {
                    name: name.to_string(),
                    ..Default::default()
                },
                sized: true,
            });
    }

    /// Check that `name` is declared; `path` is where it was written.
    pub fn require(&self, name: &str, path: &str) -> Result<()> {
        if self.links.contains_key(name) {
            Ok(())
        } else {
            Err(Error::spec(
                path,
                SpecErrorKind::UnknownLink {
                    name: name.to_string(),
                    suggestion: suggest(name, self.links.keys().map(String::as_str)),
                },
            ))
        }
    }
}

/// Expand a spec into a [`Draft`].
pub(crate) fn expand(spec: &Spec) -> Result<Draft> {
    let mut d = Draft::default();
    if spec.frame.trim().is_empty() {
        return Err(Error::spec(
            "frame",
            SpecErrorKind::Missing {
                what: "frame link name".into(),
            },
        ));
    }
    d.declare(&spec.frame);

    for (n, l) in spec.links.iter().enumerate() {
        let path = format!("links[{n}]");
        if l.name.trim().is_empty() {
            return Err(Error::spec(
                format!("{path}.name"),
                SpecErrorKind::Missing {
                    what: "link name".into(),
                },
            ));
        }
        if l.name == spec.frame {
            if l.inertia.is_some() || l.mass.is_some() || l.copies.is_some() {
                return Err(Error::invalid(
                    path,
                    "the frame carries no inertia, mass or copies",
                ));
            }
            continue;
        }
        if d.links.contains_key(&l.name) {
            return Err(Error::spec(
                format!("{path}.name"),
                SpecErrorKind::DuplicateLink {
                    name: l.name.clone(),
                },
            ));
        }
        d.links.insert(
            l.name.clone(),
            DraftLink {
                data: l.clone(),
                sized: true,
            },
        );
    }

    for (n, set) in spec.planetary.iter().enumerate() {
        expand_planetary(&mut d, set, &spec.frame, &format!("planetary[{n}]"))?;
    }

    if let Some(adj) = &spec.adjacency {
        expand_adjacency(&mut d, adj)?;
    }

    for (n, r) in spec.revolutes.iter().enumerate() {
        let path = format!("revolutes[{n}]");
        for (s, name) in r.links.iter().enumerate() {
            d.require(name, &format!("{path}.links[{s}]"))?;
        }
        if r.level.trim().is_empty() {
            return Err(Error::spec(
                format!("{path}.level"),
                SpecErrorKind::Missing {
                    what: "axis level".into(),
                },
            ));
        }
        d.revolutes.push(DraftRevolute {
            links: r.links.clone(),
            level: r.level.clone(),
            path,
        });
    }

    for (n, g) in spec.gears.iter().enumerate() {
        let path = format!("gears[{n}]");
        for (s, name) in g.links.iter().enumerate() {
            d.require(name, &format!("{path}.links[{s}]"))?;
        }
        let name = g.name.clone().unwrap_or_default();
        d.gears.push(DraftGear {
            name,
            spec: g.clone(),
            path,
        });
    }

    // Default gear names G1, G2, ... in final order, where none was given.
    for (m, g) in d.gears.iter_mut().enumerate() {
        if g.name.is_empty() {
            g.name = format!("G{}", m + 1);
        }
    }
    // The frame must be a link of the graph: named by some pair.
    let used = |name: &str| {
        d.revolutes
            .iter()
            .any(|r| r.links.iter().any(|l| l == name))
            || d.gears
                .iter()
                .any(|g| g.spec.links.iter().any(|l| l == name))
    };
    if !used(&spec.frame) && (!d.revolutes.is_empty() || !d.gears.is_empty()) {
        let others = d
            .links
            .keys()
            .map(String::as_str)
            .filter(|l| *l != spec.frame);
        return Err(Error::spec(
            "frame",
            SpecErrorKind::UnknownLink {
                name: spec.frame.clone(),
                suggestion: suggest(&spec.frame, others),
            },
        ));
    }
    Ok(d)
}

fn expand_planetary(d: &mut Draft, set: &PlanetarySpec, frame: &str, path: &str) -> Result<()> {
    let t = &set.teeth;
    let axis = set.axis.clone().unwrap_or_else(|| "a".to_string());
    let need = |v: Option<i64>, field: &str| -> Result<i64> {
        v.ok_or_else(|| {
            Error::spec(
                format!("{path}.teeth.{field}"),
                SpecErrorKind::Missing {
                    what: format!("tooth count `{field}` ({:?} set)", set.kind),
                },
            )
        })
    };
    let need_link = |v: &Option<String>, field: &str| -> Result<String> {
        v.clone().ok_or_else(|| {
            Error::spec(
                format!("{path}.{field}"),
                SpecErrorKind::Missing {
                    what: format!("link `{field}` ({:?} set)", set.kind),
                },
            )
        })
    };
    let planet = set
        .planet
        .clone()
        .unwrap_or_else(|| format!("{}.planet", set.name));
    let planet2 = set
        .planet2
        .clone()
        .unwrap_or_else(|| format!("{}.planet2", set.name));

    // Central members on the main axis, planets on the carrier.
    let mut central = vec![set.sun.clone(), set.carrier.clone()];
    if let Some(r) = &set.ring {
        central.push(r.clone());
    }
    if let Some(s2) = &set.sun2 {
        central.push(s2.clone());
    }
    // Two members of one set on one link would lock the set (or mesh a gear with itself).
    for (k, a) in central.iter().enumerate() {
        if central[..k].contains(a) {
            return Err(Error::invalid(
                path,
                format!(
                    "two central members of set `{}` are the same link `{a}`; join members with a clutch or name distinct links",
                    set.name
                ),
            ));
        }
    }
    for c in &central {
        d.declare(c);
        mount(
            d,
            frame,
            c,
            &axis,
            &format!("{path} (central member `{c}`)"),
        )?;
    }

    let add_planet = |d: &mut Draft, name: &str, teeth: Option<i64>| -> Result<()> {
        if d.links.contains_key(name) && !d.links[name].sized {
            return Err(Error::invalid(
                path,
                format!("planet `{name}` is already used by another set"),
            ));
        }
        d.declare(name);
        if teeth.is_none()
            && let Some(l) = d.links.get_mut(name)
        {
            l.sized = false;
        }
        d.revolutes.push(DraftRevolute {
            links: [set.carrier.clone(), name.to_string()],
            level: name.to_string(),
            path: format!("{path} (planet `{name}` on carrier `{}`)", set.carrier),
        });
        Ok(())
    };

    let mesh =
        |a: &str, za: Option<i64>, b: &str, zb: Option<i64>, kind: MeshKind, tag: &str| DraftGear {
            name: format!("{}/{tag}", set.name),
            spec: GearSpec {
                name: None,
                links: [a.to_string(), b.to_string()],
                // An unsized planet gets one virtual tooth: the product of ratios round the
                // set, and so every central speed, does not depend on it.
                teeth: Some([za.unwrap_or(1), zb.unwrap_or(1)]),
                mesh: Some(kind),
                ratio: None,
                module: if za.is_some() && zb.is_some() {
                    set.module
                } else {
                    None
                },
                radii: None,
                efficiency: set.efficiency,
            },
            path: format!("{path} ({tag} mesh)"),
        };
    if set.module.is_some()
        && (t.planet.is_none()
            || (matches!(
                set.kind,
                PlanetaryKind::DoublePinion | PlanetaryKind::Ravigneaux
            ) && t.planet2.is_none()))
    {
        return Err(Error::spec(
            format!("{path}.teeth.planet"),
            SpecErrorKind::Missing {
                what: "planet tooth count (needed with `module` for radii and offsets)".into(),
            },
        ));
    }

    let zs = Some(need(t.sun, "sun")?);
    // Every kind meshes the sun with the (first) planet.
    let sun_planet =
        |zp: Option<i64>| mesh(&set.sun, zs, &planet, zp, MeshKind::External, "sun-planet");
    match set.kind {
        // The sun meshes with the planet and the ring with the outer planet:
        // the planet itself, or in a double-pinion set planet2, which meshes
        // with the planet between them. A Ravigneaux set is a double-pinion
        // set whose long planet (planet2) also meshes with a second sun.
        PlanetaryKind::Simple | PlanetaryKind::DoublePinion | PlanetaryKind::Ravigneaux => {
            let ring = need_link(&set.ring, "ring")?;
            let zr = Some(need(t.ring, "ring")?);
            let sun2 = match set.kind {
                PlanetaryKind::Ravigneaux => {
                    Some((need_link(&set.sun2, "sun2")?, Some(need(t.sun2, "sun2")?)))
                }
                _ => None,
            };
            add_planet(d, &planet, t.planet)?;
            d.gears.push(sun_planet(t.planet));
            let (outer, z_outer, tag) = if set.kind == PlanetaryKind::Simple {
                (&planet, t.planet, "planet-ring")
            } else {
                add_planet(d, &planet2, t.planet2)?;
                d.gears.push(mesh(
                    &planet,
                    t.planet,
                    &planet2,
                    t.planet2,
                    MeshKind::External,
                    "planet-planet2",
                ));
                if let Some((sun2, z2)) = sun2 {
                    d.gears.push(mesh(
                        &sun2,
                        z2,
                        &planet2,
                        t.planet2,
                        MeshKind::External,
                        "sun2-planet2",
                    ));
                }
                (&planet2, t.planet2, "planet2-ring")
            };
            d.gears
                .push(mesh(outer, z_outer, &ring, zr, MeshKind::Internal, tag));
        }
        PlanetaryKind::Stepped => {
            let zp = Some(need(t.planet, "planet")?);
            let zp2 = Some(need(t.planet2, "planet2")?);
            add_planet(d, &planet, zp)?;
            if let Some(l) = d.links.get_mut(&planet) {
                l.data.wheels.get_or_insert(2);
            }
            d.gears.push(sun_planet(zp));
            match (&set.ring, &set.sun2) {
                (Some(ring), None) => {
                    let zr = Some(need(t.ring, "ring")?);
                    d.gears.push(mesh(
                        &planet,
                        zp2,
                        ring,
                        zr,
                        MeshKind::Internal,
                        "planet2-ring",
                    ));
                }
                (None, Some(sun2)) => {
                    let z2 = Some(need(t.sun2, "sun2")?);
                    d.gears.push(mesh(
                        sun2,
                        z2,
                        &planet,
                        zp2,
                        MeshKind::External,
                        "sun2-planet2",
                    ));
                }
                _ => {
                    return Err(Error::invalid(
                        path,
                        "a stepped set needs exactly one of `ring` and `sun2`",
                    ));
                }
            }
        }
    }
    Ok(())
}

/// Mount a central member on the frame at the main axis, once per link.
fn mount(d: &mut Draft, frame: &str, link: &str, axis: &str, path: &str) -> Result<()> {
    if link == frame {
        return Ok(());
    }
    if let Some(existing) = d.mounts.get(link).map(|&k| &d.revolutes[k]) {
        if existing.level != axis {
            return Err(Error::invalid(
                path,
                format!(
                    "link `{link}` is on axis level `{}` in {} but `{axis}` here",
                    existing.level, existing.path
                ),
            ));
        }
        return Ok(());
    }
    d.mounts.insert(link.to_string(), d.revolutes.len());
    d.revolutes.push(DraftRevolute {
        links: [frame.to_string(), link.to_string()],
        level: axis.to_string(),
        path: path.to_string(),
    });
    Ok(())
}

fn expand_adjacency(d: &mut Draft, text: &str) -> Result<()> {
    for (n, tok) in text
        .split(|c: char| c.is_whitespace() || c == ',' || c == ';')
        .filter(|t| !t.is_empty())
        .enumerate()
    {
        let path = format!("adjacency (item {}: `{tok}`)", n + 1);
        let bad = || Error::invalid(&path, "expected `A-B:level` or `A-B:G` or `A-B:G=ratio`");
        let (pair, label) = tok.split_once(':').ok_or_else(bad)?;
        let (a, b) = pair.split_once('-').ok_or_else(bad)?;
        if a.is_empty() || b.is_empty() || label.is_empty() {
            return Err(bad());
        }
        d.declare(a);
        d.declare(b);
        if label == "G" || label.starts_with("G=") {
            let ratio = label
                .strip_prefix("G=")
                .map(|r| RatioSpec::Text(r.to_string()));
            d.gears.push(DraftGear {
                name: String::new(),
                spec: GearSpec {
                    links: [a.to_string(), b.to_string()],
                    ratio,
                    ..Default::default()
                },
                path,
            });
        } else {
            d.revolutes.push(DraftRevolute {
                links: [a.to_string(), b.to_string()],
                level: label.to_string(),
                path,
            });
        }
    }
    Ok(())
}

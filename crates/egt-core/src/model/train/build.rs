//! Building a [`Train`] from a draft: the links, gear pairs and turning pairs
//! checked and typed, the graph, the tree, the circuits and the DOF.

use super::extras::{planetary_warnings, resolve_extras};
use super::teeth::{finite, non_negative, positive, teeth_value};
use super::*;

/// Validate one gear pair's numbers into a [`GearPair`].
fn gear_pair(g: &DraftGear, ids: &HashMap<&str, LinkId>) -> Result<GearPair> {
    let p = &g.path;
    let s = &g.spec;
    let gear_i = ids[s.links[0].as_str()];
    let gear_j = ids[s.links[1].as_str()];
    let teeth = match s.teeth {
        Some([zi, zj]) => Some([
            teeth_value(format!("{p}.teeth[0]"), zi)?,
            teeth_value(format!("{p}.teeth[1]"), zj)?,
        ]),
        None => None,
    };
    let ratio = match (&teeth, &s.ratio) {
        (Some(_), Some(_)) => {
            return Err(Error::invalid(
                p.clone(),
                "give either `teeth` (with `mesh`) or `ratio`, not both",
            ));
        }
        (Some([zi, zj]), None) => {
            let mesh = s.mesh.ok_or_else(|| {
                Error::spec(
                    format!("{p}.mesh"),
                    SpecErrorKind::Missing {
                        what: "mesh kind (`external` or `internal`) for `teeth`".into(),
                    },
                )
            })?;
            let tau = ratio_from_teeth(&format!("{p}.teeth"), mesh, [(*zi).into(), (*zj).into()])?;
            Some(Ratio {
                value: exact::to_f64(&tau),
                exact: Some(tau),
            })
        }
        (None, Some(RatioSpec::Number(v))) => {
            let v = finite(format!("{p}.ratio"), *v)?;
            Some(Ratio {
                value: v,
                exact: None,
            })
        }
        (None, Some(RatioSpec::Text(t))) => {
            let (q, value) = exact::parse_finite(t)
                .map_err(|e| Error::invalid(format!("{p}.ratio"), format!("`{t}`: {e}")))?;
            Some(Ratio {
                value,
                exact: Some(q),
            })
        }
        (None, None) => {
            if s.mesh.is_some() {
                return Err(Error::spec(
                    format!("{p}.teeth"),
                    SpecErrorKind::Missing {
                        what: "`teeth` for `mesh`".into(),
                    },
                ));
            }
            None
        }
    };
    if let Some(r) = &ratio
        && r.value == 0.0
    {
        return Err(Error::spec(
            format!("{p}.ratio"),
            SpecErrorKind::OutOfRange {
                value: 0.0,
                expected: "a Willis ratio is never 0".into(),
            },
        ));
    }
    let mut radii = match s.radii {
        Some([ri, rj]) => Some([
            positive(format!("{p}.radii[0]"), ri)?,
            positive(format!("{p}.radii[1]"), rj)?,
        ]),
        None => None,
    };
    if let Some(m) = s.module {
        let m = positive(format!("{p}.module"), m)?;
        let [zi, zj] = teeth.ok_or_else(|| {
            Error::spec(
                format!("{p}.teeth"),
                SpecErrorKind::Missing {
                    what: "`teeth` for `module`".into(),
                },
            )
        })?;
        let from_module = [m * f64::from(zi) / 2.0, m * f64::from(zj) / 2.0];
        if let Some(r) = radii
            && (0..2).any(|k| (r[k] - from_module[k]).abs() > 1e-9 * from_module[k])
        {
            return Err(Error::invalid(
                p.clone(),
                format!("`radii` {r:?} disagree with `module` x `teeth` / 2 = {from_module:?}"),
            ));
        }
        radii = Some(from_module);
    }
    let efficiency = match s.efficiency {
        Some(e) => {
            let e = finite(format!("{p}.efficiency"), e)?;
            if !(e > 0.0 && e <= 1.0) {
                return Err(Error::spec(
                    format!("{p}.efficiency"),
                    SpecErrorKind::OutOfRange {
                        value: e,
                        expected: "efficiency must be in (0, 1]".into(),
                    },
                ));
            }
            e
        }
        None => 1.0,
    };
    Ok(GearPair {
        name: g.name.clone(),
        gear_i,
        gear_j,
        ratio,
        teeth,
        mesh: s.mesh,
        radii,
        efficiency,
        path: p.clone(),
    })
}

pub(super) fn build(spec: &Spec, draft: &Draft) -> Result<Train> {
    let n = draft.links.len();
    if n > MAX_TRAIN_LINKS {
        #[allow(clippy::cast_precision_loss)]
        return Err(Error::spec(
            "links",
            SpecErrorKind::OutOfRange {
                value: n as f64,
                expected: format!("at most {MAX_TRAIN_LINKS} links in a train"),
            },
        ));
    }
    // Links.
    let mut links = Vec::with_capacity(draft.links.len());
    let written: HashMap<&str, usize> = spec
        .links
        .iter()
        .enumerate()
        .map(|(k, l)| (l.name.as_str(), k))
        .collect();
    for (n, (name, dl)) in draft.links.iter().enumerate() {
        let path = written
            .get(name.as_str())
            .map_or_else(|| format!("link `{name}`"), |k| format!("links[{k}]"));
        let d = &dl.data;
        let inertia = d
            .inertia
            .map(|v| non_negative(format!("{path}.inertia"), v))
            .transpose()?;
        let mass = d
            .mass
            .map(|v| non_negative(format!("{path}.mass"), v))
            .transpose()?;
        let copies = match d.copies {
            Some(0) => {
                return Err(Error::spec(
                    format!("{path}.copies"),
                    SpecErrorKind::OutOfRange {
                        value: 0.0,
                        expected: "at least 1".into(),
                    },
                ));
            }
            Some(c) => c,
            None => 1,
        };
        if d.wheels == Some(0) {
            return Err(Error::spec(
                format!("{path}.wheels"),
                SpecErrorKind::OutOfRange {
                    value: 0.0,
                    expected: "at least 1".into(),
                },
            ));
        }
        let phases = match &d.phases {
            None => None,
            Some(p) if p.len() != copies as usize => {
                return Err(Error::invalid(
                    format!("{path}.phases"),
                    format!(
                        "{} phases given for {copies} copies: give one angle per copy",
                        p.len()
                    ),
                ));
            }
            Some(p) => Some(
                p.iter()
                    .enumerate()
                    .map(|(k, &v)| finite(format!("{path}.phases[{k}]"), v).map(f64::to_radians))
                    .collect::<Result<Vec<f64>>>()?,
            ),
        };
        debug_assert!(n > 0 || name == &spec.frame);
        links.push(Link {
            name: name.clone(),
            inertia,
            mass,
            copies,
            phases,
            wheels: d.wheels,
            sized: dl.sized,
        });
    }
    let ids: HashMap<&str, LinkId> = draft
        .links
        .keys()
        .enumerate()
        .map(|(i, k)| (k.as_str(), LinkId::from_index(i)))
        .collect();
    let frame = ids[spec.frame.as_str()];

    // Levels, interned in first-appearance order.
    let mut levels: Vec<String> = Vec::new();
    let mut level_ids: HashMap<String, LevelId> = HashMap::new();
    let mut level_id = |name: &str| -> LevelId {
        if let Some(&id) = level_ids.get(name) {
            return id;
        }
        let id = LevelId::from_index(levels.len());
        levels.push(name.to_string());
        level_ids.insert(name.to_string(), id);
        id
    };

    // Turning pairs: no self-loops, no duplicates.
    let mut seen: HashMap<(LinkId, LinkId), String> = HashMap::new();
    let key = |a: LinkId, b: LinkId| if a < b { (a, b) } else { (b, a) };
    let mut revolutes = Vec::with_capacity(draft.revolutes.len());
    for r in &draft.revolutes {
        let a = ids[r.links[0].as_str()];
        let b = ids[r.links[1].as_str()];
        if a == b {
            return Err(Error::spec(
                format!("{}.links", r.path),
                SpecErrorKind::SelfLoop {
                    link: r.links[0].clone(),
                },
            ));
        }
        if let Some(first) = seen.insert(key(a, b), r.path.clone()) {
            return Err(Error::spec(
                r.path.clone(),
                SpecErrorKind::Duplicate {
                    first,
                    what: format!(
                        "a second turning pair between `{}` and `{}`",
                        r.links[0], r.links[1]
                    ),
                },
            ));
        }
        revolutes.push(Revolute {
            links: [a, b],
            level: level_id(&r.level),
        });
    }

    // Gear pairs.
    let mut seen_gear: HashMap<(LinkId, LinkId), String> = HashMap::new();
    let mut seen_name: HashMap<&str, &str> = HashMap::new();
    let mut gears = Vec::with_capacity(draft.gears.len());
    for g in &draft.gears {
        let gp = gear_pair(g, &ids)?;
        if gp.gear_i == gp.gear_j {
            return Err(Error::spec(
                format!("{}.links", g.path),
                SpecErrorKind::SelfLoop {
                    link: g.spec.links[0].clone(),
                },
            ));
        }
        if let Some(first) = seen_gear.insert(key(gp.gear_i, gp.gear_j), g.path.clone()) {
            return Err(Error::spec(
                g.path.clone(),
                SpecErrorKind::Duplicate {
                    first,
                    what: format!(
                        "a second gear pair between `{}` and `{}`",
                        g.spec.links[0], g.spec.links[1]
                    ),
                },
            ));
        }
        if let Some(first) = seen_name.insert(g.name.as_str(), g.path.as_str()) {
            return Err(Error::spec(
                format!("{}.name", g.path),
                SpecErrorKind::Duplicate {
                    first: first.to_string(),
                    what: format!("gear pair name `{}`", g.name),
                },
            ));
        }
        for (side, l) in [gp.gear_i, gp.gear_j].into_iter().enumerate() {
            if !links[l.index()].sized && !g.path.starts_with("planetary") {
                return Err(Error::invalid(
                    format!("{}.links[{side}]", g.path),
                    format!(
                        "planet `{}` has no tooth count in its planetary set; give `teeth.planet` there to mesh it elsewhere",
                        links[l.index()].name
                    ),
                ));
            }
        }
        gears.push(gp);
    }
    check_single_wheels(&links, &gears)?;

    // Offsets between levels.
    let mut offsets = Vec::new();
    for (n, o) in spec.offsets.iter().enumerate() {
        let path = format!("offsets[{n}]");
        let mut lv = [LevelId(0); 2];
        for (s, name) in o.levels.iter().enumerate() {
            lv[s] = match level_ids.get(name.as_str()) {
                Some(&id) => id,
                None => {
                    return Err(Error::invalid(
                        format!("{path}.levels[{s}]"),
                        format!(
                            "unknown axis level `{name}` (levels in use: {})",
                            levels.join(", ")
                        ),
                    ));
                }
            };
        }
        if lv[0] == lv[1] {
            return Err(Error::invalid(
                format!("{path}.levels"),
                "an offset joins two different levels",
            ));
        }
        offsets.push((
            lv[0],
            lv[1],
            positive(format!("{path}.distance"), o.distance)?,
        ));
    }

    // The typed graph: node i is link i.
    let mut graph =
        UnGraph::<LinkId, Edge>::with_capacity(links.len(), revolutes.len() + gears.len());
    for i in 0..links.len() {
        graph.add_node(LinkId::from_index(i));
    }
    for (i, r) in revolutes.iter().enumerate() {
        graph.add_edge(
            node(r.links[0]),
            node(r.links[1]),
            Edge::Revolute(RevoluteId::from_index(i)),
        );
    }
    for (i, g) in gears.iter().enumerate() {
        graph.add_edge(
            node(g.gear_i),
            node(g.gear_j),
            Edge::Gear(GearId::from_index(i)),
        );
    }

    // Clutches as pairs of links (a malformed element is reported later, by name).
    let clutches: Vec<[LinkId; 2]> = spec
        .elements
        .iter()
        .filter(|e| matches!(e.kind, ElementKind::Clutch | ElementKind::OneWayClutch))
        .filter_map(|e| match e.links.as_slice() {
            [a, b] => Some([*ids.get(a.as_str())?, *ids.get(b.as_str())?]),
            _ => None,
        })
        .collect();
    let topo = topology::analyse(
        &links, frame, &levels, &revolutes, &gears, &graph, &clutches,
    )?;

    let coordinates: Vec<LinkId> = (0..links.len())
        .map(LinkId::from_index)
        .filter(|&l| l != frame)
        .collect();
    let mut coord_of = vec![None; links.len()];
    for (c, l) in coordinates.iter().enumerate() {
        coord_of[l.index()] = Some(c);
    }

    let link_ids = links
        .iter()
        .enumerate()
        .map(|(i, l)| (l.name.clone(), LinkId::from_index(i)))
        .collect();
    let mut train = Train {
        name: spec.name.clone(),
        links,
        link_ids,
        frame,
        levels,
        revolutes,
        gears,
        offsets,
        graph,
        tree: topo.tree,
        circuits: topo.circuits,
        dof: topo.dof,
        coordinates,
        coord_of,
        elements: Vec::new(),
        transmission: None,
        analysis: Analysis::default(),
        compliance: None,
        checks: topo.checks,
        design_warnings: Vec::new(),
    };
    resolve_extras(spec, &mut train)?;
    if let Some(c) = &spec.compliance {
        train.compliance = Some(super::compliance::resolve_compliance(c, &train)?);
    }
    train.design_warnings = planetary_warnings(spec, &train);
    Ok(train)
}

fn node(l: LinkId) -> NodeIndex {
    NodeIndex::new(l.index())
}

/// A link declared with a single wheel meshes with that one wheel everywhere.
fn check_single_wheels(links: &[Link], gears: &[GearPair]) -> Result<()> {
    for (li, link) in links.iter().enumerate() {
        if link.wheels != Some(1) {
            continue;
        }
        let mut first: Option<(&GearPair, Option<u32>, Option<f64>)> = None;
        for g in gears {
            let side = if g.gear_i.index() == li {
                0
            } else if g.gear_j.index() == li {
                1
            } else {
                continue;
            };
            let z = g.teeth.map(|t| t[side]);
            let r = g.radii.map(|r| r[side]);
            if let Some((g0, z0, r0)) = first {
                let z_clash = matches!((z0, z), (Some(a), Some(b)) if a != b);
                let r_clash =
                    matches!((r0, r), (Some(a), Some(b)) if (a - b).abs() > 1e-9 * a.abs());
                if z_clash || r_clash {
                    return Err(Error::invalid(
                        g.path.clone(),
                        format!(
                            "link `{}` has one wheel, but it has different teeth or radius here than in {}",
                            link.name, g0.path
                        ),
                    ));
                }
            } else {
                first = Some((g, z, r));
            }
        }
    }
    Ok(())
}

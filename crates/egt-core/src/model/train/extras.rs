//! The names in shift elements, transmission and analysis data resolved on a
//! built [`Train`], and its design warnings.

use super::teeth::{finite, positive};
use super::*;

/// The design warnings of the simple planetary sets of `spec` (see
/// [`Train::design_warnings`]).
pub(super) fn planetary_warnings(spec: &Spec, train: &Train) -> Vec<String> {
    let mut out = Vec::new();
    for (i, set) in spec.planetary.iter().enumerate() {
        if set.kind != crate::spec::PlanetaryKind::Simple {
            continue;
        }
        let (Some(zs), Some(zr)) = (set.teeth.sun, set.teeth.ring) else {
            continue;
        };
        let at = format!("planetary[{i}] (`{}`)", set.name);
        if zr <= zs {
            out.push(format!(
                "{at}: the ring ({zr} teeth) is not larger than the sun ({zs}): no planet fits between them"
            ));
            continue;
        }
        if let Some(zp) = set.teeth.planet
            && zr != zs + 2 * zp
        {
            out.push(format!(
                "{at}: z_ring = {zr} differs from z_sun + 2 z_planet = {}: the planets are not coaxial unless the gears are profile-shifted",
                zs + 2 * zp
            ));
        }
        let planet = set
            .planet
            .clone()
            .unwrap_or_else(|| format!("{}.planet", set.name));
        let copies = train.link_id(&planet).map_or(1, |l| train.link(l).copies);
        if copies >= 2 && (zs + zr) % i64::from(copies) != 0 {
            out.push(format!(
                "{at}: (z_sun + z_ring) / n = ({zs} + {zr}) / {copies} is not an integer: {copies} equally spaced planets cannot be assembled"
            ));
        }
    }
    out
}

/// Resolve the names in shift elements, transmission and analysis data.
pub(super) fn resolve_extras(spec: &Spec, train: &mut Train) -> Result<()> {
    let mut elements: Vec<ShiftElement> = Vec::new();
    for (n, e) in spec.elements.iter().enumerate() {
        let path = format!("elements[{n}]");
        if let Some(k) = elements.iter().position(|x| x.name == e.name) {
            return Err(Error::spec(
                format!("{path}.name"),
                SpecErrorKind::Duplicate {
                    first: format!("elements[{k}]"),
                    what: format!("element name `{}`", e.name),
                },
            ));
        }
        let want = match e.kind {
            ElementKind::Brake | ElementKind::OneWayBrake => 1,
            ElementKind::Clutch | ElementKind::OneWayClutch => 2,
        };
        if e.links.len() != want {
            return Err(Error::invalid(
                format!("{path}.links"),
                format!("a {:?} takes {want} link(s), got {}", e.kind, e.links.len()),
            ));
        }
        let links = e
            .links
            .iter()
            .enumerate()
            .map(|(s, l)| train.resolve(l, &format!("{path}.links[{s}]")))
            .collect::<Result<Vec<_>>>()?;
        if links.contains(&train.frame) {
            return Err(Error::invalid(
                format!("{path}.links"),
                "name the held link; the frame is implied for a brake",
            ));
        }
        if want == 2 && links[0] == links[1] {
            return Err(Error::spec(
                format!("{path}.links"),
                SpecErrorKind::SelfLoop {
                    link: e.links[0].clone(),
                },
            ));
        }
        elements.push(ShiftElement {
            name: e.name.clone(),
            kind: e.kind,
            links,
        });
    }
    train.elements = elements;

    if let Some(t) = &spec.transmission {
        let input = train.resolve(&t.input, "transmission.input")?;
        let output = train.resolve(&t.output, "transmission.output")?;
        let mut states = Vec::new();
        for (name, engaged) in &t.states {
            let path = format!("transmission.states.{name}");
            let mut ids = Vec::new();
            for (s, e) in engaged.iter().enumerate() {
                let id = train
                    .elements
                    .iter()
                    .position(|x| &x.name == e)
                    .ok_or_else(|| {
                        Error::invalid(
                            format!("{path}[{s}]"),
                            format!(
                                "unknown shift element `{e}`{}",
                                suggest(e, train.elements.iter().map(|x| x.name.as_str()))
                                    .map(|s| format!(" (did you mean `{s}`?)"))
                                    .unwrap_or_default()
                            ),
                        )
                    })?;
                let id = ElementId::from_index(id);
                if ids.contains(&id) {
                    return Err(Error::invalid(
                        format!("{path}[{s}]"),
                        format!("element `{e}` is listed twice"),
                    ));
                }
                ids.push(id);
            }
            states.push(GearState {
                name: name.clone(),
                engaged: ids,
            });
        }
        let shifts = named_shifts(&spec.shift, &states)?;
        train.transmission = Some(Transmission {
            input,
            output,
            states,
            shifts,
        });
    } else if !spec.shift.is_empty() {
        return Err(Error::invalid(
            "shift[0]",
            "a [[shift]] runs between gear states: the spec needs a [transmission] with `states`",
        ));
    }

    if let Some(a) = &spec.analysis {
        let mut out = Analysis::default();
        for (name, v) in &a.speeds {
            let path = format!("analysis.speeds.{name}");
            let l = train.resolve(name, &path)?;
            let (value, exact) = match v {
                // A decimal written in the spec is read as the decimal the user
                // wrote (its shortest round-trip form), not as the binary value
                // of the double: 0.1 is 1/10, not 3602879701896397/2^55.
                RatioSpec::Number(x) => (
                    finite(path, *x)?,
                    exact::parse_rational(&x.to_string())
                        .ok()
                        .or_else(|| exact::from_f64(*x)),
                ),
                RatioSpec::Text(t) => {
                    let (q, value) = exact::parse_finite(t)
                        .map_err(|e| Error::invalid(&path, format!("`{t}`: {e}")))?;
                    (value, Some(q))
                }
            };
            out.speeds.push((l, value, exact));
        }
        for (name, v) in &a.torques {
            let path = format!("analysis.torques.{name}");
            out.torques
                .push((train.resolve(name, &path)?, finite(path, *v)?));
        }
        for (name, v) in &a.accelerations {
            let path = format!("analysis.accelerations.{name}");
            out.accelerations
                .push((train.resolve(name, &path)?, finite(path, *v)?));
        }
        for (k, name) in a.driving.iter().enumerate() {
            out.driving
                .push(train.resolve(name, &format!("analysis.driving[{k}]"))?);
        }
        for (name, v) in &a.angles {
            let path = format!("analysis.angles.{name}");
            out.angles
                .push((train.resolve(name, &path)?, finite(path, *v)?));
        }
        if let Some(r) = &a.reduce_to {
            out.reduce_to = Some(train.resolve(r, "analysis.reduce_to")?);
        }
        for (k, c) in a.curves.iter().enumerate() {
            let path = format!("analysis.curves[{k}]");
            out.curves.push(Curve {
                link: train.resolve(&c.link, &format!("{path}.link"))?,
                torque: finite(format!("{path}.torque"), c.torque)?,
                slope: finite(format!("{path}.slope"), c.slope)?,
                speed: finite(format!("{path}.speed"), c.speed)?,
            });
        }
        if let Some(s) = &a.simulate {
            let mut initial = Vec::new();
            for (name, v) in &s.initial {
                let path = format!("analysis.simulate.initial.{name}");
                initial.push((train.resolve(name, &path)?, finite(path, *v)?));
            }
            out.simulate = Some(Simulate {
                t_end: s
                    .t_end
                    .map(|v| positive("analysis.simulate.t_end".into(), v))
                    .transpose()?,
                dt: s
                    .dt
                    .map(|v| positive("analysis.simulate.dt".into(), v))
                    .transpose()?,
                method: s.method.clone(),
                initial,
            });
        }
        train.analysis = out;
    }
    Ok(())
}

/// The spec's `[[shift]]` entries, checked as far as the spec alone can:
/// unique names, `from` and `to` gear states of `states`.
fn named_shifts(shifts: &[ShiftSpec], states: &[GearState]) -> Result<Vec<ShiftSpec>> {
    for (k, sh) in shifts.iter().enumerate() {
        let path = format!("shift[{k}]");
        if sh.name.trim().is_empty() {
            return Err(Error::invalid(format!("{path}.name"), "is empty"));
        }
        if let Some(first) = shifts[..k].iter().position(|o| o.name == sh.name) {
            return Err(Error::invalid(
                format!("{path}.name"),
                format!("`{}` names shift[{first}] too", sh.name),
            ));
        }
        for (field, state) in [("from", &sh.from), ("to", &sh.to)] {
            if !states.iter().any(|g| &g.name == state) {
                return Err(Error::invalid(
                    format!("{path}.{field}"),
                    format!(
                        "unknown gear state `{state}`{}",
                        suggest(state, states.iter().map(|g| g.name.as_str()))
                            .map(|s| format!(" (did you mean `{s}`?)"))
                            .unwrap_or_default()
                    ),
                ));
            }
        }
        if sh.from == sh.to {
            return Err(Error::invalid(
                format!("{path}.to"),
                format!("is `from` (`{}`): a shift changes the gear", sh.to),
            ));
        }
    }
    Ok(shifts.to_vec())
}

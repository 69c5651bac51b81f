//! A structure with a layout written as a train spec: its shafts named by
//! their members, the sets as `[[planetary]]` entries, the elements, and the
//! transmission's input, output and gear states.

use crate::design::spec::ConceptSpec;
use crate::spec::{
    ElementSpec, LinkSpec, PlanetaryKind, PlanetarySpec, RevoluteSpec, Spec, TransmissionSpec,
};

use super::structures::{SetSlot, Structure, roles};

/// The case (frame) of every concept train.
pub(crate) const CASE: &str = "case";

/// The separate input shaft's name.
pub(crate) const INPUT: &str = "input";

/// Each free shaft's name: its members joined by `=`, or `input`.
pub(crate) fn shaft_names(s: &Structure, members: &[String]) -> Vec<String> {
    s.shafts
        .iter()
        .map(|sh| {
            if sh.is_empty() {
                INPUT.to_string()
            } else {
                sh.iter()
                    .map(|&m| members[m as usize].as_str())
                    .collect::<Vec<_>>()
                    .join("=")
            }
        })
        .collect()
}

/// The train of a structure with its elements on `layout`'s links (teeth
/// left out: the search writes them).
pub(crate) fn train(
    concept: &ConceptSpec,
    sets: &[SetSlot],
    members: &[String],
    s: &Structure,
    layout: &[(String, Vec<String>)],
) -> Spec {
    let names = shaft_names(s, members);
    let mut link = vec![CASE.to_string(); members.len()];
    for (i, sh) in s.shafts.iter().enumerate() {
        for &m in sh {
            link[m as usize].clone_from(&names[i]);
        }
    }
    let planetary = concept
        .sets
        .iter()
        .zip(sets)
        .map(|((name, &kind), slot)| {
            let at = |role: &str| {
                let r = roles(kind).iter().position(|x| *x == role).unwrap_or(0);
                link[slot.first + r].clone()
            };
            PlanetarySpec {
                name: name.clone(),
                kind,
                sun: at("sun"),
                ring: Some(at("ring")),
                sun2: (kind == PlanetaryKind::Ravigneaux).then(|| at("sun2")),
                carrier: at("carrier"),
                ..PlanetarySpec::default()
            }
        })
        .collect();
    let separate = s.shafts.iter().any(Vec::is_empty);
    let links = if separate {
        vec![LinkSpec {
            name: INPUT.to_string(),
            ..LinkSpec::default()
        }]
    } else {
        Vec::new()
    };
    let revolutes = if separate {
        vec![RevoluteSpec {
            links: [CASE.to_string(), INPUT.to_string()],
            level: "a".into(),
        }]
    } else {
        Vec::new()
    };
    let elements = concept
        .elements
        .iter()
        .map(|(name, &kind)| ElementSpec {
            name: name.clone(),
            kind,
            links: layout
                .iter()
                .find(|(n, _)| n == name)
                .map(|(_, l)| l.clone())
                .unwrap_or_default(),
        })
        .collect();
    Spec {
        name: Some("concept".into()),
        frame: CASE.into(),
        links,
        revolutes,
        planetary,
        elements,
        transmission: Some(TransmissionSpec {
            input: names[s.input].clone(),
            output: names[s.output].clone(),
            states: concept.states.clone(),
        }),
        ..Spec::default()
    }
}

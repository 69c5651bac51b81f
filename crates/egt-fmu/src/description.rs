//! The model description (`modelDescription.xml`, FMI 2.0 Co-Simulation) of
//! a unit: serde structs in the schema's element order, written by
//! quick-xml, from [`Variables`]. The GUID is a hash of the spec's text, so
//! an instance can check that its resources are the spec it was described
//! from.

use serde::Serialize;

use crate::variables::{Causality, INITIAL_GEAR, Kind, LOCKED_ELEMENTS, Variables};

/// The units the variables use, with their SI base-unit exponents
/// (`rad`, `kg`, `m`, `s`).
const UNITS: [(&str, [i32; 4]); 7] = [
    ("rad/s", [1, 0, 0, -1]),
    ("N.m", [0, 1, 2, -2]),
    ("J", [0, 1, 2, -2]),
    ("s", [0, 0, 0, 1]),
    ("kg.m2", [0, 1, 2, 0]),
    ("N.m.s/rad", [-1, 1, 2, -1]),
    ("N.m.s2/rad2", [-2, 1, 2, 0]),
];

#[derive(Serialize)]
#[serde(rename = "fmiModelDescription")]
struct ModelDescription<'a> {
    #[serde(rename = "@fmiVersion")]
    fmi_version: &'a str,
    #[serde(rename = "@modelName")]
    model_name: &'a str,
    #[serde(rename = "@guid")]
    guid: &'a str,
    #[serde(rename = "@description")]
    description: &'a str,
    #[serde(rename = "@generationTool")]
    generation_tool: String,
    #[serde(rename = "@variableNamingConvention")]
    naming: &'a str,
    #[serde(rename = "@numberOfEventIndicators")]
    event_indicators: u32,
    #[serde(rename = "CoSimulation")]
    co_simulation: CoSimulation<'a>,
    #[serde(rename = "UnitDefinitions")]
    units: UnitDefinitions,
    #[serde(rename = "DefaultExperiment")]
    experiment: DefaultExperiment,
    #[serde(rename = "ModelVariables")]
    variables: ModelVariables,
    #[serde(rename = "ModelStructure")]
    structure: ModelStructure,
}

#[derive(Serialize)]
struct CoSimulation<'a> {
    #[serde(rename = "@modelIdentifier")]
    model_identifier: &'a str,
    #[serde(rename = "@canHandleVariableCommunicationStepSize")]
    variable_step: bool,
    #[serde(rename = "@canInterpolateInputs")]
    interpolate_inputs: bool,
    #[serde(rename = "@maxOutputDerivativeOrder")]
    output_derivatives: u32,
    #[serde(rename = "@canNotUseMemoryManagementFunctions")]
    no_memory_functions: bool,
}

#[derive(Serialize)]
struct UnitDefinitions {
    #[serde(rename = "Unit")]
    units: Vec<Unit>,
}

#[derive(Serialize)]
struct Unit {
    #[serde(rename = "@name")]
    name: &'static str,
    #[serde(rename = "BaseUnit")]
    base: BaseUnit,
}

#[derive(Serialize)]
struct BaseUnit {
    #[serde(rename = "@rad", skip_serializing_if = "is_zero")]
    rad: i32,
    #[serde(rename = "@kg", skip_serializing_if = "is_zero")]
    kg: i32,
    #[serde(rename = "@m", skip_serializing_if = "is_zero")]
    m: i32,
    #[serde(rename = "@s", skip_serializing_if = "is_zero")]
    s: i32,
}

#[allow(clippy::trivially_copy_pass_by_ref)] // serde's skip_serializing_if passes a reference
fn is_zero(v: &i32) -> bool {
    *v == 0
}

#[derive(Serialize)]
struct DefaultExperiment {
    #[serde(rename = "@startTime")]
    start: f64,
    #[serde(rename = "@stopTime")]
    stop: f64,
    #[serde(rename = "@stepSize")]
    step: f64,
}

#[derive(Serialize)]
struct ModelVariables {
    #[serde(rename = "ScalarVariable")]
    list: Vec<ScalarVariable>,
}

#[derive(Serialize)]
struct ScalarVariable {
    #[serde(rename = "@name")]
    name: String,
    #[serde(rename = "@valueReference")]
    value_reference: u32,
    #[serde(rename = "@description")]
    description: String,
    #[serde(rename = "@causality")]
    causality: &'static str,
    #[serde(rename = "@variability")]
    variability: &'static str,
    #[serde(rename = "@initial", skip_serializing_if = "Option::is_none")]
    initial: Option<&'static str>,
    #[serde(rename = "Real", skip_serializing_if = "Option::is_none")]
    real: Option<Real>,
    #[serde(rename = "Integer", skip_serializing_if = "Option::is_none")]
    integer: Option<Integer>,
}

#[derive(Serialize)]
struct Real {
    #[serde(rename = "@unit", skip_serializing_if = "Option::is_none")]
    unit: Option<&'static str>,
    #[serde(rename = "@start", skip_serializing_if = "Option::is_none")]
    start: Option<f64>,
}

#[derive(Serialize)]
struct Integer {
    #[serde(rename = "@start", skip_serializing_if = "Option::is_none")]
    start: Option<i32>,
    #[serde(rename = "@min", skip_serializing_if = "Option::is_none")]
    min: Option<i32>,
    #[serde(rename = "@max", skip_serializing_if = "Option::is_none")]
    max: Option<i32>,
}

#[derive(Serialize)]
struct ModelStructure {
    #[serde(rename = "Outputs")]
    outputs: Unknowns,
    #[serde(rename = "InitialUnknowns")]
    initial: Unknowns,
}

#[derive(Serialize)]
struct Unknowns {
    #[serde(rename = "Unknown")]
    list: Vec<Unknown>,
}

#[derive(Serialize)]
struct Unknown {
    #[serde(rename = "@index")]
    index: usize,
}

/// The GUID of a unit made from `spec` (the spec's text as packaged): a
/// 128-bit FNV-1a hash of the text and egt's version, written as a UUID.
pub fn guid(spec: &str) -> String {
    let hash = |seed: u64| {
        let mut h = seed;
        for b in spec.bytes().chain(env!("CARGO_PKG_VERSION").bytes()) {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
        h
    };
    let (a, b) = (hash(0xcbf2_9ce4_8422_2325), hash(0x6c62_272e_07bb_0142));
    format!(
        "{{{:08x}-{:04x}-{:04x}-{:04x}-{:012x}}}",
        a >> 32,
        (a >> 16) & 0xffff,
        a & 0xffff,
        b >> 48,
        b & 0xffff_ffff_ffff
    )
}

/// `modelDescription.xml` of the unit with `variables`, named `model_name`,
/// whose shared library is `<model_identifier>.so`, made from `spec`.
///
/// # Errors
/// The XML writer's error (none is expected of these structs).
pub fn model_description(
    variables: &Variables,
    model_name: &str,
    model_identifier: &str,
    spec: &str,
) -> Result<String, quick_xml::SeError> {
    let mut list: Vec<ScalarVariable> = (variables.reals.iter().enumerate())
        .map(|(vr, r)| {
            let (causality, variability, initial) = match r.causality {
                Causality::Parameter => ("parameter", "fixed", Some("exact")),
                Causality::Input => ("input", "continuous", None),
                Causality::Output => ("output", "continuous", Some("calculated")),
            };
            ScalarVariable {
                name: r.name.clone(),
                value_reference: u32::try_from(vr).unwrap_or(u32::MAX),
                description: r.description.clone(),
                causality,
                variability,
                initial,
                real: Some(Real {
                    unit: r.unit,
                    start: r.start,
                }),
                integer: None,
            }
        })
        .collect();
    let gears = (variables.gears.iter().enumerate())
        .map(|(i, g)| format!("{} = `{g}`", i + 1))
        .collect::<Vec<_>>()
        .join(", ");
    let bits = (variables.elements.iter().enumerate())
        .map(|(i, e)| format!("{} = `{e}`", 1u64 << i.min(63)))
        .collect::<Vec<_>>()
        .join(", ");
    let count = i32::try_from(variables.gears.len()).unwrap_or(i32::MAX);
    let transmission = variables.kind == Kind::Transmission;
    list.extend(transmission.then(|| ScalarVariable {
        name: "initial_gear".into(),
        value_reference: INITIAL_GEAR,
        description: format!("the gear at the start: {gears}"),
        causality: "parameter",
        variability: "fixed",
        initial: Some("exact"),
        real: None,
        integer: Some(Integer {
            start: Some(1),
            min: Some(1),
            max: Some(count),
        }),
    }));
    list.extend(transmission.then(|| ScalarVariable {
        name: "locked_elements".into(),
        value_reference: LOCKED_ELEMENTS,
        description: format!("the mode: the sum of the locked elements' bits, {bits}"),
        causality: "output",
        variability: "discrete",
        initial: Some("calculated"),
        real: None,
        integer: Some(Integer {
            start: None,
            min: None,
            max: None,
        }),
    }));
    // 1-based indices of the outputs in the list, in order.
    let outputs: Vec<Unknown> = (list.iter().enumerate())
        .filter(|(_, v)| v.causality == "output")
        .map(|(i, _)| Unknown { index: i + 1 })
        .collect();
    let initial = outputs.iter().map(|u| Unknown { index: u.index }).collect();
    let guid = guid(spec);
    let doc = ModelDescription {
        fmi_version: "2.0",
        model_name,
        guid: &guid,
        description: if transmission {
            "a transmission's shift dynamics (egt): friction elements that slip, lock and overrun, driven by their capacities"
        } else {
            "a gear train's forward dynamics (egt): its links' speeds under the spec's torque-speed curves and the applied torques"
        },
        generation_tool: format!("egt {}", env!("CARGO_PKG_VERSION")),
        naming: "flat",
        event_indicators: 0,
        co_simulation: CoSimulation {
            model_identifier,
            variable_step: true,
            interpolate_inputs: true,
            output_derivatives: 0,
            no_memory_functions: true,
        },
        units: UnitDefinitions {
            units: UNITS
                .iter()
                .map(|&(name, [rad, kg, m, s])| Unit {
                    name,
                    base: BaseUnit { rad, kg, m, s },
                })
                .collect(),
        },
        experiment: DefaultExperiment {
            start: 0.0,
            stop: 1.0,
            step: 1e-3,
        },
        variables: ModelVariables { list },
        structure: ModelStructure {
            outputs: Unknowns { list: outputs },
            initial: Unknowns { list: initial },
        },
    };
    let mut xml = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    let mut ser = quick_xml::se::Serializer::new(&mut xml);
    ser.indent(' ', 2);
    doc.serialize(ser)?;
    xml.push('\n');
    Ok(xml)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use std::collections::HashMap;

    use egt_core::{Format, Train};
    use quick_xml::Reader;
    use quick_xml::events::Event;

    use super::*;

    fn spec(name: &str) -> String {
        std::fs::read_to_string(format!(
            "{}/../../examples/{name}.toml",
            env!("CARGO_MANIFEST_DIR")
        ))
        .unwrap()
    }

    /// Each element of the XML with its attributes, in document order.
    fn elements(xml: &str) -> Vec<(String, HashMap<String, String>)> {
        let mut reader = Reader::from_str(xml);
        let mut out = Vec::new();
        loop {
            match reader.read_event().unwrap() {
                Event::Start(e) | Event::Empty(e) => {
                    let attrs = e
                        .attributes()
                        .map(|a| {
                            let a = a.unwrap();
                            let value = a
                                .normalized_value(quick_xml::XmlVersion::Explicit1_0)
                                .unwrap()
                                .into_owned();
                            (a.key.as_ref().to_string(), value)
                        })
                        .collect();
                    out.push((e.name().as_ref().to_string(), attrs));
                }
                Event::Eof => break,
                _ => {}
            }
        }
        out
    }

    fn describe(name: &str) -> String {
        let text = spec(name);
        let train = Train::from_str(&text, Format::Toml, name).unwrap();
        let vars = Variables::of(&train).unwrap();
        model_description(&vars, train.name().unwrap(), name, &text).unwrap()
    }

    #[test]
    fn the_8hp_description_lists_every_element_and_link_with_units_and_its_outputs() {
        let xml = describe("zf_8hp70");
        assert!(
            xml.starts_with("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<fmiModelDescription")
        );
        let els = elements(&xml);
        let root = &els[0].1;
        assert_eq!(root["fmiVersion"], "2.0");
        assert_eq!(root["modelName"], "ZF 8HP70");
        assert_eq!(root["guid"], guid(&spec("zf_8hp70")));
        let cs = els.iter().find(|(n, _)| n == "CoSimulation").unwrap();
        assert_eq!(cs.1["modelIdentifier"], "zf_8hp70");
        let declared: Vec<&str> = (els.iter())
            .filter(|(n, _)| n == "Unit")
            .map(|(_, a)| a["name"].as_str())
            .collect();
        // The variables in order: each ScalarVariable, then its type element.
        let mut vars = Vec::new();
        for (i, (n, a)) in els.iter().enumerate() {
            if n == "ScalarVariable" {
                vars.push((a.clone(), els[i + 1].clone()));
            }
        }
        let by_name: HashMap<&str, usize> = (vars.iter().enumerate())
            .map(|(i, (a, _))| (a["name"].as_str(), i))
            .collect();
        assert_eq!(by_name.len(), vars.len(), "names are unique");
        for e in ["A", "B", "C", "D", "E"] {
            for (suffix, causality, unit) in [
                ("capacity", "input", "N.m"),
                ("slip", "output", "rad/s"),
                ("torque", "output", "N.m"),
                ("energy", "output", "J"),
                ("lock_time", "output", "s"),
            ] {
                let (a, ty) = &vars[by_name[format!("{e}.{suffix}").as_str()]];
                assert_eq!(a["causality"], causality);
                assert_eq!(ty.0, "Real");
                assert_eq!(ty.1["unit"], unit);
            }
        }
        for link in ["input", "output", "sun12", "ring1", "carrier3"] {
            let (a, ty) = &vars[by_name[format!("{link}.speed").as_str()]];
            assert_eq!(
                (a["causality"].as_str(), ty.1["unit"].as_str()),
                ("output", "rad/s")
            );
        }
        assert_eq!(vars[by_name["input.torque"]].0["causality"], "input");
        assert_eq!(vars[by_name["output.torque"]].0["causality"], "output");
        // The engaged elements of the first gear (A, B, C) start held.
        assert_eq!(vars[by_name["A.capacity"]].1.1["start"], "100000");
        assert_eq!(vars[by_name["D.capacity"]].1.1["start"], "0");
        // Every unit used is declared; every input and parameter has a start.
        for (a, ty) in &vars {
            if let Some(u) = ty.1.get("unit") {
                assert!(declared.contains(&u.as_str()), "{u}");
            }
            if a["causality"] != "output" {
                assert!(ty.1.contains_key("start"), "{}", a["name"]);
            }
        }
        // Value references: reals dense from 0, the two integers 0 and 1.
        let mut reals: Vec<u32> = (vars.iter())
            .filter(|(_, ty)| ty.0 == "Real")
            .map(|(a, _)| a["valueReference"].parse().unwrap())
            .collect();
        reals.sort_unstable();
        assert!(reals.iter().enumerate().all(|(i, &v)| v as usize == i));
        // Outputs and initial unknowns: exactly the outputs, by 1-based index.
        let outputs: Vec<usize> = (vars.iter().enumerate())
            .filter(|(_, (a, _))| a["causality"] == "output")
            .map(|(i, _)| i + 1)
            .collect();
        let unknowns: Vec<usize> = (els.iter())
            .filter(|(n, _)| n == "Unknown")
            .map(|(_, a)| a["index"].parse().unwrap())
            .collect();
        assert_eq!(unknowns, [outputs.clone(), outputs].concat());
    }

    #[test]
    fn the_guid_follows_the_spec_text() {
        let a = spec("zf_8hp70");
        assert_eq!(guid(&a), guid(&a));
        assert_ne!(guid(&a), guid(&format!("{a}\n")));
        assert_eq!(guid(&a).len(), 38);
    }

    #[test]
    fn a_train_without_elements_is_a_unit_of_its_links_and_has_no_integers() {
        let xml = describe("fig5_stability");
        let els = elements(&xml);
        let vars: HashMap<&str, &HashMap<String, String>> = (els.iter())
            .filter(|(n, _)| n == "ScalarVariable")
            .map(|(_, a)| (a["name"].as_str(), a))
            .collect();
        for link in ["2", "3", "4", "5", "6"] {
            assert_eq!(
                vars[format!("{link}.torque").as_str()]["causality"],
                "input"
            );
            assert_eq!(
                vars[format!("{link}.speed").as_str()]["causality"],
                "output"
            );
        }
        // The spec's `[analysis.simulate] initial` links are the parameters.
        for p in ["2.initial_speed", "4.initial_speed", "dt"] {
            assert_eq!(vars[p]["causality"], "parameter");
        }
        assert!(!vars.contains_key("3.initial_speed") && !vars.contains_key("1.speed"));
        assert!(!vars.contains_key("initial_gear") && !vars.contains_key("locked_elements"));
        assert!(!els.iter().any(|(n, _)| n == "Integer"));
        assert_eq!(vars["work"]["causality"], "output");
    }

    #[test]
    fn elements_without_a_transmission_or_clashing_names_are_refused() {
        // Shift elements with no gear states: neither a transmission nor a
        // train without elements.
        let text = spec("zf_8hp70");
        let cut = &text[..text.find("[transmission]").unwrap()];
        let train = Train::from_str(cut, Format::Toml, "cut").unwrap();
        let e = Variables::of(&train).unwrap_err().0;
        assert!(e.contains("shift elements"), "{e}");
        // an element named like the input link: two `input.torque`
        let clash = spec("zf_8hp70")
            .replace("name = \"A\"", "name = \"input\"")
            .replace("\"A\"", "\"input\"");
        let train = Train::from_str(&clash, Format::Toml, "clash").unwrap();
        let e = Variables::of(&train).unwrap_err().0;
        assert!(e.contains("`input.torque`"), "{e}");
    }
}

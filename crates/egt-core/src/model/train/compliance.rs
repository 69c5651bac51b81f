//! The spec's `[compliance]` section resolved on a built [`Train`]: mesh
//! stiffnesses by gear pair, torsional springs by link, compliant shift
//! elements by element (the data of the lumped torsional model, docs/vibration.md).

use super::teeth::{finite, non_negative, positive};
use super::*;
use crate::spec::ComplianceSpec;

/// Pressure angle of a mesh when neither it nor `[compliance]` gives one \[degrees\].
pub const DEFAULT_PRESSURE_ANGLE_DEG: f64 = 20.0;

/// The stiffness of one gear pair along its line of action.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MeshStiffness {
    /// The gear pair.
    pub gear: GearId,
    /// Stiffness along the line of action \[N/m\] (of each planet's mesh).
    pub stiffness: f64,
    /// Damping along the line of action \[N s/m\].
    pub damping: f64,
    /// Pressure angle \[rad\].
    pub pressure_angle: f64,
    /// Base radii [r_bi, r_bj] \[m\], when given.
    pub base_radii: Option<[f64; 2]>,
    /// Where it was written.
    pub path: String,
}

/// A torsional spring between two links (the second may be the frame).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TorsionSpring {
    /// Name (`S<n>` by default).
    pub name: String,
    /// The two links; the frame for a spring to ground.
    pub links: [LinkId; 2],
    /// Stiffness \[N m/rad\].
    pub stiffness: f64,
    /// Damping \[N m s/rad\].
    pub damping: f64,
}

/// A shift element that is a torsional spring when engaged.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ElementStiffness {
    /// The element.
    pub element: ElementId,
    /// Stiffness \[N m/rad\].
    pub stiffness: f64,
    /// Damping \[N m s/rad\].
    pub damping: f64,
}

/// The compliance data of a train, resolved to ids.
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
pub struct Compliance {
    /// Mesh stiffnesses, at most one per gear pair.
    pub meshes: Vec<MeshStiffness>,
    /// Torsional springs.
    pub springs: Vec<TorsionSpring>,
    /// Compliant shift elements.
    pub elements: Vec<ElementStiffness>,
}

impl Compliance {
    /// The stiffness given for gear pair `g`.
    pub fn mesh(&self, g: GearId) -> Option<&MeshStiffness> {
        self.meshes.iter().find(|m| m.gear == g)
    }

    /// The stiffness given for element `e`.
    pub fn element(&self, e: ElementId) -> Option<&ElementStiffness> {
        self.elements.iter().find(|m| m.element == e)
    }
}

fn angle(path: String, degrees: f64) -> Result<f64> {
    let v = finite(path.clone(), degrees)?;
    if v > 0.0 && v < 90.0 {
        Ok(v.to_radians())
    } else {
        Err(Error::spec(
            path,
            SpecErrorKind::OutOfRange {
                value: v,
                expected: "a pressure angle in (0, 90) degrees".into(),
            },
        ))
    }
}

fn damping(path: String, v: Option<f64>) -> Result<f64> {
    v.map_or(Ok(0.0), |d| non_negative(path, d))
}

/// Resolve `[compliance]`: names to ids, numbers checked.
pub(super) fn resolve_compliance(spec: &ComplianceSpec, train: &Train) -> Result<Compliance> {
    let default_angle = angle(
        "compliance.pressure_angle".into(),
        spec.pressure_angle.unwrap_or(DEFAULT_PRESSURE_ANGLE_DEG),
    )?;
    let mut out = Compliance::default();
    for (n, m) in spec.meshes.iter().enumerate() {
        let path = format!("compliance.meshes[{n}]");
        let g = train
            .gears()
            .iter()
            .position(|g| g.name == m.gear)
            .ok_or_else(|| {
                Error::invalid(
                    format!("{path}.gear"),
                    format!(
                        "unknown gear pair `{}`{}",
                        m.gear,
                        suggest(&m.gear, train.gears().iter().map(|g| g.name.as_str()))
                            .map(|s| format!(" (did you mean `{s}`?)"))
                            .unwrap_or_default()
                    ),
                )
            })?;
        let gear = GearId::from_index(g);
        if let Some(k) = out.meshes.iter().position(|x| x.gear == gear) {
            return Err(Error::spec(
                format!("{path}.gear"),
                SpecErrorKind::Duplicate {
                    first: format!("compliance.meshes[{k}]"),
                    what: format!("the stiffness of gear pair `{}`", m.gear),
                },
            ));
        }
        let base_radii = match m.base_radii {
            Some([a, b]) => Some([
                positive(format!("{path}.base_radii[0]"), a)?,
                positive(format!("{path}.base_radii[1]"), b)?,
            ]),
            None => None,
        };
        out.meshes.push(MeshStiffness {
            gear,
            stiffness: positive(format!("{path}.stiffness"), m.stiffness)?,
            damping: damping(format!("{path}.damping"), m.damping)?,
            pressure_angle: match m.pressure_angle {
                Some(a) => angle(format!("{path}.pressure_angle"), a)?,
                None => default_angle,
            },
            base_radii,
            path,
        });
    }
    for (n, s) in spec.springs.iter().enumerate() {
        let path = format!("compliance.springs[{n}]");
        let links = match s.links.as_slice() {
            [a] => [
                train.resolve(a, &format!("{path}.links[0]"))?,
                train.frame(),
            ],
            [a, b] => [
                train.resolve(a, &format!("{path}.links[0]"))?,
                train.resolve(b, &format!("{path}.links[1]"))?,
            ],
            _ => {
                return Err(Error::invalid(
                    format!("{path}.links"),
                    format!(
                        "a spring joins two links, or one link to the frame; got {}",
                        s.links.len()
                    ),
                ));
            }
        };
        if links[0] == links[1] {
            return Err(Error::spec(
                format!("{path}.links"),
                SpecErrorKind::SelfLoop {
                    link: s.links[0].clone(),
                },
            ));
        }
        let name = s.name.clone().unwrap_or_else(|| format!("S{}", n + 1));
        if let Some(k) = out.springs.iter().position(|x| x.name == name) {
            return Err(Error::spec(
                format!("{path}.name"),
                SpecErrorKind::Duplicate {
                    first: format!("compliance.springs[{k}]"),
                    what: format!("spring name `{name}`"),
                },
            ));
        }
        out.springs.push(TorsionSpring {
            name,
            links,
            stiffness: positive(format!("{path}.stiffness"), s.stiffness)?,
            damping: damping(format!("{path}.damping"), s.damping)?,
        });
    }
    for (n, e) in spec.elements.iter().enumerate() {
        let path = format!("compliance.elements[{n}]");
        let k = train
            .elements()
            .iter()
            .position(|x| x.name == e.element)
            .ok_or_else(|| {
                Error::invalid(
                    format!("{path}.element"),
                    format!(
                        "unknown shift element `{}`{}",
                        e.element,
                        suggest(&e.element, train.elements().iter().map(|x| x.name.as_str()))
                            .map(|s| format!(" (did you mean `{s}`?)"))
                            .unwrap_or_default()
                    ),
                )
            })?;
        let element = ElementId::from_index(k);
        if let Some(k) = out.elements.iter().position(|x| x.element == element) {
            return Err(Error::spec(
                format!("{path}.element"),
                SpecErrorKind::Duplicate {
                    first: format!("compliance.elements[{k}]"),
                    what: format!("the stiffness of element `{}`", e.element),
                },
            ));
        }
        out.elements.push(ElementStiffness {
            element,
            stiffness: positive(format!("{path}.stiffness"), e.stiffness)?,
            damping: damping(format!("{path}.damping"), e.damping)?,
        });
    }
    Ok(out)
}

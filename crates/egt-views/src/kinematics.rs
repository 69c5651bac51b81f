//! The kinematics document (`egt kinematics --format json`, `Speeds.to_dict()`):
//! every link's speed, exact where the ratios are, the ratio input/link of a
//! 1-DOF train, speeds relative to carriers, the Willis residual and condition.

use egt_core::{LinkId, SpeedInput, Speeds, Train};
use num_traits::Zero;
use serde::Serialize;

use crate::format;

#[derive(Debug, Serialize)]
pub struct InputRow {
    pub link: String,
    pub speed: f64,
    pub exact: String,
}

#[derive(Debug, Serialize)]
pub struct LinkRow {
    pub name: String,
    pub frame: bool,
    pub input: bool,
    /// False for a planet without tooth count: its speed is unknown.
    pub known: bool,
    pub speed: Option<f64>,
    pub exact: Option<String>,
    /// 1-DOF trains: input speed / link speed (None where the link is at rest or unknown).
    pub ratio: Option<f64>,
    pub ratio_exact: Option<String>,
}

#[derive(Debug, Serialize)]
pub struct RelativeRow {
    pub link: String,
    pub carrier: String,
    pub speed: f64,
    pub exact: Option<String>,
}

#[derive(Debug, Serialize)]
pub struct Report {
    pub source: String,
    pub name: Option<String>,
    pub dof: usize,
    pub inputs: Vec<InputRow>,
    pub links: Vec<LinkRow>,
    pub relative: Vec<RelativeRow>,
    pub residual: f64,
    pub condition: f64,
    pub warnings: Vec<String>,
}

pub fn build(train: &Train, source: &str, inputs: &[SpeedInput], s: &Speeds) -> Report {
    let one_dof = inputs.len() == 1;
    let is_input = |l: LinkId| inputs.iter().any(|i| i.link == l);
    let exact_of = |l: LinkId| s.exact.as_ref().map(|e| &e[l.index()]);
    let links = train
        .links_with_ids()
        .map(|(id, link)| {
            let i = id.index();
            let known = s.known[i];
            let speed = known.then_some(s.speed[i]);
            let ex = exact_of(id).filter(|_| known);
            let (ratio, ratio_exact) = if one_dof && known && id != train.frame() {
                let inp = &inputs[0];
                let ratio = (s.speed[i] != 0.0).then(|| inp.speed / s.speed[i]);
                let ratio_exact = match (&inp.exact, ex) {
                    (Some(a), Some(b)) if !b.is_zero() => Some(format::exact(&(a / b))),
                    _ => None,
                };
                (ratio, ratio_exact)
            } else {
                (None, None)
            };
            LinkRow {
                name: link.name.clone(),
                frame: id == train.frame(),
                input: is_input(id),
                known,
                speed,
                exact: ex.map(format::exact),
                ratio,
                ratio_exact,
            }
        })
        .collect();
    Report {
        source: source.to_string(),
        name: train.name().map(str::to_string),
        dof: train.dof(),
        inputs: inputs
            .iter()
            .map(|i| InputRow {
                link: train.link_name(i.link).to_string(),
                speed: i.speed,
                exact: i
                    .exact
                    .as_ref()
                    .map_or_else(|| format::float(i.speed), format::exact),
            })
            .collect(),
        links,
        relative: s
            .relative
            .iter()
            .map(|r| RelativeRow {
                link: train.link_name(r.link).to_string(),
                carrier: train.link_name(r.carrier).to_string(),
                speed: r.speed,
                exact: r.exact.as_ref().map(format::exact),
            })
            .collect(),
        residual: s.residual,
        condition: s.condition,
        warnings: s.warnings.clone(),
    }
}

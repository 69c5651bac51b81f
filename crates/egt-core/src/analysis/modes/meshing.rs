//! Tooth-pass (mesh) frequencies per unit input speed of a train with one
//! rigid-body mode, and the Campbell diagram's crossings: the input speeds at
//! which a mesh's tooth-pass frequency equals a natural frequency.
//!
//! The speeds come from the rigid-body mode, which is the kinematics
//! (docs/vibration.md): gear i of a mesh passes z_i teeth per turn of its
//! carrier-relative rotation, so its mesh order (tooth passes per input
//! revolution) is z_i |w_i - w_k| / |w_in|, the same from gear j.

use serde::Serialize;

use super::NaturalMode;
use crate::error::{AnalysisError, Result};
use crate::model::train::{LinkId, Train};

/// One gear pair's tooth-pass frequency per unit input speed.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MeshOrder {
    /// The gear pair's name.
    pub gear: String,
    /// Tooth passes per input revolution (the mesh order).
    pub order: f64,
    /// Tooth-pass frequency per input speed \[Hz per rpm\] (order / 60).
    pub hertz_per_rpm: f64,
}

/// An input speed at which a mesh's tooth-pass frequency meets a natural frequency.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Crossing {
    /// The gear pair.
    pub gear: String,
    /// The mode (index into the modes, rigid-body modes first).
    pub mode: usize,
    /// Its natural frequency \[Hz\].
    pub hertz: f64,
    /// The input speed of the crossing \[rpm\].
    pub speed: f64,
}

/// Mesh orders, and the crossings within a speed range when asked for.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Meshing {
    /// The input link (`[transmission] input`, else the one link of
    /// `[analysis] speeds`).
    pub input: LinkId,
    /// One per gear pair.
    pub orders: Vec<MeshOrder>,
    /// The input speed range of the Campbell diagram \[rpm\], when asked for.
    pub range: Option<[f64; 2]>,
    /// Crossings in that range, by speed (first harmonic of the tooth-pass
    /// frequency; one per group of equal frequencies).
    pub crossings: Vec<Crossing>,
}

/// The input link: `[transmission] input`, else the one link of `[analysis] speeds`.
fn input_link(train: &Train) -> Option<LinkId> {
    if let Some(t) = train.transmission() {
        return Some(t.input);
    }
    match train.analysis().speeds.as_slice() {
        [(l, _, _)] => Some(*l),
        _ => None,
    }
}

fn refuse(what: String) -> crate::Error {
    AnalysisError::MissingData {
        what,
        analysis: "the mesh frequencies (egt modes --campbell)".into(),
        hint: "a gear state (--state) or a train of one DOF, an input link ([transmission] input, or one link in [analysis] speeds), and the tooth counts of every gear pair".into(),
    }
    .into()
}

impl Train {
    /// The mesh orders from the rigid-body mode `rigid` (its values by
    /// link in `speed_of`), and the Campbell crossings within `range` \[rpm\].
    ///
    /// # Errors
    /// [`AnalysisError::MissingData`] when there is not exactly one
    /// rigid-body mode, no input link, the input at rest, or a gear pair
    /// without teeth.
    pub(crate) fn meshing(
        &self,
        speed_of: &dyn Fn(LinkId) -> f64,
        dof: usize,
        modes: &[NaturalMode],
        range: Option<[f64; 2]>,
    ) -> Result<Meshing> {
        if dof != 1 {
            return Err(refuse(format!("one rigid-body mode (the model has {dof})")));
        }
        let input = input_link(self).ok_or_else(|| refuse("an input link".into()))?;
        let w_in = speed_of(input);
        let scale = modes
            .iter()
            .flat_map(|m| m.shape.iter())
            .fold(0.0_f64, |a, v| a.max(v.abs()));
        if w_in.abs() <= 1e-12 * scale {
            return Err(refuse(format!(
                "a turning input (`{}` is at rest in this state)",
                self.link_name(input)
            )));
        }
        let mut orders = Vec::with_capacity(self.gears().len());
        for (c, g) in self.circuits().iter().zip(self.gears()) {
            let z = g
                .teeth
                .ok_or_else(|| refuse(format!("the tooth counts of gear pair `{}`", g.name)))?;
            let relative = speed_of(c.gear_i) - speed_of(c.carrier);
            let order = f64::from(z[0]) * (relative / w_in).abs();
            // A mesh that turns with its carrier passes no teeth; its order
            // is round-off.
            let order = if order <= 1e-12 * f64::from(z[0]) {
                0.0
            } else {
                order
            };
            orders.push(MeshOrder {
                gear: g.name.clone(),
                order,
                hertz_per_rpm: order / 60.0,
            });
        }
        let mut crossings = Vec::new();
        if let Some([lo, hi]) = range {
            if !(lo.is_finite() && hi.is_finite() && lo >= 0.0 && lo <= hi) {
                return Err(crate::Error::invalid(
                    "campbell",
                    format!("the speed range {lo}:{hi} rpm must be finite with 0 <= MIN <= MAX"),
                ));
            }
            for o in orders.iter().filter(|o| o.order > 0.0) {
                for (k, m) in modes.iter().enumerate() {
                    if m.rigid || m.group != k {
                        continue;
                    }
                    let speed = m.hertz / o.hertz_per_rpm;
                    if (lo..=hi).contains(&speed) {
                        crossings.push(Crossing {
                            gear: o.gear.clone(),
                            mode: k,
                            hertz: m.hertz,
                            speed,
                        });
                    }
                }
            }
            crossings.sort_by(|a, b| a.speed.total_cmp(&b.speed));
        }
        Ok(Meshing {
            input,
            orders,
            range,
            crossings,
        })
    }
}

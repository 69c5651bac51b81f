//! Fundamental circuits and their transfer vertices (paper section 2.1, Table 1).
//!
//! Each gear pair m closes exactly one circuit with the turning-pair tree. Its
//! transfer vertex k (the carrier) divides the circuit's turning pairs at one
//! axis level from those at another; the Willis equation (2) of circuit m
//! relates gear i, gear j and carrier k.

use serde::Serialize;

use crate::error::TopologyError;
use crate::model::topology::Tree;
use crate::model::train::{GearId, GearPair, LevelId, Link, LinkId, Revolute};

/// One row of the fundamental-circuit table (Table 1).
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct FundamentalCircuit {
    /// The gear pair closing the circuit (circuit m is gear pair m).
    pub gear: GearId,
    /// Gear i.
    pub gear_i: LinkId,
    /// Gear j.
    pub gear_j: LinkId,
    /// Transfer vertex k: the carrier.
    pub carrier: LinkId,
    /// Level of the turning pairs between gear i and the carrier.
    pub level_i: LevelId,
    /// Level of the turning pairs between the carrier and gear j.
    pub level_j: LevelId,
    /// The circuit's links from gear i through the tree to gear j.
    pub path: Vec<LinkId>,
}

/// Find the transfer vertex of every gear pair, following section 2.1 step by step.
pub(crate) fn fundamental_circuits(
    links: &[Link],
    levels: &[String],
    revolutes: &[Revolute],
    gears: &[GearPair],
    tree: &Tree,
) -> Result<Vec<FundamentalCircuit>, TopologyError> {
    gears
        .iter()
        .enumerate()
        .map(|(m, g)| {
            // Steps 2-4: the circuit's tree edges, from gear i to gear j.
            let (path, edges) = tree.path(g.gear_i, g.gear_j);
            let edge_levels: Vec<LevelId> =
                edges.iter().map(|e| revolutes[e.index()].level).collect();
            // Step 5: split by level.
            let mut distinct: Vec<LevelId> = Vec::new();
            for l in &edge_levels {
                if !distinct.contains(l) {
                    distinct.push(*l);
                }
            }
            if distinct.len() != 2 {
                return Err(TopologyError::NoTransferVertex {
                    pair: g.name.clone(),
                    levels: edge_levels
                        .iter()
                        .map(|l| levels[l.index()].clone())
                        .collect(),
                });
            }
            // Step 6: the vertices touched by level-a edges intersected with those of level-b edges.
            let touched = |lv: LevelId| -> Vec<LinkId> {
                let mut v: Vec<LinkId> = Vec::new();
                for (k, l) in edge_levels.iter().enumerate() {
                    if *l == lv {
                        for x in [path[k], path[k + 1]] {
                            if !v.contains(&x) {
                                v.push(x);
                            }
                        }
                    }
                }
                v
            };
            let (ta, tb) = (touched(distinct[0]), touched(distinct[1]));
            let common: Vec<LinkId> = ta.into_iter().filter(|x| tb.contains(x)).collect();
            match common.as_slice() {
                [k] => Ok(FundamentalCircuit {
                    gear: GearId::from_index(m),
                    gear_i: g.gear_i,
                    gear_j: g.gear_j,
                    carrier: *k,
                    level_i: edge_levels[0],
                    level_j: edge_levels[edge_levels.len() - 1],
                    path,
                }),
                _ => Err(TopologyError::AmbiguousTransferVertex {
                    pair: g.name.clone(),
                    candidates: common
                        .iter()
                        .map(|l| links[l.index()].name.clone())
                        .collect(),
                }),
            }
        })
        .collect()
}

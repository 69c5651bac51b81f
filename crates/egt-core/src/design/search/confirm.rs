//! The exact confirmation of a leaf: the candidate train rebuilt and solved
//! by the transmission analysis, checked against the targets.

use crate::error::DesignError;
use crate::model::train::Train;
use crate::spec::Spec;

use super::Search;
use super::candidates::Candidate;
use super::layouts::place;
use super::space::Teeth;

impl Search {
    /// The base spec with a candidate's layout and teeth written in.
    pub fn candidate_spec(&self, teeth: &[Teeth], layout: &[(String, Vec<String>)]) -> Spec {
        let mut spec = place(&self.base, layout);
        write_teeth(&mut spec, &self.set_names, teeth);
        spec
    }

    /// The targets only the exact analysis checks: every step in range, a
    /// progressive set, and per targeted state the efficiency, the element
    /// torques and the mesh torques.
    pub(super) fn meets_analysis_targets(&self, table: &crate::ShiftTable) -> bool {
        let t = &self.spec.targets;
        if let Some([lo, hi]) = t.steps
            && table
                .steps
                .iter()
                .any(|s| !(s.value >= lo && s.value <= hi))
        {
            return false;
        }
        if t.progressive && table.steps.windows(2).any(|w| w[1].value > w[0].value) {
            return false;
        }
        if t.single_swap
            && table
                .shifts
                .iter()
                .any(|s| s.kind == crate::ShiftKind::Sequential && !s.single_swap)
        {
            return false;
        }
        table
            .gears
            .iter()
            .filter(|g| t.ratios.contains_key(&g.state))
            .all(|g| {
                let efficiency = g.power.as_ref().map(|p| p.efficiency);
                t.efficiency
                    .is_none_or(|min| efficiency.is_some_and(|e| e >= min))
                    && t.max_element_torque
                        .is_none_or(|max| g.elements.iter().all(|e| e.torque.abs() <= max))
                    && t.max_mesh_torque
                        .is_none_or(|max| g.meshes.iter().all(|m| m.multiplier.abs() <= max))
            })
    }

    /// Rebuild the train with the candidate's teeth and solve it exactly;
    /// None when it fails a target only that analysis can check.
    /// In a freed layout, a candidate egt cannot analyse (a state it
    /// refuses) is rejected; in the base layout it is the base train's error.
    pub(super) fn confirm(
        &self,
        pick: &[u32],
        ks: &[usize],
    ) -> Result<Option<Candidate>, DesignError> {
        let layout = self.layouts.named(pick);
        let point: Vec<(usize, usize)> = ks.iter().map(|&i| (i, i + 1)).collect();
        let sets = self.teeth_of(&point).ok_or_else(|| DesignError::Invalid {
            field: "sets".into(),
            message: "a leaf without teeth reached confirmation".into(),
        })?;
        let teeth: Vec<Teeth> = sets.iter().map(|t| t[0]).collect();
        let analysed =
            Train::from_spec(&self.candidate_spec(&teeth, &layout)).and_then(|t| t.shift_table());
        let table = match analysed {
            Ok(table) => table,
            Err(_) if !layout.is_empty() => return Ok(None),
            Err(e) => return Err(e.into()),
        };
        if !self.meets_analysis_targets(&table) {
            return Ok(None);
        }
        let mut ratios = Vec::new();
        let mut err2 = 0.0;
        let mut nt = 0;
        for g in &table.gears {
            let exact = g
                .ratio_exact
                .as_ref()
                .map(crate::numerics::exact::display)
                .unwrap_or_default();
            if let Some(t) = self.spec.targets.ratios.get(&g.state) {
                err2 += ((g.ratio - t) / t).powi(2);
                nt += 1;
            }
            ratios.push((g.state.clone(), g.ratio, exact));
        }
        let ratio = |ring: i64, sun: i64| {
            crate::numerics::exact::display(&crate::numerics::exact::frac(ring, sun))
        };
        let targeted = || {
            table
                .gears
                .iter()
                .filter(|g| self.spec.targets.ratios.contains_key(&g.state))
        };
        let efficiency = targeted()
            .filter_map(|g| g.power.as_ref().map(|p| p.efficiency))
            .reduce(f64::min);
        let element_torque = targeted()
            .flat_map(|g| g.elements.iter().map(|e| e.torque.abs()))
            .reduce(f64::max);
        let mesh_torque = targeted()
            .flat_map(|g| g.meshes.iter().map(|m| m.multiplier.abs()))
            .reduce(f64::max);
        let planet_speed = targeted()
            .flat_map(|g| g.relative.iter().map(|r| r.speed.abs()))
            .reduce(f64::max);
        Ok(Some(Candidate {
            same_ratio_teeth: sets.iter().map(|t| (*t).clone()).collect(),
            efficiency,
            element_torque,
            mesh_torque,
            planet_speed,
            concept: None,
            basic: teeth
                .iter()
                .map(|t| {
                    let (n, d) = t.basic();
                    ratio(n, d)
                })
                .collect(),
            basic2: teeth
                .iter()
                .map(|t| t.sun2.map(|s2| ratio(t.ring, s2)))
                .collect(),
            alternatives: sets.iter().map(|t| t.len()).collect(),
            teeth,
            ratios,
            spread: table.spread.as_ref().map(|s| s.value),
            layout,
            score: if nt > 0 {
                (err2 / nt as f64).sqrt()
            } else {
                0.0
            },
        }))
    }
}

/// Write each named set's teeth into a train spec.
pub(crate) fn write_teeth(spec: &mut Spec, set_names: &[String], teeth: &[Teeth]) {
    for (name, t) in set_names.iter().zip(teeth) {
        if let Some(p) = spec.planetary.iter_mut().find(|p| &p.name == name) {
            p.teeth.sun = Some(t.sun);
            p.teeth.ring = Some(t.ring);
            p.teeth.planet = Some(t.planet);
            if t.sun2.is_some() {
                p.teeth.sun2 = t.sun2;
            }
            if t.planet2.is_some() {
                p.teeth.planet2 = t.planet2;
            }
        }
    }
}

//! The shift asked for, checked before a run: every number finite and in
//! range ([`ShiftSim`]'s fields), and each changing element's capacity (its
//! own ramp, or the single off-going / on-coming ramp).

use super::friction::Capacity;
use super::shift::{MAX_STEP, MIN_RTOL, ShiftSim};
use crate::error::{AnalysisError, Error, Result};

impl ShiftSim {
    pub(super) fn validate(&self) -> Result<()> {
        let finite = |name: &str, v: f64| {
            if v.is_finite() {
                Ok(())
            } else {
                Err(Error::invalid(
                    format!("shift.{name}"),
                    format!("{v} is not finite"),
                ))
            }
        };
        finite("input_speed", self.input_speed)?;
        for (i, c) in self.road_load.iter().enumerate() {
            finite(&format!("road_load[{i}]"), *c)?;
        }
        for (name, v) in [("vehicle_inertia", self.vehicle_inertia)] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::invalid(
                    format!("shift.{name}"),
                    format!("{v} must be finite and >= 0"),
                ));
            }
        }
        for (name, v) in [
            ("t_end", self.t_end),
            ("rtol", self.rtol),
            ("atol", self.atol),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::invalid(
                    format!("shift.{name}"),
                    format!("{v} must be finite and > 0"),
                ));
            }
        }
        if self.rtol < MIN_RTOL {
            return Err(Error::invalid(
                "shift.rtol",
                format!(
                    "{:e} is below {MIN_RTOL:e}, the smallest relative tolerance a step can meet in double precision",
                    self.rtol
                ),
            ));
        }
        if self.max_steps == 0 {
            return Err(Error::invalid("shift.max_steps", "must be at least 1"));
        }
        // Steps are at most MAX_STEP long: an end time past the budget is
        // refused before any work.
        let least = self.t_end / MAX_STEP;
        if least > self.max_steps as f64 {
            return Err(Error::Analysis(AnalysisError::Budget {
                what: format!("a shift simulation to t_end = {:e} s", self.t_end),
                estimate: format!("at least {least:e} steps (a step is at most {MAX_STEP} s)"),
                limit: format!("{} steps", self.max_steps),
                raise: "shorten `t_end` (`--t-end`) or raise `max_steps` (`--max-steps`)".into(),
            }));
        }
        if let Some(shaft) = &self.output_shaft {
            shaft.validate(self.vehicle_inertia)?;
        }
        self.input_torque.validate()?;
        self.law.validate("shift.law")?;
        if let Some(c) = &self.off_going {
            c.validate("shift.off_going")?;
        }
        if let Some(c) = &self.on_coming {
            c.validate("shift.on_coming")?;
        }
        for (i, (name, c)) in self.ramps.iter().enumerate() {
            c.validate(&format!("shift.ramps.{name}"))?;
            if self.ramps[..i].iter().any(|(n, _)| n == name) {
                return Err(Error::invalid(
                    format!("shift.ramps.{name}"),
                    format!("`{name}` has two ramps"),
                ));
            }
        }
        Ok(())
    }

    /// The capacity of each element that has one: off-going, on-coming,
    /// then held (engaged in both gears and named in `ramps`): its ramp in
    /// `ramps`, else `off_going` / `on_coming` when it is the only element
    /// going its way.
    pub(super) fn capacities(
        &self,
        off: &[String],
        on: &[String],
        held: &[String],
    ) -> Result<Vec<Capacity>> {
        let changing: Vec<&String> = off.iter().chain(on).collect();
        for (name, _) in &self.ramps {
            if !changing.contains(&name) && !held.contains(name) {
                return Err(Error::invalid(
                    format!("shift.ramps.{name}"),
                    format!(
                        "`{name}` is not engaged in `{}` or `{}`: a capacity is for an element that changes (here {}) or one engaged in both (then held by it, not rigidly)",
                        self.from,
                        self.to,
                        listed(&changing)
                    ),
                ));
            }
        }
        let mut out = Vec::with_capacity(changing.len());
        for (group, single, field, verb) in [
            (off, &self.off_going, "off_going", "releases"),
            (on, &self.on_coming, "on_coming", "applies"),
        ] {
            if single.is_some() && group.len() != 1 {
                return Err(Error::invalid(
                    format!("shift.{field}"),
                    format!(
                        "`{}` -> `{}` {verb} {}: `{field}` is for a single element; give each its own ramp (`ramps`)",
                        self.from,
                        self.to,
                        listed(&group.iter().collect::<Vec<_>>())
                    ),
                ));
            }
            for name in group {
                let own = self.ramps.iter().find(|(n, _)| n == name).map(|r| r.1);
                match own.or(*single) {
                    Some(c) => out.push(c),
                    None => {
                        return Err(Error::invalid(
                            format!("shift.ramps.{name}"),
                            format!(
                                "element `{name}` changes in `{}` -> `{}` but has no capacity ramp: give it one (`ramps`){}",
                                self.from,
                                self.to,
                                if group.len() == 1 {
                                    format!(", or `{field}`")
                                } else {
                                    String::new()
                                }
                            ),
                        ));
                    }
                }
            }
        }
        // A held element has its own ramp (that is what makes it held).
        out.extend(
            held.iter()
                .filter_map(|h| self.ramps.iter().find(|(n, _)| n == h).map(|r| r.1)),
        );
        Ok(out)
    }
}

/// `` `A`, `B` `` (or `nothing`).
pub(super) fn listed(names: &[&String]) -> String {
    if names.is_empty() {
        return "nothing".into();
    }
    names
        .iter()
        .map(|n| format!("`{n}`"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The first time in `[0, t_end]` a capacity is positive.
pub(super) fn first_positive(c: &Capacity, t_end: f64) -> Option<f64> {
    if c.at(0.0) > 0.0 {
        return Some(0.0);
    }
    let [a, b] = c.breakpoints();
    // A linear ramp rises from its start.
    [a, b]
        .into_iter()
        .find(|&s| s.is_finite() && s <= t_end && c.at(s + 1e-12 * s.abs().max(1.0)) > 0.0)
}

//! The friction law of a clutch or brake: Coulomb friction with a static
//! coefficient not below the kinetic one, optionally falling from static to
//! kinetic with slip speed (a Stribeck-like exponential), times a capacity
//! (normal force times radius times surface count, lumped) that is a function
//! of time, e.g. a linear pressure ramp.

use crate::error::{Error, Result};

/// Capacity of a friction element (N·m per unit coefficient) against time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Capacity {
    /// The same capacity at all times.
    Constant(f64),
    /// `from` until `t0`, a straight line to `to` at `t1`, `to` after.
    Ramp {
        /// Start of the ramp (s).
        t0: f64,
        /// End of the ramp (s).
        t1: f64,
        /// Capacity before `t0`.
        from: f64,
        /// Capacity after `t1`.
        to: f64,
    },
}

impl Capacity {
    /// Checks that every value is finite and non-negative and that the ramp
    /// runs forward in time.
    ///
    /// # Errors
    /// An `Invalid` spec error at `path` naming the offending value.
    pub fn validate(&self, path: &str) -> Result<()> {
        let ok = |v: f64| v.is_finite() && v >= 0.0;
        match *self {
            Capacity::Constant(c) if !ok(c) => Err(Error::invalid(
                path,
                format!("capacity {c} must be finite and >= 0"),
            )),
            Capacity::Ramp { t0, t1, from, to } => {
                if !(t0.is_finite() && t1.is_finite() && t1 >= t0) {
                    return Err(Error::invalid(
                        path,
                        format!("ramp times t0 = {t0}, t1 = {t1} must be finite with t1 >= t0"),
                    ));
                }
                if !ok(from) || !ok(to) {
                    return Err(Error::invalid(
                        path,
                        format!("ramp capacities {from} -> {to} must be finite and >= 0"),
                    ));
                }
                Ok(())
            }
            Capacity::Constant(_) => Ok(()),
        }
    }

    /// Capacity at time `t`.
    pub fn at(&self, t: f64) -> f64 {
        match *self {
            Capacity::Constant(c) => c,
            Capacity::Ramp { t0, t1, from, to } => {
                if t <= t0 {
                    from
                } else if t >= t1 {
                    to
                } else {
                    from + (to - from) * (t - t0) / (t1 - t0)
                }
            }
        }
    }

    /// Times at which the capacity has a kink (the integrator steps onto them).
    pub fn breakpoints(&self) -> [f64; 2] {
        match *self {
            Capacity::Constant(_) => [f64::INFINITY; 2],
            Capacity::Ramp { t0, t1, .. } => [t0, t1],
        }
    }
}

/// Friction coefficients of an element.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrictionLaw {
    /// Coefficient at rest (the lock holds while |torque| <= static × capacity).
    pub mu_static: f64,
    /// Coefficient while slipping fast.
    pub mu_kinetic: f64,
    /// Slip speed (rad/s) over which the coefficient falls from static to
    /// kinetic as `exp(-|slip| / decay)`; `None` means pure Coulomb
    /// (kinetic at any non-zero slip).
    pub decay: Option<f64>,
}

impl FrictionLaw {
    /// Pure Coulomb friction with one coefficient for rest and slip.
    pub fn coulomb(mu: f64) -> Self {
        FrictionLaw {
            mu_static: mu,
            mu_kinetic: mu,
            decay: None,
        }
    }

    /// Checks `0 < mu_kinetic <= mu_static` and a positive finite decay.
    ///
    /// # Errors
    /// An `Invalid` spec error at `path` naming the offending coefficient.
    pub fn validate(&self, path: &str) -> Result<()> {
        let (s, k) = (self.mu_static, self.mu_kinetic);
        if !(k.is_finite() && s.is_finite() && k > 0.0 && s >= k) {
            return Err(Error::invalid(
                format!("{path}.mu_kinetic"),
                format!("need 0 < mu_kinetic ({k}) <= mu_static ({s}), both finite"),
            ));
        }
        if let Some(d) = self.decay
            && !(d.is_finite() && d > 0.0)
        {
            return Err(Error::invalid(
                format!("{path}.decay"),
                format!("decay speed {d} must be finite and > 0"),
            ));
        }
        Ok(())
    }

    /// Coefficient at slip speed `slip` (rad/s).
    pub fn mu(&self, slip: f64) -> f64 {
        match self.decay {
            None => self.mu_kinetic,
            Some(d) => {
                self.mu_kinetic + (self.mu_static - self.mu_kinetic) * (-slip.abs() / d).exp()
            }
        }
    }

    /// Friction torque acting on the faster side (opposing `slip`, the speed
    /// of that side relative to the other) with capacity `capacity`.
    pub fn slipping_torque(&self, slip: f64, capacity: f64) -> f64 {
        if slip == 0.0 {
            0.0
        } else {
            -slip.signum() * self.mu(slip) * capacity
        }
    }

    /// Largest torque a locked element transmits with capacity `capacity`.
    pub fn static_limit(&self, capacity: f64) -> f64 {
        self.mu_static * capacity
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ramp_is_continuous_and_clamped() {
        let c = Capacity::Ramp {
            t0: 0.1,
            t1: 0.3,
            from: 0.0,
            to: 200.0,
        };
        c.validate("shift.ramp").expect("test case is valid");
        assert_eq!(c.at(0.0), 0.0);
        assert_eq!(c.at(0.1), 0.0);
        assert!((c.at(0.2) - 100.0).abs() < 1e-12);
        assert_eq!(c.at(0.3), 200.0);
        assert_eq!(c.at(9.0), 200.0);
    }

    #[test]
    fn bad_coefficients_and_ramps_are_named() {
        let bad = FrictionLaw {
            mu_static: 0.1,
            mu_kinetic: 0.2,
            decay: None,
        };
        let e = bad
            .validate("shift.c")
            .expect_err("test case is invalid")
            .to_string();
        assert!(e.contains("shift.c.mu_kinetic"), "{e}");
        let back = Capacity::Ramp {
            t0: 1.0,
            t1: 0.5,
            from: 0.0,
            to: 1.0,
        };
        assert!(
            back.validate("shift.ramp")
                .expect_err("test case is invalid")
                .to_string()
                .contains("shift.ramp")
        );
        assert!(Capacity::Constant(f64::NAN).validate("cap").is_err());
    }

    #[test]
    fn coefficient_falls_from_static_to_kinetic() {
        let law = FrictionLaw {
            mu_static: 0.15,
            mu_kinetic: 0.1,
            decay: Some(2.0),
        };
        law.validate("c").expect("test case is valid");
        assert!((law.mu(0.0) - 0.15).abs() < 1e-15);
        assert!((law.mu(2.0) - (0.1 + 0.05 * (-1.0f64).exp())).abs() < 1e-15);
        assert!(law.mu(1e3) - 0.1 < 1e-15);
        // Friction always opposes slip: its power is never positive.
        for s in [-5.0, -0.1, 0.1, 5.0] {
            assert!(law.slipping_torque(s, 100.0) * s < 0.0);
        }
    }
}

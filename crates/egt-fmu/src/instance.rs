//! One instance of the unit, in safe Rust: its values by value reference,
//! the FMI 2.0 Co-Simulation state machine (instantiated, initialisation,
//! stepping, terminated), and `do_step` over egt-core's [`ShiftStepper`]
//! (a transmission) or [`SimulationStepper`] (a train without elements).
//! Every call returns `Err(message)` for the boundary to log and turn into
//! `fmi2Error`; a refused call leaves the instance as it was.

use egt_core::shift_dynamics::{
    DEFAULT_MAX_STEPS, FrictionLaw, InputTorque, ShiftMethod, ShiftSim, ShiftStepper, StepInputs,
};
use egt_core::{Format, LinkId, Method, SimulationStepper, Train};

use crate::variables::{Causality, INITIAL_GEAR, Kind, LOCKED_ELEMENTS, Role, Variables};

/// What an initialised instance steps.
#[derive(Debug, Clone)]
enum Stepper {
    Shift(Box<ShiftStepper>),
    Train(Box<SimulationStepper>),
}

/// Where an instance is in the FMI 2.0 Co-Simulation state machine.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum State {
    /// After `fmi2Instantiate` or `fmi2Reset`: parameters may be set.
    Instantiated,
    /// Between `fmi2EnterInitializationMode` and its exit.
    Initialization,
    /// After initialisation: `fmi2DoStep`.
    Stepping,
    /// After `fmi2Terminate`.
    Terminated,
}

/// One instance: the train, the variables, their values and the stepper.
#[derive(Debug, Clone)]
pub struct Instance {
    train: Train,
    variables: Variables,
    reals: Vec<f64>,
    /// The first time derivative of each real input (0: held over the step).
    rates: Vec<f64>,
    initial_gear: i32,
    locked: i32,
    state: State,
    start_time: f64,
    stepper: Option<Stepper>,
}

/// What a refused call says.
pub type Refusal = String;

impl Instance {
    /// An instance of the unit made from `spec` (TOML, or JSON when it
    /// starts with `{`).
    ///
    /// # Errors
    /// The spec's error, or a spec that is not a transmission.
    pub fn new(spec: &str) -> Result<Instance, Refusal> {
        let format = if spec.trim_start().starts_with('{') {
            Format::Json
        } else {
            Format::Toml
        };
        let train = Train::from_str(spec, format, "spec").map_err(|e| e.to_string())?;
        let variables = Variables::of(&train).map_err(|e| e.to_string())?;
        let n = variables.reals.len();
        let mut instance = Instance {
            train,
            variables,
            reals: vec![0.0; n],
            rates: vec![0.0; n],
            initial_gear: 1,
            locked: 0,
            state: State::Instantiated,
            start_time: 0.0,
            stepper: None,
        };
        instance.reset();
        Ok(instance)
    }

    /// The variables.
    pub fn variables(&self) -> &Variables {
        &self.variables
    }

    /// The state.
    pub fn state(&self) -> State {
        self.state
    }

    /// Back to the state after instantiation, with the start values.
    pub fn reset(&mut self) {
        for (v, r) in self.reals.iter_mut().zip(&self.variables.reals) {
            *v = r.start.unwrap_or(0.0);
        }
        self.rates.fill(0.0);
        self.initial_gear = 1;
        self.locked = 0;
        self.state = State::Instantiated;
        self.start_time = 0.0;
        self.stepper = None;
    }

    /// `fmi2SetupExperiment`: the start time.
    ///
    /// # Errors
    /// Not instantiated, or a start time that is not finite.
    pub fn setup_experiment(&mut self, start: f64) -> Result<(), Refusal> {
        self.expect(&[State::Instantiated], "fmi2SetupExperiment")?;
        if !start.is_finite() {
            return Err(format!("the start time {start} is not finite"));
        }
        self.start_time = start;
        Ok(())
    }

    /// `fmi2EnterInitializationMode`.
    ///
    /// # Errors
    /// Not instantiated.
    pub fn enter_initialization(&mut self) -> Result<(), Refusal> {
        self.expect(&[State::Instantiated], "fmi2EnterInitializationMode")?;
        self.state = State::Initialization;
        Ok(())
    }

    /// `fmi2ExitInitializationMode`: the train in the initial gear's steady
    /// motion, its consistent mode, the outputs at the start.
    ///
    /// # Errors
    /// Not initialising; egt's refusal (a parameter out of range, missing
    /// inertias, an initial gear whose elements cannot hold).
    pub fn exit_initialization(&mut self) -> Result<(), Refusal> {
        self.expect(&[State::Initialization], "fmi2ExitInitializationMode")?;
        let stepper = match self.variables.kind {
            Kind::Transmission => Stepper::Shift(Box::new(self.shift_stepper()?)),
            Kind::Train => Stepper::Train(Box::new(self.train_stepper()?)),
        };
        self.stepper = Some(stepper);
        self.state = State::Stepping;
        self.write_outputs();
        Ok(())
    }

    fn value(&self, role: Role) -> f64 {
        self.variables
            .real(role)
            .map_or(0.0, |vr| self.reals[vr as usize])
    }

    /// A transmission's inputs for a step: the input and load torques and
    /// each element's capacity with its rate.
    fn step_inputs(&self) -> StepInputs {
        let k = self.variables.elements.len();
        let mut inputs = StepInputs {
            input_torque: 0.0,
            load_torque: 0.0,
            capacity: vec![0.0; k],
            capacity_rate: vec![0.0; k],
        };
        for (vr, r) in self.variables.reals.iter().enumerate() {
            match r.role {
                Role::Capacity(i) => {
                    inputs.capacity[i] = self.reals[vr];
                    inputs.capacity_rate[i] = self.rates[vr];
                }
                Role::InputTorque => inputs.input_torque = self.reals[vr],
                Role::LoadTorque => inputs.load_torque = self.reals[vr],
                _ => {}
            }
        }
        inputs
    }

    /// A train's applied torques, by link index.
    fn link_torques(&self) -> Vec<f64> {
        let mut torques = vec![0.0; self.train.links().len()];
        for (vr, r) in self.variables.reals.iter().enumerate() {
            if let Role::LinkTorque(l) = r.role {
                torques[l] = self.reals[vr];
            }
        }
        torques
    }

    fn shift_stepper(&self) -> Result<ShiftStepper, Refusal> {
        let gear = usize::try_from(self.initial_gear - 1)
            .ok()
            .and_then(|g| self.variables.gears.get(g))
            .ok_or_else(|| {
                format!(
                    "initial_gear {} is not in 1..={}",
                    self.initial_gear,
                    self.variables.gears.len()
                )
            })?
            .clone();
        let value = |role| self.value(role);
        let sim = ShiftSim {
            from: gear.clone(),
            to: gear,
            input_speed: value(Role::InitialSpeed),
            input_torque: InputTorque::Constant(value(Role::InputTorque)),
            road_load: [0, 1, 2].map(|i| value(Role::RoadLoad(i))),
            vehicle_inertia: value(Role::VehicleInertia),
            output_shaft: None,
            law: FrictionLaw {
                mu_static: value(Role::MuStatic),
                mu_kinetic: value(Role::MuKinetic),
                decay: None,
            },
            off_going: None,
            on_coming: None,
            ramps: Vec::new(),
            t_end: 1.0,
            rtol: value(Role::Rtol),
            atol: value(Role::Atol),
            method: ShiftMethod::Auto,
            max_steps: DEFAULT_MAX_STEPS,
            // The unit steps the ideal model (ShiftStepper has no mesh losses).
            losses: false,
        };
        ShiftStepper::new(&self.train, &sim, &self.step_inputs()).map_err(|e| e.to_string())
    }

    fn train_stepper(&self) -> Result<SimulationStepper, Refusal> {
        let initial: Vec<(LinkId, f64)> = (self.variables.reals.iter().enumerate())
            .filter_map(|(vr, r)| match r.role {
                Role::InitialLinkSpeed(l) => Some((LinkId::from_index(l), self.reals[vr])),
                _ => None,
            })
            .collect();
        let method = match &self.train.analysis().simulate {
            Some(s) => match &s.method {
                Some(m) => m.parse().map_err(|e: String| e)?,
                None => Method::default(),
            },
            None => Method::default(),
        };
        SimulationStepper::new(&self.train, &initial, self.value(Role::Dt), method)
            .map_err(|e| e.to_string())
    }

    /// `fmi2Terminate`.
    ///
    /// # Errors
    /// Not stepping or initialising.
    pub fn terminate(&mut self) -> Result<(), Refusal> {
        self.expect(&[State::Stepping, State::Initialization], "fmi2Terminate")?;
        self.state = State::Terminated;
        Ok(())
    }

    fn expect(&self, states: &[State], call: &str) -> Result<(), Refusal> {
        if states.contains(&self.state) {
            Ok(())
        } else {
            Err(format!("{call} is not allowed in state {:?}", self.state))
        }
    }

    fn variable(&self, vr: u32) -> Result<&crate::variables::RealVariable, Refusal> {
        self.variables
            .reals
            .get(vr as usize)
            .ok_or_else(|| format!("no real variable with value reference {vr}"))
    }

    /// `fmi2SetReal`. Every value is checked before any is stored; setting
    /// an input clears its derivative.
    ///
    /// # Errors
    /// An unknown reference, an output, a parameter after initialisation, a
    /// value not finite, a negative capacity, a tolerance or coefficient
    /// that is not positive.
    pub fn set_real(&mut self, vrs: &[u32], values: &[f64]) -> Result<(), Refusal> {
        for (&vr, &v) in vrs.iter().zip(values) {
            let var = self.variable(vr)?;
            let name = &var.name;
            match var.causality {
                Causality::Output => return Err(format!("`{name}` is an output")),
                Causality::Parameter
                    if !matches!(self.state, State::Instantiated | State::Initialization) =>
                {
                    return Err(format!(
                        "`{name}` is a parameter: set it before initialisation ends"
                    ));
                }
                Causality::Input if self.state == State::Terminated => {
                    return Err(format!("`{name}` cannot be set after fmi2Terminate"));
                }
                _ => {}
            }
            if !v.is_finite() {
                return Err(format!("`{name}` = {v} is not finite"));
            }
            let positive = matches!(
                var.role,
                Role::MuStatic | Role::MuKinetic | Role::Rtol | Role::Atol | Role::Dt
            );
            if positive && v <= 0.0 {
                return Err(format!("`{name}` = {v} must be > 0"));
            }
            let non_negative = matches!(var.role, Role::Capacity(_) | Role::VehicleInertia);
            if non_negative && v < 0.0 {
                return Err(format!("`{name}` = {v} must be >= 0"));
            }
        }
        for (&vr, &v) in vrs.iter().zip(values) {
            self.reals[vr as usize] = v;
            self.rates[vr as usize] = 0.0;
        }
        Ok(())
    }

    /// `fmi2GetReal`.
    ///
    /// # Errors
    /// An unknown reference.
    pub fn get_real(&self, vrs: &[u32], values: &mut [f64]) -> Result<(), Refusal> {
        for (&vr, v) in vrs.iter().zip(values) {
            self.variable(vr)?;
            *v = self.reals[vr as usize];
        }
        Ok(())
    }

    /// `fmi2SetInteger`: `initial_gear`, before initialisation ends.
    ///
    /// # Errors
    /// Another reference, or too late.
    pub fn set_integer(&mut self, vrs: &[u32], values: &[i32]) -> Result<(), Refusal> {
        for (&vr, &v) in vrs.iter().zip(values) {
            if vr != INITIAL_GEAR || self.variables.kind != Kind::Transmission {
                return Err(format!("integer {vr} cannot be set"));
            }
            self.expect(
                &[State::Instantiated, State::Initialization],
                "setting initial_gear",
            )?;
            self.initial_gear = v;
        }
        Ok(())
    }

    /// `fmi2GetInteger`.
    ///
    /// # Errors
    /// An unknown reference.
    pub fn get_integer(&self, vrs: &[u32], values: &mut [i32]) -> Result<(), Refusal> {
        for (&vr, v) in vrs.iter().zip(values) {
            if self.variables.kind != Kind::Transmission {
                return Err(format!("no integer variable with value reference {vr}"));
            }
            *v = match vr {
                INITIAL_GEAR => self.initial_gear,
                LOCKED_ELEMENTS => self.locked,
                _ => return Err(format!("no integer variable with value reference {vr}")),
            };
        }
        Ok(())
    }

    /// `fmi2SetRealInputDerivatives`: first derivatives of inputs, used over
    /// the next step (a capacity then moves on a straight line over it; the
    /// input torque stays held).
    ///
    /// # Errors
    /// An order other than 1, a reference that is not an input, a value not
    /// finite.
    pub fn set_input_derivatives(
        &mut self,
        vrs: &[u32],
        orders: &[i32],
        values: &[f64],
    ) -> Result<(), Refusal> {
        for ((&vr, &order), &v) in vrs.iter().zip(orders).zip(values) {
            let var = self.variable(vr)?;
            if var.causality != Causality::Input {
                return Err(format!("`{}` is not an input", var.name));
            }
            if order != 1 {
                return Err(format!(
                    "derivative of order {order} of `{}`: only order 1 is taken",
                    var.name
                ));
            }
            if !v.is_finite() {
                return Err(format!(
                    "the derivative of `{}` = {v} is not finite",
                    var.name
                ));
            }
        }
        for (&vr, &v) in vrs.iter().zip(values) {
            self.rates[vr as usize] = v;
        }
        Ok(())
    }

    /// `fmi2DoStep`: egt's integrator from `current` to `current + h`, with
    /// events located inside the step; the outputs at its end. The input
    /// derivatives are used for this step and then cleared.
    ///
    /// # Errors
    /// Not stepping, `current` not the time reached, egt's refusal (the
    /// instance stays at `current`).
    pub fn do_step(&mut self, current: f64, h: f64) -> Result<(), Refusal> {
        self.expect(&[State::Stepping], "fmi2DoStep")?;
        let reached = self.time();
        if (current - reached).abs() > 1e-9 * reached.abs().max(1.0) {
            return Err(format!(
                "the step starts at {current}, but the unit is at {reached}"
            ));
        }
        let (inputs, torques) = (self.step_inputs(), self.link_torques());
        match self.stepper.as_mut().ok_or("no stepper")? {
            Stepper::Shift(s) => s.advance(&inputs, h),
            Stepper::Train(s) => s.advance(&torques, h),
        }
        .map_err(|e| e.to_string())?;
        self.rates.fill(0.0);
        self.write_outputs();
        Ok(())
    }

    /// The time reached.
    pub fn time(&self) -> f64 {
        self.start_time
            + match &self.stepper {
                Some(Stepper::Shift(s)) => s.time(),
                Some(Stepper::Train(s)) => s.time(),
                None => 0.0,
            }
    }

    fn write_outputs(&mut self) {
        match &self.stepper {
            Some(Stepper::Shift(s)) => {
                for (vr, r) in self.variables.reals.iter().enumerate() {
                    self.reals[vr] = match r.role {
                        Role::Speed(c) => s.speeds()[c],
                        Role::OutputTorque => s.output_torque(),
                        Role::Slip(i) => s.slip(i),
                        Role::ElementTorque(i) => s.element_torque(i),
                        Role::Energy(i) => s.dissipated(i),
                        Role::LockTime(i) => s.lock_time(i).map_or(-1.0, |t| self.start_time + t),
                        _ => continue,
                    };
                }
                self.locked = (0..self.variables.elements.len().min(31))
                    .filter(|&i| s.locked(i))
                    .map(|i| 1 << i)
                    .sum();
            }
            Some(Stepper::Train(s)) => {
                for (vr, r) in self.variables.reals.iter().enumerate() {
                    self.reals[vr] = match r.role {
                        Role::LinkSpeed(l) => s.speeds()[l],
                        Role::Work => s.work(),
                        Role::KineticEnergy => s.energy(),
                        _ => continue,
                    };
                }
            }
            None => {}
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    fn zf() -> Instance {
        let spec = std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../examples/zf_8hp70.toml"
        ))
        .unwrap();
        Instance::new(&spec).unwrap()
    }

    fn vr(i: &Instance, name: &str) -> u32 {
        let at = i.variables().reals.iter().position(|r| r.name == name);
        u32::try_from(at.unwrap()).unwrap()
    }

    #[test]
    fn the_state_machine_refuses_calls_out_of_order_and_bad_values() {
        let mut i = zf();
        assert!(i.do_step(0.0, 1e-3).unwrap_err().contains("not allowed"));
        let cap = vr(&i, "C.capacity");
        assert!(
            i.set_real(&[cap], &[f64::NAN])
                .unwrap_err()
                .contains("not finite")
        );
        assert!(i.set_real(&[cap], &[-1.0]).unwrap_err().contains(">= 0"));
        let out = vr(&i, "output.speed");
        assert!(i.set_real(&[out], &[1.0]).unwrap_err().contains("output"));
        i.setup_experiment(0.0).unwrap();
        i.enter_initialization().unwrap();
        i.exit_initialization().unwrap();
        let speed = vr(&i, "initial_input_speed");
        assert!(
            i.set_real(&[speed], &[1.0])
                .unwrap_err()
                .contains("parameter")
        );
        assert!(
            i.do_step(0.5, 1e-3)
                .unwrap_err()
                .contains("the unit is at 0")
        );
        i.do_step(0.0, 1e-3).unwrap();
        assert!((i.time() - 1e-3).abs() < 1e-15);
        // The start values hold the first gear: A, B and C locked (bits 1, 2, 4).
        let mut locked = [0];
        i.get_integer(&[LOCKED_ELEMENTS], &mut locked).unwrap();
        assert_eq!(locked[0], 1 + 2 + 4);
        i.reset();
        assert_eq!(i.state(), State::Instantiated);
        assert!((i.time()).abs() < 1e-15);
    }

    #[test]
    fn an_initial_gear_out_of_range_is_refused_at_initialisation() {
        let mut i = zf();
        i.set_integer(&[INITIAL_GEAR], &[10]).unwrap();
        i.enter_initialization().unwrap();
        let e = i.exit_initialization().unwrap_err();
        assert!(e.contains("initial_gear 10 is not in 1..=9"), "{e}");
    }

    #[test]
    fn a_train_without_elements_steps_as_its_simulation_and_has_no_integers() {
        let text = std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../examples/fig5_stability.toml"
        ))
        .unwrap();
        let mut i = Instance::new(&text).unwrap();
        assert!(i.set_integer(&[INITIAL_GEAR], &[1]).is_err());
        assert!(i.get_integer(&[LOCKED_ELEMENTS], &mut [0]).is_err());
        let dt = vr(&i, "dt");
        assert!(i.set_real(&[dt], &[0.0]).unwrap_err().contains("> 0"));
        i.enter_initialization().unwrap();
        i.exit_initialization().unwrap();
        for k in 0..100 {
            i.do_step(f64::from(k) * 1e-2, 1e-2).unwrap();
        }
        // The spec's own simulation: RK4, dt 1e-3, t_end 1, from 330 and 80.
        let train = egt_core::Train::from_str(&text, Format::Toml, "fig5").unwrap();
        let req = egt_core::SimulationRequest::from_spec(&train).unwrap();
        let last = train.simulate(&req).unwrap().samples.pop().unwrap();
        for link in ["2", "3", "4", "6"] {
            let l = train.link_id(link).unwrap().index();
            let mut w = [0.0];
            i.get_real(&[vr(&i, &format!("{link}.speed"))], &mut w)
                .unwrap();
            assert!((w[0] - last.speed[l]).abs() < 1e-9 * last.speed[l].abs().max(1.0));
        }
        let mut work = [0.0];
        i.get_real(&[vr(&i, "work")], &mut work).unwrap();
        assert!((work[0] - last.work).abs() < 1e-9 * last.work.abs().max(1.0));
    }
}

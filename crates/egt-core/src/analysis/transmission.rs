//! Automatic transmissions: a multi-DOF gear train plus shift elements, and a
//! table of gear states ("clutching sequence", the use the paper's introduction
//! names). Each state engages some elements; each engaged element adds one
//! constraint row to the Willis equations (2):
//!
//! - brake on link x: w_x = 0 ([`Extra::Hold`]);
//! - clutch joining links x and y: w_x - w_y = 0 ([`Extra::Join`]);
//! - one-way brake / one-way clutch: engaged as their two-way counterpart, and
//!   then checked: can they carry the torque the state puts on them?
//!
//! **One-way convention.** For a one-way element on links (x, y) (y = the
//! frame for a one-way brake) the slip is w_x - w_y. The element lets x
//! overrun (slip > 0) freely and locks against negative slip: engaged, it can
//! only apply a torque T >= 0 to x (and -T to y), i.e. it holds x against
//! turning backwards relative to y. An open one-way element whose slip would be
//! negative would lock, and the state is flagged.
//!
//! Per state, everything is decided exactly first: the rank over the rationals
//! of the Willis rows plus the element rows gives the state's DOF; a state must
//! leave exactly one DOF, with no dependent element rows, the input turning and
//! the output turning, or a [`TransmissionError`] names the state and the
//! redundant elements, the links left free, or what is held. The one null vector
//! of the rows, scaled to a unit input speed, is every link's speed exactly
//! (the ratio input/output as a fraction such as `108/23`). Then, per unit input
//! torque: the static force analysis of section 4 (eq. 10 with no
//! accelerations) with the element rows, giving the output torque, every
//! engaged element's reaction torque (the multiplier of its row), the housing
//! torque and the meshing forces (eq. 11); and the power flow with the meshes'
//! basic efficiencies (efficiency, circulating power). Across the table:
//! steps, spread and the elements swapped at each shift (`transmission/table.rs`).

use num_traits::{Signed, Zero};
use serde::Serialize;

use crate::analysis::dynamics::{DynamicsRequest, MeshLoad};
use crate::analysis::power::{MeshPower, PowerRequest};
use crate::error::{AnalysisError, Error, Result, TransmissionError, suggest};
use crate::model::train::{
    ElementId, GearId, GearState, LinkId, ShiftElement, Train, Transmission,
};
use crate::numerics::exact::{self, Q, QMatrix};
use crate::solve::kinematics::{RelativeSpeed, SpeedInput};
use crate::solve::rows::Extra;
use crate::spec::ElementKind;

mod table;

pub use table::{Shift, ShiftKind, ShiftTable, Spread, Step};

/// A one-way element holds when its torque on its first link is at least
/// minus this (per unit input torque): a torque this small is round-off.
pub const HOLD_TOLERANCE: f64 = 1e-9;
/// Largest acceptable relative residual of the independent power and torque
/// balances; above it the state carries a warning.
pub const BALANCE_TOLERANCE: f64 = 1e-9;

/// The most gear states one transmission may list. Real automatics have about
/// ten; the bound keeps `egt shift` to well under a second (100,000 states took
/// 29 s and 800 MB before it).
pub const MAX_GEAR_STATES: usize = 256;

/// How an open one-way element behaves at the state's speeds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Freewheel {
    /// Positive slip: it overruns freely.
    Overruns,
    /// Zero slip: it turns with no relative motion and carries no torque.
    Idle,
    /// Negative slip: it would lock, adding a constraint the state does not list.
    Locks,
}

/// The slip across an open (disengaged) element, per unit input speed.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Slip {
    /// The element.
    pub element: ElementId,
    /// w_x - w_y for a clutch on (x, y); w_x for a brake on x.
    pub speed: f64,
    /// Exact slip, when the ratios are exact.
    #[serde(serialize_with = "exact::text::option")]
    pub exact: Option<Q>,
    /// For one-way elements: whether it overruns or would lock.
    pub freewheel: Option<Freewheel>,
}

/// How an engaged element is loaded, per unit input torque.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ElementLoad {
    /// The element.
    pub element: ElementId,
    /// Torque the element applies to its first link (a clutch applies minus
    /// this to its second link; a brake takes minus this from the housing).
    pub torque: f64,
    /// For one-way elements: true when the torque has the direction it can
    /// hold (T >= 0 on the first link, see the module's convention).
    pub holds: Option<bool>,
    /// True for a one-way element engaged in parallel with elements that
    /// already impose its constraint: it idles and carries no torque.
    pub parallel: bool,
}

/// Power flow of a state with the meshes' basic efficiencies, per unit input power.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GearPower {
    /// Output power over input power.
    pub efficiency: f64,
    /// Torque delivered at the output per unit input torque, with losses.
    pub output_torque: f64,
    /// Per mesh: absolute powers, rolling power, loss.
    pub meshes: Vec<MeshPower>,
    /// Total mesh loss.
    pub loss: f64,
    /// Largest branch power over the input power (> 1 when power circulates).
    pub circulation_ratio: f64,
    /// The meshes and shafts carrying more than the input power, if any.
    pub circulating: Option<(Vec<GearId>, Vec<LinkId>)>,
}

/// Everything egt reports for one gear state.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GearAnalysis {
    /// State name.
    pub state: String,
    /// Position in the spec's state list.
    pub index: usize,
    /// Engaged elements, as listed.
    pub engaged: Vec<ElementId>,
    /// Input speed over output speed.
    pub ratio: f64,
    /// The exact ratio, when every gear ratio is exact.
    #[serde(serialize_with = "exact::text::option")]
    pub ratio_exact: Option<Q>,
    /// Speed of every link per unit input speed (by link index; None for a
    /// planet without a tooth count).
    pub speed: Vec<Option<f64>>,
    /// Exact speeds, when every gear ratio is exact.
    #[serde(serialize_with = "exact::text::option_vec_option")]
    pub speed_exact: Option<Vec<Option<Q>>>,
    /// Planets' speeds relative to their carriers, per unit input speed.
    pub relative: Vec<RelativeSpeed>,
    /// Slip across every open element.
    pub slips: Vec<Slip>,
    /// Torque delivered at the output per unit input torque (ideal meshes):
    /// minus the load torque the output link must receive.
    pub output_torque: f64,
    /// Torque the housing applies through meshes with the frame (a fixed ring, a
    /// fixed-axis gear), per unit input torque.
    pub housing_torque: f64,
    /// Loads of the engaged elements, in the order engaged.
    pub elements: Vec<ElementLoad>,
    /// Per mesh (ideal): multiplier, torques, tangential forces when radii are known.
    pub meshes: Vec<MeshLoad>,
    /// Power flow with mesh losses (None, with a warning, when it cannot be solved).
    pub power: Option<GearPower>,
    /// |P_out - P_in| / P_in for ideal meshes (an independent check).
    pub power_balance: f64,
    /// |T_in + T_load + T_housing + sum of brake torques| (per unit input torque).
    pub torque_balance: f64,
    /// Warnings (one-way elements that cannot hold or would lock, ill-conditioning).
    pub warnings: Vec<String>,
    /// Notes from the solvers (e.g. how the power-flow directions were found).
    pub notes: Vec<String>,
}

impl GearAnalysis {
    /// The engaged element with the largest absolute torque, and that torque.
    pub fn largest_element_torque(&self) -> Option<(ElementId, f64)> {
        self.elements.iter().map(|e| (e.element, e.torque)).fold(
            None,
            |best: Option<(ElementId, f64)>, (e, t)| match best {
                Some((_, b)) if b.abs() >= t.abs() => best,
                _ => Some((e, t)),
            },
        )
    }
}

/// The constraint row an element imposes, as an extra row of the dynamics.
pub fn element_constraint(e: &ShiftElement) -> Extra {
    match e.kind {
        ElementKind::Brake | ElementKind::OneWayBrake => Extra::Hold(e.links[0]),
        ElementKind::Clutch | ElementKind::OneWayClutch => Extra::Join(e.links[0], e.links[1]),
    }
}

/// True for one-way brakes and clutches.
pub fn is_one_way(kind: ElementKind) -> bool {
    matches!(kind, ElementKind::OneWayBrake | ElementKind::OneWayClutch)
}

/// The index of gear state `state` among `states`.
///
/// # Errors
/// [`TransmissionError::UnknownState`], with the name it may have meant.
pub(crate) fn state_index(states: &[GearState], state: &str) -> Result<usize> {
    states.iter().position(|s| s.name == state).ok_or_else(|| {
        Error::Transmission(TransmissionError::UnknownState {
            state: state.to_string(),
            suggestion: states
                .iter()
                .find(|s| s.name.eq_ignore_ascii_case(state))
                .map(|s| s.name.clone())
                .or_else(|| suggest(state, states.iter().map(|s| s.name.as_str()))),
        })
    })
}

impl Train {
    /// The transmission data, checked for analysis: states present, input and
    /// output distinct moving links with known speeds, elements on sized links.
    ///
    /// # Errors
    /// [`TransmissionError::NoStates`]; spec errors naming the field.
    pub fn checked_transmission(&self) -> Result<&Transmission> {
        let t = self
            .transmission()
            .filter(|t| !t.states.is_empty())
            .ok_or(Error::Transmission(TransmissionError::NoStates))?;
        if t.states.len() > MAX_GEAR_STATES {
            #[allow(clippy::cast_precision_loss)]
            return Err(Error::spec(
                "transmission.states",
                crate::SpecErrorKind::OutOfRange {
                    value: t.states.len() as f64,
                    expected: format!(
                        "at most {MAX_GEAR_STATES} gear states (each is solved and compared with its neighbours)"
                    ),
                },
            ));
        }
        for (link, field) in [(t.input, "input"), (t.output, "output")] {
            if link == self.frame() {
                return Err(Error::invalid(
                    format!("transmission.{field}"),
                    format!("the {field} cannot be the frame `{}`", self.link_name(link)),
                ));
            }
            if !self.link(link).sized {
                return Err(Error::invalid(
                    format!("transmission.{field}"),
                    format!(
                        "the {field} `{}` is a planet without a tooth count; its speed is unknown",
                        self.link_name(link)
                    ),
                ));
            }
        }
        if t.input == t.output {
            return Err(Error::invalid(
                "transmission.output",
                format!(
                    "the output is the input `{}`; name two links",
                    self.link_name(t.input)
                ),
            ));
        }
        for (n, e) in self.elements().iter().enumerate() {
            if let Some(&l) = e.links.iter().find(|&&l| !self.link(l).sized) {
                return Err(Error::invalid(
                    format!("elements[{n}].links"),
                    format!(
                        "element `{}` acts on planet `{}`, which has no tooth count; give `teeth.planet` in its planetary set",
                        e.name,
                        self.link_name(l)
                    ),
                ));
            }
        }
        Ok(t)
    }

    /// Analyse one gear state by name.
    ///
    /// # Errors
    /// [`TransmissionError::UnknownState`], and as [`Train::shift_table`].
    pub fn analyse_gear(&self, state: &str) -> Result<GearAnalysis> {
        let t = self.checked_transmission()?;
        let k = state_index(&t.states, state)?;
        GearSolver::new(self, t)?.analyse(k)
    }

    /// Analyse every gear state and the table across them.
    ///
    /// ```
    /// use egt_core::numerics::exact;
    /// use egt_core::{Format, Train};
    ///
    /// // One simple set (sun 30, ring 72): brake the ring for low, lock the set for direct.
    /// let spec = r#"
    ///     frame = "case"
    ///     [[planetary]]
    ///     name = "P"
    ///     sun = "sun"
    ///     ring = "ring"
    ///     carrier = "carrier"
    ///     teeth = { sun = 30, ring = 72 }
    ///     [[elements]]
    ///     name = "B"
    ///     kind = "brake"
    ///     links = ["ring"]
    ///     [[elements]]
    ///     name = "C"
    ///     kind = "clutch"
    ///     links = ["sun", "carrier"]
    ///     [transmission]
    ///     input = "sun"
    ///     output = "carrier"
    ///     states = { low = ["B"], direct = ["C"] }
    /// "#;
    /// let train = Train::from_str(spec, Format::Toml, "example").unwrap();
    /// let table = train.shift_table().unwrap();
    /// let low = &table.gears[0];
    /// assert_eq!(exact::display(low.ratio_exact.as_ref().unwrap()), "17/5"); // 1 + 72/30
    /// // The brake holds the ring against z_r/z_s of the input torque.
    /// assert!((low.elements[0].torque - 72.0 / 30.0).abs() < 1e-12);
    /// assert_eq!(table.steps[0].exact.as_ref().map(exact::display).as_deref(), Some("17/5"));
    /// assert!(table.shifts[0].single_swap);
    /// ```
    ///
    /// # Errors
    /// Missing ratios; [`TransmissionError`] for the first state that does not
    /// leave exactly one DOF with input and output turning, or whose analysis fails.
    pub fn shift_table(&self) -> Result<ShiftTable> {
        let t = self.checked_transmission()?;
        let solver = GearSolver::new(self, t)?;
        let gears = (0..t.states.len())
            .map(|k| solver.analyse(k))
            .collect::<Result<Vec<_>>>()?;
        Ok(table::build(self, t, gears))
    }
}

/// What a state's constraint rows decide: one DOF, with every link's speed
/// per unit input speed as the null vector of the rows.
struct StateMotion {
    /// Exact speed of every coordinate per unit input speed.
    coords: Vec<Q>,
    /// Engaged elements whose rows are kept (one-way elements in parallel dropped).
    active: Vec<ElementId>,
    /// One-way elements dropped as parallel.
    parallel: Vec<ElementId>,
}

/// Per-train data shared by every state: exact Willis rows.
struct GearSolver<'a> {
    train: &'a Train,
    t: &'a Transmission,
    willis: QMatrix,
    exact: bool,
}

impl<'a> GearSolver<'a> {
    fn new(train: &'a Train, t: &'a Transmission) -> Result<Self> {
        let ratios = train.ratios()?;
        // Exact ratios where given; otherwise the exact value of the double, so
        // that the rank decision itself never depends on round-off.
        let taus: Vec<Q> = train
            .gears()
            .iter()
            .zip(&ratios)
            .map(|(g, &r)| {
                g.ratio
                    .as_ref()
                    .and_then(|x| x.exact.clone())
                    .or_else(|| exact::from_f64(r))
                    .ok_or_else(|| {
                        Error::from(AnalysisError::NonFinite {
                            what: format!("the ratio of gear pair `{}`", g.name),
                            detail: format!("{r}"),
                        })
                    })
            })
            .collect::<Result<_>>()?;
        let willis = crate::model::topology::willis_exact(
            train.links().len(),
            train.frame(),
            train.circuits(),
            |m| taus[m].clone(),
        );
        Ok(GearSolver {
            train,
            t,
            willis,
            exact: train.has_exact_ratios(),
        })
    }

    fn n(&self) -> usize {
        self.train.coordinates().len()
    }

    fn col(&self, l: LinkId) -> usize {
        // Input, output and element links are never the frame (checked).
        self.train.coordinate(l).unwrap_or(usize::MAX)
    }

    fn element(&self, e: ElementId) -> &ShiftElement {
        &self.train.elements()[e.index()]
    }

    fn element_row(&self, e: ElementId) -> Vec<Q> {
        let mut row = vec![Q::zero(); self.n()];
        let links = &self.element(e).links;
        for (s, &l) in links.iter().enumerate() {
            if let Some(c) = self.train.coordinate(l) {
                row[c] += exact::q(if s == 0 { 1 } else { -1 });
            }
        }
        row
    }

    fn rows(&self, elements: &[ElementId]) -> QMatrix {
        let mut a = self.willis.clone();
        a.extend(elements.iter().map(|&e| self.element_row(e)));
        a
    }

    fn names(&self, cols: impl IntoIterator<Item = usize>) -> Vec<String> {
        cols.into_iter()
            .map(|c| {
                self.train
                    .link_name(self.train.coordinates()[c])
                    .to_string()
            })
            .collect()
    }

    fn element_names(&self, es: &[ElementId]) -> Vec<String> {
        es.iter().map(|&e| self.element(e).name.clone()).collect()
    }

    /// Decide the state's DOF exactly and find its motion, or say what is wrong.
    fn motion(&self, k: usize) -> Result<StateMotion> {
        let state = &self.t.states[k];
        let name = state.name.clone();
        let n = self.n();

        // A one-way element whose row adds nothing idles beside the element(s)
        // doing its job (e.g. a band applied over a one-way brake for engine braking).
        let mut active = state.engaged.clone();
        let mut parallel = Vec::new();
        for &e in &state.engaged {
            if !is_one_way(self.element(e).kind) {
                continue;
            }
            let others: Vec<ElementId> = active.iter().copied().filter(|&x| x != e).collect();
            if exact::rank(&self.rows(&others)) == exact::rank(&self.rows(&active)) {
                active = others;
                parallel.push(e);
            }
        }

        let a = self.rows(&active);
        let rank = exact::rank(&a);
        let dof = n - rank;
        if rank < a.len() {
            let jg = self.willis.len();
            let dependent = exact::support(&left_nullspace(&a));
            let elements: Vec<ElementId> = dependent
                .iter()
                .filter(|&&r| r >= jg)
                .map(|&r| active[r - jg])
                .collect();
            let gears = dependent
                .iter()
                .filter(|&&r| r < jg)
                .map(|&r| self.train.gears()[r].name.clone())
                .collect();
            return Err(Error::Transmission(TransmissionError::Redundant {
                state: name,
                elements: self.element_names(&elements),
                gears,
                dof,
            }));
        }
        if dof == 0 {
            return Err(Error::Transmission(TransmissionError::Locked {
                state: name,
                elements: self.element_names(&state.engaged),
            }));
        }
        let input = self.col(self.t.input);
        if dof > 1 {
            let mut held = a.clone();
            let mut row = vec![Q::zero(); n];
            row[input] = exact::q(1);
            held.push(row);
            let free = exact::support(&exact::nullspace(&held, n));
            return Err(Error::Transmission(TransmissionError::Underconstrained {
                state: name,
                dof,
                free: self.names(free),
            }));
        }
        let mut v = exact::nullspace(&a, n).pop().unwrap_or_default();
        if v.len() != n {
            return Err(AnalysisError::Singular {
                what: format!("gear state `{name}`"),
                detail: "no motion found for one degree of freedom".into(),
            }
            .into());
        }
        if v[input].is_zero() {
            return Err(Error::Transmission(TransmissionError::InputHeld {
                state: name,
                input: self.train.link_name(self.t.input).to_string(),
                moving: self.names(exact::support(std::slice::from_ref(&v))),
            }));
        }
        let scale = v[input].clone();
        for x in &mut v {
            *x /= &scale;
        }
        if v[self.col(self.t.output)].is_zero() {
            return Err(Error::Transmission(TransmissionError::OutputHeld {
                state: name,
                output: self.train.link_name(self.t.output).to_string(),
            }));
        }
        Ok(StateMotion {
            coords: v,
            active,
            parallel,
        })
    }

    fn analyse(&self, k: usize) -> Result<GearAnalysis> {
        let train = self.train;
        let state = &self.t.states[k];
        let in_state = |e: Error| -> Error {
            match e {
                Error::Transmission(_) => e,
                other => Error::Transmission(TransmissionError::InState {
                    state: state.name.clone(),
                    cause: Box::new(other),
                }),
            }
        };
        let motion = self.motion(k)?;
        let mut warnings = Vec::new();
        let mut notes = Vec::new();

        // Speeds per unit input speed, exact, by link index.
        let mut exact_speed: Vec<Q> = vec![Q::zero(); train.links().len()];
        for (c, &l) in train.coordinates().iter().enumerate() {
            exact_speed[l.index()] = motion.coords[c].clone();
        }
        let known: Vec<bool> = train.links().iter().map(|l| l.sized).collect();
        let float_speed: Vec<f64> = exact_speed.iter().map(exact::to_f64).collect();
        let speed: Vec<Option<f64>> = float_speed
            .iter()
            .zip(&known)
            .map(|(&v, &kn)| kn.then_some(v))
            .collect();
        let out_speed = &exact_speed[self.t.output.index()];
        let ratio_q = out_speed.recip();
        let ratio = exact::to_f64(&ratio_q);
        let relative = train
            .relative_speeds(&float_speed, Some(&exact_speed), &known)
            .into_iter()
            .map(|mut r| {
                if !self.exact {
                    r.exact = None;
                }
                r
            })
            .collect();

        // Slips across the open elements.
        let slip_of = |e: &ShiftElement| -> Q {
            let w = |s: usize| {
                e.links
                    .get(s)
                    .map_or_else(Q::zero, |l| exact_speed[l.index()].clone())
            };
            w(0) - w(1)
        };
        let mut slips = Vec::new();
        for (i, e) in train.elements().iter().enumerate() {
            let id = ElementId::from_index(i);
            if state.engaged.contains(&id) {
                continue;
            }
            let s = slip_of(e);
            let freewheel = is_one_way(e.kind).then(|| {
                if s.is_positive() {
                    Freewheel::Overruns
                } else if s.is_negative() {
                    Freewheel::Locks
                } else {
                    Freewheel::Idle
                }
            });
            if freewheel == Some(Freewheel::Locks) {
                warnings.push(format!(
                    "open one-way element `{}` would lock: its slip is {} per unit input speed (it holds against negative slip), so it engages in this state",
                    e.name,
                    exact::display(&s)
                ));
            }
            slips.push(Slip {
                element: id,
                speed: exact::to_f64(&s),
                exact: self.exact.then_some(s),
                freewheel,
            });
        }

        // Statics per unit input torque: the load on the output is the unknown.
        let extras: Vec<Extra> = motion
            .active
            .iter()
            .map(|&e| element_constraint(self.element(e)))
            .collect();
        let req = DynamicsRequest {
            torques: vec![(self.t.input, 1.0)],
            accelerations: Vec::new(),
            driving: vec![self.t.output],
            extras,
        };
        let statics = train.inverse_dynamics(&req, None).map_err(in_state)?;
        warnings.extend(statics.warnings.iter().cloned());
        // Multiplier lambda of an element row is the torque its first link spends
        // on it (eq. 7), so the element applies -lambda to that link.
        let load_torque = statics.driving_torques.first().map_or(0.0, |d| d.1);
        let output_torque = -load_torque;
        let housing_torque = statics.torque[train.frame().index()];
        let mut elements = Vec::new();
        let mut brake_sum = 0.0;
        for &e in &state.engaged {
            let el = self.element(e);
            let parallel = motion.parallel.contains(&e);
            let torque = match motion.active.iter().position(|&x| x == e) {
                Some(p) => -statics.element_torques[p],
                None => 0.0,
            };
            if matches!(el.kind, ElementKind::Brake | ElementKind::OneWayBrake) {
                brake_sum += torque;
            }
            let holds = is_one_way(el.kind).then_some(torque >= -HOLD_TOLERANCE);
            if holds == Some(false) {
                warnings.push(format!(
                    "one-way element `{}` cannot hold this state in drive: the state needs {} on `{}` (per unit input torque), against its locking direction; it overruns",
                    el.name,
                    fmt_torque(torque),
                    train.link_name(el.links[0])
                ));
            }
            if parallel {
                warnings.push(format!(
                    "one-way element `{}` is in parallel with other engaged elements that impose its constraint; it idles and carries no torque",
                    el.name
                ));
            }
            elements.push(ElementLoad {
                element: e,
                torque,
                holds,
                parallel,
            });
        }

        // Independent checks: virtual power and the balance of external torques.
        let w_out = exact::to_f64(out_speed);
        let power_balance = (1.0 - output_torque * w_out).abs();
        let torque_balance = (1.0 + load_torque + housing_torque + brake_sum).abs();
        for (what, r) in [
            ("power balance", power_balance),
            ("torque balance", torque_balance),
        ] {
            if r.is_nan() || r > BALANCE_TOLERANCE {
                warnings.push(format!(
                    "{what} residual {r:.3e} exceeds {BALANCE_TOLERANCE:.0e}"
                ));
            }
        }

        // Power flow with the meshes' basic efficiencies.
        let preq = PowerRequest {
            speeds: vec![SpeedInput {
                link: self.t.input,
                speed: 1.0,
                exact: Some(exact::q(1)),
            }],
            dynamics: req,
            losses: true,
        };
        let power = match train.power_flow(&preq, None) {
            Ok(p) => {
                notes.extend(p.notes.iter().cloned());
                Some(GearPower {
                    efficiency: p.totals.efficiency.unwrap_or(0.0),
                    output_torque: -p.dynamics.driving_torques.first().map_or(0.0, |d| d.1),
                    meshes: p.meshes,
                    loss: p.totals.loss,
                    circulation_ratio: p.totals.circulation_ratio,
                    circulating: p.circulating,
                })
            }
            Err(e) => {
                warnings.push(format!("no power flow with mesh losses: {e}"));
                None
            }
        };

        Ok(GearAnalysis {
            state: state.name.clone(),
            index: k,
            engaged: state.engaged.clone(),
            ratio,
            ratio_exact: self.exact.then_some(ratio_q),
            speed,
            speed_exact: self.exact.then(|| {
                exact_speed
                    .into_iter()
                    .zip(&known)
                    .map(|(v, &kn)| kn.then_some(v))
                    .collect()
            }),
            relative,
            slips,
            output_torque,
            housing_torque,
            elements,
            meshes: statics.meshes,
            power,
            power_balance,
            torque_balance,
            warnings,
            notes,
        })
    }
}

fn fmt_torque(t: f64) -> String {
    format!("{t:+.6}")
}

/// A basis of {y : y^T a = 0}.
fn left_nullspace(a: &QMatrix) -> Vec<Vec<Q>> {
    let rows = a.len();
    let cols = a.first().map_or(0, Vec::len);
    let at: QMatrix = (0..cols)
        .map(|c| (0..rows).map(|r| a[r][c].clone()).collect())
        .collect();
    exact::nullspace(&at, rows)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spec::parse::Format;

    /// One simple set, sun 30 / ring 72, ring held by brake `B`, sun = input,
    /// carrier = output; a clutch `C` can lock sun to carrier.
    fn set(states: &str) -> Train {
        let text = format!(
            r#"
            frame = "case"
            [[planetary]]
            name = "P"
            sun = "sun"
            ring = "ring"
            carrier = "carrier"
            teeth = {{ sun = 30, ring = 72, planet = 21 }}
            [[elements]]
            name = "B"
            kind = "brake"
            links = ["ring"]
            [[elements]]
            name = "B2"
            kind = "brake"
            links = ["ring"]
            [[elements]]
            name = "C"
            kind = "clutch"
            links = ["sun", "carrier"]
            [[elements]]
            name = "F"
            kind = "one_way_brake"
            links = ["ring"]
            [transmission]
            input = "sun"
            output = "carrier"
            [transmission.states]
            {states}
            "#
        );
        Train::from_str(&text, Format::Toml, "test").unwrap_or_else(|e| panic!("{e}"))
    }

    #[test]
    fn brake_torque_is_what_the_brake_applies() {
        let t = set(r#""1" = ["B"]"#);
        let g = t.analyse_gear("1").expect("one DOF");
        assert_eq!(
            g.ratio_exact.as_ref().map(exact::display).as_deref(),
            Some("17/5")
        );
        // Hand statics: the ring carries z_r/z_s of the sun torque, the brake
        // holds it with +72/30 (the sun's torque turns the ring backwards).
        assert!((g.elements[0].torque - 72.0 / 30.0).abs() < 1e-12);
        assert!((g.output_torque - 102.0 / 30.0).abs() < 1e-12);
        assert!(g.torque_balance < 1e-12 && g.power_balance < 1e-12);
    }

    #[test]
    fn one_way_brake_in_parallel_idles_and_duplicate_brake_is_redundant() {
        let t = set("\"1\" = [\"B\", \"F\"]\n\"x\" = [\"B\", \"B2\"]");
        let g = t.analyse_gear("1").expect("one DOF");
        assert_eq!(g.elements[1].torque, 0.0);
        assert!(g.elements[1].parallel);
        match t.analyse_gear("x") {
            Err(Error::Transmission(TransmissionError::Redundant { elements, dof, .. })) => {
                assert_eq!(elements, vec!["B".to_string(), "B2".to_string()]);
                assert_eq!(dof, 1);
            }
            other => panic!("{other:?}"),
        }
    }
}

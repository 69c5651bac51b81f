//! # egt-core
//!
//! Graph-based kinematics and dynamics of epicyclic gear trains, after
//! E. Pennestrì, "Dynamic Analysis of Epicyclic Gear Train by Means of Computer
//! Algebra". A gear train is written as a graph (links; turning pairs labelled
//! with an axis level; gear pairs) plus numbers, validated once into a
//! [`Train`], and then analysed.
//!
//! Data flows one way: [`Spec`] (as written) -> [`Train`] (typed graph, tree,
//! fundamental circuits, DOF) -> prepared analyses -> plain result structs.
//!
//! ```
//! use egt_core::{Format, Train, SpeedInput};
//!
//! // A simple planetary set with the ring fixed: sun 30, ring 72 teeth.
//! let spec = r#"
//!     frame = "ring"
//!     [[planetary]]
//!     name = "P"
//!     sun = "sun"
//!     ring = "ring"
//!     carrier = "carrier"
//!     teeth = { sun = 30, ring = 72, planet = 21 }
//! "#;
//! let train = Train::from_str(spec, Format::Toml, "example").unwrap();
//! assert_eq!(train.dof(), 1);
//! let sun = train.link_id("sun").unwrap();
//! let carrier = train.link_id("carrier").unwrap();
//! let speeds = train.kinematics(&[SpeedInput::from((sun, 102.0))]).unwrap();
//! // Willis: w_carrier = w_sun * z_s / (z_s + z_r) = 102 * 30 / 102.
//! assert!((speeds.speed[carrier.index()] - 30.0).abs() < 1e-12);
//! assert_eq!(egt_core::numerics::exact::display(&speeds.exact.unwrap()[carrier.index()]), "30");
//! ```
//!
//! The other analyses of the paper on its example 6.1 (Fig. 3), each checked
//! here against an independent relation:
//!
//! ```
//! use egt_core::{DynamicsRequest, Format, LoadOverrides, PowerRequest, SpeedInput, Train};
//!
//! let text = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/fig3_example61.toml"));
//! let train = Train::from_str(text, Format::Toml, "fig3").unwrap();
//!
//! // Inverse dynamics (eq. 6-11) with the spec's [analysis] loads; the mass
//! // matrix only because an acceleration is prescribed.
//! let req = DynamicsRequest::resolve(&train, &LoadOverrides::default()).unwrap();
//! let mass = train.mass_for(&req).unwrap();
//! let dynamics = train.inverse_dynamics(&req, mass.as_ref()).unwrap();
//! // The accelerations satisfy the Willis equations (eq. 2 differentiated).
//! let ratios = train.ratios().unwrap();
//! let residual = egt_core::solve::kinematics::willis_residual(&train, &ratios, &dynamics.acceleration);
//! assert!(residual < 1e-12);
//!
//! // Power flow: input = output + mesh losses + dK/dt.
//! let speeds: Vec<SpeedInput> = train.analysis().speeds.iter()
//!     .map(|(l, v, q)| SpeedInput { link: *l, speed: *v, exact: q.clone() })
//!     .collect();
//! let flow = train.power_flow(&PowerRequest { speeds, dynamics: req, losses: true }, mass.as_ref()).unwrap();
//! let balance = flow.totals.input_power - flow.totals.output_power - flow.totals.loss - flow.totals.kinetic_rate;
//! assert!(balance.abs() <= 1e-9 * flow.totals.input_power.abs());
//! ```
//!
//! Stability about an operating point (eq. 12-27) and an automatic
//! transmission's shift table from its tooth counts:
//!
//! ```
//! use egt_core::{Format, StabilityRequest, Train, Verdict};
//!
//! let text = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/fig5_stability.toml"));
//! let report = Train::from_str(text, Format::Toml, "fig5").unwrap()
//!     .stability(&StabilityRequest::default()).unwrap();
//! // Stable exactly when no eigenvalue is positive.
//! let stable = report.stability.eigenvalues.iter().all(|&l| l <= report.stability.tolerance);
//! assert_eq!(report.stability.verdict == Verdict::Stable, stable);
//!
//! let text = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/zf_8hp70.toml"));
//! let table = Train::from_str(text, Format::Toml, "8hp").unwrap().shift_table().unwrap();
//! // First gear of the ZF 8HP70: 4.696 as published, exactly 108/23 from the teeth.
//! let first = &table.gears[0];
//! assert_eq!(egt_core::numerics::exact::display(first.ratio_exact.as_ref().unwrap()), "108/23");
//! assert!((first.ratio - 4.696).abs() < 5e-4);
//! ```

#![deny(missing_docs)]
// The compiled batch program (feature `jit`) is the crate's only `unsafe`.
#![cfg_attr(not(feature = "jit"), forbid(unsafe_code))]

// The unit tests share the generated train families of `lab/`, which name
// the crate as its users do.
#[cfg(test)]
extern crate self as egt_core;

// The layers, bottom to top (a blank line between layers keeps rustfmt from
// sorting them); no module imports one above it (`scripts/layers.py`).
pub mod error;

pub mod numerics;

pub mod spec;

pub mod model;

pub mod solve;

pub mod analysis;

pub mod motion;

pub mod batch;
pub mod design;
pub mod synthesis;

pub use analysis::dynamics::{DynamicsRequest, InverseDynamics, LoadOverrides, MeshLoad};
pub use analysis::modes::{
    MeshCheck, ModesRequest, NaturalMode, NaturalModes, SpringLoad, StaticCheck, StaticDeflection,
};
pub use analysis::power::{Driver, LinkPower, MeshPower, PowerFlow, PowerRequest};
pub use analysis::stability::{
    CoordinateSource, Mode, OperatingPoint, ReducedModel, Stability, StabilityReport,
    StabilityRequest, Verdict,
};
pub use analysis::transmission::{
    ElementLoad, Freewheel, GearAnalysis, GearPower, Shift, ShiftKind, ShiftTable, Slip, Spread,
    Step,
};
pub use error::{
    AnalysisError, Error, Result, SpecErrorKind, SyntaxError, TopologyError, TransmissionError,
};
pub use model::circuits::FundamentalCircuit;
pub use model::mass::{MassMatrix, Offset};
pub use model::train::{Edge, GearId, GearPair, LevelId, Link, LinkId, Ratio, RevoluteId, Train};
pub use model::train::{ElementId, GearState, ShiftElement, Transmission};
pub use motion::shift_dynamics;
pub use motion::simulate::{
    LinearCurves, Method, ReducedDynamics, Sample, Simulation, SimulationOptions,
    SimulationOverrides, SimulationRequest, SimulationStepper, TorqueFn, TorqueModel,
};
pub use solve::kinematics::{RelativeSpeed, SpeedInput, Speeds};
pub use solve::rows::Extra;
pub use spec::Spec;
pub use spec::parse::{Format, parse_spec, spec_schema};

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

#![deny(missing_docs)]

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
pub use motion::simulate::{
    LinearCurves, Method, ReducedDynamics, Sample, Simulation, SimulationOptions,
    SimulationOverrides, SimulationRequest, TorqueFn, TorqueModel,
};
pub use solve::kinematics::{KinematicsPlan, RelativeSpeed, SpeedInput, Speeds};
pub use solve::rows::Extra;
pub use spec::Spec;
pub use spec::parse::{Format, parse_spec, spec_schema};

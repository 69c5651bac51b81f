//! # egt-fmu
//!
//! A transmission of egt, or a train without shift elements, as an FMI 2.0
//! Co-Simulation unit (a `.fmu`): the shared library an importer loads (this
//! crate built as a `cdylib`), the model description generated from the
//! spec, and the packager `egt fmu` calls. The physics is egt-core's shift
//! model or its forward dynamics, advanced step by step
//! ([`egt_core::shift_dynamics::ShiftStepper`],
//! [`egt_core::SimulationStepper`]); this crate is the boundary only. docs/fmu.md says what a unit exposes and its limits.
//!
//! - `variables`: the unit's variables from a spec (names, value
//!   references, causalities, units, start values).
//! - `description`: `modelDescription.xml` from the variables (quick-xml).
//! - `instance`: one instance in safe Rust, the FMI state machine and
//!   `do_step`.
//! - `ffi`: the `fmi2*` C functions over an instance.
//! - `package`: the `.fmu` zip.

pub mod description;
// The workspace denies `unsafe_code`; the FMI boundary cannot be written
// without it (raw pointers from the importer, a C-variadic logger), so it is
// allowed in this one module, each block with its SAFETY comment.
#[allow(unsafe_code)]
mod ffi;
pub mod instance;
pub mod package;
pub mod variables;

pub use description::{guid, model_description};
pub use instance::{Instance, State};
pub use package::{LIBRARY_FILE, PLATFORM, PackageError, model_identifier, package};
pub use variables::{NotAUnit, Variables};

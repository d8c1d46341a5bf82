//! Stark-rs: strongly coupled simulation of rigid and deformable bodies with frictional contact.
//!
//! Every phenomenon is an energy written in world positions; one Newton solve per time step
//! minimises their sum over the end-of-step velocities (DESIGN.md §2).
#![warn(missing_docs)]

pub mod contact;
pub mod deformables;
pub mod energy;
pub mod error;
pub mod generated;
pub mod geometry;
pub mod io;
pub mod meshes;
pub mod params;
pub mod presets;
pub mod rigidbodies;
pub mod robots;
pub mod scenes;
pub mod settings;
pub mod simulation;
pub mod solver;
pub mod state;

pub use error::{Result, StarkError};
pub use settings::Settings;
pub use simulation::{RunSummary, Simulation, StateCheck, StepReport, UserEnergyHandle};

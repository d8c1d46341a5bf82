//! The step loop: Newton's method on end-of-step velocities, line search, linear solvers and
//! adaptive time stepping.

pub mod linear;
pub mod newton;
mod trace;
// Settings sit below the solver (they aggregate the contact settings, a model floor);
// `solver::settings` stays as a path.
pub use crate::settings;

pub use newton::{ConvergedBy, NewtonFailure, NewtonReport, PhaseTimes};
pub use settings::{FrameFormat, LinearSolver, NewtonSettings, OutputSettings, Projection, Settings};

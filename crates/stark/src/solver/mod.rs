//! The step loop: Newton's method on end-of-step velocities, line search, linear solvers and
//! adaptive time stepping.

pub mod linear;

//! Joints between rigid bodies (or a body and the world): every joint of Stark's catalogue
//! (stark-features §2.3), a universal joint, position servos and readouts.
//!
//! A joint is a set of primitive energies ([`Primitive`]) on body-fixed points, world points and
//! angular velocities; the kinematic map turns them into forces on the bodies' DOFs, so the same
//! code serves body–body and body–world joints. Hard primitives are penalties hardened to a
//! tolerance: after Newton converges, any whose violation exceeds its tolerance doubles its
//! stiffness and the step is retried (stiffness never decreases), as in Stark. Every accepted
//! step records each primitive's violation and the force and torque it applies to each body
//! (the generalised forces on the body's velocity DOFs, see [`JointReadout`]).
//!
//! The types live here; [`JointSet`] (the joint term) in `set.rs`, the composite-joint builder in
//! `builder.rs`, `Simulation::add_joint` (from a [`JointKind`]) in `add_joint.rs`, the `add_*`
//! wrappers in `constructors.rs`, and run-time control and readouts in `control.rs`.

mod add_joint;
mod builder;
mod constructors;
mod control;
pub mod coupling;
pub mod kind;
#[cfg(test)]
mod old_paths_test;
pub mod primitives;
mod set;

use crate::energy::{Node, PotentialTerm};
use crate::error::{check_param, Result, StarkError};
pub use kind::{JointKind, JointTarget};
use nalgebra::{UnitQuaternion, Vector3};
pub use primitives::Primitive;
pub use set::JointSet;

/// Default stiffness of hard joints, N/m (Stark's default).
pub const DEFAULT_JOINT_STIFFNESS: f64 = 1e6;
/// Default tolerance of point joints, m (Stark's default).
pub const DEFAULT_TOLERANCE_M: f64 = 1e-3;
/// Default tolerance of direction joints, degrees (Stark's default).
pub const DEFAULT_TOLERANCE_DEG: f64 = 1.0;
/// Default delay (velocity error at which a controller reaches its cap), m/s or rad/s.
pub const DEFAULT_CONTROLLER_DELAY: f64 = 0.01;

/// One primitive joint element.
#[derive(Clone, Debug)]
pub struct JointElement {
    /// Label (the composite joint's).
    pub label: String,
    /// The primitive and its parameters.
    pub primitive: Primitive,
    /// Nodes (padded with world points).
    pub nodes: [Node; 4],
    /// The two bodies it acts on (`None` = world), for readouts.
    pub bodies: [Option<u32>; 2],
    /// Stiffness: N/m for hard and spring primitives (unused by controllers).
    pub stiffness: f64,
    /// Tolerance of a hard primitive: m, or rad if angular (∞: never hardened).
    pub tolerance: f64,
    /// Disabled elements have no energy.
    pub enabled: bool,
    /// Position servo driving a velocity controller, if any.
    pub servo: Option<Servo>,
    /// Readout at the last converged step.
    pub readout: JointReadout,
}

/// A position servo: each step the controller's target velocity is set to close the remaining
/// error to `target` within `response_time_s` (capped by the controller's force or torque).
///
/// It is a proportional controller on the velocity target, so a steady load `L` (below the
/// controller's cap `F`, with its delay `δ`) leaves the offset `L·δ·response_time_s/F` (e.g.
/// 0.025° for a 30° arm held at half the cap with δ = 0.01 rad/s and 0.1 s). Angle errors are
/// taken modulo 360° into (−180°, 180°]: a hinge servo turns the shorter way to its target.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Servo {
    /// Target angle (rad, modulo 2π) or position (m).
    pub target: f64,
    /// Time constant of the approach, s (at least one step).
    pub response_time_s: f64,
    /// How to measure the current angle or position.
    pub measure: Measure,
}

/// A joint coordinate, measured from body-fixed directions and points.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Measure {
    /// Angle of b relative to a about a's axis: `atan2((u_a × u_b)·axis, u_a·u_b)` with the
    /// reference directions `u_a`, `u_b` (perpendicular to the axis, equal at creation).
    Angle {
        /// Body a (None = world).
        a: Option<u32>,
        /// Body b.
        b: Option<u32>,
        /// Axis in a's frame.
        axis_a: Vector3<f64>,
        /// Reference direction in a's frame.
        ref_a: Vector3<f64>,
        /// Reference direction in b's frame.
        ref_b: Vector3<f64>,
    },
    /// Position of b's anchor relative to a's along a's axis (zero at creation).
    Position {
        /// Body a (None = world).
        a: Option<u32>,
        /// Body b.
        b: Option<u32>,
        /// Anchor in a's frame.
        anchor_a: Vector3<f64>,
        /// Anchor in b's frame.
        anchor_b: Vector3<f64>,
        /// Axis in a's frame.
        axis_a: Vector3<f64>,
    },
}

/// Pose source for measuring: body positions and orientations.
struct Poses<'a> {
    t: &'a dyn Fn(usize) -> Vector3<f64>,
    q: &'a dyn Fn(usize) -> UnitQuaternion<f64>,
}

impl Measure {
    fn frame(p: &Poses, body: Option<u32>) -> (Vector3<f64>, UnitQuaternion<f64>) {
        match body {
            None => (Vector3::zeros(), UnitQuaternion::identity()),
            Some(b) => ((p.t)(b as usize), (p.q)(b as usize)),
        }
    }

    fn value(&self, p: &Poses) -> f64 {
        match *self {
            Measure::Angle {
                a,
                b,
                axis_a,
                ref_a,
                ref_b,
            } => {
                let (_, qa) = Self::frame(p, a);
                let (_, qb) = Self::frame(p, b);
                let (axis, ua, ub) = (qa * axis_a, qa * ref_a, qb * ref_b);
                ua.cross(&ub).dot(&axis).atan2(ua.dot(&ub))
            }
            Measure::Position {
                a,
                b,
                anchor_a,
                anchor_b,
                axis_a,
            } => {
                let (ta, qa) = Self::frame(p, a);
                let (tb, qb) = Self::frame(p, b);
                ((tb + qb * anchor_b) - (ta + qa * anchor_a)).dot(&(qa * axis_a))
            }
        }
    }
}

/// What a primitive did at the last accepted step.
///
/// Forces and torques are the generalised forces the joint's energy puts on each body's velocity
/// DOFs, divided by the time step: `f = −(∂x/∂v)ᵀ∇ₓE/dt` and `τ = −(∂x/∂ω)ᵀ∇ₓE/dt`, summed over
/// the joint's points `x`. They are what the discrete momentum balance of the step sees, so at
/// equilibrium (or in a steady state) they are exactly minus the external load. The force is
/// `−∇ₓE` summed over the points; the torque is the moment of those forces about the centre of
/// mass up to `O(ω·dt)`: for a body turning by `ω·dt` per step, the moment taken at the
/// end-of-step pose is rotated by about `ω·dt/2` against it (8% of the load for a body spinning
/// at 16 rad/s with dt = 10 ms, which the generalised torque does not suffer).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct JointReadout {
    /// Violation: m, or rad for angular primitives.
    pub violation: f64,
    /// Force on body a (world frame), N.
    pub force_a_n: [f64; 3],
    /// Torque on body a about its centre of mass, N·m.
    pub torque_a_n_m: [f64; 3],
    /// Force on body b, N.
    pub force_b_n: [f64; 3],
    /// Torque on body b about its centre of mass, N·m.
    pub torque_b_n_m: [f64; 3],
}

/// A joint: the primitive elements it is made of.
#[derive(Clone, Debug, PartialEq)]
pub struct JointHandle {
    /// Label.
    pub label: String,
    /// Its elements in [`JointSet::elements`].
    pub elements: Vec<u32>,
    /// The element of its velocity controller or spring, if any.
    pub driver: Option<u32>,
    /// Its coordinate (hinge angle or slider position), if any.
    pub measure: Option<Measure>,
}

/// State of a joint at the last accepted step.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct JointState {
    /// Largest violation of its length constraints, m.
    pub violation_m: f64,
    /// Largest violation of its angle constraints, rad.
    pub violation_rad: f64,
    /// Total force of the joint on body b (world), N (on a it is the opposite when both are
    /// bodies).
    pub force_on_b_n: [f64; 3],
    /// Total torque of the joint on body b about its centre of mass, N·m.
    pub torque_on_b_n_m: [f64; 3],
    /// Its driver's effort: for motors, presses and velocity controllers the torque (N·m) or
    /// force (N) on b along the driver's axis, positive when it drives b in the +axis direction
    /// (a motor lifting a load reports the load's torque; a stalled one, its max torque); for a
    /// spring its tension (N, damping included), positive when it pulls the two points together.
    pub driver_effort: f64,
    /// Its coordinate: angle (rad) or position (m), if it has one.
    pub coordinate: Option<f64>,
    /// Rate of its coordinate: rad/s or m/s.
    pub coordinate_rate: Option<f64>,
}

fn check_vec(label: &str, what: &str, v: &Vector3<f64>) -> Result<()> {
    if v.iter().all(|c| c.is_finite()) {
        Ok(())
    } else {
        Err(StarkError::InvalidInput(format!(
            "joint '{label}': {what} is not finite: {v:?}"
        )))
    }
}

fn check_axis(label: &str, axis: &Vector3<f64>) -> Result<()> {
    check_vec(label, "axis", axis)?;
    if axis.norm() < 1e-12 {
        return Err(StarkError::InvalidInput(format!("joint '{label}': the axis is zero")));
    }
    Ok(())
}

crate::params::param_struct! {
    /// Parameters common to the composite joints: the penalty stiffness of their hard
    /// constraints and the tolerances they are hardened to.
    #[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
    pub struct JointParams {
        /// Stiffness of the hard primitives, N/m (default: 1e6).
        pub stiffness: f64,
        /// Tolerance of the point primitives, m (default: 1e-3).
        pub tolerance_m: f64,
        /// Tolerance of the direction primitives, degrees (default: 1).
        pub tolerance_deg: f64,
    }
}

impl Default for JointParams {
    fn default() -> Self {
        JointParams {
            stiffness: DEFAULT_JOINT_STIFFNESS,
            tolerance_m: DEFAULT_TOLERANCE_M,
            tolerance_deg: DEFAULT_TOLERANCE_DEG,
        }
    }
}

impl JointParams {
    fn validate(&self, label: &str) -> Result<()> {
        check_param(
            label,
            "stiffness",
            self.stiffness,
            self.stiffness > 0.0 && self.stiffness.is_finite(),
            "must be positive (N/m)",
        )?;
        check_param(
            label,
            "tolerance_m",
            self.tolerance_m,
            self.tolerance_m > 0.0,
            "must be positive (m; inf for none)",
        )?;
        check_param(
            label,
            "tolerance_deg",
            self.tolerance_deg,
            self.tolerance_deg > 0.0,
            "must be positive (degrees; inf for none)",
        )?;
        Ok(())
    }
}

/// The joint term of a simulation.
pub type Joints = PotentialTerm<JointSet, 4>;

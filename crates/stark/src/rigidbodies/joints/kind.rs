//! [`JointKind`]: one typed description of every joint, motor, servo, controller and coupling;
//! [`Simulation::add_joint`] (in `add_joint.rs`) is the one place that builds each of them.
//!
//! The enum is the reference: its serde form (`type = "hinge"`, `point_m = [...]`, ...) is a
//! `[[joint]]` entry of a scene file (docs/scene-format.md) and the dict of the Python
//! `Simulation.add_joint`; the `add_*` constructors are one-line wrappers over `add_joint`.
//! Points and axes are world coordinates at creation (stored in the bodies' frames); angles are
//! in degrees, as in the scene files. Adding a joint type means adding a variant and its arm in
//! [`Simulation::add_joint`] (and, if it has a target, in [`JointKind::target`]).

use super::{JointHandle, DEFAULT_CONTROLLER_DELAY};
use crate::error::Result;
// Upward on purpose: each model adds its builder methods to `Simulation` in its own
// `impl Simulation` block (the public builder API), so it names the simulation floor.
use crate::simulation::Simulation;
use serde::{Deserialize, Serialize};

fn default_delay_m_s() -> f64 {
    DEFAULT_CONTROLLER_DELAY
}

fn one() -> f64 {
    1.0
}

/// Every joint Stark-rs builds, with its parameters in the units its field names carry.
///
/// Body `a` may be the world (`None`), body `b` is a rigid body, except for `fix` (b alone, held
/// in the world), `attachment` (two bodies) and the couplings (`joint_coupling`, `joint_spring`),
/// which act on joints named by label and take no bodies.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum JointKind {
    /// Ball joint: b's point at `point_m` stays on a's (3 rotations left).
    Ball {
        /// The joint point, m (world, at creation).
        point_m: [f64; 3],
    },
    /// Ball joint whose relative rotation stays in a cone: the angle between the bodies' copies
    /// of `axis` stays below `limit_deg`.
    BallCone {
        /// The joint point, m.
        point_m: [f64; 3],
        /// The cone's axis (any length).
        axis: [f64; 3],
        /// Half-angle of the cone, degrees, in [0, 180].
        limit_deg: f64,
    },
    /// Hinge: b rotates relative to a about `axis` through `point_m` (1 rotation left). Its
    /// coordinate is the angle (zero at creation).
    Hinge {
        /// A point on the axis, m.
        point_m: [f64; 3],
        /// The hinge axis (any length).
        axis: [f64; 3],
    },
    /// Hinge whose angle stays within ±`limit_deg` of its creation angle.
    HingeLimit {
        /// A point on the axis, m.
        point_m: [f64; 3],
        /// The hinge axis.
        axis: [f64; 3],
        /// Largest angle either way, degrees, in [0, 180].
        limit_deg: f64,
    },
    /// Angle limits alone (no hinge; add one with the same point and axis): b's rotation about
    /// `axis` relative to a (zero at creation) stays in `limits_deg = [lower, upper]`, which
    /// must contain 0 and be at most a turn wide. An angle-limit primitive between a's copy of a
    /// direction perpendicular to the axis, turned to the middle of the range, and b's copy.
    HingeRange {
        /// A point on the axis, m.
        point_m: [f64; 3],
        /// The hinge axis.
        axis: [f64; 3],
        /// `[lower, upper]`, degrees.
        limits_deg: [f64; 2],
    },
    /// Universal (Cardan) joint: a ball joint at `point_m` whose cross keeps `axis_a` (fixed in
    /// a) perpendicular to `axis_b` (fixed in b); they must be perpendicular at creation. While
    /// it transmits a large twist torque keep `dt` small (see
    /// [`Simulation::add_universal_joint`]).
    Universal {
        /// The centre of the cross, m.
        point_m: [f64; 3],
        /// The cross's arm fixed in a.
        axis_a: [f64; 3],
        /// The cross's arm fixed in b (perpendicular to `axis_a`).
        axis_b: [f64; 3],
    },
    /// Slider (cylindrical joint): b's point at `point_m` moves along a's `axis` and b keeps the
    /// axis direction; the rotation about it stays free (2 DOFs). Coordinate: the position.
    Slider {
        /// A point on the axis, m.
        point_m: [f64; 3],
        /// The sliding axis.
        axis: [f64; 3],
    },
    /// Prismatic joint: a slider that also locks the rotation about its axis (1 DOF).
    /// Coordinate: the displacement along the axis (zero at creation).
    Prismatic {
        /// A point on the axis, m.
        point_m: [f64; 3],
        /// The sliding axis.
        axis: [f64; 3],
    },
    /// Position limits alone (no slider): b's displacement along `axis` relative to a (zero at
    /// creation) stays in `limits_m = [lower, upper]`, which must contain 0. A distance-limits
    /// primitive from a's point at `lower − L` on the axis (`L` = 1 m plus the range, so that
    /// the distance stays far from zero and nearly linear in the displacement) to b's point.
    SliderRange {
        /// A point on the axis, m.
        point_m: [f64; 3],
        /// The sliding axis.
        axis: [f64; 3],
        /// `[lower, upper]`, m.
        limits_m: [f64; 2],
    },
    /// b's point at `point_m` stays on a's line through it along `axis` (4 DOFs).
    /// Coordinate: the position along the line.
    PointOnAxis {
        /// The point, m.
        point_m: [f64; 3],
        /// The line's direction.
        axis: [f64; 3],
    },
    /// Planar joint: b's point at `point_m` stays on a's plane through it and b keeps the
    /// plane's `normal` (3 DOFs: two translations in the plane and the rotation about the
    /// normal).
    Planar {
        /// A point of the plane, m.
        point_m: [f64; 3],
        /// The plane's normal.
        normal: [f64; 3],
    },
    /// Prismatic press (pistons, grippers): a prismatic joint driven at `target_velocity_m_s`
    /// along `axis` with at most `max_force_n`; the force is linear in the velocity error below
    /// `delay_m_s`. Target: `target_velocity_m_s`.
    PrismaticPress {
        /// A point on the axis, m.
        point_m: [f64; 3],
        /// The sliding axis (the driven direction).
        axis: [f64; 3],
        /// Target velocity of b relative to a along the axis, m/s (default 0).
        #[serde(default)]
        target_velocity_m_s: f64,
        /// Force cap, N.
        max_force_n: f64,
        /// Velocity error at which the cap is reached, m/s (default 0.01).
        #[serde(default = "default_delay_m_s")]
        delay_m_s: f64,
    },
    /// Motor: a hinge driven at `target_velocity_deg_s` about `axis` with at most
    /// `max_torque_n_m`; the torque is linear in the speed error below `delay_deg_s`.
    /// Target: `target_velocity_deg_s`.
    Motor {
        /// A point on the axis, m.
        point_m: [f64; 3],
        /// The hinge axis (the driven direction).
        axis: [f64; 3],
        /// Target rate of b relative to a about the axis, degrees/s (default 0).
        #[serde(default)]
        target_velocity_deg_s: f64,
        /// Torque cap, N·m.
        max_torque_n_m: f64,
        /// Speed error at which the cap is reached, degrees/s (default: 0.01 rad/s ≈ 0.573 °/s).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        delay_deg_s: Option<f64>,
    },
    /// Position servo on a hinge: a motor whose target speed each step closes the remaining
    /// angle error within `response_time_s`, with at most `max_torque_n_m`. The target is an
    /// angle modulo 360° (the servo turns the shorter way). Target: `target_deg`.
    HingeServo {
        /// A point on the axis, m.
        point_m: [f64; 3],
        /// The hinge axis.
        axis: [f64; 3],
        /// Target angle, degrees, from the creation angle (default 0).
        #[serde(default)]
        target_deg: f64,
        /// Torque cap, N·m.
        max_torque_n_m: f64,
        /// Time constant of the approach, s (default 0: within one step, as fast as the cap
        /// allows).
        #[serde(default)]
        response_time_s: f64,
    },
    /// Position servo on a prismatic joint: a press whose target velocity each step closes the
    /// remaining position error within `response_time_s`, with at most `max_force_n`.
    /// Target: `target_m`.
    PrismaticServo {
        /// A point on the axis, m.
        point_m: [f64; 3],
        /// The sliding axis.
        axis: [f64; 3],
        /// Target position, m, from the creation position (default 0).
        #[serde(default)]
        target_m: f64,
        /// Force cap, N.
        max_force_n: f64,
        /// Time constant of the approach, s (default 0).
        #[serde(default)]
        response_time_s: f64,
    },
    /// Holds body b at its current pose in the world (body a must be the world); drive it
    /// kinematically with [`Simulation::set_fixed_transform`].
    Fix {},
    /// Glues body b to body a at their current relative pose.
    Attachment {},
    /// The points `point_a_m` of a and `point_b_m` of b keep their current distance.
    Distance {
        /// Point of a, m.
        point_a_m: [f64; 3],
        /// Point of b, m.
        point_b_m: [f64; 3],
    },
    /// The distance between `point_a_m` of a and `point_b_m` of b stays in `[min_m, max_m]`
    /// (the current distance must lie inside).
    DistanceLimits {
        /// Point of a, m.
        point_a_m: [f64; 3],
        /// Point of b, m.
        point_b_m: [f64; 3],
        /// Smallest distance, m.
        min_m: f64,
        /// Largest distance, m.
        max_m: f64,
    },
    /// A damped spring between `point_a_m` of a and `point_b_m` of b, at rest at the current
    /// distance; optionally with hard distance limits `limits_m = [min, max]`.
    Spring {
        /// Point of a, m.
        point_a_m: [f64; 3],
        /// Point of b, m.
        point_b_m: [f64; 3],
        /// Spring stiffness, N/m.
        spring_stiffness_n_m: f64,
        /// Damping, N·s/m (default 0).
        #[serde(default)]
        damping_n_s_m: f64,
        /// Hard limits `[min, max]` of the distance, m (default: none); they must contain the
        /// rest length.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        limits_m: Option<[f64; 2]>,
    },
    /// The bodies' copies of `axis` stay aligned (2 rotations removed; with a = world, b's
    /// direction keeps its world direction).
    Direction {
        /// The direction.
        axis: [f64; 3],
    },
    /// The angle between the bodies' copies of `axis` stays below `limit_deg`.
    AngleLimit {
        /// The direction.
        axis: [f64; 3],
        /// Largest angle, degrees, in [0, 180].
        limit_deg: f64,
    },
    /// Linear velocity controller alone (no other constraint): drives the velocity of b's point
    /// at `point_m` relative to a's along a's `axis` to `target_velocity_m_s`.
    /// Target: `target_velocity_m_s`.
    LinearVelocity {
        /// The driven point, m.
        point_m: [f64; 3],
        /// The driven direction.
        axis: [f64; 3],
        /// Target velocity, m/s (default 0).
        #[serde(default)]
        target_velocity_m_s: f64,
        /// Force cap, N.
        max_force_n: f64,
        /// Velocity error at which the cap is reached, m/s (default 0.01).
        #[serde(default = "default_delay_m_s")]
        delay_m_s: f64,
    },
    /// Angular velocity controller alone: drives `(ω_b − ω_a)·axis` to
    /// `target_velocity_deg_s`. Target: `target_velocity_deg_s`.
    AngularVelocity {
        /// The driven axis.
        axis: [f64; 3],
        /// Target rate, degrees/s (default 0).
        #[serde(default)]
        target_velocity_deg_s: f64,
        /// Torque cap, N·m.
        max_torque_n_m: f64,
        /// Speed error at which the cap is reached, degrees/s (default: 0.01 rad/s).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        delay_deg_s: Option<f64>,
    },
    /// Coupling of two joint coordinates (URDF `<mimic>`): `q_b = multiplier·q_a + offset`,
    /// both measured from the joints' creation, in SI units (hinge angles in rad, slider
    /// positions in m), as a hard penalty of the joint's `stiffness`, hardened to the tolerance
    /// of `joint_b`'s kind. Takes no bodies.
    JointCoupling {
        /// Label of the leading joint (a hinge, slider, prismatic or point-on-axis joint).
        joint_a: String,
        /// Label of the following joint.
        joint_b: String,
        /// `q_b` per `q_a` (rad or m per rad or m; default 1).
        #[serde(default = "one")]
        multiplier: f64,
        /// `q_b` at `q_a = 0`: rad or m (default 0).
        #[serde(default)]
        offset: f64,
    },
    /// A spring–damper on a joint's coordinate: torque or force `−spring_stiffness·(q − rest) −
    /// damping·q̇`, `q` measured from the joint's creation; with zero stiffness, pure joint
    /// damping. Takes no bodies.
    JointSpring {
        /// Label of the joint (a hinge, slider, prismatic or point-on-axis joint).
        joint: String,
        /// N·m/rad for a hinge, N/m for a slider.
        spring_stiffness: f64,
        /// Rest coordinate: rad or m (default 0).
        #[serde(default)]
        rest: f64,
        /// N·m·s/rad or N·s/m (default 0).
        #[serde(default)]
        damping: f64,
    },
}

/// What the target of a driven joint is, and its unit (the unit of its field).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum JointTarget {
    /// A target rate, degrees/s ([`Simulation::set_joint_target_velocity`] in rad/s).
    VelocityDegS,
    /// A target velocity, m/s ([`Simulation::set_joint_target_velocity`]).
    VelocityMS,
    /// A servo angle, degrees ([`Simulation::set_servo_target`]).
    AngleDeg,
    /// A servo position, m ([`Simulation::set_servo_target`]).
    PositionM,
}

impl JointTarget {
    /// Set the target of joint `h` to `value` (in this target's unit).
    pub fn set(self, sim: &mut Simulation, h: &JointHandle, value: f64) -> Result<()> {
        match self {
            JointTarget::VelocityDegS => sim.set_joint_target_velocity(h, value.to_radians()),
            JointTarget::VelocityMS => sim.set_joint_target_velocity(h, value),
            JointTarget::AngleDeg | JointTarget::PositionM => sim.set_servo_target(h, value),
        }
    }
}

impl JointKind {
    /// The name of its `type` (`"hinge"`, `"motor"`, ...).
    pub fn type_name(&self) -> String {
        match serde_json::to_value(self) {
            Ok(serde_json::Value::Object(m)) => m.get("type").and_then(|t| t.as_str()).unwrap_or("?").to_string(),
            _ => "?".to_string(),
        }
    }

    /// The target of a driven joint (a `target_schedule` replaces it in scene files): the field,
    /// its value and what it sets.
    pub fn target(&mut self) -> Option<(&'static str, &mut f64, JointTarget)> {
        use JointKind::*;
        match self {
            PrismaticPress {
                target_velocity_m_s: t, ..
            }
            | LinearVelocity {
                target_velocity_m_s: t, ..
            } => Some(("target_velocity_m_s", t, JointTarget::VelocityMS)),
            Motor {
                target_velocity_deg_s: t,
                ..
            }
            | AngularVelocity {
                target_velocity_deg_s: t,
                ..
            } => Some(("target_velocity_deg_s", t, JointTarget::VelocityDegS)),
            HingeServo { target_deg: t, .. } => Some(("target_deg", t, JointTarget::AngleDeg)),
            PrismaticServo { target_m: t, .. } => Some(("target_m", t, JointTarget::PositionM)),
            _ => None,
        }
    }

    /// The target field of a driven joint and what it sets.
    pub fn target_field(&self) -> Option<(&'static str, JointTarget)> {
        self.clone().target().map(|(field, _, target)| (field, target))
    }

    /// The names of every joint type, from its serde form.
    pub fn type_names() -> Vec<String> {
        // A type no joint has: the error lists the types.
        expected_names(&probe(serde_json::json!({ "type": "\u{1}" })))
    }

    /// The fields of the joint type `type_name` (besides `type`), from its serde form: `None`
    /// if there is no such type.
    pub fn fields_of(type_name: &str) -> Option<Vec<String>> {
        if !Self::type_names().iter().any(|t| t == type_name) {
            return None;
        }
        // A field no type has: the error lists the fields the type takes ("there are no
        // fields" lists none).
        Some(expected_names(&probe(
            serde_json::json!({ "type": type_name, "\u{1}": 0 }),
        )))
    }
}

/// The error message of deserialising `value` as a [`JointKind`] (empty if it is one).
fn probe(value: serde_json::Value) -> String {
    serde_json::from_value::<JointKind>(value)
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default()
}

/// The names in backticks after "expected" in a serde error message.
fn expected_names(message: &str) -> Vec<String> {
    match message.split_once("expected") {
        Some((_, rest)) => rest.split('`').skip(1).step_by(2).map(str::to_string).collect(),
        None => Vec::new(),
    }
}

#[cfg(test)]
#[path = "kind_tests.rs"]
mod tests;

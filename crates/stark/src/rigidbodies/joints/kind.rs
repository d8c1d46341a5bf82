//! [`JointKind`]: one typed description of every joint, motor, servo, controller and coupling,
//! and [`Simulation::add_joint`], the one place that builds each of them.
//!
//! The enum is the reference: its serde form (`type = "hinge"`, `point_m = [...]`, ...) is a
//! `[[joint]]` entry of a scene file (docs/scene-format.md) and the dict of the Python
//! `Simulation.add_joint`; the `add_*` constructors are one-line wrappers over `add_joint`.
//! Points and axes are world coordinates at creation (stored in the bodies' frames); angles are
//! in degrees, as in the scene files. Adding a joint type means adding a variant and its arm in
//! [`Simulation::add_joint`] (and, if it has a target, in [`JointKind::target`]).

use super::DEFAULT_CONTROLLER_DELAY;
use super::{coupling, perpendicular, Builder, JointHandle, JointParams, Measure, Primitive, Servo};
use crate::error::{check_param, Result, StarkError};
use crate::rigidbodies::RigidBodyHandle;
// Upward on purpose: each model adds its builder methods to `Simulation` in its own
// `impl Simulation` block (the public builder API), so it names the simulation floor.
use crate::simulation::Simulation;
use nalgebra::{Unit, UnitQuaternion, Vector3};
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

/// The value of a vector field, checked finite.
fn vector(label: &str, field: &str, v: [f64; 3]) -> Result<Vector3<f64>> {
    if v.iter().all(|c| c.is_finite()) {
        Ok(Vector3::from(v))
    } else {
        Err(StarkError::InvalidInput(format!(
            "joint '{label}': `{field}` = {v:?} must be finite"
        )))
    }
}

/// The value of a direction field, checked finite and non-zero (any length).
fn direction(label: &str, field: &str, v: [f64; 3]) -> Result<Vector3<f64>> {
    let d = Vector3::from(v);
    if d.iter().all(|c| c.is_finite()) && d.norm() >= 1e-12 {
        Ok(d)
    } else {
        Err(StarkError::InvalidInput(format!(
            "joint '{label}': `{field}` = {v:?} must be finite and non-zero"
        )))
    }
}

fn finite(label: &str, field: &'static str, x: f64) -> Result<f64> {
    check_param(label, field, x, x.is_finite(), "must be finite")?;
    Ok(x)
}

fn angle_deg(label: &str, field: &'static str, x: f64) -> Result<f64> {
    check_param(label, field, x, (0.0..=180.0).contains(&x), "must be in [0, 180]")?;
    Ok(x)
}

/// A controller's cap: N or N·m.
fn check_max(label: &str, field: &'static str, max: f64) -> Result<()> {
    check_param(label, field, max, max >= 0.0 && max.is_finite(), "must be non-negative")
}

/// A controller's delay (the velocity error at which it reaches its cap): m/s.
fn check_delay_m_s(label: &str, delay: f64) -> Result<f64> {
    check_param(
        label,
        "delay_m_s",
        delay,
        delay > 0.0 && delay.is_finite(),
        "must be positive",
    )?;
    Ok(delay)
}

fn response_time(label: &str, t: f64) -> Result<f64> {
    check_param(
        label,
        "response_time_s",
        t,
        t >= 0.0 && t.is_finite(),
        "must be non-negative (s)",
    )?;
    Ok(t)
}

/// A controller delay given in degrees/s, or the default 0.01 rad/s: rad/s.
fn delay_rad_s(label: &str, delay_deg_s: Option<f64>) -> Result<f64> {
    let Some(deg) = delay_deg_s else {
        return Ok(DEFAULT_CONTROLLER_DELAY);
    };
    check_param(
        label,
        "delay_deg_s",
        deg,
        deg > 0.0 && deg.is_finite(),
        "must be positive",
    )?;
    Ok(deg.to_radians())
}

fn invalid(label: &str, message: impl std::fmt::Display) -> StarkError {
    StarkError::InvalidInput(format!("joint '{label}': {message}"))
}

impl Simulation {
    /// The joint labelled `label` (a clear error if there is none, or several).
    pub fn joint_by_label(&self, label: &str) -> Result<JointHandle> {
        let joints = &self.rigid_bodies.named_joints;
        let found: Vec<_> = joints.iter().filter(|j| j.label == label).collect();
        match found[..] {
            [h] => Ok(h.clone()),
            [] => {
                let known: Vec<_> = joints.iter().map(|j| format!("'{}'", j.label)).collect();
                Err(StarkError::InvalidInput(format!(
                    "no joint is labelled '{label}'; the joints are {}",
                    if known.is_empty() {
                        "none yet".to_string()
                    } else {
                        known.join(", ")
                    }
                )))
            }
            _ => Err(StarkError::InvalidInput(format!(
                "{} joints are labelled '{label}': give them unique labels",
                found.len()
            ))),
        }
    }

    /// Add a joint of any kind between body `a` (`None`: the world) and body `b` (`None` only
    /// for the couplings, which name their joints inside `kind`), with the hard constraints'
    /// `params`. Errors name the joint's label and the field of `kind` (its serde name).
    pub fn add_joint(
        &mut self,
        label: &str,
        a: Option<RigidBodyHandle>,
        b: Option<RigidBodyHandle>,
        kind: JointKind,
        params: JointParams,
    ) -> Result<JointHandle> {
        use JointKind::*;
        let type_name = kind.type_name();
        let acts_on_joints = matches!(kind, JointCoupling { .. } | JointSpring { .. });
        if acts_on_joints && (a.is_some() || b.is_some()) {
            return Err(invalid(
                label,
                format_args!("a {type_name} acts on joints named by label: `a` and `b` must be None"),
            ));
        }
        let b = match (b, acts_on_joints) {
            (Some(b), _) => Some(b),
            (None, true) => None,
            (None, false) => {
                return Err(invalid(
                    label,
                    format_args!(
                    "`b` must be a rigid body (a {type_name} joint moves body b relative to a; `a` may be the world)"
                ),
                ))
            }
        };
        let l = label;
        // The builder of a joint between a and b (after the checks of its fields).
        macro_rules! new {
            ($sim:expr) => {
                Builder::new($sim, l, a, b, params)
            };
        }
        let j = match kind {
            Ball { point_m } => {
                let p = vector(l, "point_m", point_m)?;
                let mut j = new!(self)?;
                j.point(&p);
                j
            }
            BallCone {
                point_m,
                axis,
                limit_deg,
            } => {
                let (p, axis) = (vector(l, "point_m", point_m)?, direction(l, "axis", axis)?);
                let limit = angle_deg(l, "limit_deg", limit_deg)?;
                let mut j = new!(self)?;
                j.point(&p);
                j.angle_limit(&axis, limit.to_radians());
                j
            }
            Hinge { point_m, axis } | HingeLimit { point_m, axis, .. } => {
                let (p, axis) = (vector(l, "point_m", point_m)?, direction(l, "axis", axis)?);
                let limit = match kind {
                    HingeLimit { limit_deg, .. } => Some(angle_deg(l, "limit_deg", limit_deg)?),
                    _ => None,
                };
                let mut j = new!(self)?;
                j.point(&p);
                j.direction(&axis);
                j.angle_measure(&axis);
                if let Some(limit) = limit {
                    j.angle_limit(&perpendicular(&axis), limit.to_radians());
                }
                j
            }
            HingeRange {
                point_m,
                axis,
                limits_deg,
            } => {
                vector(l, "point_m", point_m)?;
                let axis = direction(l, "axis", axis)?;
                let [lower, upper] = limits_deg.map(f64::to_radians);
                if !(lower.is_finite() && upper.is_finite() && lower <= 1e-12 && upper >= -1e-12) {
                    return Err(invalid(
                        l,
                        format_args!("`limits_deg` = {limits_deg:?} must be finite and contain the current angle 0"),
                    ));
                }
                if upper - lower > std::f64::consts::TAU {
                    return Err(invalid(
                        l,
                        format_args!("`limits_deg` = {limits_deg:?} is wider than a turn"),
                    ));
                }
                let u = perpendicular(&axis);
                let middle = UnitQuaternion::from_axis_angle(&Unit::new_normalize(axis), 0.5 * (lower + upper));
                let mut j = new!(self)?;
                let [a0, a1] = j.a.direction(&(middle * u));
                let [b0, b1] = j.b.direction(&u);
                j.push(
                    Primitive::AngleLimit {
                        limit_rad: 0.5 * (upper - lower),
                    },
                    &[a0, a1, b0, b1],
                );
                j
            }
            Universal {
                point_m,
                axis_a,
                axis_b,
            } => {
                let p = vector(l, "point_m", point_m)?;
                let (da, db) = (direction(l, "axis_a", axis_a)?, direction(l, "axis_b", axis_b)?);
                if da.normalize().dot(&db.normalize()).abs() > 1e-6 {
                    return Err(invalid(
                        l,
                        format_args!("`axis_b` = {axis_b:?} must be perpendicular to `axis_a` = {axis_a:?}"),
                    ));
                }
                let mut j = new!(self)?;
                j.point(&p);
                let [a0, a1] = j.a.direction(&da);
                let [b0, b1] = j.b.direction(&db);
                j.push(Primitive::Perpendicular, &[a0, a1, b0, b1]);
                j
            }
            Slider { point_m, axis } | Prismatic { point_m, axis } => {
                let (p, axis) = (vector(l, "point_m", point_m)?, direction(l, "axis", axis)?);
                let mut j = new!(self)?;
                j.point_on_axis(&p, &axis);
                j.direction(&axis);
                j.position_measure(&p, &axis);
                if matches!(kind, Prismatic { .. }) {
                    j.direction(&perpendicular(&axis));
                }
                j
            }
            SliderRange {
                point_m,
                axis,
                limits_m,
            } => {
                let (p, axis) = (vector(l, "point_m", point_m)?, direction(l, "axis", axis)?);
                let [lower, upper] = limits_m;
                if !(lower.is_finite() && upper.is_finite() && lower <= 1e-12 && upper >= -1e-12) {
                    return Err(invalid(
                        l,
                        format_args!("`limits_m` = {limits_m:?} must be finite and contain the current position 0"),
                    ));
                }
                let n = axis.normalize();
                let reach = 1.0 + (upper - lower);
                let mut j = new!(self)?;
                let nodes = [j.a.point(&(p + n * (lower - reach))), j.b.point(&p)];
                j.push(
                    Primitive::DistanceLimits {
                        min_m: reach,
                        max_m: reach + (upper - lower),
                    },
                    &nodes,
                );
                j
            }
            PointOnAxis { point_m, axis } => {
                let (p, axis) = (vector(l, "point_m", point_m)?, direction(l, "axis", axis)?);
                let mut j = new!(self)?;
                j.point_on_axis(&p, &axis);
                j.position_measure(&p, &axis);
                j
            }
            Planar { point_m, normal } => {
                let (p, normal) = (vector(l, "point_m", point_m)?, direction(l, "normal", normal)?);
                let mut j = new!(self)?;
                let nodes = [j.a.point(&p), j.a.point(&(p + normal.normalize())), j.b.point(&p)];
                j.push(Primitive::PointOnPlane, &nodes);
                j.direction(&normal);
                j
            }
            PrismaticPress {
                point_m,
                axis,
                target_velocity_m_s,
                max_force_n,
                delay_m_s,
            } => {
                let (p, axis) = (vector(l, "point_m", point_m)?, direction(l, "axis", axis)?);
                let target = finite(l, "target_velocity_m_s", target_velocity_m_s)?;
                check_max(l, "max_force_n", max_force_n)?;
                let delay_m_s = check_delay_m_s(l, delay_m_s)?;
                let mut j = new!(self)?;
                j.point_on_axis(&p, &axis);
                j.direction(&axis);
                j.position_measure(&p, &axis);
                j.direction(&perpendicular(&axis));
                j.linear_velocity(&p, &axis, target, max_force_n, delay_m_s);
                j
            }
            Motor {
                point_m,
                axis,
                target_velocity_deg_s,
                max_torque_n_m,
                delay_deg_s,
            } => {
                let (p, axis) = (vector(l, "point_m", point_m)?, direction(l, "axis", axis)?);
                let target = finite(l, "target_velocity_deg_s", target_velocity_deg_s)?.to_radians();
                let delay = delay_rad_s(l, delay_deg_s)?;
                check_max(l, "max_torque_n_m", max_torque_n_m)?;
                let mut j = new!(self)?;
                j.point(&p);
                j.direction(&axis);
                j.angle_measure(&axis);
                j.angular_velocity(&axis, target, max_torque_n_m, delay);
                j
            }
            HingeServo {
                point_m,
                axis,
                target_deg,
                max_torque_n_m,
                response_time_s,
            } => {
                let (p, axis) = (vector(l, "point_m", point_m)?, direction(l, "axis", axis)?);
                let target = finite(l, "target_deg", target_deg)?.to_radians();
                let response_time_s = response_time(l, response_time_s)?;
                let delay = DEFAULT_CONTROLLER_DELAY;
                check_max(l, "max_torque_n_m", max_torque_n_m)?;
                let mut j = new!(self)?;
                j.point(&p);
                j.direction(&axis);
                j.angle_measure(&axis);
                j.angular_velocity(&axis, 0.0, max_torque_n_m, delay);
                j.servo(target, response_time_s);
                j
            }
            PrismaticServo {
                point_m,
                axis,
                target_m,
                max_force_n,
                response_time_s,
            } => {
                let (p, axis) = (vector(l, "point_m", point_m)?, direction(l, "axis", axis)?);
                let target = finite(l, "target_m", target_m)?;
                let response_time_s = response_time(l, response_time_s)?;
                let delay = DEFAULT_CONTROLLER_DELAY;
                check_max(l, "max_force_n", max_force_n)?;
                let mut j = new!(self)?;
                j.point_on_axis(&p, &axis);
                j.direction(&axis);
                j.position_measure(&p, &axis);
                j.direction(&perpendicular(&axis));
                j.linear_velocity(&p, &axis, 0.0, max_force_n, delay);
                j.servo(target, response_time_s);
                j
            }
            Fix {} | Attachment {} => {
                match (&kind, a) {
                    (Fix {}, Some(_)) => {
                        return Err(invalid(
                            l,
                            "a fix joint holds body b in the world: `a` must be the world (leave it out)",
                        ))
                    }
                    (Attachment {}, None) => return Err(invalid(
                        l,
                        "an attachment glues two bodies: `a` must be a rigid body (a fix joint holds b in the world)",
                    )),
                    _ => {}
                }
                let mut j = new!(self)?;
                let at = match kind {
                    Fix {} => j.b.t,
                    _ => 0.5 * (j.a.t + j.b.t),
                };
                j.point(&at);
                j.direction(&Vector3::z());
                j.direction(&Vector3::x());
                j
            }
            Distance { point_a_m, point_b_m } => {
                let (pa, pb) = (vector(l, "point_a_m", point_a_m)?, vector(l, "point_b_m", point_b_m)?);
                let mut j = new!(self)?;
                let nodes = [j.a.point(&pa), j.b.point(&pb)];
                j.push(
                    Primitive::Distance {
                        target_m: (pb - pa).norm(),
                    },
                    &nodes,
                );
                j
            }
            DistanceLimits {
                point_a_m,
                point_b_m,
                min_m,
                max_m,
            } => {
                let (pa, pb) = (vector(l, "point_a_m", point_a_m)?, vector(l, "point_b_m", point_b_m)?);
                let d = (pb - pa).norm();
                if !(min_m >= 0.0 && min_m <= max_m && d >= min_m - 1e-12 && d <= max_m + 1e-12) {
                    return Err(invalid(
                        l,
                        format_args!(
                            "`min_m` = {min_m}, `max_m` = {max_m}: need 0 ≤ min_m ≤ current distance {d} ≤ max_m"
                        ),
                    ));
                }
                let mut j = new!(self)?;
                let nodes = [j.a.point(&pa), j.b.point(&pb)];
                j.push(Primitive::DistanceLimits { min_m, max_m }, &nodes);
                j
            }
            Spring {
                point_a_m,
                point_b_m,
                spring_stiffness_n_m,
                damping_n_s_m,
                limits_m,
            } => {
                let (pa, pb) = (vector(l, "point_a_m", point_a_m)?, vector(l, "point_b_m", point_b_m)?);
                let k = spring_stiffness_n_m;
                check_param(
                    l,
                    "spring_stiffness_n_m",
                    k,
                    k >= 0.0 && k.is_finite(),
                    "must be non-negative (N/m)",
                )?;
                let d = damping_n_s_m;
                check_param(
                    l,
                    "damping_n_s_m",
                    d,
                    d >= 0.0 && d.is_finite(),
                    "must be non-negative (N·s/m)",
                )?;
                let rest = (pb - pa).norm();
                if let Some([min, max]) = limits_m {
                    if !(min >= 0.0 && min <= rest && rest <= max) {
                        return Err(invalid(
                            l,
                            format_args!("`limits_m` = [{min}, {max}]: need 0 ≤ min ≤ rest length {rest} ≤ max"),
                        ));
                    }
                }
                let mut j = new!(self)?;
                let nodes = [j.a.point(&pa), j.b.point(&pb)];
                let e = j.push(
                    Primitive::Spring {
                        rest_length_m: rest,
                        damping_n_s_m: d,
                    },
                    &nodes,
                );
                j.sim.rigid_bodies.joints.potential.elements[e as usize].stiffness = k;
                j.driver = Some(e);
                if let Some([min_m, max_m]) = limits_m {
                    j.push(Primitive::DistanceLimits { min_m, max_m }, &nodes);
                }
                j
            }
            Direction { axis } => {
                let axis = direction(l, "axis", axis)?;
                let mut j = new!(self)?;
                j.direction(&axis);
                j
            }
            AngleLimit { axis, limit_deg } => {
                let axis = direction(l, "axis", axis)?;
                let limit = angle_deg(l, "limit_deg", limit_deg)?;
                let mut j = new!(self)?;
                j.angle_limit(&axis, limit.to_radians());
                j
            }
            LinearVelocity {
                point_m,
                axis,
                target_velocity_m_s,
                max_force_n,
                delay_m_s,
            } => {
                let (p, axis) = (vector(l, "point_m", point_m)?, direction(l, "axis", axis)?);
                let target = finite(l, "target_velocity_m_s", target_velocity_m_s)?;
                check_max(l, "max_force_n", max_force_n)?;
                let delay_m_s = check_delay_m_s(l, delay_m_s)?;
                let mut j = new!(self)?;
                j.linear_velocity(&p, &axis, target, max_force_n, delay_m_s);
                j
            }
            AngularVelocity {
                axis,
                target_velocity_deg_s,
                max_torque_n_m,
                delay_deg_s,
            } => {
                let axis = direction(l, "axis", axis)?;
                let target = finite(l, "target_velocity_deg_s", target_velocity_deg_s)?.to_radians();
                let delay = delay_rad_s(l, delay_deg_s)?;
                check_max(l, "max_torque_n_m", max_torque_n_m)?;
                let mut j = new!(self)?;
                j.angular_velocity(&axis, target, max_torque_n_m, delay);
                j
            }
            JointCoupling {
                joint_a,
                joint_b,
                multiplier,
                offset,
            } => {
                let multiplier = finite(l, "multiplier", multiplier)?;
                let offset = finite(l, "offset", offset)?;
                let ma = self.coordinate_of(l, "joint_a", &joint_a)?;
                let mb = self.coordinate_of(l, "joint_b", &joint_b)?;
                let c = coupling::Coupling {
                    a: Some(coupling::CoupledCoordinate::new(ma)),
                    b: coupling::CoupledCoordinate::new(mb),
                    multiplier,
                    offset,
                    damping: 0.0,
                    hard: true,
                };
                self.coupling_builder(l, c, params)?
            }
            JointSpring {
                joint,
                spring_stiffness,
                rest,
                damping,
            } => {
                let k = spring_stiffness;
                check_param(
                    l,
                    "spring_stiffness",
                    k,
                    k >= 0.0 && k.is_finite(),
                    "must be non-negative",
                )?;
                let rest = finite(l, "rest", rest)?;
                check_param(
                    l,
                    "damping",
                    damping,
                    damping >= 0.0 && damping.is_finite(),
                    "must be non-negative",
                )?;
                let m = self.coordinate_of(l, "joint", &joint)?;
                let c = coupling::Coupling {
                    a: None,
                    b: coupling::CoupledCoordinate::new(m),
                    multiplier: 0.0,
                    offset: rest,
                    damping,
                    hard: false,
                };
                let j = self.coupling_builder(l, c, params)?;
                let e = j.elements[0] as usize;
                j.sim.rigid_bodies.joints.potential.elements[e].stiffness = k;
                j
            }
        };
        Ok(j.finish())
    }

    /// The coordinate of the joint labelled `joint` (the field `field` of joint `label`).
    fn coordinate_of(&self, label: &str, field: &str, joint: &str) -> Result<Measure> {
        let h = self
            .joint_by_label(joint)
            .map_err(|e| invalid(label, format_args!("`{field}`: {e}")))?;
        h.measure.ok_or_else(|| {
            invalid(
                label,
                format_args!("`{field}` = '{joint}' has no coordinate (hinges, sliders, prismatic and point-on-axis joints have)"),
            )
        })
    }

    /// A builder holding one coupling element, between the bodies of its last coordinate.
    fn coupling_builder(&mut self, label: &str, c: coupling::Coupling, params: JointParams) -> Result<Builder<'_>> {
        let (parent, child) = match c.b.measure {
            Measure::Angle { a, b, .. } | Measure::Position { a, b, .. } => (a, b),
        };
        let handle = |i: Option<u32>| i.map(|index| RigidBodyHandle { index });
        let child = handle(child).ok_or_else(|| invalid(label, "no body"))?;
        let mut j = Builder::new(self, label, handle(parent), Some(child), params)?;
        let nodes = c.nodes();
        j.push(Primitive::Coupling(Box::new(c)), &nodes);
        Ok(j)
    }
}

impl Builder<'_> {
    /// Make the driver a position servo of the joint's coordinate.
    fn servo(&mut self, target: f64, response_time_s: f64) {
        let e = self.driver.expect("a servo drives a controller") as usize;
        let measure = self.measure.expect("a servo measures its coordinate");
        self.sim.rigid_bodies.joints.potential.elements[e].servo = Some(Servo {
            target,
            response_time_s,
            measure,
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Settings;
    use nalgebra::Matrix3;

    /// One value of every variant, optional fields given (non-default) where it has them.
    fn one_of_each() -> Vec<JointKind> {
        use JointKind::*;
        let (p, q, axis, axis2) = ([0.1, -0.2, 0.3], [0.4, 0.5, -0.6], [0.0, 0.6, 0.8], [1.0, 0.0, 0.0]);
        vec![
            Ball { point_m: p },
            BallCone {
                point_m: p,
                axis,
                limit_deg: 33.3,
            },
            Hinge { point_m: p, axis },
            HingeLimit {
                point_m: p,
                axis,
                limit_deg: 45.0,
            },
            HingeRange {
                point_m: p,
                axis,
                limits_deg: [-10.0, 20.5],
            },
            Universal {
                point_m: p,
                axis_a: axis,
                axis_b: axis2,
            },
            Slider { point_m: p, axis },
            Prismatic { point_m: p, axis },
            SliderRange {
                point_m: p,
                axis,
                limits_m: [-0.1, 0.2],
            },
            PointOnAxis { point_m: p, axis },
            Planar {
                point_m: p,
                normal: axis,
            },
            PrismaticPress {
                point_m: p,
                axis,
                target_velocity_m_s: -0.05,
                max_force_n: 20.0,
                delay_m_s: 0.002,
            },
            Motor {
                point_m: p,
                axis,
                target_velocity_deg_s: 90.0,
                max_torque_n_m: 1.5,
                delay_deg_s: Some(0.1),
            },
            HingeServo {
                point_m: p,
                axis,
                target_deg: 30.0,
                max_torque_n_m: 2.0,
                response_time_s: 0.1,
            },
            PrismaticServo {
                point_m: p,
                axis,
                target_m: 0.02,
                max_force_n: 10.0,
                response_time_s: 0.2,
            },
            Fix {},
            Attachment {},
            Distance {
                point_a_m: p,
                point_b_m: q,
            },
            DistanceLimits {
                point_a_m: p,
                point_b_m: q,
                min_m: 0.1,
                max_m: 2.0,
            },
            Spring {
                point_a_m: p,
                point_b_m: q,
                spring_stiffness_n_m: 100.0,
                damping_n_s_m: 1.5,
                limits_m: Some([0.1, 2.0]),
            },
            Direction { axis },
            AngleLimit { axis, limit_deg: 10.0 },
            LinearVelocity {
                point_m: p,
                axis,
                target_velocity_m_s: 0.3,
                max_force_n: 5.0,
                delay_m_s: 0.02,
            },
            AngularVelocity {
                axis,
                target_velocity_deg_s: -45.0,
                max_torque_n_m: 2.0,
                delay_deg_s: None,
            },
            JointCoupling {
                joint_a: "hinge".into(),
                joint_b: "slider".into(),
                multiplier: -0.5,
                offset: 0.01,
            },
            JointSpring {
                joint: "hinge".into(),
                spring_stiffness: 3.0,
                rest: 0.2,
                damping: 0.1,
            },
        ]
    }

    #[test]
    fn every_variant_survives_a_serde_round_trip_through_json_and_toml() {
        let kinds = one_of_each();
        // The list has every type once.
        let mut names: Vec<String> = kinds.iter().map(JointKind::type_name).collect();
        names.sort();
        let mut all = JointKind::type_names();
        all.sort();
        assert_eq!(names, all);
        assert_eq!(all.len(), 26);
        for kind in kinds {
            let json = serde_json::to_string(&kind).unwrap();
            assert_eq!(serde_json::from_str::<JointKind>(&json).unwrap(), kind, "{json}");
            let toml = toml::to_string(&kind).unwrap();
            assert_eq!(toml::from_str::<JointKind>(&toml).unwrap(), kind, "{toml}");
        }
    }

    #[test]
    fn optional_fields_take_their_documented_defaults() {
        let kind: JointKind =
            toml::from_str("type = \"motor\"\npoint_m = [0, 0, 0]\naxis = [0, 0, 1]\nmax_torque_n_m = 1").unwrap();
        let expected = JointKind::Motor {
            point_m: [0.0; 3],
            axis: [0.0, 0.0, 1.0],
            target_velocity_deg_s: 0.0,
            max_torque_n_m: 1.0,
            delay_deg_s: None,
        };
        assert_eq!(kind, expected);
        let kind: JointKind = serde_json::from_str(
            r#"{"type": "linear_velocity", "point_m": [0, 0, 0], "axis": [1, 0, 0], "max_force_n": 2}"#,
        )
        .unwrap();
        assert!(
            matches!(kind, JointKind::LinearVelocity { delay_m_s, target_velocity_m_s, .. }
            if delay_m_s == DEFAULT_CONTROLLER_DELAY && target_velocity_m_s == 0.0)
        );
        let kind: JointKind =
            serde_json::from_str(r#"{"type": "joint_coupling", "joint_a": "x", "joint_b": "y"}"#).unwrap();
        assert!(
            matches!(kind, JointKind::JointCoupling { multiplier, offset, .. } if multiplier == 1.0 && offset == 0.0)
        );
        // Unknown fields are errors that list the type's fields.
        let e = serde_json::from_str::<JointKind>(
            r#"{"type": "hinge", "point_m": [0, 0, 0], "axis": [0, 0, 1], "limit": 3}"#,
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("unknown field `limit`, expected `point_m` or `axis`"), "{e}");
        assert_eq!(JointKind::fields_of("fix"), Some(vec![]));
        assert_eq!(
            JointKind::fields_of("spring").unwrap(),
            [
                "point_a_m",
                "point_b_m",
                "spring_stiffness_n_m",
                "damping_n_s_m",
                "limits_m"
            ]
        );
        assert_eq!(JointKind::fields_of("hing"), None);
    }

    fn two_bodies() -> (Simulation, RigidBodyHandle, RigidBodyHandle) {
        let mut s = Settings::default();
        s.output.frames = false;
        s.output.step_log = false;
        let mut sim = Simulation::new(s).unwrap();
        let q = UnitQuaternion::identity();
        let a = sim
            .add_rigid_body("a", 1.0, Matrix3::identity(), Vector3::zeros(), q)
            .unwrap();
        let b = sim
            .add_rigid_body("b", 1.0, Matrix3::identity(), Vector3::new(0.0, 0.0, -0.5), q)
            .unwrap();
        (sim, a, b)
    }

    #[test]
    fn every_variant_builds_through_add_joint_and_registers_its_label() {
        let (mut sim, a, b) = two_bodies();
        let p = JointParams::default();
        for kind in one_of_each() {
            let label = kind.type_name();
            // The couplings name the hinge and the slider built before them.
            let label = match &kind {
                JointKind::Hinge { .. } => "hinge".to_string(),
                JointKind::Slider { .. } => "slider".to_string(),
                _ => label,
            };
            let (ja, jb) = match kind {
                JointKind::JointCoupling { .. } | JointKind::JointSpring { .. } => (None, None),
                JointKind::Fix {} => (None, Some(b)),
                _ => (Some(a), Some(b)),
            };
            let h = sim
                .add_joint(&label, ja, jb, kind, p)
                .unwrap_or_else(|e| panic!("{label}: {e}"));
            assert_eq!(sim.joint_by_label(&label).unwrap(), h);
        }
        assert_eq!(sim.rigid_bodies.named_joints.len(), 26);
        // The couplings' elements act between the bodies of their joints.
        let coupling = sim.joint_by_label("joint_coupling").unwrap();
        let e = &sim.rigid_bodies.joints.potential.elements[coupling.elements[0] as usize];
        assert_eq!(e.bodies, [Some(0), Some(1)]);
    }

    #[test]
    fn errors_name_the_joint_and_the_field() {
        let (mut sim, a, b) = two_bodies();
        let p = JointParams::default();
        let err = |sim: &mut Simulation, a, b, kind| sim.add_joint("j", a, b, kind, p).unwrap_err().to_string();
        let hinge = JointKind::Hinge {
            point_m: [0.0; 3],
            axis: [0.0, 0.0, 0.0],
        };
        let e = err(&mut sim, Some(a), Some(b), hinge.clone());
        assert_eq!(e, "joint 'j': `axis` = [0.0, 0.0, 0.0] must be finite and non-zero");
        let e = err(&mut sim, Some(a), None, hinge);
        assert!(e.contains("joint 'j': `b` must be a rigid body"), "{e}");
        let e = err(&mut sim, Some(a), Some(b), JointKind::Fix {});
        assert!(
            e.contains("joint 'j': a fix joint holds body b in the world: `a` must be the world"),
            "{e}"
        );
        let motor = JointKind::Motor {
            point_m: [0.0; 3],
            axis: [0.0, 0.0, 1.0],
            target_velocity_deg_s: 0.0,
            max_torque_n_m: -1.0,
            delay_deg_s: None,
        };
        let e = err(&mut sim, None, Some(b), motor);
        assert!(e.contains("`max_torque_n_m` = -1 on 'j'"), "{e}");
        let spring = JointKind::JointSpring {
            joint: "pivot".into(),
            spring_stiffness: 1.0,
            rest: 0.0,
            damping: 0.0,
        };
        let e = err(&mut sim, Some(a), None, spring.clone());
        assert!(e.contains("`a` and `b` must be None"), "{e}");
        let e = err(&mut sim, None, None, spring.clone());
        assert!(
            e.contains("joint 'j': `joint`: no joint is labelled 'pivot'; the joints are none yet"),
            "{e}"
        );
        sim.add_ball_joint("ball", None, b, Vector3::zeros(), p).unwrap();
        let e = err(&mut sim, None, None, spring);
        assert!(e.contains("the joints are 'ball'"), "{e}");
        let spring = JointKind::JointSpring {
            joint: "ball".into(),
            spring_stiffness: 1.0,
            rest: 0.0,
            damping: 0.0,
        };
        let e = err(&mut sim, None, None, spring);
        assert!(e.contains("`joint` = 'ball' has no coordinate"), "{e}");
        // Nothing was added by the failed calls.
        assert_eq!(sim.rigid_bodies.named_joints.len(), 1);
        assert_eq!(sim.rigid_bodies.joints.potential.elements.len(), 1);
    }

    /// docs/scene-format.md lists every joint type with exactly the fields of its variant.
    #[test]
    fn the_scene_format_lists_every_type_with_its_fields() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/scene-format.md");
        let doc = std::fs::read_to_string(path).unwrap();
        let section = doc.split("\n## `[[joint]]`").nth(1).unwrap();
        let section = section.split("\n## ").next().unwrap();
        let types = JointKind::type_names();
        let mut listed = Vec::new();
        for line in section.lines() {
            // `| type | required | optional | call |`: cells 1 to 4.
            let cells: Vec<&str> = line.split('|').map(str::trim).collect();
            if cells.len() < 5 {
                continue;
            }
            let cells = &cells[1..];
            let Some(t) = cells[0].strip_prefix('`').and_then(|c| c.strip_suffix('`')) else {
                continue;
            };
            if !types.iter().any(|x| x == t) {
                continue;
            }
            let fields = JointKind::fields_of(t).unwrap();
            let named: Vec<String> = cells[1..3]
                .iter()
                .flat_map(|c| c.split('`').skip(1).step_by(2))
                .map(|f| f.split(' ').next().unwrap_or_default().to_string())
                .filter(|f| f != "a" && f != "b")
                .collect();
            for f in &fields {
                assert!(named.contains(f), "docs: `{t}` does not list its field `{f}`");
            }
            for f in &named {
                assert!(fields.contains(f), "docs: `{t}` lists `{f}`, which it does not take");
            }
            listed.push(t.to_string());
        }
        assert_eq!(
            listed, types,
            "docs: the types table lists other types or another order"
        );
    }
}

//! The `add_*` joint constructors of [`Simulation`]: one-line wrappers over
//! [`Simulation::add_joint`] with their [`JointKind`].

use super::{JointHandle, JointKind, JointParams, DEFAULT_CONTROLLER_DELAY};
use crate::error::Result;
use crate::rigidbodies::RigidBodyHandle;
use crate::simulation::Simulation;
use nalgebra::Vector3;

/// A world vector as a field of [`JointKind`].
fn arr(v: Vector3<f64>) -> [f64; 3] {
    v.into()
}

/// A controller delay in rad/s as [`JointKind`]'s `delay_deg_s` (`None`: the default).
fn delay_deg_s(delay_rad_s: f64) -> Option<f64> {
    (delay_rad_s != DEFAULT_CONTROLLER_DELAY).then(|| delay_rad_s.to_degrees())
}

/// The composite joint constructors: each is [`Simulation::add_joint`] with its [`JointKind`]
/// (see there for what each joint does). Angles given here in radians are converted to the
/// kind's degrees.
impl Simulation {
    /// Ball joint ([`JointKind::Ball`]): body b's point at `point_m` (world, at creation) stays
    /// on body a's (a = None: the world). 3 rotational DOFs left.
    pub fn add_ball_joint(
        &mut self,
        label: &str,
        a: Option<RigidBodyHandle>,
        b: RigidBodyHandle,
        point_m: Vector3<f64>,
        params: JointParams,
    ) -> Result<JointHandle> {
        let kind = JointKind::Ball { point_m: arr(point_m) };
        self.add_joint(label, a, Some(b), kind, params)
    }

    /// Ball joint within a cone ([`JointKind::BallCone`]): the angle between the bodies'
    /// copies of `direction` stays below `limit_deg`.
    #[allow(clippy::too_many_arguments)]
    pub fn add_ball_joint_with_cone_limit(
        &mut self,
        label: &str,
        a: Option<RigidBodyHandle>,
        b: RigidBodyHandle,
        point_m: Vector3<f64>,
        direction: Vector3<f64>,
        limit_deg: f64,
        params: JointParams,
    ) -> Result<JointHandle> {
        let kind = JointKind::BallCone {
            point_m: arr(point_m),
            axis: arr(direction),
            limit_deg,
        };
        self.add_joint(label, a, Some(b), kind, params)
    }

    /// [`JointKind::PointOnAxis`]: body b's point at `point_m` stays on body a's line through
    /// `point_m` along `axis`.
    pub fn add_point_on_axis_joint(
        &mut self,
        label: &str,
        a: Option<RigidBodyHandle>,
        b: RigidBodyHandle,
        point_m: Vector3<f64>,
        axis: Vector3<f64>,
        params: JointParams,
    ) -> Result<JointHandle> {
        let kind = JointKind::PointOnAxis {
            point_m: arr(point_m),
            axis: arr(axis),
        };
        self.add_joint(label, a, Some(b), kind, params)
    }

    /// [`JointKind::Distance`]: the points `point_a_m` of a and `point_b_m` of b keep their
    /// current distance.
    pub fn add_distance_joint(
        &mut self,
        label: &str,
        a: Option<RigidBodyHandle>,
        b: RigidBodyHandle,
        point_a_m: Vector3<f64>,
        point_b_m: Vector3<f64>,
        params: JointParams,
    ) -> Result<JointHandle> {
        let kind = JointKind::Distance {
            point_a_m: arr(point_a_m),
            point_b_m: arr(point_b_m),
        };
        self.add_joint(label, a, Some(b), kind, params)
    }

    /// [`JointKind::DistanceLimits`]: the distance between `point_a_m` of a and `point_b_m` of
    /// b stays in `[min_m, max_m]` (the current distance must lie inside).
    #[allow(clippy::too_many_arguments)]
    pub fn add_distance_limits(
        &mut self,
        label: &str,
        a: Option<RigidBodyHandle>,
        b: RigidBodyHandle,
        point_a_m: Vector3<f64>,
        point_b_m: Vector3<f64>,
        min_m: f64,
        max_m: f64,
        params: JointParams,
    ) -> Result<JointHandle> {
        let kind = JointKind::DistanceLimits {
            point_a_m: arr(point_a_m),
            point_b_m: arr(point_b_m),
            min_m,
            max_m,
        };
        self.add_joint(label, a, Some(b), kind, params)
    }

    /// [`JointKind::Spring`]: a damped spring between `point_a_m` of a and `point_b_m` of b,
    /// at rest at the current distance, optionally with hard distance limits `[min, max]`.
    #[allow(clippy::too_many_arguments)]
    pub fn add_spring(
        &mut self,
        label: &str,
        a: Option<RigidBodyHandle>,
        b: RigidBodyHandle,
        point_a_m: Vector3<f64>,
        point_b_m: Vector3<f64>,
        stiffness_n_m: f64,
        damping_n_s_m: f64,
        limits_m: Option<(f64, f64)>,
        params: JointParams,
    ) -> Result<JointHandle> {
        let kind = JointKind::Spring {
            point_a_m: arr(point_a_m),
            point_b_m: arr(point_b_m),
            spring_stiffness_n_m: stiffness_n_m,
            damping_n_s_m,
            limits_m: limits_m.map(|(min, max)| [min, max]),
        };
        self.add_joint(label, a, Some(b), kind, params)
    }

    /// [`JointKind::Direction`]: the copies of `direction` in a and b stay aligned.
    pub fn add_direction_joint(
        &mut self,
        label: &str,
        a: Option<RigidBodyHandle>,
        b: RigidBodyHandle,
        direction: Vector3<f64>,
        params: JointParams,
    ) -> Result<JointHandle> {
        let kind = JointKind::Direction { axis: arr(direction) };
        self.add_joint(label, a, Some(b), kind, params)
    }

    /// [`JointKind::AngleLimit`]: the angle between the copies of `direction` in a and b
    /// stays below `limit_deg`.
    pub fn add_angle_limit(
        &mut self,
        label: &str,
        a: Option<RigidBodyHandle>,
        b: RigidBodyHandle,
        direction: Vector3<f64>,
        limit_deg: f64,
        params: JointParams,
    ) -> Result<JointHandle> {
        let kind = JointKind::AngleLimit {
            axis: arr(direction),
            limit_deg,
        };
        self.add_joint(label, a, Some(b), kind, params)
    }

    /// [`JointKind::Fix`]: fix a body to the world at its current pose; drive it kinematically
    /// with [`Simulation::set_fixed_transform`].
    pub fn add_fix_joint(&mut self, label: &str, body: RigidBodyHandle, params: JointParams) -> Result<JointHandle> {
        self.add_joint(label, None, Some(body), JointKind::Fix {}, params)
    }

    /// [`JointKind::Attachment`]: glue two bodies together at their current relative pose.
    pub fn add_attachment_joint(
        &mut self,
        label: &str,
        a: RigidBodyHandle,
        b: RigidBodyHandle,
        params: JointParams,
    ) -> Result<JointHandle> {
        self.add_joint(label, Some(a), Some(b), JointKind::Attachment {}, params)
    }

    /// [`JointKind::Hinge`]: b rotates relative to a about `axis` through `point_m` (1 DOF).
    /// Its coordinate is the rotation angle (zero at creation).
    pub fn add_hinge_joint(
        &mut self,
        label: &str,
        a: Option<RigidBodyHandle>,
        b: RigidBodyHandle,
        point_m: Vector3<f64>,
        axis: Vector3<f64>,
        params: JointParams,
    ) -> Result<JointHandle> {
        let kind = JointKind::Hinge {
            point_m: arr(point_m),
            axis: arr(axis),
        };
        self.add_joint(label, a, Some(b), kind, params)
    }

    /// [`JointKind::HingeLimit`]: a hinge whose angle stays within ±`limit_deg` of its
    /// creation angle.
    #[allow(clippy::too_many_arguments)]
    pub fn add_hinge_joint_with_limit(
        &mut self,
        label: &str,
        a: Option<RigidBodyHandle>,
        b: RigidBodyHandle,
        point_m: Vector3<f64>,
        axis: Vector3<f64>,
        limit_deg: f64,
        params: JointParams,
    ) -> Result<JointHandle> {
        let kind = JointKind::HingeLimit {
            point_m: arr(point_m),
            axis: arr(axis),
            limit_deg,
        };
        self.add_joint(label, a, Some(b), kind, params)
    }

    /// [`JointKind::Universal`] (Cardan) joint: a ball joint at `point_m` whose cross keeps
    /// `axis_a` (fixed in a) perpendicular to `axis_b` (fixed in b); they must be perpendicular
    /// now (2 DOFs).
    ///
    /// While it transmits a twist torque `τ`, pivoting about its cross is neutral in reality but
    /// grows in the discrete step at about `(dt·τ²/2J²)^(1/3)` per second (the joint torque enters
    /// the step rotated by half the step rotation; see `tests/physics/joints_hold_their_load.rs`):
    /// keep `dt` small (1 ms held 52 N·m on a 3.4 kg, 0.1 m cube) when it carries large torques.
    #[allow(clippy::too_many_arguments)]
    pub fn add_universal_joint(
        &mut self,
        label: &str,
        a: Option<RigidBodyHandle>,
        b: RigidBodyHandle,
        point_m: Vector3<f64>,
        axis_a: Vector3<f64>,
        axis_b: Vector3<f64>,
        params: JointParams,
    ) -> Result<JointHandle> {
        let kind = JointKind::Universal {
            point_m: arr(point_m),
            axis_a: arr(axis_a),
            axis_b: arr(axis_b),
        };
        self.add_joint(label, a, Some(b), kind, params)
    }

    /// [`JointKind::Slider`] (cylindrical joint): b's point at `point_m` moves along a's `axis`
    /// and b keeps the axis direction; rotation about the axis stays free (2 DOFs).
    pub fn add_slider_joint(
        &mut self,
        label: &str,
        a: Option<RigidBodyHandle>,
        b: RigidBodyHandle,
        point_m: Vector3<f64>,
        axis: Vector3<f64>,
        params: JointParams,
    ) -> Result<JointHandle> {
        let kind = JointKind::Slider {
            point_m: arr(point_m),
            axis: arr(axis),
        };
        self.add_joint(label, a, Some(b), kind, params)
    }

    /// [`JointKind::Prismatic`]: a slider that also locks the rotation about its axis (1 DOF).
    /// Its coordinate is the displacement along the axis.
    pub fn add_prismatic_joint(
        &mut self,
        label: &str,
        a: Option<RigidBodyHandle>,
        b: RigidBodyHandle,
        point_m: Vector3<f64>,
        axis: Vector3<f64>,
        params: JointParams,
    ) -> Result<JointHandle> {
        let kind = JointKind::Prismatic {
            point_m: arr(point_m),
            axis: arr(axis),
        };
        self.add_joint(label, a, Some(b), kind, params)
    }

    /// [`JointKind::PrismaticPress`] (pistons, grippers): a prismatic joint driven at
    /// `target_m_s` along `axis` with at most `max_force_n`; the force is linear in the velocity
    /// error below `delay_m_s` (default 0.01 m/s).
    #[allow(clippy::too_many_arguments)]
    pub fn add_prismatic_press(
        &mut self,
        label: &str,
        a: Option<RigidBodyHandle>,
        b: RigidBodyHandle,
        point_m: Vector3<f64>,
        axis: Vector3<f64>,
        target_m_s: f64,
        max_force_n: f64,
        delay_m_s: f64,
        params: JointParams,
    ) -> Result<JointHandle> {
        let kind = JointKind::PrismaticPress {
            point_m: arr(point_m),
            axis: arr(axis),
            target_velocity_m_s: target_m_s,
            max_force_n,
            delay_m_s,
        };
        self.add_joint(label, a, Some(b), kind, params)
    }

    /// [`JointKind::Motor`]: a hinge driven at `target_rad_s` about `axis` with at most
    /// `max_torque_n_m`; the torque is linear in the speed error below `delay_rad_s` (default
    /// 0.01 rad/s).
    #[allow(clippy::too_many_arguments)]
    pub fn add_motor(
        &mut self,
        label: &str,
        a: Option<RigidBodyHandle>,
        b: RigidBodyHandle,
        point_m: Vector3<f64>,
        axis: Vector3<f64>,
        target_rad_s: f64,
        max_torque_n_m: f64,
        delay_rad_s: f64,
        params: JointParams,
    ) -> Result<JointHandle> {
        let kind = JointKind::Motor {
            point_m: arr(point_m),
            axis: arr(axis),
            target_velocity_deg_s: target_rad_s.to_degrees(),
            max_torque_n_m,
            delay_deg_s: delay_deg_s(delay_rad_s),
        };
        self.add_joint(label, a, Some(b), kind, params)
    }

    /// [`JointKind::AngularVelocity`] controller alone (no hinge): drives `(ω_b − ω_a)·axis` to
    /// `target_rad_s`.
    #[allow(clippy::too_many_arguments)]
    pub fn add_angular_velocity_controller(
        &mut self,
        label: &str,
        a: Option<RigidBodyHandle>,
        b: RigidBodyHandle,
        axis: Vector3<f64>,
        target_rad_s: f64,
        max_torque_n_m: f64,
        delay_rad_s: f64,
    ) -> Result<JointHandle> {
        let kind = JointKind::AngularVelocity {
            axis: arr(axis),
            target_velocity_deg_s: target_rad_s.to_degrees(),
            max_torque_n_m,
            delay_deg_s: delay_deg_s(delay_rad_s),
        };
        self.add_joint(label, a, Some(b), kind, JointParams::default())
    }

    /// [`JointKind::LinearVelocity`] controller alone: drives the velocity of b's point at
    /// `point_m` relative to a's along a's `axis` to `target_m_s`.
    #[allow(clippy::too_many_arguments)]
    pub fn add_linear_velocity_controller(
        &mut self,
        label: &str,
        a: Option<RigidBodyHandle>,
        b: RigidBodyHandle,
        point_m: Vector3<f64>,
        axis: Vector3<f64>,
        target_m_s: f64,
        max_force_n: f64,
        delay_m_s: f64,
    ) -> Result<JointHandle> {
        let kind = JointKind::LinearVelocity {
            point_m: arr(point_m),
            axis: arr(axis),
            target_velocity_m_s: target_m_s,
            max_force_n,
            delay_m_s,
        };
        self.add_joint(label, a, Some(b), kind, JointParams::default())
    }

    /// [`JointKind::HingeServo`]: a motor whose target speed each step closes the remaining
    /// angle error within `response_time_s`, with at most `max_torque_n_m`. The target is an
    /// angle modulo 360° (the hinge angle is measured in (−180°, 180°]); the servo turns the
    /// shorter way to it. See [`Servo`](super::Servo) for its steady offset under load.
    #[allow(clippy::too_many_arguments)]
    pub fn add_hinge_servo(
        &mut self,
        label: &str,
        a: Option<RigidBodyHandle>,
        b: RigidBodyHandle,
        point_m: Vector3<f64>,
        axis: Vector3<f64>,
        target_deg: f64,
        max_torque_n_m: f64,
        response_time_s: f64,
        params: JointParams,
    ) -> Result<JointHandle> {
        let kind = JointKind::HingeServo {
            point_m: arr(point_m),
            axis: arr(axis),
            target_deg,
            max_torque_n_m,
            response_time_s,
        };
        self.add_joint(label, a, Some(b), kind, params)
    }

    /// [`JointKind::PrismaticServo`]: a press whose target velocity each step closes the
    /// remaining position error within `response_time_s`, with at most `max_force_n`.
    #[allow(clippy::too_many_arguments)]
    pub fn add_prismatic_servo(
        &mut self,
        label: &str,
        a: Option<RigidBodyHandle>,
        b: RigidBodyHandle,
        point_m: Vector3<f64>,
        axis: Vector3<f64>,
        target_m: f64,
        max_force_n: f64,
        response_time_s: f64,
        params: JointParams,
    ) -> Result<JointHandle> {
        let kind = JointKind::PrismaticServo {
            point_m: arr(point_m),
            axis: arr(axis),
            target_m,
            max_force_n,
            response_time_s,
        };
        self.add_joint(label, a, Some(b), kind, params)
    }

    /// [`JointKind::HingeRange`]: b's rotation about `axis` relative to a (zero now) stays in
    /// `[lower_rad, upper_rad]` (which must contain 0, at most one turn wide).
    #[allow(clippy::too_many_arguments)]
    pub fn add_hinge_range(
        &mut self,
        label: &str,
        a: Option<RigidBodyHandle>,
        b: RigidBodyHandle,
        point_m: Vector3<f64>,
        axis: Vector3<f64>,
        lower_rad: f64,
        upper_rad: f64,
        params: JointParams,
    ) -> Result<JointHandle> {
        let kind = JointKind::HingeRange {
            point_m: arr(point_m),
            axis: arr(axis),
            limits_deg: [lower_rad.to_degrees(), upper_rad.to_degrees()],
        };
        self.add_joint(label, a, Some(b), kind, params)
    }

    /// [`JointKind::SliderRange`]: b's displacement along `axis` relative to a (zero now)
    /// stays in `[lower_m, upper_m]` (which must contain 0).
    #[allow(clippy::too_many_arguments)]
    pub fn add_slider_range(
        &mut self,
        label: &str,
        a: Option<RigidBodyHandle>,
        b: RigidBodyHandle,
        point_m: Vector3<f64>,
        axis: Vector3<f64>,
        lower_m: f64,
        upper_m: f64,
        params: JointParams,
    ) -> Result<JointHandle> {
        let kind = JointKind::SliderRange {
            point_m: arr(point_m),
            axis: arr(axis),
            limits_m: [lower_m, upper_m],
        };
        self.add_joint(label, a, Some(b), kind, params)
    }

    /// [`JointKind::Planar`] joint: b's point at `point_m` stays on a's plane through it with
    /// `normal`, and b keeps the normal's direction (3 DOFs).
    pub fn add_planar_joint(
        &mut self,
        label: &str,
        a: Option<RigidBodyHandle>,
        b: RigidBodyHandle,
        point_m: Vector3<f64>,
        normal: Vector3<f64>,
        params: JointParams,
    ) -> Result<JointHandle> {
        let kind = JointKind::Planar {
            point_m: arr(point_m),
            normal: arr(normal),
        };
        self.add_joint(label, a, Some(b), kind, params)
    }

    /// [`JointKind::JointCoupling`] (URDF `<mimic>`): `q_b = multiplier·q_a + offset`, both
    /// measured from the joints' creation (hinge angles in rad, slider positions in m), as a
    /// hard penalty of stiffness `params.stiffness` hardened to the tolerance of `b`'s kind (see
    /// [`coupling`](super::coupling)). The joints must have coordinates and unique labels.
    pub fn add_joint_coupling(
        &mut self,
        label: &str,
        a: &JointHandle,
        b: &JointHandle,
        multiplier: f64,
        offset: f64,
        params: JointParams,
    ) -> Result<JointHandle> {
        let kind = JointKind::JointCoupling {
            joint_a: a.label.clone(),
            joint_b: b.label.clone(),
            multiplier,
            offset,
        };
        self.add_joint(label, None, None, kind, params)
    }

    /// [`JointKind::JointSpring`]: a spring–damper on a joint's coordinate: torque or force
    /// `−k·(q − rest) − d·q̇`, with `q` measured from the joint's creation (rad or m).
    /// `stiffness` in N·m/rad or N/m, `damping` in N·m·s/rad or N·s/m; with zero stiffness it
    /// is pure joint damping.
    pub fn add_joint_spring(
        &mut self,
        label: &str,
        joint: &JointHandle,
        stiffness: f64,
        rest: f64,
        damping: f64,
    ) -> Result<JointHandle> {
        let kind = JointKind::JointSpring {
            joint: joint.label.clone(),
            spring_stiffness: stiffness,
            rest,
            damping,
        };
        self.add_joint(label, None, None, kind, JointParams::default())
    }
}

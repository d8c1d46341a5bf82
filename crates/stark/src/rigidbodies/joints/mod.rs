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

pub mod coupling;
pub mod kind;
#[cfg(test)]
mod old_paths_test;
pub mod primitives;

use crate::energy::potential::{dual_derivatives, Potential, Stencil};
use crate::energy::term::StepCheck;
use crate::energy::{Node, PotentialTerm, Scalar, Vec3};
use crate::error::{check_param, Result, StarkError};
use crate::rigidbodies::RigidBodyHandle;
// Upward on purpose: each model adds its builder methods to `Simulation` in its own
// `impl Simulation` block (the public builder API), so it names the simulation floor.
use crate::simulation::Simulation;
use crate::state::EvalState;
pub use kind::{JointKind, JointTarget};
use nalgebra::{Unit, UnitQuaternion, Vector3};
pub use primitives::Primitive;

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

/// The parameters of a primitive, in a fixed order (targets and limits change at run time).
/// A checkpoint stores these rather than the `Primitive` itself, whose internally tagged serde
/// form postcard cannot read.
fn primitive_parameters(p: &mut Primitive) -> Vec<&mut f64> {
    match p {
        Primitive::Point
        | Primitive::PointOnAxis
        | Primitive::PointOnPlane
        | Primitive::Direction
        | Primitive::Perpendicular => vec![],
        // Its start-of-step coordinates are measured again at the next step; its parameters
        // change at run time.
        Primitive::Coupling(c) => {
            let c = &mut **c;
            let mut v = vec![&mut c.multiplier, &mut c.offset, &mut c.damping];
            if let Some(a) = c.a.as_mut() {
                v.push(&mut a.q0);
            }
            v.push(&mut c.b.q0);
            v
        }
        Primitive::Distance { target_m } => vec![target_m],
        Primitive::DistanceLimits { min_m, max_m } => vec![min_m, max_m],
        Primitive::AngleLimit { limit_rad } => vec![limit_rad],
        Primitive::Spring {
            rest_length_m,
            damping_n_s_m,
        } => vec![rest_length_m, damping_n_s_m],
        Primitive::LinearVelocity {
            target_m_s,
            max_force_n,
            delay_m_s,
        } => vec![target_m_s, max_force_n, delay_m_s],
        Primitive::AngularVelocity {
            target_rad_s,
            max_torque_n_m,
            delay_rad_s,
            ..
        } => vec![target_rad_s, max_torque_n_m, delay_rad_s],
    }
}

/// What a checkpoint keeps of a joint element.
#[derive(serde::Serialize, serde::Deserialize)]
struct SavedJointElement {
    parameters: Vec<f64>,
    nodes: [Node; 4],
    stiffness: f64,
    tolerance: f64,
    enabled: bool,
    servo: Option<(f64, f64)>,
    readout: JointReadout,
}

/// All joint elements of a simulation.
#[derive(Default)]
pub struct JointSet {
    /// The elements.
    pub elements: Vec<JointElement>,
    version: u64,
}

impl JointSet {
    fn readout(&self, e: usize, state: &EvalState) -> JointReadout {
        let el = &self.elements[e];
        let stencil = Stencil::new(el.nodes, state);
        let x = stencil.x;
        let violation = match &el.primitive {
            Primitive::Coupling(c) => {
                let q: Vec<UnitQuaternion<f64>> =
                    state.poses.iter().map(|p| UnitQuaternion::from_matrix(&p.r)).collect();
                c.residual(&|b| state.poses[b].t, &|b| q[b]).abs()
            }
            _ => el.primitive.violation(&x),
        };
        let mut r = JointReadout {
            violation,
            ..Default::default()
        };
        if !el.enabled {
            return r;
        }
        let d = dual_derivatives(self, e, &stencil);
        let mut f = [Vector3::zeros(); 2];
        let mut t = [Vector3::zeros(); 2];
        for (a, node) in el.nodes.iter().enumerate() {
            let g = Vector3::from(d.grad[a]);
            match *node {
                Node::Rigid { body, local } => {
                    // The generalised force on the body's DOFs, per unit time: −(∂x/∂v)ᵀg/dt = −g
                    // and −(∂x/∂ω)ᵀg/dt. The torque is what the step's angular-momentum balance
                    // sees, so it balances the external torque exactly at equilibrium; the
                    // moment `(x − c) × f` at the end-of-step pose differs from it by a rotation of
                    // about half the step's rotation `ω·dt` (see `JointReadout`).
                    let side = if Some(body) == el.bodies[0] { 0 } else { 1 };
                    let jw = state.poses[body as usize].point_jacobian_w(&Vector3::from(local));
                    f[side] -= g;
                    t[side] -= jw.transpose() * g / state.dt;
                }
                Node::AngularVelocity(body) => {
                    // ∂E/∂ω is an angular impulse over the step.
                    let side = if Some(body) == el.bodies[0] { 0 } else { 1 };
                    t[side] -= g / state.dt;
                }
                _ => {}
            }
        }
        r.force_a_n = f[0].into();
        r.torque_a_n_m = t[0].into();
        r.force_b_n = f[1].into();
        r.torque_b_n_m = t[1].into();
        r
    }
}

impl Potential<4> for JointSet {
    fn name(&self) -> &str {
        "joints"
    }
    fn save_state(&self) -> Vec<u8> {
        // Hardened stiffnesses, targets and world anchors (`set_*` between steps, time events),
        // servo targets and the last readouts (the joint log's next line depends on nothing else).
        let saved: Vec<SavedJointElement> = self
            .elements
            .iter()
            .map(|e| SavedJointElement {
                parameters: primitive_parameters(&mut e.primitive.clone())
                    .into_iter()
                    .map(|p| *p)
                    .collect(),
                nodes: e.nodes,
                stiffness: e.stiffness,
                tolerance: e.tolerance,
                enabled: e.enabled,
                servo: e.servo.map(|s| (s.target, s.response_time_s)),
                readout: e.readout,
            })
            .collect();
        crate::energy::encode_state(&saved)
    }
    fn restore_state(&mut self, bytes: &[u8]) -> Result<(), String> {
        let saved: Vec<SavedJointElement> = crate::energy::decode_state(bytes)?;
        if saved.len() != self.elements.len() {
            return Err(format!(
                "{} joint elements saved, {} in the rebuilt scene",
                saved.len(),
                self.elements.len()
            ));
        }
        for (e, s) in self.elements.iter_mut().zip(saved) {
            if e.servo.is_some() != s.servo.is_some() {
                return Err(format!(
                    "joint '{}' has a servo in only one of checkpoint and scene",
                    e.label
                ));
            }
            let mut params = primitive_parameters(&mut e.primitive);
            if params.len() != s.parameters.len() {
                return Err(format!(
                    "joint '{}' has another kind of primitive than the saved one",
                    e.label
                ));
            }
            for (p, v) in params.iter_mut().zip(&s.parameters) {
                **p = *v;
            }
            e.nodes = s.nodes;
            e.stiffness = s.stiffness;
            e.tolerance = s.tolerance;
            e.enabled = s.enabled;
            if let (Some(servo), Some((target, response_time_s))) = (e.servo.as_mut(), s.servo) {
                servo.target = target;
                servo.response_time_s = response_time_s;
            }
            e.readout = s.readout;
        }
        Ok(())
    }
    fn num_elements(&self) -> usize {
        self.elements.len()
    }
    fn nodes(&self, e: usize) -> [Node; 4] {
        self.elements[e].nodes
    }
    fn energy<S: Scalar>(&self, e: usize, x: &[Vec3<S>; 4], stencil: &Stencil<4>) -> S {
        let el = &self.elements[e];
        if el.enabled {
            el.primitive.energy(x, stencil, el.stiffness)
        } else {
            S::zero()
        }
    }
    fn topology_version(&self) -> u64 {
        self.version
    }
    fn before_step(&mut self, state: &EvalState) {
        let poses = Poses {
            t: &|b| state.bodies.position[b],
            q: &|b| state.bodies.orientation[b],
        };
        for el in &mut self.elements {
            if let Primitive::Coupling(c) = &mut el.primitive {
                c.begin_step(&|b| state.bodies.position[b], &|b| state.bodies.orientation[b]);
            }
            if let Some(servo) = el.servo {
                let mut error = servo.target - servo.measure.value(&poses);
                if let Measure::Angle { .. } = servo.measure {
                    // The angle is measured in (−π, π]: without wrapping, a target beyond ±180°
                    // is never reached and the servo spins for ever.
                    error = wrap_angle(error);
                }
                let speed = error / servo.response_time_s.max(state.dt);
                match &mut el.primitive {
                    Primitive::AngularVelocity { target_rad_s, .. } => *target_rad_s = speed,
                    Primitive::LinearVelocity { target_m_s, .. } => *target_m_s = speed,
                    _ => {}
                }
            }
        }
    }
    fn check_converged_step(&mut self, state: &EvalState) -> StepCheck {
        let mut hardened = Vec::new();
        for e in 0..self.elements.len() {
            let r = self.readout(e, state);
            let el = &mut self.elements[e];
            el.readout = r;
            if el.enabled && el.primitive.is_hard() && r.violation > el.tolerance {
                el.stiffness *= 2.0;
                hardened.push(format!(
                    "joint '{}' violated by {:.3e} {} > {:.3e}: stiffness doubled to {:.3e}",
                    el.label,
                    r.violation,
                    if el.primitive.is_angular() { "rad" } else { "m" },
                    el.tolerance,
                    el.stiffness
                ));
            }
        }
        if hardened.is_empty() {
            StepCheck::Accept
        } else {
            StepCheck::Retry(hardened.join("; "))
        }
    }
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

/// Everything a joint is attached to, resolved from handles and world coordinates.
#[derive(Clone, Copy)]
struct Side {
    body: Option<u32>,
    t: Vector3<f64>,
    q: UnitQuaternion<f64>,
}

impl Side {
    fn point(&self, world: &Vector3<f64>) -> Node {
        match self.body {
            None => Node::World((*world).into()),
            Some(b) => Node::rigid(b as usize, &(self.q.inverse() * (world - self.t))),
        }
    }
    fn local_dir(&self, world: &Vector3<f64>) -> Vector3<f64> {
        self.q.inverse() * world
    }
    /// A unit direction as two points one unit apart, starting at the centre of mass.
    fn direction(&self, world_dir: &Vector3<f64>) -> [Node; 2] {
        let d = world_dir.normalize();
        [self.point(&self.t), self.point(&(self.t + d))]
    }
    fn omega(&self) -> Node {
        match self.body {
            None => Node::World([0.0; 3]),
            Some(b) => Node::AngularVelocity(b),
        }
    }
}

/// `angle` (rad) moved into (−π, π] by whole turns.
fn wrap_angle(angle: f64) -> f64 {
    let tau = std::f64::consts::TAU;
    let w = angle - tau * (angle / tau).round();
    if w <= -std::f64::consts::PI {
        w + tau
    } else {
        w
    }
}

/// A unit vector perpendicular to `axis`.
fn perpendicular(axis: &Vector3<f64>) -> Vector3<f64> {
    let a = axis.normalize();
    let trial = if a.x.abs() < 0.9 { Vector3::x() } else { Vector3::y() };
    (trial - a * a.dot(&trial)).normalize()
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

/// Builds one composite joint.
struct Builder<'s> {
    sim: &'s mut Simulation,
    label: String,
    params: JointParams,
    a: Side,
    b: Side,
    elements: Vec<u32>,
    driver: Option<u32>,
    measure: Option<Measure>,
}

impl<'s> Builder<'s> {
    fn new(
        sim: &'s mut Simulation,
        label: &str,
        a: Option<RigidBodyHandle>,
        b: Option<RigidBodyHandle>,
        params: JointParams,
    ) -> Result<Self> {
        params.validate(label)?;
        let side = |sim: &Simulation, h: Option<RigidBodyHandle>| -> Result<Side> {
            Ok(match h {
                None => Side {
                    body: None,
                    t: Vector3::zeros(),
                    q: UnitQuaternion::identity(),
                },
                Some(h) => {
                    let i = sim.check_body(h)?;
                    Side {
                        body: Some(i as u32),
                        t: sim.bodies.position[i],
                        q: sim.bodies.orientation[i],
                    }
                }
            })
        };
        let (sa, sb) = (side(sim, a)?, side(sim, b)?);
        if sa.body.is_none() && sb.body.is_none() {
            return Err(StarkError::InvalidInput(format!(
                "joint '{label}' connects the world to itself"
            )));
        }
        if let (Some(ia), Some(ib)) = (sa.body, sb.body) {
            if ia == ib {
                let name = &sim.rigid_bodies.labels[ia as usize];
                return Err(StarkError::InvalidInput(format!(
                    "joint '{label}' connects '{name}' to itself: `b` must be another body than `a`"
                )));
            }
        }
        Ok(Builder {
            sim,
            label: label.to_string(),
            params,
            a: sa,
            b: sb,
            elements: Vec::new(),
            driver: None,
            measure: None,
        })
    }

    fn push(&mut self, primitive: Primitive, nodes: &[Node]) -> u32 {
        let mut all = [Node::World([0.0; 3]); 4];
        all[..nodes.len()].copy_from_slice(nodes);
        let tolerance = if !primitive.is_hard() {
            f64::INFINITY
        } else if primitive.is_angular() {
            self.params.tolerance_deg.to_radians()
        } else {
            self.params.tolerance_m
        };
        let set = &mut self.sim.rigid_bodies.joints.potential;
        set.elements.push(JointElement {
            label: self.label.clone(),
            primitive,
            nodes: all,
            bodies: [self.a.body, self.b.body],
            stiffness: self.params.stiffness,
            tolerance,
            enabled: true,
            servo: None,
            readout: JointReadout::default(),
        });
        set.version += 1;
        let e = (set.elements.len() - 1) as u32;
        self.elements.push(e);
        e
    }

    fn point(&mut self, p: &Vector3<f64>) {
        let nodes = [self.a.point(p), self.b.point(p)];
        self.push(Primitive::Point, &nodes);
    }

    fn direction(&mut self, d: &Vector3<f64>) {
        let [a0, a1] = self.a.direction(d);
        let [b0, b1] = self.b.direction(d);
        self.push(Primitive::Direction, &[a0, a1, b0, b1]);
    }

    fn point_on_axis(&mut self, p: &Vector3<f64>, axis: &Vector3<f64>) {
        let nodes = [self.a.point(p), self.a.point(&(p + axis.normalize())), self.b.point(p)];
        self.push(Primitive::PointOnAxis, &nodes);
    }

    fn angle_limit(&mut self, d: &Vector3<f64>, limit_rad: f64) {
        let [a0, a1] = self.a.direction(d);
        let [b0, b1] = self.b.direction(d);
        self.push(Primitive::AngleLimit { limit_rad }, &[a0, a1, b0, b1]);
    }

    fn angular_velocity(&mut self, axis: &Vector3<f64>, target_rad_s: f64, max_torque_n_m: f64, delay_rad_s: f64) {
        let [a0, a1] = self.a.direction(axis);
        let e = self.push(
            Primitive::AngularVelocity {
                target_rad_s,
                max_torque_n_m,
                delay_rad_s,
                drive_only: false,
            },
            &[self.a.omega(), self.b.omega(), a0, a1],
        );
        self.driver = Some(e);
    }

    fn linear_velocity(
        &mut self,
        p: &Vector3<f64>,
        axis: &Vector3<f64>,
        target_m_s: f64,
        max_force_n: f64,
        delay_m_s: f64,
    ) {
        let nodes = [self.a.point(p), self.a.point(&(p + axis.normalize())), self.b.point(p)];
        let e = self.push(
            Primitive::LinearVelocity {
                target_m_s,
                max_force_n,
                delay_m_s,
            },
            &nodes,
        );
        self.driver = Some(e);
    }

    fn angle_measure(&mut self, axis: &Vector3<f64>) {
        let u = perpendicular(axis);
        self.measure = Some(Measure::Angle {
            a: self.a.body,
            b: self.b.body,
            axis_a: self.a.local_dir(&axis.normalize()),
            ref_a: self.a.local_dir(&u),
            ref_b: self.b.local_dir(&u),
        });
    }

    fn position_measure(&mut self, p: &Vector3<f64>, axis: &Vector3<f64>) {
        let local = |s: &Side| s.q.inverse() * (p - s.t);
        self.measure = Some(Measure::Position {
            a: self.a.body,
            b: self.b.body,
            anchor_a: local(&self.a),
            anchor_b: local(&self.b),
            axis_a: self.a.local_dir(&axis.normalize()),
        });
    }

    fn finish(self) -> JointHandle {
        self.sim.register_joint(JointHandle {
            label: self.label,
            elements: self.elements,
            driver: self.driver,
            measure: self.measure,
        })
    }
}

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
    /// shorter way to it. See [`Servo`] for its steady offset under load.
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
    /// [`coupling`]). The joints must have coordinates and unique labels.
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

impl Simulation {
    // ---- Run-time control and readouts ----

    fn joint_elements_mut(&mut self, h: &JointHandle) -> Result<Vec<&mut JointElement>> {
        let n = self.rigid_bodies.joints.potential.elements.len();
        if let Some(&bad) = h.elements.iter().find(|&&e| e as usize >= n) {
            return Err(StarkError::InvalidHandle {
                kind: "joint element",
                index: bad as usize,
                len: n,
            });
        }
        let wanted: std::collections::HashSet<u32> = h.elements.iter().copied().collect();
        Ok(self
            .rigid_bodies
            .joints
            .potential
            .elements
            .iter_mut()
            .enumerate()
            .filter(|(i, _)| wanted.contains(&(*i as u32)))
            .map(|(_, e)| e)
            .collect())
    }

    fn driver_mut(&mut self, h: &JointHandle) -> Result<&mut JointElement> {
        let e = h
            .driver
            .ok_or_else(|| StarkError::InvalidInput(format!("joint '{}' has no driver", h.label)))?;
        self.rigid_bodies
            .joints
            .potential
            .elements
            .get_mut(e as usize)
            .ok_or(StarkError::InvalidHandle {
                kind: "joint element",
                index: e as usize,
                len: 0,
            })
    }

    /// Enable or disable a joint (a disabled joint has no energy).
    pub fn set_joint_enabled(&mut self, h: &JointHandle, enabled: bool) -> Result<()> {
        for e in self.joint_elements_mut(h)? {
            e.enabled = enabled;
        }
        Ok(())
    }

    /// Set the stiffness (N/m) of a joint's hard constraints.
    pub fn set_joint_stiffness(&mut self, h: &JointHandle, stiffness: f64) -> Result<()> {
        check_param(
            &h.label,
            "stiffness",
            stiffness,
            stiffness > 0.0 && stiffness.is_finite(),
            "must be positive (N/m)",
        )?;
        for e in self.joint_elements_mut(h)? {
            if e.primitive.is_hard() {
                e.stiffness = stiffness;
            }
        }
        Ok(())
    }

    /// Set the tolerances of a joint's hard constraints (m for points, degrees for directions).
    pub fn set_joint_tolerance(&mut self, h: &JointHandle, tolerance_m: f64, tolerance_deg: f64) -> Result<()> {
        check_param(
            &h.label,
            "tolerance_m",
            tolerance_m,
            tolerance_m > 0.0,
            "must be positive (m)",
        )?;
        check_param(
            &h.label,
            "tolerance_deg",
            tolerance_deg,
            tolerance_deg > 0.0,
            "must be positive (degrees)",
        )?;
        for e in self.joint_elements_mut(h)? {
            if e.primitive.is_hard() {
                e.tolerance = if e.primitive.is_angular() {
                    tolerance_deg.to_radians()
                } else {
                    tolerance_m
                };
            }
        }
        Ok(())
    }

    /// Largest stiffness of a joint's hard constraints (after hardening), N/m.
    pub fn joint_stiffness(&self, h: &JointHandle) -> f64 {
        h.elements
            .iter()
            .filter_map(|&e| self.rigid_bodies.joints.potential.elements.get(e as usize))
            .filter(|e| e.primitive.is_hard())
            .map(|e| e.stiffness)
            .fold(0.0, f64::max)
    }

    /// Set the target speed of a motor or velocity controller (rad/s), or of a press (m/s).
    pub fn set_joint_target_velocity(&mut self, h: &JointHandle, target: f64) -> Result<()> {
        check_param(
            &h.label,
            "target velocity",
            target,
            target.is_finite(),
            "must be finite",
        )?;
        let el = self.driver_mut(h)?;
        el.servo = None;
        match &mut el.primitive {
            Primitive::AngularVelocity { target_rad_s, .. } => *target_rad_s = target,
            Primitive::LinearVelocity { target_m_s, .. } => *target_m_s = target,
            _ => {
                return Err(StarkError::InvalidInput(format!(
                    "joint '{}' has no velocity controller",
                    h.label
                )))
            }
        }
        Ok(())
    }

    /// Set the largest torque (N·m) or force (N) of a joint's controller.
    pub fn set_joint_max_effort(&mut self, h: &JointHandle, max: f64) -> Result<()> {
        check_param(
            &h.label,
            "max effort",
            max,
            max >= 0.0 && max.is_finite(),
            "must be non-negative",
        )?;
        let el = self.driver_mut(h)?;
        match &mut el.primitive {
            Primitive::AngularVelocity { max_torque_n_m, .. } => *max_torque_n_m = max,
            Primitive::LinearVelocity { max_force_n, .. } => *max_force_n = max,
            _ => {
                return Err(StarkError::InvalidInput(format!(
                    "joint '{}' has no velocity controller",
                    h.label
                )))
            }
        }
        Ok(())
    }

    /// Make a motor (or angular velocity controller) drive only: its torque never opposes the
    /// direction of its target, so it does not brake a joint turning faster than the target
    /// (see [`Primitive::AngularVelocity`]). Set it when building the scene (it is part of the
    /// scene, not of a checkpoint).
    pub fn set_motor_drive_only(&mut self, h: &JointHandle, drive_only: bool) -> Result<()> {
        let el = self.driver_mut(h)?;
        match &mut el.primitive {
            Primitive::AngularVelocity { drive_only: d, .. } => *d = drive_only,
            _ => {
                return Err(StarkError::InvalidInput(format!(
                    "joint '{}' has no motor (angular velocity controller)",
                    h.label
                )))
            }
        }
        Ok(())
    }

    /// Set the target of a servo: degrees for a hinge servo, m for a prismatic one.
    pub fn set_servo_target(&mut self, h: &JointHandle, target: f64) -> Result<()> {
        check_param(&h.label, "servo target", target, target.is_finite(), "must be finite")?;
        let el = self.driver_mut(h)?;
        let servo = el
            .servo
            .as_mut()
            .ok_or_else(|| StarkError::InvalidInput(format!("joint '{}' is not a servo", h.label)))?;
        servo.target = match servo.measure {
            Measure::Angle { .. } => target.to_radians(),
            Measure::Position { .. } => target,
        };
        Ok(())
    }

    /// Set the rest length (m) and damping (N·s/m) of a spring.
    pub fn set_spring(&mut self, h: &JointHandle, rest_length: f64, damping: f64) -> Result<()> {
        check_param(
            &h.label,
            "rest length",
            rest_length,
            rest_length >= 0.0 && rest_length.is_finite(),
            "must be non-negative (m)",
        )?;
        check_param(
            &h.label,
            "damping",
            damping,
            damping >= 0.0 && damping.is_finite(),
            "must be non-negative (N·s/m)",
        )?;
        let el = self.driver_mut(h)?;
        match &mut el.primitive {
            Primitive::Spring {
                rest_length_m,
                damping_n_s_m,
            } => {
                *rest_length_m = rest_length;
                *damping_n_s_m = damping;
                Ok(())
            }
            _ => Err(StarkError::InvalidInput(format!("joint '{}' is not a spring", h.label))),
        }
    }

    /// Drive a fixed body (see [`Simulation::add_fix_joint`]) to centre of mass `position_m` and
    /// orientation `orientation` (met at the end of the next step).
    pub fn set_fixed_transform(
        &mut self,
        h: &JointHandle,
        position_m: Vector3<f64>,
        orientation: UnitQuaternion<f64>,
    ) -> Result<()> {
        check_vec(&h.label, "position", &position_m)?;
        let els = self.joint_elements_mut(h)?;
        if els.len() != 3 || els.iter().any(|e| e.bodies[0].is_some()) {
            return Err(StarkError::InvalidInput(format!(
                "joint '{}' is not a fix joint",
                h.label
            )));
        }
        let axes = [Vector3::z(), Vector3::x()];
        let mut dir = 0;
        for e in els {
            match e.primitive {
                Primitive::Point => e.nodes[0] = Node::World(position_m.into()),
                Primitive::Direction => {
                    let d = orientation * axes[dir];
                    dir += 1;
                    e.nodes[0] = Node::World([0.0; 3]);
                    e.nodes[1] = Node::World(d.into());
                }
                _ => {}
            }
        }
        Ok(())
    }

    /// [`Simulation::set_fixed_transform`] with a rotation of `angle_deg` about `axis`.
    pub fn set_fixed_transform_deg(
        &mut self,
        h: &JointHandle,
        position_m: Vector3<f64>,
        angle_deg: f64,
        axis: Vector3<f64>,
    ) -> Result<()> {
        check_axis(&h.label, &axis)?;
        let q = UnitQuaternion::from_axis_angle(&Unit::new_normalize(axis), angle_deg.to_radians());
        self.set_fixed_transform(h, position_m, q)
    }

    /// Readouts of each primitive of a joint at the last accepted step.
    pub fn joint_primitive_readouts(&self, h: &JointHandle) -> Vec<(Primitive, JointReadout)> {
        h.elements
            .iter()
            .filter_map(|&e| self.rigid_bodies.joints.potential.elements.get(e as usize))
            .map(|e| (e.primitive.clone(), e.readout))
            .collect()
    }

    /// The joint's state at the last accepted step: violations, its total force and torque on
    /// body b, its driver's effort, and its coordinate (angle or position) and rate now.
    pub fn joint_state(&self, h: &JointHandle) -> JointState {
        let mut s = JointState::default();
        let els = &self.rigid_bodies.joints.potential.elements;
        for &e in &h.elements {
            let Some(el) = els.get(e as usize) else { continue };
            let r = &el.readout;
            if el.primitive.is_hard() {
                if el.primitive.is_angular() {
                    s.violation_rad = s.violation_rad.max(r.violation);
                } else {
                    s.violation_m = s.violation_m.max(r.violation);
                }
            }
            for k in 0..3 {
                s.force_on_b_n[k] += r.force_b_n[k];
                s.torque_on_b_n_m[k] += r.torque_b_n_m[k];
            }
        }
        if let Some(d) = h.driver.and_then(|d| els.get(d as usize)) {
            let r = &d.readout;
            s.driver_effort = match d.primitive {
                Primitive::AngularVelocity { .. } => {
                    let axis =
                        (d.nodes[3].start_position_world(self) - d.nodes[2].start_position_world(self)).normalize();
                    Vector3::from(r.torque_b_n_m).dot(&axis)
                }
                Primitive::LinearVelocity { .. } => {
                    let axis =
                        (d.nodes[1].start_position_world(self) - d.nodes[0].start_position_world(self)).normalize();
                    Vector3::from(r.force_b_n).dot(&axis)
                }
                Primitive::Spring { .. } => {
                    // Tension: the force on b along the line from b's point to a's.
                    let line = d.nodes[0].start_position_world(self) - d.nodes[1].start_position_world(self);
                    let f = Vector3::from(r.force_b_n);
                    if line.norm() > 0.0 {
                        f.dot(&line.normalize())
                    } else {
                        f.norm()
                    }
                }
                _ => Vector3::from(r.force_b_n).norm(),
            };
        }
        if let Some(m) = h.measure {
            let poses = Poses {
                t: &|b| self.bodies.position[b],
                q: &|b| self.bodies.orientation[b],
            };
            s.coordinate = Some(m.value(&poses));
            s.coordinate_rate = Some(match m {
                Measure::Angle { a, b, axis_a, .. } => {
                    let w =
                        |body: Option<u32>| body.map_or(Vector3::zeros(), |b| self.bodies.angular_velocity[b as usize]);
                    let qa = a.map_or(UnitQuaternion::identity(), |b| self.bodies.orientation[b as usize]);
                    (w(b) - w(a)).dot(&(qa * axis_a))
                }
                Measure::Position {
                    a,
                    b,
                    anchor_a,
                    anchor_b,
                    axis_a,
                } => {
                    let vel = |body: Option<u32>, local: &Vector3<f64>| {
                        body.map_or(Vector3::zeros(), |b| {
                            let b = b as usize;
                            self.bodies.velocity[b]
                                + self.bodies.angular_velocity[b].cross(&(self.bodies.orientation[b] * local))
                        })
                    };
                    let qa = a.map_or(UnitQuaternion::identity(), |b| self.bodies.orientation[b as usize]);
                    (vel(b, &anchor_b) - vel(a, &anchor_a)).dot(&(qa * axis_a))
                }
            });
        }
        s
    }
}

impl Node {
    /// Current (committed) world position of a body-fixed or world node in `sim`.
    fn start_position_world(&self, sim: &Simulation) -> Vector3<f64> {
        match *self {
            Node::Rigid { body, local } => {
                sim.body_point_to_world(RigidBodyHandle { index: body }, &Vector3::from(local))
            }
            Node::World(p) => Vector3::from(p),
            Node::Point(i) => sim.nodes.x[i as usize],
            Node::AngularVelocity(b) => sim.bodies.angular_velocity[b as usize],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::wrap_angle;
    use std::f64::consts::PI;

    #[test]
    fn servo_angle_errors_wrap_into_the_half_open_turn() {
        for (a, w) in [
            (0.0, 0.0),
            (PI, PI),
            (-PI, PI),
            (1.5 * PI, -0.5 * PI),
            (-1.5 * PI, 0.5 * PI),
            (200f64.to_radians(), -160f64.to_radians()),
            (7.0 * PI + 0.1, -PI + 0.1),
        ] {
            assert!((wrap_angle(a) - w).abs() < 1e-12, "{a} → {} (want {w})", wrap_angle(a));
        }
    }
}

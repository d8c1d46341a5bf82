//! A linear coupling of joint coordinates (URDF `<mimic>`), a spring–damper on one coordinate,
//! and joint damping (URDF `<dynamics damping>`): one energy on two joint coordinates.
//!
//! With the coordinates `q_a` (of joint A; absent for a single-joint spring) and `q_b` (joint B),
//! each a hinge angle (rad) or a slider position (m) measured by a [`Measure`], the energy is
//!
//! `E = ½k·(q_b − m·q_a − c)² + ½(d/dt)·(Δq_b − m·Δq_a)²`
//!
//! with `Δq` the change of a coordinate over the step: a hard mimic constraint for `k` large
//! (hardened to its tolerance like every hard joint), a spring of stiffness `k` about `q_b = c`
//! for `m = 0`, and viscous damping `d·q̇` (N·s/m or N·m·s/rad) from the second term, whose
//! gradient with respect to the velocities is the damping impulse `d·q̇·dt`.
//!
//! A coordinate is a non-linear function of two bodies' poses (an `atan2` of body-fixed
//! directions for angles), and a mimic between two joints of three bodies would need up to ten
//! body points. Instead, each coordinate is its start-of-step value `q0` plus the step's increment
//! along the joint axis frozen at the start of the step:
//! - hinge: `Δq = dt·axis·(ω_child − ω_parent)` (nodes: the two angular velocities), the
//!   backward-Euler rotation of the step about the axis to first order;
//! - slider: `Δq = axis·(Δx_child − Δx_parent)` of the joint's anchor points.
//!
//! `q0` and the axes are measured exactly from the poses before every step ([`Coupling::begin_step`]),
//! so the linearisation error (second order in the step's rotation) does not accumulate. Nodes of
//! the element: `[a_parent, a_child, b_parent, b_child]` (world placeholders for an absent A).

use super::Measure;
use crate::energy::{Node, Scalar, Stencil, Vec3};
use nalgebra::{UnitQuaternion, Vector3};

/// One coordinate of a [`Coupling`]: how to measure it, and its value and axis at the start of
/// the current step.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CoupledCoordinate {
    /// The joint coordinate (zero at the joint's creation).
    pub measure: Measure,
    /// Its value at the start of the step: rad or m.
    pub q0: f64,
    /// The joint axis in world coordinates at the start of the step.
    pub axis: [f64; 3],
}

impl CoupledCoordinate {
    /// A coordinate measured by `measure` (start-of-step values set by [`Coupling::begin_step`]).
    pub fn new(measure: Measure) -> Self {
        CoupledCoordinate {
            measure,
            q0: 0.0,
            axis: [0.0; 3],
        }
    }

    /// Whether it is an angle (rad) rather than a position (m).
    pub fn is_angle(&self) -> bool {
        matches!(self.measure, Measure::Angle { .. })
    }

    /// The element nodes of its increment: the parent's and the child's angular velocity for an
    /// angle, the joint's anchor point on each for a position.
    pub fn nodes(&self) -> [Node; 2] {
        let omega = |b: Option<u32>| b.map_or(Node::World([0.0; 3]), Node::AngularVelocity);
        let point = |b: Option<u32>, local: &Vector3<f64>| match b {
            Some(b) => Node::rigid(b as usize, local),
            None => Node::World((*local).into()),
        };
        match self.measure {
            Measure::Angle { a, b, .. } => [omega(a), omega(b)],
            Measure::Position {
                a,
                b,
                anchor_a,
                anchor_b,
                ..
            } => [point(a, &anchor_a), point(b, &anchor_b)],
        }
    }

    /// Its value at the trial state: `q0 + Δq` from the element nodes `x` (and `x0`).
    fn value<S: Scalar>(&self, x: &[Vec3<S>], x0: &[Vector3<f64>], dt: f64) -> S {
        let axis = Vector3::from(self.axis);
        let axis = Vec3::<S>::constant(&axis);
        let delta = if self.is_angle() {
            (x[1] - x[0]).dot(&axis) * dt
        } else {
            (x[1].sub_f64(&x0[1]) - x[0].sub_f64(&x0[0])).dot(&axis)
        };
        delta + self.q0
    }
}

/// `q_b = m·q_a + c` as a penalty, with damping of `q̇_b − m·q̇_a` (see the module doc).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Coupling {
    /// The leading coordinate (None: a spring–damper on `b` alone).
    pub a: Option<CoupledCoordinate>,
    /// The following coordinate.
    pub b: CoupledCoordinate,
    /// `m`, unitless when both coordinates are of one kind (m/rad or rad/m otherwise).
    pub multiplier: f64,
    /// `c`: rad or m (of `b`).
    pub offset: f64,
    /// Viscous damping `d` of `q̇_b − m·q̇_a`: N·s/m or N·m·s/rad.
    pub damping: f64,
    /// Whether it is a hard constraint, hardened to a tolerance (mimic), or soft (spring).
    pub hard: bool,
}

impl Coupling {
    /// The four element nodes: `[a_parent, a_child, b_parent, b_child]`.
    pub fn nodes(&self) -> [Node; 4] {
        let [a0, a1] = self.a.map_or([Node::World([0.0; 3]); 2], |a| a.nodes());
        let [b0, b1] = self.b.nodes();
        [a0, a1, b0, b1]
    }

    /// Measure both coordinates and their world axes from the start-of-step poses `t` (body
    /// positions) and `q` (orientations).
    pub fn begin_step(&mut self, t: &dyn Fn(usize) -> Vector3<f64>, q: &dyn Fn(usize) -> UnitQuaternion<f64>) {
        for c in self.a.iter_mut().chain(std::iter::once(&mut self.b)) {
            let poses = super::Poses { t, q };
            c.q0 = c.measure.value(&poses);
            let (parent, axis_local) = match c.measure {
                Measure::Angle { a, axis_a, .. } => (a, axis_a),
                Measure::Position { a, axis_a, .. } => (a, axis_a),
            };
            let rotation = parent.map_or(UnitQuaternion::identity(), |p| q(p as usize));
            c.axis = (rotation * axis_local).into();
        }
    }

    /// The residual `q_b − m·q_a − c` measured from poses: rad or m.
    pub fn residual(&self, t: &dyn Fn(usize) -> Vector3<f64>, q: &dyn Fn(usize) -> UnitQuaternion<f64>) -> f64 {
        let poses = super::Poses { t, q };
        let qa = self.a.map_or(0.0, |a| a.measure.value(&poses));
        self.b.measure.value(&poses) - self.multiplier * qa - self.offset
    }

    /// The energy at the element positions `x` with stiffness `k` (N/m or N·m/rad).
    pub fn energy<S: Scalar>(&self, x: &[Vec3<S>; 4], s: &Stencil<4>, k: f64) -> S {
        let dt = s.dt;
        let (qa, dqa) = match &self.a {
            Some(a) => {
                let q = a.value(&x[0..2], &s.x0[0..2], dt);
                (q, q - a.q0)
            }
            None => (S::zero(), S::zero()),
        };
        let qb = self.b.value(&x[2..4], &s.x0[2..4], dt);
        let dqb = qb - self.b.q0;
        let r = qb - qa * self.multiplier - self.offset;
        let rate = dqb - dqa * self.multiplier;
        r * r * (0.5 * k) + rate * rate * (0.5 * self.damping / dt)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Settings;
    use crate::Simulation;

    /// The increments the energy predicts match the measured change of the coordinates over a
    /// step of a free body turning and sliding: the linearisation is exact to first order.
    #[test]
    fn predicted_coordinates_follow_the_measured_ones() {
        let mut s = Settings::default();
        s.output.frames = false;
        s.output.step_log = false;
        s.gravity_m_s2 = [0.0; 3];
        s.time_step_s = 1e-3;
        let mut sim = Simulation::new(s).unwrap();
        let props = crate::rigidbodies::MassProperties::cuboid(1.0, Vector3::new(0.1, 0.2, 0.3));
        let base = sim
            .add_rigid_body_with("base", &props, Vector3::zeros(), UnitQuaternion::identity())
            .unwrap();
        let arm = sim
            .add_rigid_body_with("arm", &props, Vector3::new(0.3, 0.0, 0.0), UnitQuaternion::identity())
            .unwrap();
        let axis = Vector3::new(0.0, 0.6, 0.8);
        let hinge = sim
            .add_hinge_joint(
                "hinge",
                Some(base),
                arm,
                Vector3::new(0.1, 0.0, 0.0),
                axis,
                Default::default(),
            )
            .unwrap();
        let slider = sim
            .add_slider_joint(
                "slider",
                Some(base),
                arm,
                Vector3::new(0.1, 0.0, 0.0),
                axis,
                Default::default(),
            )
            .unwrap();
        sim.set_joint_enabled(&hinge, false).unwrap();
        sim.set_joint_enabled(&slider, false).unwrap();
        let mut c = Coupling {
            a: Some(CoupledCoordinate::new(hinge.measure.unwrap())),
            b: CoupledCoordinate::new(slider.measure.unwrap()),
            multiplier: 0.5,
            offset: 0.0,
            damping: 0.0,
            hard: true,
        };
        sim.set_body_angular_velocity(arm, axis.normalize() * 2.0).unwrap();
        sim.set_body_velocity(arm, axis.normalize() * 0.3).unwrap();
        sim.step().unwrap();
        let bodies = &sim.bodies;
        c.begin_step(&|b| bodies.position[b], &|b| bodies.orientation[b]);
        let (q0a, q0b) = (c.a.unwrap().q0, c.b.q0);
        // After one step of 1 ms at 2 rad/s and 0.3 m/s along the axis (the backward-Euler
        // rotation is 2·atan(ω·dt/2) ≈ ω·dt − (ω·dt)³/12):
        assert!((q0a - 2e-3).abs() < 2e-9, "angle {q0a}");
        assert!((q0b - 3e-4).abs() < 1e-9, "position {q0b}");
        assert!((c.residual(&|b| bodies.position[b], &|b| bodies.orientation[b]) - (q0b - 0.5 * q0a)).abs() < 1e-15);
    }
}

//! The joint term: [`JointSet`], every primitive element of a simulation as one potential, with
//! servo updates, hardening, readouts and the checkpointed state.

use super::{JointElement, JointReadout, Measure, Poses, Primitive};
use crate::energy::potential::{element_derivatives, FastDerivatives, Potential, Stencil};
use crate::energy::term::StepCheck;
use crate::energy::{HyperDual, Node, Scalar, Vec3};
use crate::error::Result;
use crate::state::EvalState;
use nalgebra::{UnitQuaternion, Vector3};

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
    pub(super) version: u64,
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
        let mut d = HyperDual::constant(0.0);
        element_derivatives(self, e, &stencil, false, &mut d);
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
    fn is_element_convex(&self, e: usize) -> bool {
        // Quadratic in the nodes' positions: `½k‖x_b − x_a‖²`, `½k‖d_b − d_a‖²` (d = a1 − a0).
        matches!(self.elements[e].primitive, Primitive::Point | Primitive::Direction)
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
    fn derivatives(&self, e: usize, stencil: &Stencil<4>, _project: bool, out: &mut HyperDual<4>) -> FastDerivatives {
        let el = &self.elements[e];
        if !el.enabled {
            *out = HyperDual::constant(0.0);
            FastDerivatives::Exact
        } else if el.primitive.quadratic_derivatives(&stencil.x, el.stiffness, out) {
            FastDerivatives::Exact
        } else {
            FastDerivatives::Unavailable
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

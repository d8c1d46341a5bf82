//! Rigid-body inertia: the kinetic part of the incremental potential for each body's linear and
//! angular velocity blocks, with gravity, external forces and torques and damping.
//!
//! Linear (per body): `½m‖v − v0‖² + ½m·d_lin·dt‖v‖² − dt·(m(g + a) + f)·v`.
//!
//! Angular: `½(ω − ω*)ᵀJp(ω − ω*) + ½d_ang·dt·ωᵀJpω − dt·(Jp·α + τ)·ω`. Stark uses the
//! start-of-step inertia `J0 = R0 J Rᵀ0` and `ω* = ω0`, which keeps `ω` (not the angular momentum
//! `L = Jω`) constant when no torque acts, so a tumbling body's `L` drifts. Here the gyroscopic
//! effect is included by taking the inertia `Jp = Rp J Rpᵀ` at the predicted end-of-step
//! orientation `Rp` (the torque-free rotation from `q0`) and `ω* = Jp⁻¹·J0ω0`: without torque the
//! step then keeps `L1 = Jp ω1 = J0 ω0`, exactly as far as `Rp` predicts the end orientation (to
//! second order in dt per step). Both `Jp` and `ω*` are lagged at the start of each step.

use crate::energy::kinematics::integrate_orientation;
use crate::energy::term::{element_stride, EnergyTerm, EvalMode};
use crate::error::{check_param, Result};
use crate::state::{angular_block, linear_block, BodyArrays, EvalState};
use nalgebra::{Matrix3, Vector3};

crate::params::param_struct! {
    /// Damping of a rigid body.
    #[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
    #[serde(deny_unknown_fields, default)]
    pub struct RigidBodyParams {
        /// Linear velocity damping ("drag"), 1/s (default: 0).
        pub linear_damping_1_s: f64,
        /// Angular velocity damping, 1/s (default: 0).
        pub angular_damping_1_s: f64,
    }
}

impl Default for RigidBodyParams {
    fn default() -> Self {
        RigidBodyParams {
            linear_damping_1_s: 0.0,
            angular_damping_1_s: 0.0,
        }
    }
}

impl RigidBodyParams {
    /// Check every field; `label` names the body in errors.
    pub fn validate(&self, label: &str) -> Result<()> {
        for (name, v) in [
            ("linear_damping_1_s", self.linear_damping_1_s),
            ("angular_damping_1_s", self.angular_damping_1_s),
        ] {
            check_param(label, name, v, v >= 0.0 && v.is_finite(), "must be non-negative (1/s)")?;
        }
        Ok(())
    }
}

/// The inertia term of all rigid bodies.
#[derive(Default)]
pub struct RigidInertia {
    /// Parameters per body.
    pub params: Vec<RigidBodyParams>,
    /// Lagged per body: predicted world inertia `Jp` and the momentum-conserving target `ω*`.
    lagged: Vec<(Matrix3<f64>, Vector3<f64>)>,
}

impl RigidInertia {
    /// Predicted inertia and target angular velocity of body `b` (see the module docs).
    pub fn lag(bodies: &BodyArrays, b: usize, dt: f64) -> (Matrix3<f64>, Vector3<f64>) {
        let j_local = bodies.inertia_local[b];
        let j0 = bodies.inertia_world(b);
        let momentum = j0 * bodies.angular_velocity[b];
        let q0 = bodies.orientation[b];
        // Two fixed-point passes: predict the orientation with ω, then ω from L0 and the predicted
        // inertia.
        let mut w = bodies.angular_velocity[b];
        let mut jp = j0;
        for _ in 0..2 {
            let r = integrate_orientation(&q0, &w, dt).to_rotation_matrix().into_inner();
            jp = r * j_local * r.transpose();
            w = jp.try_inverse().map_or(w, |inv| inv * momentum);
        }
        (jp, w)
    }

    fn body_energy(&self, b: usize, state: &EvalState) -> (f64, [Vector3<f64>; 2], [Matrix3<f64>; 2]) {
        let n = state.n_nodes();
        let bodies = state.bodies;
        let dt = state.dt;
        let p = &self.params[b];
        let m = bodies.mass[b];
        let v = state.v[linear_block(n, b) as usize];
        let w = state.v[angular_block(n, b) as usize];
        let (jp, w_star) = self.lagged[b];
        let f = (state.gravity + bodies.acceleration[b]) * m + bodies.force[b];
        let dv = v - bodies.velocity[b];
        let dl = p.linear_damping_1_s * dt;
        let e_lin = 0.5 * m * dv.norm_squared() + 0.5 * m * dl * v.norm_squared() - dt * f.dot(&v);
        let g_lin = dv * m + v * (m * dl) - f * dt;
        let h_lin = Matrix3::identity() * (m * (1.0 + dl));
        let tau = jp * bodies.angular_acceleration[b] + bodies.torque[b];
        let dw = w - w_star;
        let da = p.angular_damping_1_s * dt;
        let e_ang = 0.5 * dw.dot(&(jp * dw)) + 0.5 * da * w.dot(&(jp * w)) - dt * tau.dot(&w);
        let g_ang = jp * dw + jp * w * da - tau * dt;
        let h_ang = jp * (1.0 + da);
        (e_lin + e_ang, [g_lin, g_ang], [h_lin, h_ang])
    }
}

impl EnergyTerm for RigidInertia {
    fn name(&self) -> &str {
        "rigid body inertia"
    }
    fn save_state(&self) -> Vec<u8> {
        // Damping and other per-body parameters may change between steps.
        crate::energy::encode_state(&self.params)
    }
    fn restore_state(&mut self, bytes: &[u8]) -> std::result::Result<(), String> {
        crate::energy::restore_vec(&mut self.params, crate::energy::decode_state(bytes)?, "bodies")
    }
    fn num_elements(&self) -> usize {
        self.params.len()
    }
    fn stencil_width(&self, _state: &EvalState) -> usize {
        2
    }
    fn write_stencils(&self, state: &EvalState, out: &mut [u32]) {
        let n = state.n_nodes();
        for (e, o) in out.chunks_exact_mut(2).enumerate() {
            o[0] = linear_block(n, e);
            o[1] = angular_block(n, e);
        }
    }
    fn energy(&self, state: &EvalState) -> f64 {
        (0..self.params.len()).map(|b| self.body_energy(b, state).0).sum()
    }
    fn evaluate_element(&self, e: usize, state: &EvalState, _mode: EvalMode, out: &mut [f64]) {
        debug_assert_eq!(out.len(), element_stride(2));
        out.iter_mut().for_each(|o| *o = 0.0);
        let (energy, g, h) = self.body_energy(e, state);
        out[0] = energy;
        for a in 0..2 {
            for i in 0..3 {
                out[1 + 3 * a + i] = g[a][i];
            }
            // Diagonal blocks (a, a) of the 2×2 block layout.
            let base = 7 + 9 * (a * 2 + a);
            for i in 0..3 {
                for j in 0..3 {
                    out[base + 3 * i + j] = h[a][(i, j)];
                }
            }
        }
    }
    fn before_step(&mut self, state: &EvalState) {
        let bodies = state.bodies;
        self.lagged = (0..bodies.len()).map(|b| Self::lag(bodies, b, state.dt)).collect();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energy::testing::{term_element_derivative_errors, TestState};
    use crate::state::angular_block;
    use nalgebra::UnitQuaternion;

    /// Two tumbling bodies with damping, forces, torques and prescribed accelerations.
    fn bodies() -> BodyArrays {
        let mut b = BodyArrays::default();
        for (k, q) in [(0.2, (0.2, 0.4, -0.3)), (-0.5, (1.1, -0.7, 2.0))] {
            b.position.push(Vector3::new(k, 2.0 * k, -k));
            b.orientation.push(UnitQuaternion::from_euler_angles(q.0, q.1, q.2));
            b.velocity.push(Vector3::new(0.3, -k, 1.0));
            b.angular_velocity.push(Vector3::new(1.0, 5.0 * k, 0.3));
            b.mass.push(1.5 + k);
            b.inertia_local
                .push(Matrix3::from_diagonal(&Vector3::new(0.1, 0.2 - k / 10.0, 0.3)));
            b.force.push(Vector3::new(k, 0.5, -2.0));
            b.torque.push(Vector3::new(0.1, -0.2 * k, 0.05));
            b.acceleration.push(Vector3::new(0.0, k, 0.3));
            b.angular_acceleration.push(Vector3::new(-0.4, 0.2, k));
        }
        b
    }

    #[test]
    fn gradient_and_hessian_match_finite_differences_of_the_energy() {
        let dt = 0.01;
        let body_v = [
            (Vector3::new(0.2, -0.1, 0.7), Vector3::new(0.9, 1.2, -0.4)),
            (Vector3::new(-0.3, 0.4, 0.1), Vector3::new(-2.0, 0.5, 1.5)),
        ];
        let st = TestState::new(vec![], vec![], vec![], vec![], dt).with_bodies(bodies(), &body_v);
        let mut term = RigidInertia {
            params: vec![
                RigidBodyParams {
                    linear_damping_1_s: 0.7,
                    angular_damping_1_s: 1.3,
                },
                RigidBodyParams::default(),
            ],
            ..Default::default()
        };
        term.before_step(&st.eval());
        for b in 0..2 {
            // The elements split the term's energy: one per body.
            let mut out = vec![0.0; element_stride(2)];
            term.evaluate_element(b, &st.eval(), EvalMode::ExactHessian, &mut out);
            let others: f64 = (0..2)
                .filter(|&o| o != b)
                .map(|o| term.body_energy(o, &st.eval()).0)
                .sum();
            assert!((out[0] + others - term.energy(&st.eval())).abs() < 1e-12);
            // The energy is quadratic in (v, ω) with the lagged inertia, so central differences
            // are exact up to rounding: ~1e-10 for first differences, ~1e-8 for the energy's
            // second differences (rounding / step²).
            let err = term_element_derivative_errors(&term, b, &st, 1e-6);
            assert!(err.gradient_norm > 1e-3, "body {b}: inactive case");
            assert!(
                err.gradient < 1e-7,
                "body {b}: gradient vs FD, relative error {:e}",
                err.gradient
            );
            assert!(
                err.hessian_of_gradient < 1e-7,
                "body {b}: Hessian vs FD of the gradient, relative error {:e}",
                err.hessian_of_gradient
            );
            assert!(
                err.hessian_of_energy < 1e-6,
                "body {b}: Hessian vs second FD of the energy, relative error {:e}",
                err.hessian_of_energy
            );
        }
        // The DOF blocks the element writes are the body's.
        let mut stencil = vec![0u32; 4];
        term.write_stencils(&st.eval(), &mut stencil);
        assert_eq!(
            stencil,
            [
                linear_block(0, 0),
                angular_block(0, 0),
                linear_block(0, 1),
                angular_block(0, 1)
            ]
        );
    }

    #[test]
    fn lagged_target_conserves_momentum_with_predicted_inertia() {
        let mut bodies = BodyArrays::default();
        bodies.position.push(Vector3::zeros());
        bodies
            .orientation
            .push(UnitQuaternion::from_euler_angles(0.2, 0.4, -0.3));
        bodies.velocity.push(Vector3::zeros());
        bodies.angular_velocity.push(Vector3::new(1.0, 5.0, 0.3));
        bodies.mass.push(1.0);
        bodies
            .inertia_local
            .push(Matrix3::from_diagonal(&Vector3::new(1.0, 2.0, 3.0)));
        let (jp, w) = RigidInertia::lag(&bodies, 0, 0.01);
        let l0 = bodies.inertia_world(0) * bodies.angular_velocity[0];
        assert!((jp * w - l0).norm() < 1e-12 * l0.norm());
    }
}

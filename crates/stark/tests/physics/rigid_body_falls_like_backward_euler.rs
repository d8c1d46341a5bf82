//! A free rigid body follows the backward-Euler recurrence of DESIGN §2 to rounding:
//! `v₊ = (v + dt·(g + a + f/m)) / (1 + d·dt)`, `t₊ = t + dt·v₊` for its centre of mass (linear
//! damping `d`, external acceleration `a`, persistent force `f`), and
//! `q₊ = normalize(q + ½·dt·(0, ω) ⊗ q)` for its orientation.
//!
//! Setup: a 2 kg solid sphere (isotropic inertia, so a torque-free spin keeps `ω` constant
//! exactly and the orientation recurrence can be followed by hand) thrown at (1, 0.5, 2) m/s,
//! spinning at (3, −1, 2) rad/s, with a force of (0.6, 0, 0) N and an extra acceleration of
//! (0, 0.2, 0) m/s², dt = 0.01 s, 50 steps, with linear damping 0 and 0.7/s. The energy is
//! quadratic in `v` and the angular part's minimiser is `ω0`, so one Newton step solves the step
//! exactly. Measured: position, velocity and orientation agree to ~1e-15 (asserted 1e-12), and a
//! box with anisotropic inertia (no spin) falls along the same recurrence.

use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use stark::rigidbodies::MassProperties;
use stark::{Settings, Simulation};

#[test]
fn rigid_body_falls_like_backward_euler() {
    for damping in [0.0, 0.7] {
        let mut settings = Settings::default();
        settings.output.frames = false;
        settings.output.step_log = false;
        settings.time_step_s = 0.01;
        settings.newton.linear_solver = stark::solver::LinearSolver::Cholesky;
        settings.newton.residual_tolerance_n = 1e-10;
        let mut sim = Simulation::new(settings).unwrap();
        let (m, q0) = (2.0, UnitQuaternion::from_euler_angles(0.3, -0.2, 0.5));
        let ball = sim
            .add_rigid_body_with("ball", &MassProperties::sphere(m, 0.1), Vector3::new(0.0, 0.0, 1.0), q0)
            .unwrap();
        let slab = sim
            .add_rigid_body_with(
                "slab",
                &MassProperties::cuboid(m, Vector3::new(0.1, 0.2, 0.4)),
                Vector3::new(1.0, 0.0, 1.0),
                q0,
            )
            .unwrap();
        let (force, accel) = (Vector3::new(0.6, 0.0, 0.0), Vector3::new(0.0, 0.2, 0.0));
        let (v0, w0) = (Vector3::new(1.0, 0.5, 2.0), Vector3::new(3.0, -1.0, 2.0));
        for b in [ball, slab] {
            let mut params = sim.body_params(b).unwrap();
            params.linear_damping_1_s = damping;
            sim.set_body_params(b, params).unwrap();
            sim.set_body_velocity(b, v0).unwrap();
            sim.set_body_force(b, force).unwrap();
            sim.set_body_acceleration(b, accel).unwrap();
        }
        sim.set_body_angular_velocity(ball, w0).unwrap();
        let g = sim.gravity();
        let dt = sim.dt();
        let (mut t, mut v, mut q) = (sim.body_position(ball), v0, q0);
        let mut t_slab = sim.body_position(slab);
        for _ in 0..50 {
            sim.step().unwrap();
            v = (v + (g + accel + force / m) * dt) / (1.0 + damping * dt);
            t += v * dt;
            t_slab += v * dt;
            q = UnitQuaternion::from_quaternion(
                q.quaternion() + Quaternion::from_parts(0.0, w0) * q.quaternion() * (0.5 * dt),
            );
        }
        let errors = [
            (sim.body_position(ball) - t).norm(),
            (sim.body_velocity(ball) - v).norm(),
            (sim.body_angular_velocity(ball) - w0).norm(),
            sim.body_orientation(ball).angle_to(&q),
            (sim.body_position(slab) - t_slab).norm(),
            (sim.body_velocity(slab) - v).norm(),
            sim.body_orientation(slab).angle_to(&q0),
        ];
        println!("rigid free fall, damping {damping}/s: errors after 50 steps {errors:?}");
        for e in errors {
            assert!(e < 1e-12, "damping {damping}: errors {errors:?}");
        }
    }
}

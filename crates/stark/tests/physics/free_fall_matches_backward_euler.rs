//! A node set with only inertia and gravity follows the backward-Euler recurrence
//! `v₊ = v + dt·g`, `x₊ = x + dt·v₊` to 1e-12, including inertial damping
//! (`v₊ = (v + dt·g)/(1 + d·dt)`) and a persistent external force.

use nalgebra::Vector3;
use stark::presets::LineMaterial;
use stark::{Settings, Simulation};

#[test]
fn free_fall_matches_backward_euler() {
    for damping in [0.0, 0.7] {
        let mut settings = Settings::default();
        settings.output.frames = false;
        settings.output.step_log = false;
        settings.time_step_s = 0.01;
        // The energy is quadratic: one exact Newton step solves it to rounding.
        settings.newton.linear_solver = stark::solver::LinearSolver::Cholesky;
        settings.newton.residual_tolerance_n = 1e-10;
        let mut sim = Simulation::new(settings).unwrap();
        let mut material = LineMaterial::default();
        material.inertia.damping = damping;
        // Very soft rod moving rigidly: no strain, so only inertia acts.
        material.strain.youngs_modulus = 1e-3;
        let rod = sim
            .add_line_segments("rod", Vector3::zeros(), Vector3::new(1.0, 0.0, 0.0), 4, &material)
            .unwrap();
        sim.set_velocity(rod.nodes, Vector3::new(1.0, 0.5, 2.0));
        let m = sim.deformables.inertia.node_masses(sim.nodes.len());
        let force = Vector3::new(0.3, 0.0, 0.0);
        for i in rod.nodes.range() {
            sim.nodes.force[i] = force * m[i];
        }
        let g = sim.gravity();
        let mut x: Vec<Vector3<f64>> = sim.positions(rod.nodes).to_vec();
        let mut v: Vec<Vector3<f64>> = sim.velocities(rod.nodes).to_vec();
        let dt = sim.dt();
        for _ in 0..50 {
            sim.step().unwrap();
            for i in 0..x.len() {
                v[i] = (v[i] + (g + force) * dt) / (1.0 + damping * dt);
                x[i] += v[i] * dt;
            }
        }
        for (p, q) in sim.positions(rod.nodes).iter().zip(&x) {
            assert!((p - q).norm() < 1e-12, "damping {damping}: {p} vs {q}");
        }
    }
}

//! `rb_point` (the original's ball-joint chain): ten 1 kg, 0.1 m boxes, the first fixed, each
//! joined to the previous by a ball joint at alternating corners, folding down under gravity for
//! 151 steps of 1/30 s. Every joint stays within its 1 mm tolerance at every accepted step (the
//! penalty hardens as needed), the fixed box stays put, and with no damping but backward Euler's
//! the total energy never grows.

use stark::rigidbodies::RigidBodyHandle;
use stark::scenes::find_scene;
use stark::Settings;

#[test]
fn rb_point_chain_holds_its_joints() {
    let mut settings = Settings::default();
    settings.output.frames = false;
    settings.output.step_log = false;
    let mut sim = (find_scene("rb_point").unwrap().build)(settings).unwrap();
    let g = 9.81;
    let energy = |sim: &stark::Simulation| -> f64 {
        (0..sim.num_rigid_bodies())
            .map(|i| {
                let b = RigidBodyHandle { index: i as u32 };
                let v = sim.body_velocity(b);
                let w = sim.body_angular_velocity(b);
                let l = sim.body_angular_momentum(b);
                0.5 * v.norm_squared() + 0.5 * w.dot(&l) + g * sim.body_position(b).z
            })
            .sum()
    };
    let e0 = energy(&sim);
    let mut max_violation: f64 = 0.0;
    let mut e_prev = e0;
    while sim.time() < 151.0 / 30.0 - 1e-9 {
        sim.step().unwrap();
        for el in &sim.rigid_bodies.joints.potential.elements {
            if !el.primitive.is_angular() {
                max_violation = max_violation.max(el.readout.violation);
            }
        }
        let e = energy(&sim);
        // Backward Euler only dissipates; allow the penalty joints' stored energy (tiny).
        assert!(
            e <= e_prev + 1e-3,
            "energy grew from {e_prev} to {e} J at t = {}",
            sim.time()
        );
        e_prev = e;
    }
    let first = RigidBodyHandle { index: 0 };
    let last = RigidBodyHandle { index: 9 };
    println!(
        "rb_point: max ball-joint violation {max_violation:.2e} m, energy {e0:.3} → {e_prev:.3} J, last box at {:?}",
        sim.body_position(last)
    );
    assert!(max_violation < 1e-3, "a joint was violated by {max_violation} m");
    assert!(sim.body_position(first).norm() < 1e-3, "the fixed box moved");
    assert!(sim.body_position(last).z < -0.1, "the chain did not fold down");
}

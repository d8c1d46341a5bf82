//! Linear and angular velocity controllers push with their cap when held and run at
//! `target − δ·load/cap` when the load is below the cap; a body–body controller conserves the
//! pair's momentum.
//!
//! The controllers are Stark's smooth capped law (`add_constraint_linear_velocity`,
//! `add_constraint_angular_velocity`): with the velocity error `u`, the force is `−(F/δ)·u` for
//! `|u| < δ` and `−F·sign(u)` beyond (δ = 0.01 m/s or rad/s). No gravity, dt = 10 ms.
//!
//! - Held (Stark's `rb_constraints.cpp` cases, seeded): a cube fixed by a fix joint, a second cube
//!   joined to it by a ball joint (linear case) or an attachment (angular case), and a controller
//!   between them driving at 3.7 m/s along x (max 50 N) or 1.7 rad/s about x (max 10 N·m). The
//!   joint holds, so the controller saturates: its effort must be the cap and the holding joint's
//!   reaction minus the cap, within 0.1%. Measured: efforts exactly the cap, reactions within
//!   1.6e-8 (ball) and 5.6e-8 (attachment).
//! - Free (random axis): a cube driven at 2 m/s (max 20 N) against a 5 N drag-like load along the
//!   axis, or at 3 rad/s (max 0.5 N·m) against 0.1 N·m. Expected: `2 − 0.01·5/20` = 1.9975 m/s
//!   and `3 − 0.01·0.1/0.5` = 2.998 rad/s, efforts equal to the loads, and a force across the axis
//!   (or a torque about another axis) acting freely. Measured: to 1e-9.
//! - Body–body: two free cubes, an angular controller between them (3 rad/s, max 0.2 N·m). Their
//!   relative spin reaches the target while `J_a ω_a + J_b ω_b` stays zero. Measured: relative
//!   spin 3.000000 rad/s, momentum 1e-17 N·m·s.
//!
//! Runtime: ~0.05 s for the file.

use super::joint_rig::*;
use nalgebra::Vector3;
use stark::rigidbodies::joints::JointParams;

const DT: f64 = 0.01;
const DELAY: f64 = 0.01;

#[test]
fn linear_velocity_controller_pushes_with_its_cap_against_a_ball_joint() {
    let mut r = rng(41);
    let mut sim = simulation("linear velocity (held)", DT);
    let mass = uniform(&mut r, 1.0, 100.0);
    let base = cube(&mut sim, "base", mass, Vector3::zeros());
    sim.add_fix_joint("base fix", base, JointParams::default()).unwrap();
    let body = cube(&mut sim, "body", mass, Vector3::new(0.1, 0.0, 0.0));
    let p = Vector3::new(0.05, 0.0, 0.0);
    let ball = sim
        .add_ball_joint("ball", Some(base), body, p, JointParams::default())
        .unwrap();
    let f_max = 50.0;
    let ctrl = sim
        .add_linear_velocity_controller("controller", Some(base), body, p, Vector3::x(), 3.7, f_max, DELAY)
        .unwrap();
    run_steps(&mut sim, 100);
    let effort = sim.joint_state(&ctrl).driver_effort;
    let held = Vector3::from(sim.joint_state(&ball).force_on_b_n);
    let (e1, e2) = (
        (effort - f_max).abs() / f_max,
        (held + Vector3::x() * f_max).norm() / f_max,
    );
    eprintln!("linear velocity (held): effort {effort:.9} N ({e1:.1e}), ball reaction {held:?} ({e2:.1e})");
    assert!(e1 < 1e-3 && e2 < 1e-3);
}

#[test]
fn angular_velocity_controller_pushes_with_its_cap_against_an_attachment() {
    let mut r = rng(42);
    let mut sim = simulation("angular velocity (held)", DT);
    let mass = uniform(&mut r, 1.0, 100.0);
    let base = cube(&mut sim, "base", mass, Vector3::zeros());
    sim.add_fix_joint("base fix", base, JointParams::default()).unwrap();
    let body = cube(&mut sim, "body", mass, Vector3::new(0.1, 0.0, 0.0));
    let glue = sim
        .add_attachment_joint("attachment", base, body, JointParams::default())
        .unwrap();
    let t_max = 10.0;
    let ctrl = sim
        .add_angular_velocity_controller("controller", Some(base), body, Vector3::x(), 1.7, t_max, DELAY)
        .unwrap();
    run_steps(&mut sim, 100);
    let effort = sim.joint_state(&ctrl).driver_effort;
    let held = Vector3::from(sim.joint_state(&glue).torque_on_b_n_m);
    let (e1, e2) = (
        (effort - t_max).abs() / t_max,
        (held + Vector3::x() * t_max).norm() / t_max,
    );
    eprintln!("angular velocity (held): effort {effort:.9} N·m ({e1:.1e}), attachment reaction {held:?} ({e2:.1e})");
    assert!(e1 < 1e-3 && e2 < 1e-3);
}

#[test]
fn linear_velocity_controller_runs_at_target_minus_droop_and_leaves_the_rest_free() {
    let mut r = rng(43);
    let mut sim = simulation("linear velocity (free)", DT);
    let mass = uniform(&mut r, 1.0, 10.0);
    let body = cube(&mut sim, "body", mass, Vector3::zeros());
    let d = random_vector(&mut r, 1.0, 1.0 + 1e-9).normalize();
    let (target, f_max, load) = (2.0, 20.0, 5.0);
    let ctrl = sim
        .add_linear_velocity_controller("controller", None, body, Vector3::zeros(), d, target, f_max, DELAY)
        .unwrap();
    let across = random_vector(&mut r, 1.0, 3.0);
    let across = across - d * d.dot(&across);
    sim.set_body_force(body, -d * load + across * mass).unwrap();
    // (F − load)/m ≥ 1.5 m/s²: at speed within 1.4 s.
    run_steps(&mut sim, 200);
    let v = sim.body_velocity(body);
    let expected = target - DELAY * load / f_max;
    let effort = sim.joint_state(&ctrl).driver_effort;
    let free_err = (v - d * v.dot(&d) - across * sim.time()).norm() / (across.norm() * sim.time());
    eprintln!(
        "linear velocity (free): {:.9} m/s vs {expected:.9} m/s, effort {effort:.9} N vs load {load} N, across the axis {free_err:.1e} off free motion",
        v.dot(&d)
    );
    assert!((v.dot(&d) - expected).abs() < 1e-6);
    assert!((effort - load).abs() < 1e-3 * load);
    assert!(free_err < 1e-6);
}

#[test]
fn angular_velocity_controller_runs_at_target_minus_droop_and_leaves_the_rest_free() {
    let mut r = rng(44);
    let mut sim = simulation("angular velocity (free)", DT);
    let mass = uniform(&mut r, 1.0, 10.0);
    let j = cube_inertia(mass);
    let body = cube(&mut sim, "body", mass, Vector3::zeros());
    let d = random_vector(&mut r, 1.0, 1.0 + 1e-9).normalize();
    let (target, t_max, load) = (3.0, 0.5, 0.1);
    let ctrl = sim
        .add_angular_velocity_controller("controller", None, body, d, target, t_max, DELAY)
        .unwrap();
    // A force is free too (the controller acts on rotation only).
    let a = random_vector(&mut r, 1.0, 3.0);
    sim.set_body_force(body, a * mass).unwrap();
    sim.set_body_torque(body, -d * load).unwrap();
    run_steps(&mut sim, 100);
    let w = sim.body_angular_velocity(body);
    let expected = target - DELAY * load / t_max;
    let effort = sim.joint_state(&ctrl).driver_effort;
    let v_err = (sim.body_velocity(body) - a * sim.time()).norm() / (a.norm() * sim.time());
    eprintln!(
        "angular velocity (free): {:.9} rad/s vs {expected:.9} rad/s (off-axis {:.1e}), effort {effort:.9} N·m vs load {load} N·m, velocity {v_err:.1e} off free motion (J = {j:.4})",
        w.dot(&d),
        (w - d * w.dot(&d)).norm()
    );
    assert!((w.dot(&d) - expected).abs() < 1e-6);
    assert!((w - d * w.dot(&d)).norm() < 1e-9);
    assert!((effort - load).abs() < 1e-3 * load);
    assert!(v_err < 1e-6);
}

#[test]
fn angular_velocity_controller_between_bodies_conserves_their_momentum() {
    let mut r = rng(45);
    let mut sim = simulation("angular velocity (body-body)", DT);
    let (ma, mb) = (uniform(&mut r, 1.0, 10.0), uniform(&mut r, 1.0, 10.0));
    let a = cube(&mut sim, "a", ma, Vector3::zeros());
    let b = cube(&mut sim, "b", mb, Vector3::new(0.3, 0.0, 0.0));
    let d = random_vector(&mut r, 1.0, 1.0 + 1e-9).normalize();
    let target = 3.0;
    let ctrl = sim
        .add_angular_velocity_controller("controller", Some(a), b, d, target, 0.2, DELAY)
        .unwrap();
    run_steps(&mut sim, 100);
    let (wa, wb) = (sim.body_angular_velocity(a), sim.body_angular_velocity(b));
    let momentum = wa * cube_inertia(ma) + wb * cube_inertia(mb);
    let relative = (wb - wa).dot(&d);
    let s = sim.joint_state(&ctrl);
    eprintln!(
        "angular velocity (body-body): relative spin {relative:.9} rad/s, momentum {:.1e} N·m·s, effort {:.1e} N·m",
        momentum.norm(),
        s.driver_effort
    );
    assert!((relative - target).abs() < 1e-6);
    assert!(momentum.norm() < 1e-9);
}

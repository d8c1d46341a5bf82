//! A hinge servo reaches its target angle and holds it under a load below its max torque; a
//! prismatic servo reaches its target position; a hinge servo turns the shorter way to a target
//! beyond ±180°.
//!
//! A servo is a motor or press whose target speed is set each step to `error / response_time`
//! (a proportional controller on the velocity target, DESIGN's "position servos (PD targets)").
//! With the controller's capped law (torque `(T_max/δ)·(ω_t − ω)` below the cap) a steady load `L`
//! is held at rest when `ω_t = L·δ/T_max`, i.e. at the offset `e = L·δ·response_time/T_max` short
//! of the target; that offset is the analytic answer checked here (the load sags the joint by
//! exactly that much, no more).
//!
//! Setup: gravity 9.81 m/s², dt = 10 ms, δ = 0.01 (default), response time 0.1 s, joints at
//! Stark's defaults (1e6 N/m, 1 mm, 1°).
//!
//! - Arm: a 2 kg ball on a massless 0.5 m lever, hinge servo at the pivot (horizontal axis),
//!   `T_max = 2·m·g·r` = 19.62 N·m, from horizontal to 30°. Expected: rests at
//!   `30° − e`, `e = m·g·r·cos 30°·δ·0.1 s/T_max` = 0.0248°, effort `m·g·r·cos θ` = 8.4978 N·m, and
//!   stays there. Measured: within 0.1° after 0.67 s (no overshoot), rests at 29.975184° against
//!   29.975190°, effort within 1e-7 relative, drift below 1e-4° over the last second.
//! - Block: 3 kg on a vertical prismatic servo, `F_max = 2·m·g`, target +0.1 m. Expected: rests at
//!   `0.1 m − m·g·δ·0.1 s/F_max` = 0.0995 m with effort `m·g`. Measured: 0.0995000 m.
//! - Turntable (no load, vertical axis), target 200°: the hinge angle is reported in
//!   (−180°, 180°], so the servo must take the target modulo 360° and turn the shorter way, to
//!   −160°. Before the fix it drove towards +200°, passed 180° where the angle jumps to −180°, and
//!   kept spinning for ever (the error never closed: 380°, 360°, …).
//!
//! Runtime: ~0.1 s for the file.

use super::joint_rig::*;
use nalgebra::{UnitQuaternion, Vector3};
use stark::rigidbodies::joints::JointParams;
use stark::rigidbodies::MassProperties;
use stark::Simulation;

const G: f64 = 9.81;
const DT: f64 = 0.01;
const DELAY: f64 = 0.01;
const RESPONSE_S: f64 = 0.1;

fn with_gravity(name: &str) -> Simulation {
    let mut s = settings(name, DT);
    s.gravity_m_s2 = [0.0, 0.0, -G];
    Simulation::new(s).unwrap()
}

#[test]
fn hinge_servo_reaches_its_angle_and_holds_the_arm() {
    let (mass, r) = (2.0, 0.5);
    let mgr = mass * G * r;
    let t_max = 2.0 * mgr;
    let target_deg: f64 = 30.0;
    let mut sim = with_gravity("hinge servo");
    let props = MassProperties::sphere(mass, 0.05);
    let arm = sim
        .add_rigid_body_with("arm", &props, Vector3::new(r, 0.0, 0.0), UnitQuaternion::identity())
        .unwrap();
    // Axis −y: positive angles lift the arm from +x towards +z.
    let servo = sim
        .add_hinge_servo(
            "servo",
            None,
            arm,
            Vector3::zeros(),
            -Vector3::y(),
            target_deg,
            t_max,
            RESPONSE_S,
            JointParams::default(),
        )
        .unwrap();
    let angle = |sim: &Simulation| sim.joint_state(&servo).coordinate.unwrap().to_degrees();
    let mut reached = None;
    let mut overshoot = f64::NEG_INFINITY;
    while sim.time() < 1.5 {
        sim.step().unwrap();
        let a = angle(&sim);
        overshoot = overshoot.max(a - target_deg);
        if reached.is_none() && (a - target_deg).abs() < 0.1 {
            reached = Some(sim.time());
        }
    }
    let settled = angle(&sim);
    run_steps(&mut sim, 100);
    let s = sim.joint_state(&servo);
    let rest = angle(&sim);
    let offset = mgr * target_deg.to_radians().cos() * DELAY * RESPONSE_S / t_max;
    let expected = target_deg - offset.to_degrees();
    let load = mgr * rest.to_radians().cos();
    eprintln!(
        "hinge servo: within 0.1° after {:.2} s, overshoot {overshoot:.4}°, rests at {rest:.6}° vs 30° − e = {expected:.6}° (drift over the last second {:.1e}°); effort {:.6} vs m·g·r·cos θ {load:.6} N·m",
        reached.unwrap_or(f64::NAN),
        rest - settled,
        s.driver_effort
    );
    assert!(reached.is_some_and(|t| t < 1.0), "did not reach the target");
    assert!(overshoot < 0.1, "overshoot {overshoot}°");
    assert!((rest - expected).abs() < 1e-3, "rest {rest}° vs {expected}°");
    assert!((rest - settled).abs() < 1e-4, "does not hold");
    assert!((s.driver_effort - load).abs() < 1e-3 * load);
}

#[test]
fn prismatic_servo_reaches_its_position() {
    let m = 3.0;
    let f_max = 2.0 * m * G;
    let target = 0.1;
    let mut sim = with_gravity("prismatic servo");
    let block = cube(&mut sim, "block", m, Vector3::zeros());
    let servo = sim
        .add_prismatic_servo(
            "servo",
            None,
            block,
            Vector3::zeros(),
            Vector3::z(),
            target,
            f_max,
            RESPONSE_S,
            JointParams::default(),
        )
        .unwrap();
    run_steps(&mut sim, 150);
    let s = sim.joint_state(&servo);
    let pos = s.coordinate.unwrap();
    let expected = target - m * G * DELAY * RESPONSE_S / f_max;
    eprintln!(
        "prismatic servo: rests at {pos:.7} m vs target − e = {expected:.7} m; effort {:.5} N vs m·g {:.5} N",
        s.driver_effort,
        m * G
    );
    assert!((pos - expected).abs() < 1e-6);
    assert!((s.driver_effort - m * G).abs() < 1e-3 * m * G);
}

#[test]
fn hinge_servo_turns_the_short_way_to_a_target_beyond_180_degrees() {
    let mut sim = simulation("turntable", DT);
    let table = cube(&mut sim, "table", 1.0, Vector3::zeros());
    let servo = sim
        .add_hinge_servo(
            "servo",
            None,
            table,
            Vector3::zeros(),
            Vector3::z(),
            200.0,
            1.0,
            RESPONSE_S,
            JointParams::default(),
        )
        .unwrap();
    let mut most_positive = f64::NEG_INFINITY;
    while sim.time() < 2.0 {
        sim.step().unwrap();
        most_positive = most_positive.max(sim.joint_state(&servo).coordinate.unwrap());
    }
    let s = sim.joint_state(&servo);
    let angle = s.coordinate.unwrap().to_degrees();
    eprintln!(
        "turntable servo: target 200°, rests at {angle:.5}° (rate {:.1e} rad/s), never above {:.2}°",
        s.coordinate_rate.unwrap(),
        most_positive.to_degrees()
    );
    assert!((angle + 160.0).abs() < 1e-3, "rests at {angle}°, want −160°");
    assert!(most_positive <= 1e-6, "went the long way round");
}

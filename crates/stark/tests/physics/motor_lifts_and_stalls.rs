//! A motor lifts a load below its max torque at its target speed and stalls at its max torque
//! against a larger one; a prismatic press does the same with forces, and two presses squeeze an
//! object with their max force (what `simple_grasp` relies on: fingers pushing with 5 N each).
//!
//! The driver is Stark's capped velocity controller: with the speed error `u = ω − ω_t`, its
//! torque is `−(T_max/δ)·u` for `|u| < δ` (δ = 0.01 rad/s or m/s, the default) and `∓T_max`
//! beyond. So below the cap a load `T` is carried at the speed `ω_t − δ·T/T_max` (0.5% slow at
//! half the cap), and a load above the cap drives the joint backwards while the driver pushes
//! with exactly `T_max`.
//!
//! Setup: gravity 9.81 m/s², dt = 10 ms, direct solves, Newton to 1e-6 N, joints at Stark's
//! defaults (1e6 N/m, 1 mm, 1°).
//!
//! - Winch arm: a 2 kg ball (radius 5 cm) on a massless 0.5 m lever, motor at the pivot with a
//!   horizontal axis, target 1 rad/s. Lift: `T_max = 2·m·g·r` (19.62 N·m), the arm starts 30°
//!   below horizontal and is lifted to 60° above. Expected: the speed
//!   `ω_t − δ·m·g·r·cos θ/T_max` ∈ [0.995, 0.9975] rad/s (within 1% of the target) and the
//!   effort `m·g·r·cos θ`. Measured: speed within 0.50% of the target and within 3.5e-6 rad/s of
//!   that law; effort within 3.5e-4·T_max of the static load (the step's chord-vs-arc error,
//!   `O(m r² ω² dt)`).
//!   Stall: `T_max = m·g·r/1.5` (6.54 N·m) from horizontal: the arm falls back with
//!   `α = (T_max − m·g·r)/J_pivot` = −6.514 rad/s² (measured over steps 2–5: −9.5e-5 relative;
//!   the first step is slower while the stiff pivot takes up the load) and, with drag switched on
//!   to settle it, hangs at `θ* = −acos(T_max/(m·g·r))` = −48.190° (measured −48.195° after 4 s);
//!   the effort is `T_max` at every step (exactly, to rounding).
//! - Vertical press: a 3 kg block on a prismatic press along +z, target 1 m/s. Lift with
//!   `F_max = 2·m·g`: speed `v_t − δ·m·g/F_max` = 0.995 m/s and effort `m·g`. Stall with
//!   `F_max = m·g/1.5`: it sinks with `a = F_max/m − g` = −3.27 m/s², effort `F_max`. Measured:
//!   speed 0.995000 m/s, effort error 2e-9; −3.270000 m/s², effort exactly `F_max`.
//! - Grasp: two 0.2 kg fingers on presses closing at 0.1 m/s with at most 5 N on a free 0.5 kg
//!   object (no gravity); a distance limit between each finger and the object stands in for
//!   contact (fingers stop 5 cm from its centre). Expected: the fingers stall against the object,
//!   each press pushes with 5 N, the object feels 5 N from each side and stays put. Measured:
//!   efforts 5 N exactly, 5 N on the object to 6e-10, net force 1e-11 N, fingers at 8e-11 m/s.
//!
//! Runtime: ~0.2 s for the file.

use super::joint_rig::*;
use nalgebra::{UnitQuaternion, Vector3};
use stark::rigidbodies::joints::{JointHandle, JointParams, Primitive};
use stark::rigidbodies::{MassProperties, RigidBodyHandle, RigidBodyParams};
use stark::Simulation;

const G: f64 = 9.81;
const DT: f64 = 0.01;
/// The controllers' delay δ (default), rad/s or m/s.
const DELAY: f64 = 0.01;
/// Mass of the arm's ball, kg.
const ARM_KG: f64 = 2.0;
/// Lever of the arm, m.
const LEVER_M: f64 = 0.5;
/// Gravity's torque on the horizontal arm, m·g·r, N·m.
const MGR: f64 = ARM_KG * G * LEVER_M;

fn with_gravity(name: &str) -> Simulation {
    let mut s = settings(name, DT);
    s.gravity_m_s2 = [0.0, 0.0, -G];
    Simulation::new(s).unwrap()
}

struct Arm {
    sim: Simulation,
    arm: RigidBodyHandle,
    motor: JointHandle,
    /// Moment of inertia about the pivot, kg·m².
    inertia: f64,
}

/// A 2 kg ball on a massless 0.5 m lever from a motor at the origin with axis −y (positive
/// angles lift the arm from +x towards +z), `angle_deg` above horizontal at the start.
fn arm(name: &str, angle_deg: f64, target_rad_s: f64, max_torque_n_m: f64) -> Arm {
    let (mass, r) = (ARM_KG, LEVER_M);
    let mut sim = with_gravity(name);
    let props = MassProperties::sphere(mass, 0.05);
    let a = angle_deg.to_radians();
    let arm = sim
        .add_rigid_body_with(
            "arm",
            &props,
            Vector3::new(r * a.cos(), 0.0, r * a.sin()),
            UnitQuaternion::identity(),
        )
        .unwrap();
    let motor = sim
        .add_motor(
            "motor",
            None,
            arm,
            Vector3::zeros(),
            -Vector3::y(),
            target_rad_s,
            max_torque_n_m,
            DELAY,
            JointParams::default(),
        )
        .unwrap();
    Arm {
        sim,
        arm,
        motor,
        inertia: props.inertia_kg_m2[(1, 1)] + mass * r * r,
    }
}

/// Elevation of the arm above horizontal, rad.
fn elevation(a: &Arm) -> f64 {
    let p = a.sim.body_position(a.arm);
    p.z.atan2(p.x)
}

#[test]
fn motor_lifts_a_load_below_its_max_torque_at_the_target_speed() {
    let target = 1.0;
    let mgr = MGR;
    let t_max = 2.0 * mgr;
    let mut a = arm("motor lift", -30.0, target, t_max);
    let (mut worst_speed, mut worst_law, mut worst_effort) = (0.0f64, 0.0f64, 0.0f64);
    let mut steps = 0;
    while elevation(&a) < 60f64.to_radians() {
        a.sim.step().unwrap();
        steps += 1;
        if a.sim.time() < 0.1 {
            continue; // spinning up: ~0.05 s at (T_max − m·g·r)/J ≥ 20 rad/s²
        }
        let s = a.sim.joint_state(&a.motor);
        let load = mgr * elevation(&a).cos();
        let rate = s.coordinate_rate.unwrap();
        worst_speed = worst_speed.max((rate - target).abs() / target);
        worst_law = worst_law.max((rate - (target - DELAY * load / t_max)).abs());
        worst_effort = worst_effort.max((s.driver_effort - load).abs() / t_max);
        assert!(s.violation_m < 1e-3 && s.violation_rad < 1f64.to_radians());
    }
    eprintln!(
        "motor lift: {steps} steps (−30° → 60°); speed within {:.3}% of the target, within {worst_law:.1e} rad/s of ω_t − δ·T/T_max; effort − m·g·r·cos θ within {worst_effort:.1e}·T_max",
        100.0 * worst_speed
    );
    assert!(worst_speed < 0.01, "speed {:.3}% off the target", 100.0 * worst_speed);
    assert!(
        worst_law < 1e-4 * target,
        "speed off the capped law by {worst_law:.2e} rad/s"
    );
    assert!(worst_effort < 1e-3, "effort off the load by {worst_effort:.2e}·T_max");
}

#[test]
fn motor_stalls_at_its_max_torque_and_the_arm_falls_back_to_equilibrium() {
    let mgr = MGR;
    let t_max = mgr / 1.5;
    let mut a = arm("motor stall", 0.0, 1.0, t_max);
    let mut rates = Vec::new();
    let mut worst_effort = 0.0f64;
    for _ in 0..5 {
        a.sim.step().unwrap();
        let s = a.sim.joint_state(&a.motor);
        rates.push(s.coordinate_rate.unwrap());
        worst_effort = worst_effort.max((s.driver_effort - t_max).abs() / t_max);
    }
    // Backwards, as the net torque says (the angle stays within 0.6° of horizontal here).
    let alpha = (rates[4] - rates[1]) / (3.0 * DT);
    let exact = (t_max - mgr) / a.inertia;
    // Drag settles the fall (it acts on the velocity only, so the rest pose is unchanged).
    a.sim
        .set_body_params(
            a.arm,
            RigidBodyParams {
                linear_damping_1_s: 5.0,
                angular_damping_1_s: 0.0,
            },
        )
        .unwrap();
    while a.sim.time() < 4.0 {
        a.sim.step().unwrap();
        let s = a.sim.joint_state(&a.motor);
        worst_effort = worst_effort.max((s.driver_effort - t_max).abs() / t_max);
    }
    let rest = elevation(&a).to_degrees();
    let rest_exact = -(t_max / mgr).acos().to_degrees();
    let s = a.sim.joint_state(&a.motor);
    eprintln!(
        "motor stall: α {alpha:.4} rad/s² vs {exact:.4} ({:+.2e}); rests at {rest:.4}° vs {rest_exact:.4}° (rate {:.1e} rad/s); effort = T_max within {worst_effort:.1e}",
        alpha / exact - 1.0,
        s.coordinate_rate.unwrap()
    );
    assert!((alpha / exact - 1.0).abs() < 1e-3);
    assert!((rest - rest_exact).abs() < 0.01, "rest angle {rest}° vs {rest_exact}°");
    assert!(worst_effort < 1e-3, "effort off T_max by {worst_effort:.2e}");
}

/// A 3 kg block on a vertical prismatic press to the world (axis +z).
fn press(name: &str, target_m_s: f64, max_force_n: f64) -> (Simulation, RigidBodyHandle, JointHandle) {
    let mut sim = with_gravity(name);
    let block = cube(&mut sim, "block", 3.0, Vector3::zeros());
    let press = sim
        .add_prismatic_press(
            "press",
            None,
            block,
            Vector3::zeros(),
            Vector3::z(),
            target_m_s,
            max_force_n,
            DELAY,
            JointParams::default(),
        )
        .unwrap();
    (sim, block, press)
}

#[test]
fn press_lifts_a_load_below_its_max_force_at_the_target_speed() {
    let (m, target) = (3.0, 1.0);
    let f_max = 2.0 * m * G;
    let (mut sim, _block, press) = press("press lift", target, f_max);
    run_steps(&mut sim, 50);
    let s = sim.joint_state(&press);
    let rate = s.coordinate_rate.unwrap();
    let expected = target - DELAY * m * G / f_max;
    let effort_err = (s.driver_effort - m * G).abs() / (m * G);
    eprintln!(
        "press lift: {rate:.6} m/s vs ω_t − δ·m·g/F_max = {expected:.6} m/s ({:.2}% below the target); effort {:.4} N vs m·g {:.4} N ({effort_err:.1e})",
        100.0 * (1.0 - rate / target),
        s.driver_effort,
        m * G
    );
    assert!((rate - target).abs() < 0.01 * target);
    assert!((rate - expected).abs() < 1e-6);
    assert!(effort_err < 1e-3);
}

#[test]
fn press_stalls_at_its_max_force_and_sinks() {
    let m = 3.0;
    let f_max = m * G / 1.5;
    let (mut sim, block, press) = press("press stall", 0.5, f_max);
    run_steps(&mut sim, 30);
    let a = sim.body_velocity(block).z / sim.time();
    let exact = f_max / m - G;
    let s = sim.joint_state(&press);
    let effort_err = (s.driver_effort - f_max).abs() / f_max;
    eprintln!(
        "press stall: sinks at {a:.6} m/s² vs F_max/m − g = {exact:.6}; effort {:.6} N vs F_max {f_max:.6} N ({effort_err:.1e})",
        s.driver_effort
    );
    assert!((a / exact - 1.0).abs() < 1e-3);
    assert!(effort_err < 1e-3);
}

#[test]
fn two_presses_squeeze_an_object_with_their_max_force() {
    let mut sim = simulation("grasp", DT);
    let object = cube(&mut sim, "object", 0.5, Vector3::zeros());
    let f_max = 5.0;
    let mut fingers = Vec::new();
    for (label, side) in [("left", -1.0), ("right", 1.0)] {
        let at = Vector3::new(0.06 * side, 0.0, 0.0);
        let finger = cube(&mut sim, label, 0.2, at);
        // Closing towards the object: along −side·x.
        let press = sim
            .add_prismatic_press(
                label,
                None,
                finger,
                at,
                Vector3::new(-side, 0.0, 0.0),
                0.1,
                f_max,
                DELAY,
                JointParams::default(),
            )
            .unwrap();
        // Contact stand-in: the finger stays at least 5 cm from the object's centre.
        let stop = sim
            .add_distance_limits(
                &format!("{label} stop"),
                Some(object),
                finger,
                Vector3::zeros(),
                at,
                0.05,
                1.0,
                JointParams::default(),
            )
            .unwrap();
        fingers.push((finger, press, stop));
    }
    run_steps(&mut sim, 60);
    let mut on_object = Vector3::zeros();
    for (finger, press, stop) in &fingers {
        let s = sim.joint_state(press);
        let push = sim.joint_primitive_readouts(stop);
        let (Primitive::DistanceLimits { .. }, r) = &push[0] else {
            panic!("stop is a distance limit")
        };
        on_object += Vector3::from(r.force_a_n);
        let effort_err = (s.driver_effort - f_max).abs() / f_max;
        let stop_err = (Vector3::from(r.force_a_n).norm() - f_max).abs() / f_max;
        eprintln!(
            "grasp finger: effort {:.6} N (max {f_max} N, {effort_err:.1e}), on the object {:.6} N ({stop_err:.1e}), finger speed {:.1e} m/s",
            s.driver_effort,
            Vector3::from(r.force_a_n).norm(),
            sim.body_velocity(*finger).norm()
        );
        assert!(effort_err < 1e-3 && stop_err < 1e-3);
        assert!(
            sim.body_velocity(*finger).norm() < 1e-6,
            "the finger should have stalled"
        );
    }
    eprintln!(
        "grasp: net force on the object {:.1e} N, object moved {:.1e} m",
        on_object.norm(),
        sim.body_position(object).norm()
    );
    assert!(on_object.norm() < 1e-6 && sim.body_position(object).norm() < 1e-6);
}

/// A 1 kg ball (radius 0.1 m, J = 0.004 kg·m²) on a motor about z through its centre, no gravity,
/// target 2 rad/s, cap 0.02 N·m (5 rad/s² on J), spinning at `w0` rad/s at the start.
fn flywheel(name: &str, w0: f64, drive_only: bool) -> (Simulation, JointHandle) {
    let mut s = settings(name, DT);
    s.gravity_m_s2 = [0.0; 3];
    let mut sim = Simulation::new(s).unwrap();
    let props = MassProperties::sphere(1.0, 0.1);
    let ball = sim
        .add_rigid_body_with("ball", &props, Vector3::zeros(), UnitQuaternion::identity())
        .unwrap();
    sim.set_body_angular_velocity(ball, Vector3::new(0.0, 0.0, w0)).unwrap();
    let motor = sim
        .add_motor(
            "motor",
            None,
            ball,
            Vector3::zeros(),
            Vector3::z(),
            2.0,
            0.02,
            DELAY,
            JointParams::default(),
        )
        .unwrap();
    sim.set_motor_drive_only(&motor, drive_only).unwrap();
    (sim, motor)
}

#[test]
fn a_drive_only_motor_drives_like_a_motor_and_never_brakes() {
    let alpha = 0.02 / 0.004;
    // From rest both accelerate at the cap, 5 rad/s², to the target.
    for drive_only in [false, true] {
        let (mut sim, motor) = flywheel("drive from rest", 0.0, drive_only);
        sim.run(0.2).unwrap();
        let s = sim.joint_state(&motor);
        let rate = s.coordinate_rate.unwrap();
        assert!((rate - alpha * 0.2).abs() < 1e-6, "drive_only {drive_only}: {rate}");
        assert!((s.driver_effort - 0.02).abs() < 1e-9, "{}", s.driver_effort);
        sim.run(1.0).unwrap();
        let rate = sim.joint_state(&motor).coordinate_rate.unwrap();
        assert!((rate - 2.0).abs() < DELAY, "drive_only {drive_only}: {rate}");
    }
    // Spinning at 5 rad/s, above the target: the motor brakes at the cap; the drive-only motor
    // lets it coast (no friction anywhere: the rate stays 5 rad/s and the torque zero).
    let (mut braked, m) = flywheel("braked", 5.0, false);
    braked.run(0.2).unwrap();
    let rate = braked.joint_state(&m).coordinate_rate.unwrap();
    assert!((rate - (5.0 - alpha * 0.2)).abs() < 1e-6, "{rate}");
    let (mut coasting, m) = flywheel("coasting", 5.0, true);
    coasting.run(0.5).unwrap();
    let s = coasting.joint_state(&m);
    assert!(
        (s.coordinate_rate.unwrap() - 5.0).abs() < 1e-9,
        "{:?}",
        s.coordinate_rate
    );
    assert!(s.driver_effort.abs() < 1e-12, "{}", s.driver_effort);
    assert!(flywheel("no motor", 0.0, true)
        .0
        .set_motor_drive_only(
            &JointHandle {
                label: "x".into(),
                elements: vec![],
                driver: None,
                measure: None,
            },
            true
        )
        .is_err());
}

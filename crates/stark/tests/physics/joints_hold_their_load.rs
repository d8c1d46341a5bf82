//! Every joint holds a known load within its tolerance, reports minus that load as its reaction
//! on the body (within 0.1%), and leaves its free DOFs free.
//!
//! Setup (Stark's `tests/rb_constraints.cpp`, with fixed seeds and more joints): a 0.1 m cube of
//! random mass (1–10 kg) at rest, no gravity, dt = 10 ms, direct solves, Newton to 1e-6 N. Joint
//! axes and loads are random (seeded per test). Hard joints start soft (1e4 N/m, 100× below
//! Stark's default) with tolerances of 1 mm and 0.1°, so every test exercises hardening.
//!
//! 1. Free phase (0.3 s): only loads along the joint's free DOFs act, as accelerations
//!    `a` (1–5 m/s²) and `α` (5–20 rad/s²). Backward Euler reproduces constant accelerations
//!    exactly, so the body must reach `v = a·t` and `ω = α·t` to 1e-6 (a joint that resisted
//!    its free DOFs would show here).
//! 2. Held phase (0.5 s): a force (10–110 N) and/or torque (10–110 N·m) that the joint must hold
//!    is added. At the end the joint must be within its tolerances and its force and torque on
//!    the body (`joint_state`) must be minus the held load within 0.1% (torque errors relative to
//!    `max(‖τ‖, ‖F‖·0.1 m)`). The free motion continues meanwhile.
//!
//! Limited joints (cone, angle limit, hinge limit, distance limits, spring with limits) move
//! freely in a shorter phase 1 (0.1 s, inside the limit), then the held load (replacing the free
//! one) drives them into the limit: the limit bites there (violation = penetration past the
//! limit, within tolerance) and holds the whole load. Body–body joints (the other body fixed by a
//! fix joint, whose own reaction is checked too), enabling and disabling at run time, the
//! kinematic driving of a fix joint and the spring's and damper's forces have their own checks.
//!
//! Measured (printed with `--nocapture`, runtime 0.4 s for the file):
//! - free motion exact to ~1e-14 (all joints);
//! - reaction errors: force ≤ 1.7e-4 (the re-enabled hinge, still settling), torque ≤ 2.8e-4
//!   (the base's fix joint behind an attachment, whose load includes the moment of the force
//!   about the base), most below 1e-8;
//! - violations 1.1e-4…6.9e-4 m and 0.02…0.084° against 1 mm / 0.1°; stiffness after hardening
//!   4e4–6.4e5 N/m (2–6 doublings from 1e4) for point, distance and direction constraints, and
//!   2.0e7–8.2e7 for the cubic angle limits (cone, angle limit, hinge limit), whose force `k·δ²`
//!   needs `k ≥ τ/δ²` to keep the penetration δ below 0.1°;
//! - the spring stretches by `F/k` to 4e-7 relative; while moving, its force is
//!   `−k(l − L) − c(l − l₀)/dt` to 1e-12; at its limit the spring keeps `k(max − L)` and the limit
//!   takes the rest.
//!
//! Torque readouts are generalised torques (see `JointReadout`): reporting the moment of the joint
//! forces at the end-of-step pose instead was off by 8% for a hinge spinning at 16 rad/s under a
//! 57 N·m cross torque (rotated by half the step rotation `ω·dt`).
//!
//! Known weakness (not asserted beyond what is stable): the step maps end-of-step angular
//! velocities to rotations non-linearly, so a joint's torque enters the momentum balance rotated
//! by about half the step rotation. While a joint transmits a torque `τ` and the body turns about a
//! free axis, this leaks `~τ·ω·dt/2` into the other free axis. For a hinge the leak stays along
//! the spin axis (the spin gains `O(dt·θ)`: 3% at 16 rad/s with θ = 1.4e-3 rad, dt = 10 ms). For a
//! universal joint holding a twist it closes a loop (pivot about a → twist load drives b → leak
//! back into a) whose physical counterpart is neutral, and the held equilibrium diverges from
//! round-off at a rate of about `(dt·τ²/2J²)^(1/3)`: measured 107/s at dt = 10 ms and 53/s at 3 ms
//! for a 3.4 kg cube holding 52 N·m (predicted 75/s and 50/s), stable at 1 ms. The twist test
//! therefore runs at dt = 1 ms; at 10 ms the twist lets go after ~0.3 s.

use super::joint_rig::*;
use nalgebra::{UnitQuaternion, Vector3};
use rand::rngs::StdRng;
use rand::Rng;
use stark::rigidbodies::joints::{JointHandle, JointParams, Primitive};
use stark::rigidbodies::{RigidBodyHandle, RigidBodyParams};
use stark::Simulation;

const DT: f64 = 0.01;
const FREE_STEPS: usize = 30;
const HELD_STEPS: usize = 50;

/// A random unit vector.
fn unit(r: &mut StdRng) -> Vector3<f64> {
    random_vector(r, 1.0, 1.0 + 1e-9).normalize()
}

/// A vector of magnitude in `[lo, hi)` perpendicular to the unit `d`.
fn perpendicular(r: &mut StdRng, d: &Vector3<f64>, lo: f64, hi: f64) -> Vector3<f64> {
    loop {
        let v = random_vector(r, 1.0, 2.0);
        let p = v - d * d.dot(&v);
        if p.norm() > 0.3 {
            return p.normalize() * uniform(r, lo, hi);
        }
    }
}

/// The loads of one test.
#[derive(Default)]
struct Loads {
    /// Free linear acceleration, m/s².
    a: Vector3<f64>,
    /// Free angular acceleration, rad/s².
    alpha: Vector3<f64>,
    /// Held force, N.
    force: Vector3<f64>,
    /// Held torque about the centre of mass, N·m.
    torque: Vector3<f64>,
    /// Drop the free loads in the held phase (limited joints: the whole load goes to the limit).
    only_held: bool,
    /// Steps of the free phase (default [`FREE_STEPS`]; fewer for limited joints, which must not
    /// reach their limit in it).
    free_steps: Option<usize>,
    /// Steps of the held phase (default [`HELD_STEPS`]).
    held_steps: Option<usize>,
}

struct Rig {
    sim: Simulation,
    body: RigidBodyHandle,
    mass: f64,
    centre: Vector3<f64>,
    params: JointParams,
}

fn rig(name: &str, r: &mut StdRng) -> Rig {
    rig_with_dt(name, r, DT)
}

fn rig_with_dt(name: &str, r: &mut StdRng, dt: f64) -> Rig {
    let mut sim = simulation(name, dt);
    let mass = uniform(r, 1.0, 10.0);
    let centre = Vector3::new(0.3, -0.2, 0.5);
    let body = cube(&mut sim, "body", mass, centre);
    Rig {
        sim,
        body,
        mass,
        centre,
        params: soft_params(),
    }
}

/// Run the free and the held phase and check both; returns the joint's final state.
fn free_then_held(rig: &mut Rig, joint: &JointHandle, loads: &Loads) -> Held {
    let (m, j) = (rig.mass, cube_inertia(rig.mass));
    let sim = &mut rig.sim;
    sim.set_body_force(rig.body, loads.a * m).unwrap();
    sim.set_body_torque(rig.body, loads.alpha * j).unwrap();
    run_steps(sim, loads.free_steps.unwrap_or(FREE_STEPS));
    let t = sim.time();
    let rel = |got: Vector3<f64>, want: Vector3<f64>| (got - want).norm() / want.norm().max(1.0);
    let v_err = rel(sim.body_velocity(rig.body), loads.a * t);
    let w_err = rel(sim.body_angular_velocity(rig.body), loads.alpha * t);
    assert!(
        v_err < 1e-6 && w_err < 1e-6,
        "{}: free motion hindered: velocity error {v_err:.2e}, angular velocity error {w_err:.2e}",
        joint.label
    );
    let keep = if loads.only_held { 0.0 } else { 1.0 };
    sim.set_body_force(rig.body, loads.a * m * keep + loads.force).unwrap();
    sim.set_body_torque(rig.body, loads.alpha * j * keep + loads.torque)
        .unwrap();
    run_steps(sim, loads.held_steps.unwrap_or(HELD_STEPS));
    let h = assert_holds(sim, joint, &rig.params, loads.force, loads.torque);
    report(&joint.label, &h);
    eprintln!("{:<28} free motion errors: v {v_err:.1e}, ω {w_err:.1e}", "",);
    h
}

#[test]
fn ball_joint_holds_a_force_and_lets_the_body_turn() {
    let mut r = rng(11);
    let mut rig = rig("ball", &mut r);
    let j = rig
        .sim
        .add_ball_joint("ball", None, rig.body, rig.centre, rig.params)
        .unwrap();
    let loads = Loads {
        alpha: random_vector(&mut r, 5.0, 20.0),
        force: random_vector(&mut r, 10.0, 110.0),
        ..Default::default()
    };
    free_then_held(&mut rig, &j, &loads);
}

#[test]
fn ball_joint_with_cone_limit_bites_at_the_limit() {
    let mut r = rng(12);
    let mut rig = rig("cone", &mut r);
    let d = unit(&mut r);
    let limit_deg = uniform(&mut r, 15.0, 45.0);
    let j = rig
        .sim
        .add_ball_joint_with_cone_limit("cone", None, rig.body, rig.centre, d, limit_deg, rig.params)
        .unwrap();
    // The held torque turns the body the same way as the free one, so it stays in one plane and
    // meets the cone where the limit's torque is opposite to the load.
    let alpha = perpendicular(&mut r, &d, 5.0, 20.0);
    let loads = Loads {
        alpha,
        force: random_vector(&mut r, 10.0, 110.0),
        torque: alpha.normalize() * uniform(&mut r, 10.0, 110.0),
        only_held: true,
        free_steps: Some(10),
        ..Default::default()
    };
    free_then_held(&mut rig, &j, &loads);
    let tilt = rig.sim.body_direction_to_world(rig.body, &d).angle(&d).to_degrees();
    eprintln!("{:<28} tilt {tilt:.4}° against the limit {limit_deg:.4}°", "");
    assert!(tilt > limit_deg && tilt < limit_deg + rig.params.tolerance_deg);
}

#[test]
fn point_on_axis_joint_holds_across_and_slides_along() {
    let mut r = rng(13);
    let mut rig = rig("point on axis", &mut r);
    let d = unit(&mut r);
    let j = rig
        .sim
        .add_point_on_axis_joint("point on axis", None, rig.body, rig.centre, d, rig.params)
        .unwrap();
    let loads = Loads {
        a: d * uniform(&mut r, 1.0, 5.0),
        alpha: random_vector(&mut r, 5.0, 20.0),
        force: perpendicular(&mut r, &d, 10.0, 110.0),
        ..Default::default()
    };
    free_then_held(&mut rig, &j, &loads);
    let s = rig.sim.joint_state(&j);
    let along = (rig.sim.body_position(rig.body) - rig.centre).dot(&d);
    assert!((s.coordinate.unwrap() - along).abs() < 1e-3, "slide coordinate");
}

#[test]
fn distance_joint_holds_along_the_line_and_lets_the_body_turn() {
    let mut r = rng(14);
    let mut rig = rig("distance", &mut r);
    let u = unit(&mut r);
    let anchor = rig.centre - u * uniform(&mut r, 0.3, 1.0);
    let j = rig
        .sim
        .add_distance_joint("distance", None, rig.body, anchor, rig.centre, rig.params)
        .unwrap();
    let loads = Loads {
        alpha: random_vector(&mut r, 5.0, 20.0),
        force: u * uniform(&mut r, 10.0, 110.0) * if r.random_bool(0.5) { 1.0 } else { -1.0 },
        ..Default::default()
    };
    free_then_held(&mut rig, &j, &loads);
}

#[test]
fn distance_limits_are_free_inside_and_hold_at_either_limit() {
    let mut r = rng(15);
    let mut rig = rig("distance limits", &mut r);
    let u = unit(&mut r);
    let l = uniform(&mut r, 0.3, 1.0);
    let anchor = rig.centre - u * l;
    let (min, max) = (l - 0.02, l + 0.02);
    let j = rig
        .sim
        .add_distance_limits(
            "distance limits",
            None,
            rig.body,
            anchor,
            rig.centre,
            min,
            max,
            rig.params,
        )
        .unwrap();
    // Outward: free for ½at² = 0.5a cm < 2 cm, then held at max.
    let loads = Loads {
        a: u * uniform(&mut r, 1.0, 3.0),
        force: u * uniform(&mut r, 10.0, 110.0),
        only_held: true,
        free_steps: Some(10),
        ..Default::default()
    };
    free_then_held(&mut rig, &j, &loads);
    let dist = (rig.sim.body_position(rig.body) - anchor).norm();
    assert!(
        dist > max && dist < max + rig.params.tolerance_m,
        "at max: {dist} m vs {max} m"
    );
    // Inward: crosses the gap, then held at min.
    let f = -u * uniform(&mut r, 10.0, 110.0);
    rig.sim.set_body_force(rig.body, f).unwrap();
    run_steps(&mut rig.sim, HELD_STEPS);
    let h = assert_holds(&rig.sim, &j, &rig.params, f, Vector3::zeros());
    report("distance limits (min)", &h);
    let dist = (rig.sim.body_position(rig.body) - anchor).norm();
    assert!(
        dist < min && dist > min - rig.params.tolerance_m,
        "at min: {dist} m vs {min} m"
    );
}

#[test]
fn direction_joint_holds_a_cross_torque_and_lets_the_body_move_and_spin() {
    let mut r = rng(16);
    let mut rig = rig("direction", &mut r);
    let d = unit(&mut r);
    let j = rig
        .sim
        .add_direction_joint("direction", None, rig.body, d, rig.params)
        .unwrap();
    let loads = Loads {
        a: random_vector(&mut r, 1.0, 5.0),
        alpha: d * uniform(&mut r, 5.0, 20.0),
        torque: perpendicular(&mut r, &d, 10.0, 110.0),
        ..Default::default()
    };
    free_then_held(&mut rig, &j, &loads);
}

#[test]
fn angle_limit_is_free_inside_and_holds_at_the_limit() {
    let mut r = rng(17);
    let mut rig = rig("angle limit", &mut r);
    let d = unit(&mut r);
    let limit_deg = uniform(&mut r, 15.0, 45.0);
    let j = rig
        .sim
        .add_angle_limit("angle limit", None, rig.body, d, limit_deg, rig.params)
        .unwrap();
    let alpha = perpendicular(&mut r, &d, 5.0, 20.0);
    let loads = Loads {
        a: random_vector(&mut r, 1.0, 5.0),
        alpha,
        torque: alpha.normalize() * uniform(&mut r, 10.0, 110.0),
        only_held: true,
        free_steps: Some(10),
        ..Default::default()
    };
    free_then_held(&mut rig, &j, &loads);
    let tilt = rig.sim.body_direction_to_world(rig.body, &d).angle(&d).to_degrees();
    eprintln!("{:<28} tilt {tilt:.4}° against the limit {limit_deg:.4}°", "");
    assert!(tilt > limit_deg && tilt < limit_deg + rig.params.tolerance_deg);
}

#[test]
fn fix_joint_holds_force_and_torque_and_drives_the_body() {
    let mut r = rng(18);
    let mut rig = rig("fix", &mut r);
    let j = rig.sim.add_fix_joint("fix", rig.body, rig.params).unwrap();
    let loads = Loads {
        force: random_vector(&mut r, 10.0, 110.0),
        torque: random_vector(&mut r, 10.0, 110.0),
        ..Default::default()
    };
    free_then_held(&mut rig, &j, &loads);
    // Kinematic driving: a new pose is met within tolerance (under the same load) a few steps
    // after it is set.
    let target = rig.centre + random_vector(&mut r, 0.01, 0.05);
    let q = UnitQuaternion::from_scaled_axis(random_vector(&mut r, 0.05, 0.2));
    rig.sim.set_fixed_transform(&j, target, q).unwrap();
    run_steps(&mut rig.sim, 20);
    let dx = (rig.sim.body_position(rig.body) - target).norm();
    let dq = rig.sim.body_orientation(rig.body).angle_to(&q).to_degrees();
    eprintln!("{:<28} driven pose error {dx:.2e} m, {dq:.2e}°", "");
    assert!(dx < rig.params.tolerance_m && dq < rig.params.tolerance_deg);
}

#[test]
fn hinge_holds_everything_but_its_axis() {
    let mut r = rng(19);
    let mut rig = rig("hinge", &mut r);
    let d = unit(&mut r);
    let j = rig
        .sim
        .add_hinge_joint("hinge", None, rig.body, rig.centre, d, rig.params)
        .unwrap();
    let alpha = uniform(&mut r, 5.0, 20.0);
    let loads = Loads {
        alpha: d * alpha,
        force: random_vector(&mut r, 10.0, 110.0),
        torque: perpendicular(&mut r, &d, 10.0, 110.0),
        ..Default::default()
    };
    free_then_held(&mut rig, &j, &loads);
    let rate = rig.sim.joint_state(&j).coordinate_rate.unwrap();
    let t = rig.sim.time();
    eprintln!(
        "{:<28} hinge rate {rate:.6} rad/s, free α·t = {:.6} rad/s",
        "",
        alpha * t
    );
}

#[test]
fn hinge_with_limit_turns_freely_then_holds_at_the_limit() {
    let mut r = rng(20);
    let mut rig = rig("hinge with limit", &mut r);
    let d = unit(&mut r);
    let limit_deg = uniform(&mut r, 15.0, 45.0);
    let j = rig
        .sim
        .add_hinge_joint_with_limit("hinge with limit", None, rig.body, rig.centre, d, limit_deg, rig.params)
        .unwrap();
    let sign = if r.random_bool(0.5) { 1.0 } else { -1.0 };
    let loads = Loads {
        alpha: d * sign * uniform(&mut r, 5.0, 20.0),
        force: random_vector(&mut r, 10.0, 110.0),
        torque: d * sign * uniform(&mut r, 10.0, 110.0) + perpendicular(&mut r, &d, 10.0, 110.0),
        only_held: true,
        free_steps: Some(10),
        ..Default::default()
    };
    free_then_held(&mut rig, &j, &loads);
    let angle = rig.sim.joint_state(&j).coordinate.unwrap().to_degrees();
    eprintln!(
        "{:<28} hinge angle {angle:.4}° against the limit {:.4}°",
        "",
        sign * limit_deg
    );
    assert!(angle * sign > limit_deg && angle * sign < limit_deg + rig.params.tolerance_deg);
}

#[test]
fn universal_joint_turns_freely_about_the_first_axis() {
    let mut r = rng(21);
    let mut rig = rig("universal", &mut r);
    let axis_a = unit(&mut r);
    let axis_b = perpendicular(&mut r, &axis_a, 1.0, 1.0 + 1e-9).normalize();
    let j = rig
        .sim
        .add_universal_joint("universal", None, rig.body, rig.centre, axis_a, axis_b, rig.params)
        .unwrap();
    let loads = Loads {
        alpha: axis_a * uniform(&mut r, 5.0, 20.0),
        force: random_vector(&mut r, 10.0, 110.0),
        ..Default::default()
    };
    free_then_held(&mut rig, &j, &loads);
}

#[test]
fn universal_joint_turns_freely_about_the_second_axis() {
    let mut r = rng(22);
    let mut rig = rig("universal (axis b)", &mut r);
    let axis_a = unit(&mut r);
    let axis_b = perpendicular(&mut r, &axis_a, 1.0, 1.0 + 1e-9).normalize();
    let j = rig
        .sim
        .add_universal_joint(
            "universal (axis b)",
            None,
            rig.body,
            rig.centre,
            axis_a,
            axis_b,
            rig.params,
        )
        .unwrap();
    let loads = Loads {
        alpha: axis_b * uniform(&mut r, 5.0, 20.0),
        force: random_vector(&mut r, 10.0, 110.0),
        ..Default::default()
    };
    free_then_held(&mut rig, &j, &loads);
}

#[test]
fn universal_joint_holds_the_twist() {
    // Held from rest, at dt = 1 ms: at 10 ms this equilibrium is unstable (see the module docs).
    let mut r = rng(31);
    let mut rig = rig_with_dt("universal (twist)", &mut r, 1e-3);
    let axis_a = unit(&mut r);
    let axis_b = perpendicular(&mut r, &axis_a, 1.0, 1.0 + 1e-9).normalize();
    let j = rig
        .sim
        .add_universal_joint(
            "universal (twist)",
            None,
            rig.body,
            rig.centre,
            axis_a,
            axis_b,
            rig.params,
        )
        .unwrap();
    let loads = Loads {
        force: random_vector(&mut r, 10.0, 110.0),
        torque: axis_a.cross(&axis_b) * uniform(&mut r, 10.0, 110.0),
        free_steps: Some(0),
        held_steps: Some(500),
        ..Default::default()
    };
    free_then_held(&mut rig, &j, &loads);
}

#[test]
fn slider_holds_across_and_lets_the_body_slide_and_spin_along_its_axis() {
    let mut r = rng(23);
    let mut rig = rig("slider", &mut r);
    let d = unit(&mut r);
    let j = rig
        .sim
        .add_slider_joint("slider", None, rig.body, rig.centre, d, rig.params)
        .unwrap();
    let loads = Loads {
        a: d * uniform(&mut r, 1.0, 5.0),
        alpha: d * uniform(&mut r, 5.0, 20.0),
        force: perpendicular(&mut r, &d, 10.0, 110.0),
        torque: perpendicular(&mut r, &d, 10.0, 110.0),
        ..Default::default()
    };
    free_then_held(&mut rig, &j, &loads);
}

#[test]
fn prismatic_slider_holds_every_torque_and_lets_the_body_slide() {
    let mut r = rng(24);
    let mut rig = rig("prismatic", &mut r);
    let d = unit(&mut r);
    let j = rig
        .sim
        .add_prismatic_joint("prismatic", None, rig.body, rig.centre, d, rig.params)
        .unwrap();
    let loads = Loads {
        a: d * uniform(&mut r, 1.0, 5.0),
        force: perpendicular(&mut r, &d, 10.0, 110.0),
        torque: random_vector(&mut r, 10.0, 110.0),
        ..Default::default()
    };
    free_then_held(&mut rig, &j, &loads);
    let s = rig.sim.joint_state(&j);
    let t = rig.sim.time();
    let a = loads.a.norm();
    eprintln!(
        "{:<28} slide {:.6} m at {:.6} m/s (free: ½at² = {:.6} m, a·t = {:.6} m/s)",
        "",
        s.coordinate.unwrap(),
        s.coordinate_rate.unwrap(),
        0.5 * a * t * t,
        a * t
    );
}

#[test]
fn spring_stretches_by_load_over_stiffness_and_reports_its_damping_force() {
    let mut r = rng(25);
    let mut rig = rig("spring", &mut r);
    let u = unit(&mut r);
    let l0 = uniform(&mut r, 0.3, 1.0);
    let anchor = rig.centre - u * l0;
    let k = uniform(&mut r, 500.0, 2000.0);
    // Damping ratio 0.5–1: settled to 1e-6 within the 3 s of the test.
    let c = 2.0 * (k * rig.mass).sqrt() * uniform(&mut r, 0.5, 1.0);
    let j = rig
        .sim
        .add_spring("spring", None, rig.body, anchor, rig.centre, k, c, None, rig.params)
        .unwrap();
    let f = u * uniform(&mut r, 1.0, 10.0);
    rig.sim.set_body_force(rig.body, f).unwrap();
    // While it moves: the reported force is the spring's plus the damper's, −k(l − L) − c·l̇ along
    // the line, with l̇ the step's change of length over dt (the damper's discretisation).
    let mut worst = 0.0f64;
    for _ in 0..20 {
        let before = (rig.sim.body_position(rig.body) - anchor).norm();
        rig.sim.step().unwrap();
        let x = rig.sim.body_position(rig.body) - anchor;
        let l = x.norm();
        let want = -(k * (l - l0) + c * (l - before) / DT) * x / l;
        let got = Vector3::from(rig.sim.joint_state(&j).force_on_b_n);
        worst = worst.max((got - want).norm() / want.norm());
    }
    assert!(worst < 1e-6, "spring + damper force off by {worst:.2e}");
    run_steps(&mut rig.sim, 300);
    let stretch = (rig.sim.body_position(rig.body) - anchor).norm() - l0;
    let exact = f.norm() / k;
    let h = assert_holds(&rig.sim, &j, &rig.params, f, Vector3::zeros());
    report("spring", &h);
    eprintln!(
        "{:<28} stretch {stretch:.6e} m vs F/k = {exact:.6e} m; spring + damper force error while moving {worst:.1e}",
        ""
    );
    assert!((stretch - exact).abs() < 1e-3 * exact);
    // Its effort is its tension, F (it pulls the body back towards the anchor).
    let tension = rig.sim.joint_state(&j).driver_effort;
    assert!(
        (tension - f.norm()).abs() < 1e-3 * f.norm(),
        "tension {tension} N vs {} N",
        f.norm()
    );
}

#[test]
fn spring_with_limits_is_soft_inside_and_hard_at_the_limit() {
    let mut r = rng(26);
    let mut rig = rig("spring with limits", &mut r);
    let u = unit(&mut r);
    let l0 = uniform(&mut r, 0.3, 1.0);
    let anchor = rig.centre - u * l0;
    let k = uniform(&mut r, 500.0, 2000.0);
    let c = 2.0 * (k * rig.mass).sqrt();
    let max = l0 + 0.02;
    let j = rig
        .sim
        .add_spring(
            "spring with limits",
            None,
            rig.body,
            anchor,
            rig.centre,
            k,
            c,
            Some((l0 - 0.02, max)),
            rig.params,
        )
        .unwrap();
    // Below the limit (F/k < 2 cm): the spring alone holds it, the limit is idle.
    let small = u * k * 0.01;
    rig.sim.set_body_force(rig.body, small).unwrap();
    run_steps(&mut rig.sim, 200);
    let parts = rig.sim.joint_primitive_readouts(&j);
    let limit_force = parts
        .iter()
        .find(|(p, _)| matches!(p, Primitive::DistanceLimits { .. }))
        .map(|(_, r)| Vector3::from(r.force_b_n).norm())
        .unwrap();
    let h = assert_holds(&rig.sim, &j, &rig.params, small, Vector3::zeros());
    report("spring with limits (inside)", &h);
    assert!(limit_force == 0.0, "the limit acts inside its range: {limit_force} N");
    // Beyond (F/k ≫ 2 cm): the limit takes the rest, k·(max − L) stays with the spring.
    let big = u * uniform(&mut r, 100.0, 200.0);
    rig.sim.set_body_force(rig.body, big).unwrap();
    run_steps(&mut rig.sim, HELD_STEPS);
    let h = assert_holds(&rig.sim, &j, &rig.params, big, Vector3::zeros());
    report("spring with limits (limit)", &h);
    let l = (rig.sim.body_position(rig.body) - anchor).norm();
    let spring = rig
        .sim
        .joint_primitive_readouts(&j)
        .iter()
        .find(|(p, _)| matches!(p, Primitive::Spring { .. }))
        .map(|(_, r)| Vector3::from(r.force_b_n).dot(&u))
        .unwrap();
    eprintln!(
        "{:<28} length {l:.6} m (max {max:.6} m), spring force {spring:.4} N = −k(l − L) {:.4} N, load {:.3} N",
        "",
        -k * (l - l0),
        big.norm()
    );
    assert!(l > max && l < max + rig.params.tolerance_m);
    assert!((spring + k * (l - l0)).abs() < 1e-6 * big.norm());
    let tension = rig.sim.joint_state(&j).driver_effort;
    assert!(
        (tension - k * (l - l0)).abs() < 1e-6 * big.norm(),
        "spring tension {tension} N"
    );
}

/// The second body of a body–body joint, fixed to the world by a fix joint.
fn fixed_base(rig: &mut Rig, r: &mut StdRng, offset: Vector3<f64>) -> (RigidBodyHandle, JointHandle) {
    let base = cube(&mut rig.sim, "base", uniform(r, 1.0, 10.0), rig.centre + offset);
    let fix = rig.sim.add_fix_joint("base fix", base, rig.params).unwrap();
    (base, fix)
}

#[test]
fn attachment_between_bodies_passes_the_load_to_the_fixed_body() {
    let mut r = rng(27);
    let mut rig = rig("attachment", &mut r);
    let offset = random_vector(&mut r, 0.1, 0.3);
    let (base, fix) = fixed_base(&mut rig, &mut r, offset);
    let j = rig
        .sim
        .add_attachment_joint("attachment", base, rig.body, rig.params)
        .unwrap();
    let loads = Loads {
        force: random_vector(&mut r, 10.0, 110.0),
        torque: random_vector(&mut r, 10.0, 110.0),
        ..Default::default()
    };
    free_then_held(&mut rig, &j, &loads);
    // Newton's third law through the attachment, and the base's fix joint holds the load moved
    // to the base's centre: F and τ + (c_body − c_base) × F.
    let parts = rig.sim.joint_primitive_readouts(&j);
    let on_base: Vector3<f64> = parts.iter().map(|(_, r)| Vector3::from(r.force_a_n)).sum();
    assert!(
        (on_base - loads.force).norm() < 1e-3 * loads.force.norm(),
        "reaction on the base"
    );
    let moved = loads.torque + (rig.centre - (rig.centre + offset)).cross(&loads.force);
    let h = assert_holds(&rig.sim, &fix, &rig.params, loads.force, moved);
    report("base fix (attachment)", &h);
}

#[test]
fn ball_joint_between_bodies_with_a_lever_arm() {
    let mut r = rng(28);
    let mut rig = rig("ball (body-body)", &mut r);
    let offset = random_vector(&mut r, 0.1, 0.3);
    let (base, fix) = fixed_base(&mut rig, &mut r, offset);
    // The joint sits between the two centres and the force acts at the joint, so the joint's
    // torque about the body's centre is −(p − c) × F. The force pulls the body away from the
    // joint (F·(c − p) > 0), which makes the rest pose a stable one (like a hanging pendulum);
    // some drag settles the small swing the joint's give starts.
    let p = rig.centre + 0.5 * offset;
    let j = rig
        .sim
        .add_ball_joint("ball (body-body)", Some(base), rig.body, p, rig.params)
        .unwrap();
    let away = (rig.centre - p).normalize();
    let f = (away * uniform(&mut r, 0.5, 1.0) + perpendicular(&mut r, &away, 0.0, 1.0)) * uniform(&mut r, 10.0, 110.0);
    rig.sim.add_body_force_at(rig.body, f, p).unwrap();
    rig.sim
        .set_body_params(
            rig.body,
            RigidBodyParams {
                linear_damping_1_s: 10.0,
                angular_damping_1_s: 10.0,
            },
        )
        .unwrap();
    run_steps(&mut rig.sim, 2 * HELD_STEPS);
    let h = assert_holds(&rig.sim, &j, &rig.params, f, (p - rig.centre).cross(&f));
    report("ball (body-body)", &h);
    let h = assert_holds(&rig.sim, &fix, &rig.params, f, (p - (rig.centre + offset)).cross(&f));
    report("base fix (ball)", &h);
}

#[test]
fn distance_joint_between_bodies() {
    let mut r = rng(29);
    let mut rig = rig("distance (body-body)", &mut r);
    let offset = random_vector(&mut r, 0.3, 1.0);
    let (base, fix) = fixed_base(&mut rig, &mut r, offset);
    let j = rig
        .sim
        .add_distance_joint(
            "distance (body-body)",
            Some(base),
            rig.body,
            rig.centre + offset,
            rig.centre,
            rig.params,
        )
        .unwrap();
    let f = offset.normalize() * uniform(&mut r, 10.0, 110.0);
    rig.sim.set_body_force(rig.body, f).unwrap();
    run_steps(&mut rig.sim, HELD_STEPS);
    let h = assert_holds(&rig.sim, &j, &rig.params, f, Vector3::zeros());
    report("distance (body-body)", &h);
    let h = assert_holds(&rig.sim, &fix, &rig.params, f, Vector3::zeros());
    report("base fix (distance)", &h);
}

#[test]
fn a_disabled_joint_lets_go_and_holds_again_when_enabled() {
    let mut r = rng(30);
    let mut rig = rig("enable", &mut r);
    let j = rig
        .sim
        .add_hinge_joint("hinge", None, rig.body, rig.centre, Vector3::y(), rig.params)
        .unwrap();
    let f = random_vector(&mut r, 10.0, 110.0);
    rig.sim.set_body_force(rig.body, f).unwrap();
    run_steps(&mut rig.sim, HELD_STEPS);
    assert_holds(&rig.sim, &j, &rig.params, f, Vector3::zeros());
    // Disabled: the body accelerates freely at F/m and the joint reports no force.
    rig.sim.set_joint_enabled(&j, false).unwrap();
    let (t0, v0) = (rig.sim.time(), rig.sim.body_velocity(rig.body));
    run_steps(&mut rig.sim, 10);
    let dv = rig.sim.body_velocity(rig.body) - v0;
    let want = f / rig.mass * (rig.sim.time() - t0);
    let s = rig.sim.joint_state(&j);
    assert!(
        (dv - want).norm() < 1e-9 * want.norm(),
        "free while disabled: {dv:?} vs {want:?}"
    );
    assert_eq!(Vector3::from(s.force_on_b_n).norm(), 0.0);
    // Enabled again after putting the body back at rest: it holds the load again.
    rig.sim
        .set_body_pose(rig.body, rig.centre, UnitQuaternion::identity())
        .unwrap();
    rig.sim.set_body_velocity(rig.body, Vector3::zeros()).unwrap();
    rig.sim.set_joint_enabled(&j, true).unwrap();
    run_steps(&mut rig.sim, HELD_STEPS);
    let h = assert_holds(&rig.sim, &j, &rig.params, f, Vector3::zeros());
    report("hinge re-enabled", &h);
}

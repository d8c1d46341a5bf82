//! Every joint built through the `add_*` constructors, compared with what the constructors
//! built before they became wrappers over [`Simulation::add_joint`] (issue 12): the elements,
//! servos, handles and registered joints, printed with `{:?}` (shortest exact floats) and stored
//! in `testdata/joints_built_before_add_joint.txt` from the code before the change.

use super::*;
use crate::rigidbodies::RigidBodyHandle;
use crate::simulation::Simulation;
use crate::Settings;
use nalgebra::{Matrix3, Unit};
use std::fmt::Write;

fn settings() -> Settings {
    let mut s = Settings::default();
    s.output.frames = false;
    s.output.step_log = false;
    s.gravity_m_s2 = [0.0; 3];
    s
}

/// A body per joint, turned so that body-frame and world coordinates differ.
fn body(sim: &mut Simulation, i: usize) -> RigidBodyHandle {
    let q = UnitQuaternion::from_axis_angle(&Unit::new_normalize(Vector3::new(1.0, 2.0, 3.0)), 0.3 + 0.1 * i as f64);
    let p = Vector3::new(0.7 * i as f64, 0.2, -0.1 * i as f64);
    sim.add_rigid_body(&format!("body{i}"), 1.0 + i as f64, Matrix3::identity() * 0.01, p, q)
        .unwrap()
}

/// Builds one joint of each constructor, to the world and between two bodies.
pub(super) fn build_every_joint() -> Simulation {
    let mut sim = Simulation::new(settings()).unwrap();
    let params = JointParams {
        stiffness: 2.5e5,
        tolerance_m: 3e-4,
        tolerance_deg: 0.7,
    };
    let p = Vector3::new(0.31, -0.12, 0.57);
    let q = Vector3::new(0.11, 0.42, -0.23);
    let axis = Vector3::new(0.3, -1.2, 0.4);
    let axis2 = axis.cross(&Vector3::new(1.0, 0.5, 0.2));
    let base = body(&mut sim, 100);
    for (k, a) in [None, Some(base)].into_iter().enumerate() {
        let mut n = 50 * k;
        let mut b = |sim: &mut Simulation| {
            n += 1;
            body(sim, n)
        };
        let l = |s: &str| format!("{s}{k}");
        let bb = b(&mut sim);
        sim.add_ball_joint(&l("ball"), a, bb, p, params).unwrap();
        let bb = b(&mut sim);
        sim.add_ball_joint_with_cone_limit(&l("cone"), a, bb, p, axis, 37.0, params)
            .unwrap();
        let bb = b(&mut sim);
        let hinge = sim.add_hinge_joint(&l("hinge"), a, bb, p, axis, params).unwrap();
        sim.add_hinge_joint_with_limit(&l("hinge_limit"), a, bb, p, axis, 25.0, params)
            .unwrap();
        sim.add_hinge_range(&l("hinge_range"), a, bb, p, axis, -0.4, 1.1, params)
            .unwrap();
        let bb = b(&mut sim);
        sim.add_universal_joint(&l("universal"), a, bb, p, axis, axis2, params)
            .unwrap();
        let bb = b(&mut sim);
        let slider = sim.add_slider_joint(&l("slider"), a, bb, p, axis, params).unwrap();
        sim.add_slider_range(&l("slider_range"), a, bb, p, axis, -0.05, 0.2, params)
            .unwrap();
        let bb = b(&mut sim);
        sim.add_prismatic_joint(&l("prismatic"), a, bb, p, axis, params)
            .unwrap();
        sim.add_point_on_axis_joint(&l("point_on_axis"), a, bb, q, axis, params)
            .unwrap();
        let bb = b(&mut sim);
        sim.add_planar_joint(&l("planar"), a, bb, p, axis, params).unwrap();
        let bb = b(&mut sim);
        sim.add_prismatic_press(&l("press"), a, bb, p, axis, 0.03, 12.0, 0.002, params)
            .unwrap();
        let bb = b(&mut sim);
        sim.add_motor(&l("motor"), a, bb, p, axis, 1.3, 3.0, 0.02, params)
            .unwrap();
        let bb = b(&mut sim);
        sim.add_hinge_servo(&l("hinge_servo"), a, bb, p, axis, 33.0, 4.0, 0.2, params)
            .unwrap();
        let bb = b(&mut sim);
        sim.add_prismatic_servo(&l("prismatic_servo"), a, bb, p, axis, 0.07, 9.0, 0.15, params)
            .unwrap();
        let bb = b(&mut sim);
        match a {
            None => sim.add_fix_joint(&l("fix"), bb, params).unwrap(),
            Some(a) => sim.add_attachment_joint(&l("attachment"), a, bb, params).unwrap(),
        };
        let bb = b(&mut sim);
        sim.add_distance_joint(&l("distance"), a, bb, p, q, params).unwrap();
        sim.add_distance_limits(&l("distance_limits"), a, bb, p, q, 0.1, 1.2, params)
            .unwrap();
        let bb = b(&mut sim);
        sim.add_spring(&l("spring"), a, bb, p, q, 150.0, 2.5, Some((0.2, 1.3)), params)
            .unwrap();
        sim.add_spring(&l("spring_free"), a, bb, q, p, 50.0, 0.0, None, params)
            .unwrap();
        let bb = b(&mut sim);
        sim.add_direction_joint(&l("direction"), a, bb, axis, params).unwrap();
        sim.add_angle_limit(&l("angle_limit"), a, bb, axis2, 12.5, params)
            .unwrap();
        sim.add_linear_velocity_controller(&l("linear_velocity"), a, bb, p, axis, 0.04, 5.0, 0.02)
            .unwrap();
        sim.add_angular_velocity_controller(&l("angular_velocity"), a, bb, axis, -0.8, 2.0, DEFAULT_CONTROLLER_DELAY)
            .unwrap();
        sim.add_joint_coupling(&l("coupling"), &hinge, &slider, -0.7, 0.05, params)
            .unwrap();
        sim.add_joint_spring(&l("joint_spring"), &hinge, 3.5, 0.25, 0.125)
            .unwrap();
    }
    sim
}

/// What the joints of `sim` are: elements, then the registered joints.
pub(super) fn describe(sim: &Simulation) -> String {
    let mut out = String::new();
    for (i, e) in sim.rigid_bodies.joints.potential.elements.iter().enumerate() {
        writeln!(out, "element {i}: {e:?}").unwrap();
    }
    for h in &sim.rigid_bodies.named_joints {
        writeln!(out, "joint: {h:?}").unwrap();
    }
    out
}

const GOLDEN: &str = "src/rigidbodies/joints/testdata/joints_built_before_add_joint.txt";

#[test]
fn every_add_constructor_builds_what_it_built_before_add_joint() {
    let now = describe(&build_every_joint());
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(GOLDEN);
    if std::env::var_os("STARK_WRITE_GOLDEN").is_some() {
        std::fs::write(&path, &now).unwrap();
    }
    if let Some(out) = std::env::var_os("STARK_WRITE_NOW") {
        std::fs::write(out, &now).unwrap();
    }
    let before = std::fs::read_to_string(&path).unwrap();
    let (now, before): (Vec<_>, Vec<_>) = (now.lines().collect(), before.lines().collect());
    assert_eq!(now.len(), before.len());
    for (n, b) in now.iter().zip(&before) {
        if n == b {
            continue;
        }
        // The wrappers taking radians (motor, angular velocity controller, hinge range) pass
        // degrees to `JointKind`: rad → deg → rad may move the last bit or two.
        let radians = ["motor", "angular_velocity", "hinge_range"]
            .iter()
            .any(|k| b.contains(&format!("label: \"{k}")));
        assert!(radians, "\n{n}\n!=\n{b}");
        assert!(same_up_to_ulps(n, b, 2), "\n{n}\n!=\n{b}");
    }
}

/// The two texts are equal except for numbers within `ulps` units in the last place.
fn same_up_to_ulps(a: &str, b: &str, ulps: u64) -> bool {
    let split = |s: &str| -> Vec<String> {
        s.split(|c: char| !(c.is_ascii_digit() || ".-e".contains(c)))
            .map(str::to_string)
            .collect()
    };
    let (ta, tb) = (split(a), split(b));
    let same_words = a.replace(|c: char| c.is_ascii_digit() || "-.".contains(c), "")
        == b.replace(|c: char| c.is_ascii_digit() || "-.".contains(c), "");
    same_words
        && ta.len() == tb.len()
        && ta.iter().zip(&tb).all(|(x, y)| {
            x == y
                || match (x.parse::<f64>(), y.parse::<f64>()) {
                    (Ok(x), Ok(y)) => x.signum() == y.signum() && x.to_bits().abs_diff(y.to_bits()) <= ulps,
                    _ => false,
                }
        })
}

//! Pendulums written as URDF behave as the same pendulums built by hand and as the analytic one.
//!
//! - A double pendulum (two 1 m links of 1 kg and 2 kg on continuous joints about y, released
//!   horizontal, the massless root link fixed as the world) imported from URDF matches the same
//!   pendulum built with `add_rigid_body` and `add_hinge_joint` to 1e-12 m after 100 steps.
//! - A single pendulum (0.5 kg bob of radius 2 cm, 0.8 m below its joint, released at 0.1 rad
//!   through the joint's initial position) swings with the physical pendulum's period
//!   `2π√(I_p/(m g L))·(1 + θ₀²/16)` to within 1%.

use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use stark::rigidbodies::joints::JointParams;
use stark::robots::{JointOverride, RobotOptions};
use stark::{Settings, Simulation};
use std::path::Path;

fn settings(dt: f64) -> Settings {
    let mut s = Settings::default();
    s.output.frames = false;
    s.output.step_log = false;
    s.time_step_s = dt;
    s.threads = 1;
    s
}

const DOUBLE: &str = r#"<?xml version="1.0"?>
<robot name="double">
  <link name="base"/>
  <link name="upper">
    <inertial>
      <origin xyz="0.5 0 0"/>
      <mass value="1"/>
      <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.0845" iyz="0" izz="0.0845"/>
    </inertial>
  </link>
  <link name="lower">
    <inertial>
      <origin xyz="0.5 0 0"/>
      <mass value="2"/>
      <inertia ixx="0.002" ixy="0" ixz="0" iyy="0.169" iyz="0" izz="0.169"/>
    </inertial>
  </link>
  <joint name="shoulder" type="continuous">
    <parent link="base"/>
    <child link="upper"/>
    <axis xyz="0 1 0"/>
  </joint>
  <joint name="elbow" type="continuous">
    <origin xyz="1 0 0"/>
    <parent link="upper"/>
    <child link="lower"/>
    <axis xyz="0 1 0"/>
  </joint>
</robot>
"#;

#[test]
fn urdf_double_pendulum_matches_the_hand_built_one() {
    let mut urdf = Simulation::new(settings(1e-2)).unwrap();
    let options = RobotOptions {
        fixed_base: true,
        ..Default::default()
    };
    let robot = urdf
        .add_robot_from_str("double", DOUBLE, "double.urdf", Path::new("."), &options)
        .unwrap();
    assert_eq!(robot.links["base"], None, "the massless fixed root is the world");

    let mut hand = Simulation::new(settings(1e-2)).unwrap();
    let q = UnitQuaternion::identity();
    let upper = hand
        .add_rigid_body(
            "double/upper",
            1.0,
            Matrix3::from_diagonal(&Vector3::new(0.001, 0.0845, 0.0845)),
            Vector3::new(0.5, 0.0, 0.0),
            q,
        )
        .unwrap();
    let lower = hand
        .add_rigid_body(
            "double/lower",
            2.0,
            Matrix3::from_diagonal(&Vector3::new(0.002, 0.169, 0.169)),
            Vector3::new(1.5, 0.0, 0.0),
            q,
        )
        .unwrap();
    let p = JointParams::default();
    hand.add_hinge_joint("double/shoulder", None, upper, Vector3::zeros(), Vector3::y(), p)
        .unwrap();
    hand.add_hinge_joint("double/elbow", Some(upper), lower, Vector3::x(), Vector3::y(), p)
        .unwrap();

    for _ in 0..100 {
        urdf.step().unwrap();
        hand.step().unwrap();
    }
    let mut worst = 0.0f64;
    for b in 0..2 {
        worst = worst.max((urdf.bodies.position[b] - hand.bodies.position[b]).norm());
        worst = worst.max(urdf.bodies.orientation[b].angle_to(&hand.bodies.orientation[b]));
    }
    println!(
        "double pendulum after 100 steps: elbow at {:?}, largest difference {worst:e}",
        urdf.bodies.position[1]
    );
    // It moved (fell from horizontal) and both agree.
    assert!(urdf.bodies.position[1].z < -0.1);
    assert!(worst < 1e-12, "URDF and hand-built pendulums differ by {worst:e}");
}

#[test]
fn urdf_pendulum_period_matches_the_physical_pendulum() {
    let (m, r, l, theta0): (f64, f64, f64, f64) = (0.5, 0.02, 0.8, 0.1);
    let i_cm = 0.4 * m * r * r;
    let text = format!(
        r#"<robot name="p">
  <link name="pivot"/>
  <link name="bob">
    <inertial>
      <origin xyz="0 0 -{l}"/>
      <mass value="{m}"/>
      <inertia ixx="{i_cm}" ixy="0" ixz="0" iyy="{i_cm}" iyz="0" izz="{i_cm}"/>
    </inertial>
    <collision><origin xyz="0 0 -{l}"/><geometry><sphere radius="{r}"/></geometry></collision>
  </link>
  <joint name="swing" type="revolute">
    <parent link="pivot"/>
    <child link="bob"/>
    <axis xyz="0 1 0"/>
    <limit lower="-1" upper="1" effort="0" velocity="0"/>
  </joint>
</robot>"#
    );
    let mut sim = Simulation::new(settings(1e-3)).unwrap();
    let mut options = RobotOptions {
        fixed_base: true,
        ..Default::default()
    };
    options.joints.insert(
        "swing".into(),
        JointOverride {
            position: Some(theta0),
            ..Default::default()
        },
    );
    let robot = sim
        .add_robot_from_str("p", &text, "pendulum.urdf", Path::new("."), &options)
        .unwrap();
    assert!((robot.joint_position(&sim, "swing").unwrap() - theta0).abs() < 1e-15);
    let mut crossings = Vec::new();
    let mut prev = (0.0, theta0);
    while crossings.len() < 3 && sim.time() < 10.0 {
        sim.step().unwrap();
        let q = robot.joint_position(&sim, "swing").unwrap();
        if prev.1 < 0.0 && q >= 0.0 {
            crossings.push(prev.0 + (sim.time() - prev.0) * (-prev.1) / (q - prev.1));
        }
        prev = (sim.time(), q);
    }
    let period = (crossings[2] - crossings[0]) / 2.0;
    let g = 9.81;
    let exact = 2.0 * std::f64::consts::PI * ((i_cm + m * l * l) / (m * g * l)).sqrt() * (1.0 + theta0 * theta0 / 16.0);
    let err = (period - exact) / exact;
    println!(
        "URDF pendulum: period {period:.5} s, physical pendulum {exact:.5} s, error {:.3}%",
        100.0 * err
    );
    assert!(err.abs() < 0.01, "period {period} s vs {exact} s");
}

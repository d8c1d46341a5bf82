//! The published robot descriptions in `../shared/data/robots` (Kobuki, Franka hand) import, and
//! what they became agrees with an independent reading of their XML (roxmltree, not urdf-rs):
//! bodies after merging the fixed joints, total mass, the type, world axis and limits of every
//! moving joint. The Franka fingers, one driven by a force-limited press and the other
//! mimicking it, close at the press's target speed symmetric to 1e-6 m and stall at the URDF
//! effort cap against their lower limit.

use nalgebra::{UnitQuaternion, Vector3};
use stark::rigidbodies::joints::{Measure, Primitive};
use stark::robots::{Actuator, JointOverride, RobotOptions};
use stark::{Settings, Simulation};
use std::path::PathBuf;

pub fn robots_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/robots")
}

fn quiet(dt: f64) -> Settings {
    let mut s = Settings::default();
    s.output.frames = false;
    s.output.step_log = false;
    s.time_step_s = dt;
    s
}

/// A URDF joint as read directly from the XML.
struct XmlJoint {
    name: String,
    kind: String,
    parent: String,
    child: String,
    axis_world: Vector3<f64>,
    limits: Option<(f64, f64)>,
}

/// `R = Rz(yaw)·Ry(pitch)·Rx(roll)`, written out (URDF's fixed-axis rpy).
fn rpy_matrix(rpy: [f64; 3]) -> nalgebra::Matrix3<f64> {
    let (sr, cr) = rpy[0].sin_cos();
    let (sp, cp) = rpy[1].sin_cos();
    let (sy, cy) = rpy[2].sin_cos();
    let rx = nalgebra::Matrix3::new(1.0, 0.0, 0.0, 0.0, cr, -sr, 0.0, sr, cr);
    let ry = nalgebra::Matrix3::new(cp, 0.0, sp, 0.0, 1.0, 0.0, -sp, 0.0, cp);
    let rz = nalgebra::Matrix3::new(cy, -sy, 0.0, sy, cy, 0.0, 0.0, 0.0, 1.0);
    rz * ry * rx
}

fn numbers(s: Option<&str>, default: [f64; 3]) -> [f64; 3] {
    match s {
        None => default,
        Some(s) => {
            let v: Vec<f64> = s.split_whitespace().map(|w| w.parse().unwrap()).collect();
            [v[0], v[1], v[2]]
        }
    }
}

/// Links (name, mass) and joints of a URDF, with each joint's axis in the root link's frame.
fn read_xml(path: &std::path::Path) -> (Vec<(String, f64)>, Vec<XmlJoint>) {
    let text = std::fs::read_to_string(path).unwrap();
    let doc = roxmltree::Document::parse(&text).unwrap();
    let robot = doc.root_element();
    let mut links = Vec::new();
    for l in robot.children().filter(|n| n.has_tag_name("link")) {
        let mass = l
            .descendants()
            .find(|n| n.has_tag_name("mass"))
            .map_or(0.0, |m| m.attribute("value").unwrap().parse().unwrap());
        links.push((l.attribute("name").unwrap().to_string(), mass));
    }
    let mut rotation: std::collections::HashMap<String, nalgebra::Matrix3<f64>> = Default::default();
    let raw: Vec<_> = robot.children().filter(|n| n.has_tag_name("joint")).collect();
    // Root: the link that is nobody's child.
    let children: Vec<&str> = raw
        .iter()
        .map(|j| {
            j.children()
                .find(|c| c.has_tag_name("child"))
                .unwrap()
                .attribute("link")
                .unwrap()
        })
        .collect();
    let root = links
        .iter()
        .find(|(n, _)| !children.contains(&n.as_str()))
        .unwrap()
        .0
        .clone();
    rotation.insert(root, nalgebra::Matrix3::identity());
    let mut joints = Vec::new();
    while joints.len() < raw.len() {
        for j in &raw {
            let child_of = |tag: &str| {
                j.children()
                    .find(|c| c.has_tag_name(tag))
                    .unwrap()
                    .attribute("link")
                    .unwrap()
            };
            let (parent, child) = (child_of("parent").to_string(), child_of("child").to_string());
            if joints.iter().any(|x: &XmlJoint| x.child == child) || !rotation.contains_key(&parent) {
                continue;
            }
            let origin = j.children().find(|c| c.has_tag_name("origin"));
            let rpy = numbers(origin.and_then(|o| o.attribute("rpy")), [0.0; 3]);
            let r = rotation[&parent] * rpy_matrix(rpy);
            rotation.insert(child.clone(), r);
            let axis = numbers(
                j.children()
                    .find(|c| c.has_tag_name("axis"))
                    .and_then(|a| a.attribute("xyz")),
                [1.0, 0.0, 0.0],
            );
            let limits = j
                .children()
                .find(|c| c.has_tag_name("limit"))
                .and_then(|l| Some((l.attribute("lower")?.parse().ok()?, l.attribute("upper")?.parse().ok()?)));
            joints.push(XmlJoint {
                name: j.attribute("name").unwrap().to_string(),
                kind: j.attribute("type").unwrap().to_string(),
                parent,
                child,
                axis_world: r * Vector3::from(axis).normalize(),
                limits,
            });
        }
    }
    (links, joints)
}

/// The world axis of a joint's coordinate and whether it is an angle.
fn measured_axis(sim: &Simulation, m: &Measure) -> (Vector3<f64>, bool) {
    let frame = |b: Option<u32>| b.map_or(UnitQuaternion::identity(), |b| sim.bodies.orientation[b as usize]);
    match *m {
        Measure::Angle { a, axis_a, .. } => (frame(a) * axis_a, true),
        Measure::Position { a, axis_a, .. } => (frame(a) * axis_a, false),
    }
}

fn check_against_xml(robot_name: &str, urdf: PathBuf, options: RobotOptions) {
    let (links, joints) = read_xml(&urdf);
    let mut sim = Simulation::new(quiet(1e-3)).unwrap();
    let robot = sim.add_robot(robot_name, &urdf, &options).unwrap();
    let moving: Vec<&XmlJoint> = joints.iter().filter(|j| j.kind != "fixed").collect();
    // Every fixed joint merges its child into its parent: one body per moving joint plus the root.
    assert_eq!(
        robot.bodies.len(),
        moving.len() + 1,
        "{robot_name}: bodies {:?}",
        robot.bodies
    );
    assert_eq!(sim.num_rigid_bodies(), moving.len() + 1);
    assert_eq!(robot.links.len(), links.len());
    let total: f64 = links.iter().map(|(_, m)| m).sum();
    let simulated: f64 = sim.bodies.mass.iter().sum();
    assert!(
        (simulated - total).abs() < 1e-12 * total,
        "{robot_name}: mass {simulated} vs {total} kg"
    );
    for (link, body) in &robot.bodies {
        assert_eq!(sim.rigid_bodies.labels[body.i()], format!("{robot_name}/{link}"));
    }
    for xj in &moving {
        let h = robot.joint(&xj.name).unwrap_or_else(|| panic!("joint {}", xj.name));
        assert_eq!(h.label, format!("{robot_name}/{}", xj.name));
        let (axis, angle) = measured_axis(&sim, &h.measure.unwrap());
        assert_eq!(angle, xj.kind != "prismatic", "{}: {}", xj.name, xj.kind);
        assert!(
            (axis - xj.axis_world).norm() < 1e-12,
            "{}: axis {axis:?} vs {:?}",
            xj.name,
            xj.axis_world
        );
        // The bodies are those of the XML's parent and child links.
        assert_ne!(robot.body(&xj.parent), robot.body(&xj.child));
        let limits = robot
            .extra_joints
            .iter()
            .find(|e| e.label == format!("{robot_name}/{}.limits", xj.name));
        match (xj.kind.as_str(), xj.limits) {
            ("prismatic", Some((lo, hi))) => {
                let e = &sim.rigid_bodies.joints.potential.elements[limits.unwrap().elements[0] as usize];
                let Primitive::DistanceLimits { min_m, max_m } = e.primitive else {
                    panic!("{:?}", e.primitive)
                };
                assert!(((max_m - min_m) - (hi - lo)).abs() < 1e-12, "{}", xj.name);
            }
            ("revolute", Some((lo, hi))) => {
                let e = &sim.rigid_bodies.joints.potential.elements[limits.unwrap().elements[0] as usize];
                let Primitive::AngleLimit { limit_rad } = e.primitive else {
                    panic!("{:?}", e.primitive)
                };
                assert!((2.0 * limit_rad - (hi - lo)).abs() < 1e-12, "{}", xj.name);
            }
            _ => assert!(limits.is_none(), "{}: continuous joints have no limits", xj.name),
        }
    }
    println!(
        "{robot_name}: {} links, {} joints ({} moving) -> {} bodies, {:.4} kg",
        links.len(),
        joints.len(),
        moving.len(),
        robot.bodies.len(),
        total
    );
}

#[test]
fn kobuki_and_franka_hand_import_as_their_xml_says() {
    let dir = robots_dir();
    let options = RobotOptions {
        package_paths: vec![dir.clone()],
        visual_meshes: true, // the COLLADA meshes load
        ..Default::default()
    };
    check_against_xml(
        "kobuki",
        dir.join("kobuki_description/urdf/kobuki_standalone.urdf"),
        options.clone(),
    );
    check_against_xml("franka", dir.join("franka_description/urdf/franka_hand.urdf"), options);
}

#[test]
fn franka_fingers_mimic_close_at_speed_and_stall_at_the_effort_cap() {
    let dir = robots_dir();
    let mut settings = quiet(2e-3);
    settings.gravity_m_s2 = [0.0, 0.0, -9.81];
    let mut sim = Simulation::new(settings).unwrap();
    let mut options = RobotOptions {
        package_paths: vec![dir.clone()],
        fixed_base: true,
        ..Default::default()
    };
    // Start open at 30 mm each; close at 0.5 m/s, which the URDF velocity limit caps at 0.2.
    options.joints.insert(
        "fr3_finger_joint1".into(),
        JointOverride {
            position: Some(0.03),
            actuator: Some(Actuator::Press {
                target_m_s: -0.5,
                max_force_n: None,
            }),
            ..Default::default()
        },
    );
    options.joints.insert(
        "fr3_finger_joint2".into(),
        JointOverride {
            position: Some(0.03),
            ..Default::default()
        },
    );
    let hand = sim
        .add_robot("franka", dir.join("franka_description/urdf/franka_hand.urdf"), &options)
        .unwrap();
    let press = hand.joint("fr3_finger_joint1").unwrap().clone();
    let (mut worst, mut closing_rates, mut t) = (0.0f64, Vec::new(), 0.0);
    while t < 0.3 {
        sim.step().unwrap();
        t = sim.time();
        let q1 = hand.joint_position(&sim, "fr3_finger_joint1").unwrap();
        let q2 = hand.joint_position(&sim, "fr3_finger_joint2").unwrap();
        worst = worst.max((q1 - q2).abs());
        if (0.05..0.1).contains(&t) {
            closing_rates.push(sim.joint_state(&press).coordinate_rate.unwrap());
        }
    }
    let state = sim.joint_state(&press);
    let q1 = hand.joint_position(&sim, "fr3_finger_joint1").unwrap();
    let (lo, hi) = closing_rates
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &r| (a.min(r), b.max(r)));
    println!(
        "franka: closing rate in [{lo:.6}, {hi:.6}] m/s, |q1 − q2| ≤ {worst:.2e} m, final q1 = {q1:.2e} m, press force {:.3} N",
        state.driver_effort
    );
    assert!(worst < 1e-6, "fingers not symmetric: {worst:e} m");
    assert!(
        lo > -0.2 - 1e-4 && hi < -0.2 + 1e-4,
        "closing rate [{lo}, {hi}] m/s, target −0.2"
    );
    // Stalled at the lower limit (0, within the limit's 1 mm tolerance), pushing with the cap.
    assert!(
        q1.abs() < 1e-3 && state.coordinate_rate.unwrap().abs() < 1e-3,
        "q1 = {q1}"
    );
    assert!(
        (state.driver_effort + 100.0).abs() < 1e-3,
        "press force {} N",
        state.driver_effort
    );
}

//! Rigid bodies, joints and spawned bodies.

use super::*;

#[test]
fn shapes_masses_poses_and_initial_state() {
    let scene = parse(
        r#"
duration_s = 1.0
[settings]
contact.default_thickness_m = 0.001
[[rigid_body]]
name = "crate"
box = { size_m = [0.1, 0.2, 0.3] }
density_kg_m3 = 500.0
position_m = [1.0, 2.0, 3.0]
rotate_deg = { angle = 90.0, axis = [0.0, 0.0, 2.0] }
velocity_m_s = [0.1, 0.0, 0.0]
angular_velocity_deg_s = [0.0, 0.0, 180.0]
linear_damping_1_s = 0.5
force_n = [0.0, 0.0, 1.0]
torque_n_m = [0.0, 0.1, 0.0]
[[rigid_body]]
name = "ball"
sphere = { radius_m = 0.1, subdivisions = 1 }
mass_kg = 2.0
position_m = [5.0, 0.0, 0.0]
quaternion_wxyz = [0.0, 2.0, 0.0, 0.0]
contact = false
[[rigid_body]]
name = "can"
cylinder = { radius_m = 0.05, height_m = 0.2, slices = 8 }
mass_kg = 0.3
position_m = [-5.0, 0.0, 0.0]
contact_thickness_m = 0.003
[[rigid_body]]
name = "ring"
torus = { major_radius_m = 0.2, minor_radius_m = 0.05, major_segments = 8, minor_segments = 6 }
density_kg_m3 = 1000.0
position_m = [0.0, 5.0, 0.0]
[[rigid_body]]
name = "tet"
vertices_m = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
triangles = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]
scale = 0.5
mass_kg = 6.0
position_m = [0.0, -5.0, 0.0]
"#,
    );
    let sim = &scene.simulation;
    assert_eq!(sim.num_rigid_bodies(), 5);
    let body = |n: &str| scene.rigid_body(n).unwrap_or_else(|| panic!("no body {n}"));
    // The box: mass from the density, pose, velocities, damping, force and torque.
    let c = body("crate");
    let size = Vector3::new(0.1, 0.2, 0.3);
    let mass = 500.0 * (0.1 * 0.2 * 0.3);
    assert_eq!(sim.bodies.mass[c.body.i()], mass);
    assert_eq!(
        sim.bodies.inertia_local[c.body.i()],
        MassProperties::cuboid(mass, size).inertia_kg_m2
    );
    assert_eq!(sim.body_position(c.body), Vector3::new(1.0, 2.0, 3.0));
    let q = sim.body_orientation(c.body);
    assert!((q.angle() - PI / 2.0).abs() < 1e-15 && close(&q.axis().unwrap(), &Vector3::z(), 1e-15));
    assert_eq!(sim.body_velocity(c.body), Vector3::new(0.1, 0.0, 0.0));
    assert_eq!(sim.body_angular_velocity(c.body), Vector3::new(0.0, 0.0, PI));
    assert_eq!(sim.body_params(c.body).unwrap().linear_damping_1_s, 0.5);
    assert_eq!(sim.body_params(c.body).unwrap().angular_damping_1_s, 0.0);
    assert_eq!(sim.bodies.force[0], Vector3::new(0.0, 0.0, 1.0));
    assert_eq!(sim.bodies.torque[0], Vector3::new(0.0, 0.1, 0.0));
    // Its mesh follows the pose: the corner (−x, −y, −z)/2 turned 90° about z.
    let corner = sim.positions(c.nodes)[0];
    assert!(close(&corner, &Vector3::new(1.1, 1.95, 2.85), 1e-15), "{corner}");
    // The sphere: a half turn about x, no contact.
    let b = body("ball");
    assert_eq!(
        sim.bodies.inertia_local[b.body.i()],
        MassProperties::sphere(2.0, 0.1).inertia_kg_m2
    );
    assert!((sim.body_orientation(b.body).angle() - PI).abs() < 1e-15);
    assert!(b.contact.is_none());
    assert_eq!(b.nodes.len, 42);
    // The cylinder's and torus's meshes and masses.
    assert_eq!(body("can").nodes.len, 2 * 8 + 2);
    let ring = body("ring");
    assert_eq!(ring.nodes.len, 48);
    let ring_mass = 1000.0 * (2.0 * PI * PI * 0.2 * 0.05 * 0.05);
    assert_eq!(sim.bodies.mass[ring.body.i()], ring_mass);
    // The inline tetrahedron: scaled, recentred at its centre of mass, mass scaled to 6 kg.
    let tet = body("tet");
    let x = sim.positions(tet.nodes);
    assert!(close(&x[0], &Vector3::new(-0.125, -5.125, -0.125), 1e-15), "{}", x[0]);
    assert!(close(&x[1], &Vector3::new(0.375, -5.125, -0.125), 1e-15), "{}", x[1]);
    let v: Vec<_> = [[0.0, 0.0, 0.0], [0.5, 0.0, 0.0], [0.0, 0.5, 0.0], [0.0, 0.0, 0.5]]
        .iter()
        .map(|p| Vector3::from(*p))
        .collect();
    let tris = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
    let props = MassProperties::from_mesh(&v, &tris, 1.0).unwrap();
    let expected = props.inertia_kg_m2 * (6.0 / props.mass_kg);
    assert!((sim.bodies.inertia_local[tet.body.i()] - expected).norm() < 1e-15);
    // Contact: thickness given, else the default; the sphere has none.
    let thickness: Vec<_> = sim
        .contact
        .objects()
        .iter()
        .map(|o| (o.label.clone(), o.thickness_m))
        .collect();
    assert_eq!(
        thickness,
        [
            ("crate".to_string(), 0.001),
            ("can".to_string(), 0.003),
            ("ring".to_string(), 0.001),
            ("tet".to_string(), 0.001)
        ]
    );
    // Every body's mesh is in the frames.
    let meshes: Vec<_> = sim.output.meshes.iter().map(|m| m.label.as_str()).collect();
    assert_eq!(meshes, ["crate", "ball", "can", "ring", "tet"]);
    assert!(scene.joints.is_empty());
}

#[test]
fn keyframes_interpolate_and_hold() {
    let q1 = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), PI / 2.0);
    let poses: Poses = vec![
        (0.0, Vector3::new(2.0, 0.0, 0.0), UnitQuaternion::identity()),
        (0.5, Vector3::new(2.0, 0.0, 1.0), q1),
        (1.0, Vector3::new(3.0, 0.0, 1.0), q1),
    ];
    let (p, q) = keyframe_pose(&poses, 0.25);
    assert!(close(&p, &Vector3::new(2.0, 0.0, 0.5), 1e-15));
    assert!((q.angle() - PI / 4.0).abs() < 1e-15);
    let (p, q) = keyframe_pose(&poses, 0.75);
    assert!(close(&p, &Vector3::new(2.5, 0.0, 1.0), 1e-15));
    assert!(q.angle_to(&q1) < 1e-15);
    assert_eq!(keyframe_pose(&poses, 7.0).0, Vector3::new(3.0, 0.0, 1.0));
    assert_eq!(keyframe_pose(&poses, 0.0).0, Vector3::new(2.0, 0.0, 0.0));
}

#[test]
fn fixed_bodies_follow_their_motion_and_keyframes() {
    let mut scene = parse(
        r#"
duration_s = 1.0
[settings]
time_step_s = 0.05
[[rigid_body]]
name = "lift"
box = { size_m = [0.2, 0.2, 0.2] }
mass_kg = 1.0
position_m = [0.3, 0.0, 0.0]
motion = { velocity_m_s = [0.0, 0.0, 0.5], angular_velocity_deg_s = 90.0, axis = [0.0, 0.0, 1.0], center_m = [0.1, 0.0, 0.0] }
[[rigid_body]]
name = "arm"
box = { size_m = [0.2, 0.2, 0.2] }
mass_kg = 1.0
position_m = [2.0, 0.0, 0.0]
keyframes = [
  { time_s = 0.5, position_m = [2.0, 0.0, 1.0], rotate_deg = { angle = 90.0, axis = [1.0, 0.0, 0.0] } },
  { time_s = 1.0, position_m = [3.0, 0.0, 1.0] },
]
[[rigid_body]]
name = "post"
box = { size_m = [0.2, 0.2, 0.2] }
mass_kg = 1.0
position_m = [0.0, 3.0, 0.0]
fixed = true
"#,
    );
    let labels: Vec<_> = scene.joints.iter().map(|j| j.label.as_str()).collect();
    assert_eq!(labels, ["lift.fixed", "arm.fixed", "post.fixed"]);
    let lift = scene.rigid_body("lift").unwrap().body;
    let arm = scene.rigid_body("arm").unwrap().body;
    let post = scene.rigid_body("post").unwrap().body;
    let fix = scene.joint("lift.fixed").unwrap().clone();
    let sim = &mut scene.simulation;
    for _ in 0..10 {
        sim.step().unwrap();
        let t = sim.time();
        // The lift: turned by 90°·t about the vertical through (0.1, 0, 0), raised by 0.5·t.
        let (s, c) = (90.0f64 * t).to_radians().sin_cos();
        let expected = Vector3::new(0.1 + 0.2 * c, 0.2 * s, 0.5 * t);
        let target = &sim.rigid_bodies.joints.potential.elements[fix.elements[0] as usize].nodes[0];
        let Node::World(target) = *target else {
            panic!("{target:?}")
        };
        assert!(close(&Vector3::from(target), &expected, 1e-14), "t = {t}: {target:?}");
        assert!(close(&sim.body_position(lift), &expected, 1e-3), "t = {t}");
        let turn = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), (90.0f64 * t).to_radians());
        assert!(
            sim.body_orientation(lift).angle_to(&turn) < 1f64.to_radians(),
            "t = {t}"
        );
        // The arm: up by 2·t and turning about x until 0.5 s.
        let z = (2.0 * t).min(1.0);
        assert!(
            close(&sim.body_position(arm), &Vector3::new(2.0, 0.0, z), 1e-3),
            "t = {t}"
        );
        let turn = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), (180.0 * t).min(90.0).to_radians());
        assert!(sim.body_orientation(arm).angle_to(&turn) < 1f64.to_radians(), "t = {t}");
        assert!(close(&sim.body_position(post), &Vector3::new(0.0, 3.0, 0.0), 1e-3));
    }
    assert!((sim.time() - 0.5).abs() < 1e-12);
    let state = sim.joint_state(&fix);
    assert!(state.violation_m <= 1e-3, "{state:?}");
}

/// One body per joint type (or two), each joint to the world or to a second body.
const ALL_JOINTS: &str = r#"
duration_s = 1.0
[settings]
gravity_m_s2 = [0.0, 0.0, 0.0]
"#;

fn all_joints_scene() -> String {
    let types = [
        ("ball", "point_m = [P]"),
        ("ball_cone", "point_m = [P]\naxis = [0.0, 0.0, 1.0]\nlimit_deg = 30.0"),
        ("hinge", "point_m = [P]\naxis = [0.0, 1.0, 0.0]"),
        ("hinge_limit", "point_m = [P]\naxis = [0.0, 1.0, 0.0]\nlimit_deg = 45.0"),
        ("universal", "point_m = [P]\naxis_a = [1.0, 0.0, 0.0]\naxis_b = [0.0, 1.0, 0.0]"),
        ("slider", "point_m = [P]\naxis = [0.0, 0.0, 1.0]"),
        ("prismatic", "point_m = [P]\naxis = [0.0, 0.0, 1.0]"),
        ("prismatic_press", "point_m = [P]\naxis = [0.0, 0.0, 1.0]\ntarget_velocity_m_s = 0.1\nmax_force_n = 10.0"),
        ("motor", "point_m = [P]\naxis = [0.0, 1.0, 0.0]\nmax_torque_n_m = 1.0\ntarget_schedule = [[0.0, 0.0], [1.0, 90.0]]"),
        ("hinge_servo", "point_m = [P]\naxis = [0.0, 1.0, 0.0]\ntarget_deg = 30.0\nmax_torque_n_m = 1.0\nresponse_time_s = 0.1"),
        ("prismatic_servo", "point_m = [P]\naxis = [0.0, 0.0, 1.0]\ntarget_schedule = [[0.0, 0.0], [0.5, 0.1]]\nmax_force_n = 10.0"),
        ("fix", ""),
        ("attachment", "a = \"base\""),
        ("distance", "point_a_m = [P]\npoint_b_m = [Q]"),
        ("distance_limits", "point_a_m = [P]\npoint_b_m = [Q]\nmin_m = 0.05\nmax_m = 0.2"),
        ("spring", "point_a_m = [P]\npoint_b_m = [Q]\nspring_stiffness_n_m = 100.0\ndamping_n_s_m = 1.0\nlimits_m = [0.05, 0.2]"),
        ("direction", "axis = [0.0, 0.0, 1.0]"),
        ("angle_limit", "axis = [0.0, 0.0, 1.0]\nlimit_deg = 10.0"),
        ("point_on_axis", "point_m = [P]\naxis = [1.0, 0.0, 0.0]"),
        ("linear_velocity", "point_m = [P]\naxis = [1.0, 0.0, 0.0]\ntarget_velocity_m_s = 0.2\nmax_force_n = 5.0\ndelay_m_s = 0.02"),
        ("angular_velocity", "axis = [0.0, 0.0, 1.0]\ntarget_velocity_deg_s = 45.0\nmax_torque_n_m = 2.0\ndelay_deg_s = 1.0"),
    ];
    let mut s = ALL_JOINTS.to_string();
    s += "[[rigid_body]]\nname = \"base\"\nbox = { size_m = [0.1, 0.1, 0.1] }\nmass_kg = 1.0\nposition_m = [0.0, -2.0, 0.0]\n";
    for (i, (t, _)) in types.iter().enumerate() {
        s += &format!(
            "[[rigid_body]]\nname = \"{t}\"\nbox = {{ size_m = [0.1, 0.1, 0.1] }}\nmass_kg = 1.0\nposition_m = [{}.0, 0.0, 0.0]\n",
            i
        );
    }
    for (i, (t, fields)) in types.iter().enumerate() {
        let p = format!("{i}.0, 0.0, 0.05");
        let q = format!("{i}.0, 0.0, -0.05");
        s += &format!(
            "[[joint]]\ntype = \"{t}\"\nb = \"{t}\"\n{}\n",
            fields
                .replace("[P]", &format!("[{p}]"))
                .replace("[Q]", &format!("[{q}]"))
        );
    }
    s
}

#[test]
fn every_joint_type_is_built_registered_and_runs() {
    let mut scene = parse(&all_joints_scene());
    let names: Vec<_> = scene.joints.iter().map(|j| j.label.clone()).collect();
    assert_eq!(names.len(), 21);
    assert_eq!(names[0], "ball world-ball");
    assert_eq!(names[12], "attachment base-attachment");
    // The simulation knows the same joints, with all their elements.
    let joints = scene.joints.clone();
    let sim = &mut scene.simulation;
    assert_eq!(sim.rigid_bodies.named_joints, joints);
    let counts: Vec<_> = joints.iter().map(|j| j.elements.len()).collect();
    assert_eq!(counts, [1, 2, 2, 3, 2, 2, 3, 4, 3, 3, 4, 3, 3, 1, 1, 2, 1, 1, 1, 1, 1]);
    let elements = sim.rigid_bodies.joints.potential.elements.len();
    assert_eq!(elements, counts.iter().sum::<usize>());
    // Parameters arrive in SI units.
    let driver = |sim: &Simulation, name: &str| {
        let h = joints.iter().find(|j| j.label == name).unwrap();
        sim.rigid_bodies.joints.potential.elements[h.driver.unwrap() as usize].clone()
    };
    match driver(sim, "angular_velocity world-angular_velocity").primitive {
        Primitive::AngularVelocity {
            target_rad_s,
            max_torque_n_m,
            delay_rad_s,
            ..
        } => {
            assert_eq!(target_rad_s, 45f64.to_radians());
            assert_eq!(max_torque_n_m, 2.0);
            assert_eq!(delay_rad_s, 1f64.to_radians());
        }
        other => panic!("{other:?}"),
    }
    let servo = driver(sim, "hinge_servo world-hinge_servo").servo.unwrap();
    assert_eq!((servo.target, servo.response_time_s), (30f64.to_radians(), 0.1));
    let spring = driver(sim, "spring world-spring");
    assert_eq!(spring.stiffness, 100.0);
    // Schedules set the targets before each step.
    for _ in 0..3 {
        sim.step().unwrap();
    }
    let t = sim.time();
    match driver(sim, "motor world-motor").primitive {
        Primitive::AngularVelocity { target_rad_s, .. } => {
            assert!((target_rad_s - (90.0 * t).to_radians()).abs() < 1e-12, "{target_rad_s}")
        }
        other => panic!("{other:?}"),
    }
    let servo = driver(sim, "prismatic_servo world-prismatic_servo").servo.unwrap();
    assert!((servo.target - 0.2 * t).abs() < 1e-12);
    // Every joint has a state; the hinge angle is measured.
    let states = sim.joint_states();
    assert_eq!(states.len(), 21);
    assert!(states[2].1.coordinate.is_some());
}

/// The scene's joints are what the loader built before `[[joint]]` deserialised into
/// `JointKind` (issue 12): elements and registered joints, printed with `{:?}`, stored from
/// the code before the change.
#[test]
fn every_joint_type_builds_what_it_built_before_joint_kind() {
    let scene = parse(&all_joints_scene());
    let mut now = String::new();
    for (i, e) in scene
        .simulation
        .rigid_bodies
        .joints
        .potential
        .elements
        .iter()
        .enumerate()
    {
        now += &format!("element {i}: {e:?}\n");
    }
    for h in &scene.simulation.rigid_bodies.named_joints {
        now += &format!("joint: {h:?}\n");
    }
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("src/rigidbodies/joints/testdata/scene_joints_built_before_joint_kind.txt");
    if std::env::var_os("STARK_WRITE_GOLDEN").is_some() {
        std::fs::write(&path, &now).unwrap();
    }
    let before = std::fs::read_to_string(&path).unwrap();
    let (now, before): (Vec<_>, Vec<_>) = (now.lines().collect(), before.lines().collect());
    assert_eq!(now.len(), before.len());
    for (n, b) in now.iter().zip(&before) {
        assert_eq!(n, b);
    }
}

#[test]
fn couplings_name_the_joints_they_couple() {
    let text = "duration_s = 1.0\n\
                [[rigid_body]]\nname = \"a\"\nbox = { size_m = [0.1, 0.1, 0.1] }\nmass_kg = 1.0\n\
                [[rigid_body]]\nname = \"b\"\nbox = { size_m = [0.1, 0.1, 0.1] }\nmass_kg = 1.0\nposition_m = [1.0, 0.0, 0.0]\n\
                [[joint]]\nname = \"h1\"\ntype = \"hinge\"\nb = \"a\"\npoint_m = [0.0, 0.0, 0.0]\naxis = [0.0, 1.0, 0.0]\n\
                [[joint]]\nname = \"h2\"\ntype = \"hinge\"\nb = \"b\"\npoint_m = [1.0, 0.0, 0.0]\naxis = [0.0, 1.0, 0.0]\n\
                [[joint]]\ntype = \"joint_coupling\"\njoint_a = \"h1\"\njoint_b = \"h2\"\nmultiplier = -1.0\n\
                [[joint]]\ntype = \"joint_spring\"\njoint = \"h1\"\nspring_stiffness = 2.0\ndamping = 0.5\n";
    let scene = parse(text);
    let names: Vec<_> = scene.joints.iter().map(|j| j.label.as_str()).collect();
    assert_eq!(names, ["h1", "h2", "joint_coupling", "joint_spring"]);
    let elements = &scene.simulation.rigid_bodies.joints.potential.elements;
    let coupling = &elements[scene.joint("joint_coupling").unwrap().elements[0] as usize];
    match &coupling.primitive {
        Primitive::Coupling(c) => assert_eq!((c.multiplier, c.offset, c.hard), (-1.0, 0.0, true)),
        other => panic!("{other:?}"),
    }
    let spring = &elements[scene.joint("joint_spring").unwrap().elements[0] as usize];
    match &spring.primitive {
        Primitive::Coupling(c) => assert_eq!((c.damping, c.hard), (0.5, false)),
        other => panic!("{other:?}"),
    }
    assert_eq!(spring.stiffness, 2.0);
}

#[test]
fn joint_names_default_and_must_be_unique() {
    let base = "duration_s = 1.0\n[[rigid_body]]\nname = \"a\"\nsphere = { radius_m = 0.1 }\nmass_kg = 1.0\n\
                [[rigid_body]]\nname = \"b\"\nsphere = { radius_m = 0.1 }\nmass_kg = 1.0\nposition_m = [0.0, 0.0, -0.5]\n";
    let ball = "[[joint]]\ntype = \"ball\"\na = \"a\"\nb = \"b\"\npoint_m = [0.0, 0.0, 0.0]\n";
    let scene = parse(&format!("{base}{ball}{ball}"));
    let names: Vec<_> = scene.joints.iter().map(|j| j.label.as_str()).collect();
    assert_eq!(names, ["ball a-b", "ball a-b #2"]);
    // `enabled = false` creates it switched off.
    let off = parse(&format!("{base}{ball}enabled = false\n"));
    let h = &off.joints[0];
    let elements = &off.simulation.rigid_bodies.joints.potential.elements;
    assert!(h.elements.iter().all(|&e| !elements[e as usize].enabled));
    let named = format!("{base}{ball}name = \"j\"\n{ball}name = \"j\"\n");
    let e = parse_err(&named).to_string();
    assert!(
        e.contains("test.toml:22:1: duplicate joint name 'j' in joint 'j' name"),
        "{e}"
    );
}

#[test]
fn rigid_bodies_take_part_in_friction_collisions_and_attachments() {
    let text = r#"
duration_s = 1.0
[settings]
contact.default_thickness_m = 0.001
[[surface]]
name = "flag"
vertices_m = [[0.05, 0.05, 0.6], [0.05, 1.05, 0.6], [0.05, 0.05, 1.6]]
elements = [[0, 1, 2]]
material = "cotton_fabric"
[[rigid_body]]
name = "pole"
box = { size_m = [0.1, 0.1, 0.2] }
mass_kg = 1.0
position_m = [0.0, 0.0, 0.5]
fixed = true
[[rigid_body]]
name = "ghost"
sphere = { radius_m = 0.1 }
mass_kg = 1.0
position_m = [3.0, 0.0, 0.0]
contact = false
[[friction]]
objects = ["flag", "pole"]
mu = 0.4
[[disable_collision]]
objects = ["flag", "pole"]
[[attachment]]
a = "flag"
b = "pole"
within_m = 1e-9
stiffness = 1e5
"#;
    let mut scene = parse(text);
    let pole = scene.rigid_body("pole").unwrap();
    let flag = scene.object("flag").unwrap().contact().unwrap();
    let sim = &mut scene.simulation;
    assert_eq!(sim.contact.friction(flag, pole.contact.unwrap()).unwrap(), 0.4);
    // The flag's corner touches the pole's top corner: only without the collision is that
    // a valid start.
    let (att_label, att) = scene.attachments[0].clone();
    assert_eq!(att_label, "flag-pole");
    for _ in 0..5 {
        sim.step().unwrap();
    }
    // The corner hangs on the pole while the rest of the flag falls.
    let gap = sim.deformables.attachments.max_gap_m(att, &sim.nodes.x).unwrap();
    assert!(gap < 1e-3, "{gap}");
    let flag_x = sim.positions(scene.objects[0].1.nodes()).to_vec();
    assert!(close(&flag_x[0], &Vector3::new(0.05, 0.05, 0.6), 1e-3), "{}", flag_x[0]);
    assert!(flag_x[1].z < 0.5, "{}", flag_x[1]);
    // A body without contact cannot have friction.
    let bad = text.replace(
        "objects = [\"flag\", \"pole\"]\nmu",
        "objects = [\"flag\", \"ghost\"]\nmu",
    );
    let e = parse_err(&bad).to_string();
    assert!(
        e.contains("test.toml:23:20: rigid body 'ghost' takes no part in contact: it has no contact thickness or `contact = false`"),
        "{e}"
    );
}

#[test]
fn json_rigid_scenes_parse() {
    let json = r#"{
  "duration_s": 1.0,
  "rigid_body": [
{ "name": "a", "box": { "size_m": [0.1, 0.1, 0.1] }, "mass_kg": 1.0, "fixed": true },
{ "name": "b", "sphere": { "radius_m": 0.05 }, "mass_kg": 0.5, "position_m": [0.0, 0.0, -0.3] }
  ],
  "joint": [ { "name": "rod", "type": "distance", "a": "a", "b": "b", "point_a_m": [0.0, 0.0, 0.0], "point_b_m": [0.0, 0.0, -0.3] } ]
}"#;
    let scene = parse_scene_with(json, "scene.json", Path::new("."), quiet).unwrap();
    assert_eq!(scene.simulation.num_rigid_bodies(), 2);
    let names: Vec<_> = scene.joints.iter().map(|j| j.label.as_str()).collect();
    assert_eq!(names, ["a.fixed", "rod"]);
    let bad = json.replace("\"distance\"", "\"distanc\"");
    let Err(StarkError::SceneFile(e)) = parse_scene(&bad, "scene.json", Path::new(".")) else {
        panic!("parsed")
    };
    assert_eq!(e.line, Some(7), "{e}");
    assert!(e.to_string().contains("unknown variant `distanc`"), "{e}");
}

const SPAWN_SCENE: &str = r#"
duration_s = 0.4
[settings]
time_step_s = 0.01
contact.default_thickness_m = 0.0005
[[obstacle]]
name = "floor"
box = { size_m = [0.4, 0.4, 0.02] }
translate_m = [0.0, 0.0, -0.01]
[[rigid_body]]
name = "ball"
sphere = { radius_m = 0.01, subdivisions = 2 }
mass_kg = 0.01
spawn = { start_s = 0.05, every_s = 0.1, count = 3, drop_to_gap_m = 0.002, positions_m = [[0.0, 0.0, 0.2], [0.05, 0.0, 0.3]] }
[[friction]]
objects = ["ball", "floor"]
mu = 0.5
[[friction]]
objects = ["ball", "ball"]
mu = 0.2
"#;

#[test]
fn spawned_bodies_come_at_their_times_lowered_onto_the_floor_with_their_friction() {
    let mut sim = parse(SPAWN_SCENE).simulation;
    assert_eq!(sim.num_rigid_bodies(), 0);
    let spawns: Vec<(f64, String)> = sim.spawns().into_iter().map(|(t, l, _)| (t, l.to_string())).collect();
    assert_eq!(
        spawns,
        [
            (0.05, "ball_1".into()),
            (0.15000000000000002, "ball_2".into()),
            (0.25, "ball_3".into())
        ]
    );
    let mut first_z = Vec::new();
    while sim.time() < 0.4 - 1e-9 {
        let before = sim.num_rigid_bodies();
        sim.step().unwrap();
        if sim.num_rigid_bodies() > before {
            let b = sim.rigid_bodies.by_label(&format!("ball_{}", before + 1)).unwrap();
            let ball_1 = sim.rigid_bodies.by_label("ball_1").unwrap();
            first_z.push((sim.body_position(b), sim.body_position(ball_1).z));
        }
        assert!(sim.state_check().intersections.is_empty());
    }
    assert_eq!(sim.num_rigid_bodies(), 3);
    // Each was lowered from its place (0.2 m, 0.3 m, 0.2 m high) to 2 mm above the floor,
    // or for ball 3, 2 mm above ball 1 (its lowest vertex is within 5% of the radius of the
    // sphere's bottom).
    // (The floor's top is at 0 within the micrometres its springs give under the balls.)
    for (k, (z, ball_1_z)) in first_z.iter().enumerate() {
        let below = if k == 2 { ball_1_z + 0.01 } else { 0.0 };
        let gap = z.z - 0.01 - below;
        assert!((0.002 - 1e-6..0.0025).contains(&gap), "ball {}: gap {gap}", k + 1);
    }
    assert_eq!((first_z[0].0.x, first_z[1].0.x, first_z[2].0.x), (0.0, 0.05, 0.0));
    let c = &sim.contact;
    let h = |l: &str| c.object_by_label(l).unwrap();
    assert_eq!(c.friction(h("ball_3"), h("floor")).unwrap(), 0.5);
    assert_eq!(c.friction(h("ball_3"), h("ball_1")).unwrap(), 0.2);
    assert_eq!(c.friction(h("ball_2"), h("ball_1")).unwrap(), 0.2);
}

#[test]
fn spawn_entries_with_bad_values_are_errors_naming_them() {
    for (change, expected) in [
        ("count = 3", "count = 0", "count must be at least 1"),
        ("every_s = 0.1", "every_s = -0.1", "every_s = -0.1 must be non-negative"),
        (
            "drop_to_gap_m = 0.002",
            "drop_to_gap_m = 0.0",
            "drop_to_gap_m = 0 must be positive",
        ),
        (
            "mass_kg = 0.01",
            "mass_kg = 0.01\nfixed = true",
            "a spawned body cannot take `fixed`",
        ),
    ]
    .map(|(a, b, e)| ((a, b), e))
    {
        let text = SPAWN_SCENE.replace(change.0, change.1);
        let e = parse_err(&text);
        assert!(e.to_string().contains(expected), "{}: {e}", change.1);
    }
    let clash = format!("{SPAWN_SCENE}[[obstacle]]\nname = \"ball_2\"\nbox = {{ size_m = [0.1, 0.1, 0.1] }}\n");
    let e = parse_err(&clash);
    assert!(e.to_string().contains("would take the name 'ball_2'"), "{e}");
    let disabled = format!("{SPAWN_SCENE}[[disable_collision]]\nobjects = [\"ball\", \"floor\"]\n");
    let e = parse_err(&disabled);
    assert!(e.to_string().contains("'ball' is spawned during the run"), "{e}");
}

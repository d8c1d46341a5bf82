//! Scene files against the same scenes built through the API (or the built-in scenes), bit for
//! bit.

use super::*;

#[test]
fn default_scene_matches_the_builtin_hanging_cloth_bit_for_bit() {
    let mut from_file = load_scene_with(&repo_scene("default.toml"), |s| {
        quiet(s);
        crate::scenes::stark_tolerances(s);
    })
    .unwrap()
    .simulation;
    let mut settings = Settings::default();
    quiet(&mut settings);
    let mut builtin = crate::scenes::hanging_cloth(settings).unwrap();
    assert_eq!(from_file.settings.newton, builtin.settings.newton);
    assert_eq!(bits(&from_file.nodes.x), bits(&builtin.nodes.x));
    for _ in 0..3 {
        from_file.step().unwrap();
        builtin.step().unwrap();
    }
    assert!(builtin.nodes.x.iter().any(|p| p.z < -0.01), "nothing moved");
    assert_eq!(bits(&from_file.nodes.x), bits(&builtin.nodes.x));
}

#[test]
fn box_scene_matches_the_builtin_hanging_deformable_box() {
    let scene = load_scene_with(&repo_scene("hanging_deformable_box.toml"), quiet).unwrap();
    let mut from_file = scene.simulation;
    let mut settings = Settings::default();
    quiet(&mut settings);
    let mut builtin = crate::scenes::hanging_deformable_box(settings).unwrap();
    // The file writes the tolerances as decimals: equal to the built-in's within rounding.
    let (f, b) = (&from_file.settings, &builtin.settings);
    assert_eq!(f.time_step_s, b.time_step_s);
    assert_eq!(f.newton.step_tolerance_m_s, b.newton.step_tolerance_m_s);
    let rel = (f.newton.residual_tolerance_n / b.newton.residual_tolerance_n - 1.0).abs();
    assert!(rel < 1e-15, "{rel}");
    assert_eq!((scene.duration_s * 30.0).round(), 151.0);
    assert_eq!(from_file.nodes.len(), 2331);
    assert_eq!(from_file.deformables.tets.num_elements(), 12000);
    assert_eq!(bits(&from_file.nodes.x), bits(&builtin.nodes.x));
    from_file.settings.newton = builtin.settings.newton.clone();
    from_file.step().unwrap();
    builtin.step().unwrap();
    assert_eq!(bits(&from_file.nodes.x), bits(&builtin.nodes.x));
}

#[test]
fn franka_cup_scene_matches_the_builtin() {
    let scene = load_scene_with(&repo_scene("franka_cup.toml"), quiet).unwrap();
    let mut from_file = scene.simulation;
    let mut settings = Settings::default();
    quiet(&mut settings);
    let mut builtin = crate::scenes::franka_cup_scene(settings).unwrap();
    from_file.settings.name = builtin.settings.name.clone();
    assert_eq!(from_file.settings, builtin.settings);
    assert_eq!(from_file.nodes.len(), builtin.nodes.len());
    let close = |a: &[Vector3<f64>], b: &[Vector3<f64>]| a.iter().zip(b).all(|(p, q)| (p - q).norm() < 1e-12);
    assert!(close(&from_file.nodes.x, &builtin.nodes.x));
    assert!(close(&from_file.nodes.rest, &builtin.nodes.rest));
    let labels = |s: &Simulation| -> Vec<(String, f64)> {
        s.contact
            .objects()
            .iter()
            .map(|o| (o.label.clone(), o.thickness_m))
            .collect()
    };
    assert_eq!(labels(&from_file), labels(&builtin));
    let n = from_file.contact.objects().len();
    for a in 0..n {
        for b in 0..n {
            let (ha, hb) = (ContactHandle(a as u32), ContactHandle(b as u32));
            let (cf, cb) = (&from_file.contact, &builtin.contact);
            assert_eq!(cf.friction(ha, hb).unwrap(), cb.friction(ha, hb).unwrap(), "{a} {b}");
            assert_eq!(
                cf.collision_enabled(ha, hb).unwrap(),
                cb.collision_enabled(ha, hb).unwrap()
            );
        }
    }
    let spawns =
        |s: &Simulation| -> Vec<(f64, String)> { s.spawns().into_iter().map(|(t, l, _)| (t, l.to_string())).collect() };
    assert_eq!(spawns(&from_file), spawns(&builtin));
    // A few steps of the closing jaws agree (the hand's height is written out in the file).
    for _ in 0..3 {
        from_file.step().unwrap();
        builtin.step().unwrap();
    }
    assert!(from_file
        .nodes
        .x
        .iter()
        .zip(&builtin.nodes.x)
        .all(|(p, q)| (p - q).norm() < 1e-9));
}

#[test]
fn cloth_on_sphere_scene_matches_the_builtin() {
    let scene = load_scene_with(&repo_scene("cloth_on_sphere.toml"), quiet).unwrap();
    assert_eq!((scene.name.as_str(), scene.duration_s), ("cloth_on_sphere", 3.0));
    let Some(SceneObject::Obstacle(sphere)) = scene.object("sphere").copied() else {
        panic!("no obstacle 'sphere'")
    };
    let mut from_file = scene.simulation;
    let mut settings = Settings::default();
    quiet(&mut settings);
    let mut builtin = crate::scenes::cloth_on_sphere(settings).unwrap();
    assert_eq!(from_file.settings, builtin.settings);
    // Same nodes (the cloth's 33², then the sphere's 642) at the same positions.
    assert_eq!(from_file.nodes.len(), 33 * 33 + 642);
    assert_eq!(from_file.nodes.len(), builtin.nodes.len());
    assert_eq!(bits(&from_file.nodes.x), bits(&builtin.nodes.x));
    let d = (&from_file.deformables, &builtin.deformables);
    assert_eq!(d.0.triangles.num_elements(), d.1.triangles.num_elements());
    assert_eq!(d.0.flat_bending.num_elements(), d.1.flat_bending.num_elements());
    // Same contact objects, thicknesses and friction coefficients.
    let (fc, bc) = (&from_file.contact, &builtin.contact);
    let describe = |c: &crate::contact::Contact| -> Vec<(String, f64, u32, u32)> {
        c.objects()
            .iter()
            .map(|o| (o.label.clone(), o.thickness_m, o.nodes.first, o.nodes.len))
            .collect()
    };
    assert_eq!(describe(fc), describe(bc));
    assert_eq!(
        describe(fc),
        [("cloth".into(), 0.002, 0, 1089), ("sphere".into(), 0.002, 1089, 642)]
    );
    for a in 0..2 {
        for b in 0..2 {
            let (ha, hb) = (ContactHandle(a), ContactHandle(b));
            assert_eq!(fc.friction(ha, hb).unwrap(), bc.friction(ha, hb).unwrap());
        }
    }
    assert_eq!(fc.friction(ContactHandle(0), sphere.contact).unwrap(), 0.5);
    // The sphere is held as in the built-in scene.
    let pp = (&d.0.prescribed, &d.1.prescribed);
    assert_eq!(
        pp.0.params(sphere.prescribed).unwrap(),
        pp.1.params(PrescribedHandle(0)).unwrap()
    );
    assert_eq!(pp.0.params(sphere.prescribed).unwrap().stiffness, 1e6);
    assert_eq!(from_file.output.meshes.len(), builtin.output.meshes.len());
    // One step (the cloth is still 5 cm above the sphere) gives the same positions.
    from_file.step().unwrap();
    builtin.step().unwrap();
    assert!(builtin.nodes.x.iter().any(|p| p.z < -1e-3), "nothing moved");
    assert_eq!(bits(&from_file.nodes.x), bits(&builtin.nodes.x));
}

/// `scenes/rb_pendulum_chain.toml` built with the Rust API.
fn pendulum_chain_in_rust(settings: Settings) -> Simulation {
    let mut sim = Simulation::new(settings).unwrap();
    let size = Vector3::new(0.2, 0.03, 0.03);
    let link = meshes::box_mesh(size);
    let mut links = Vec::new();
    for i in 0..5 {
        let b = sim
            .add_rigid_body_with(
                &format!("link{i}"),
                &MassProperties::cuboid(0.2, size),
                Vector3::new([0.1, 0.3, 0.5, 0.7, 0.9][i], 0.0, 0.0),
                UnitQuaternion::identity(),
            )
            .unwrap();
        sim.add_rigid_output_mesh(b, &link.vertices, &link.elements).unwrap();
        links.push(b);
    }
    let (r, h) = (0.15, 0.02);
    let disc = meshes::cylinder_mesh(r, h, 24, 1);
    let q = UnitQuaternion::from_axis_angle(&Unit::new_normalize(Vector3::x()), 90f64.to_radians());
    let wheel = sim
        .add_rigid_body_with(
            "wheel",
            &MassProperties::cylinder(1000.0 * (PI * r * r * h), r, h),
            Vector3::new(0.0, 0.5, 0.0),
            q,
        )
        .unwrap();
    sim.add_rigid_output_mesh(wheel, &disc.vertices, &disc.elements)
        .unwrap();
    let p = JointParams::default();
    sim.add_hinge_joint("pivot", None, links[0], Vector3::zeros(), Vector3::y(), p)
        .unwrap();
    for i in 1..5 {
        let at = Vector3::new([0.2, 0.4, 0.6, 0.8][i - 1], 0.0, 0.0);
        sim.add_hinge_joint(&format!("hinge{i}"), Some(links[i - 1]), links[i], at, Vector3::y(), p)
            .unwrap();
    }
    sim.add_motor(
        "motor",
        None,
        wheel,
        Vector3::new(0.0, 0.5, 0.0),
        Vector3::y(),
        90f64.to_radians(),
        1.0,
        DEFAULT_CONTROLLER_DELAY,
        p,
    )
    .unwrap();
    sim
}

#[test]
fn pendulum_chain_scene_matches_the_same_scene_built_in_rust() {
    let scene = load_scene_with(&repo_scene("rb_pendulum_chain.toml"), quiet).unwrap();
    assert_eq!((scene.name.as_str(), scene.duration_s), ("rb_pendulum_chain", 3.0));
    let mut from_file = scene.simulation;
    let mut settings = from_file.settings.clone();
    quiet(&mut settings);
    let mut in_rust = pendulum_chain_in_rust(settings);
    assert_eq!(from_file.bodies.mass, in_rust.bodies.mass);
    assert_eq!(from_file.bodies.inertia_local, in_rust.bodies.inertia_local);
    assert_eq!(body_bits(&from_file), body_bits(&in_rust));
    assert_eq!(bits(&from_file.nodes.x), bits(&in_rust.nodes.x));
    assert_eq!(from_file.rigid_bodies.named_joints, in_rust.rigid_bodies.named_joints);
    assert!(from_file.contact.objects().is_empty());
    for _ in 0..4 {
        from_file.step().unwrap();
        in_rust.step().unwrap();
    }
    assert!(
        in_rust.body_position(RigidBodyHandle { index: 4 }).z < -1e-3,
        "nothing moved"
    );
    assert_eq!(body_bits(&from_file), body_bits(&in_rust));
    assert_eq!(bits(&from_file.nodes.x), bits(&in_rust.nodes.x));
    assert_eq!(from_file.joint_states(), in_rust.joint_states());
}

/// `scenes/rb_box_on_cloth.toml` built with the Rust API.
fn box_on_cloth_in_rust(settings: Settings) -> Simulation {
    use crate::deformables::PrescribedParams;
    use crate::presets::SurfaceMaterial;
    let mut sim = Simulation::new(settings).unwrap();
    let grid = meshes::triangle_grid([0.0, 0.0], [1.0, 1.0], [20, 20], 0.0);
    let material = SurfaceMaterial {
        contact_thickness_m: Some(0.002),
        ..SurfaceMaterial::cotton_fabric()
    };
    let cloth = sim
        .add_surface("cloth", &grid.vertices, &grid.elements, &material)
        .unwrap();
    let size = Vector3::repeat(0.15);
    let cube = meshes::box_mesh(size);
    let q = UnitQuaternion::from_axis_angle(&Unit::new_normalize(Vector3::new(1.0, 1.0, 0.0)), 30f64.to_radians());
    let body = sim
        .add_rigid_body_with(
            "box",
            &MassProperties::cuboid(0.5, size),
            Vector3::new(0.1, 0.0, 0.2),
            q,
        )
        .unwrap();
    let box_mesh = sim
        .add_rigid_collision_mesh(body, &cube.vertices, &cube.elements, Some(0.002))
        .unwrap();
    let paddle_size = Vector3::new(0.1, 0.4, 0.02);
    let plate = meshes::box_mesh(paddle_size);
    let start = Vector3::new(-0.3, 0.0, -0.15);
    let paddle = sim
        .add_rigid_body_with(
            "paddle",
            &MassProperties::cuboid(1.0, paddle_size),
            start,
            UnitQuaternion::identity(),
        )
        .unwrap();
    let paddle_mesh = sim
        .add_rigid_collision_mesh(paddle, &plate.vertices, &plate.elements, Some(0.002))
        .unwrap();
    let fix = sim
        .add_fix_joint("paddle.fixed", paddle, JointParams::default())
        .unwrap();
    let tilt = UnitQuaternion::from_axis_angle(&Unit::new_normalize(Vector3::y()), 20f64.to_radians());
    let poses: Poses = vec![
        (0.0, start, UnitQuaternion::identity()),
        (1.0, start, UnitQuaternion::identity()),
        (1.5, Vector3::new(-0.25, 0.0, -0.05), tilt),
        (2.0, Vector3::new(-0.2, 0.0, -0.1), tilt),
    ];
    sim.add_time_event(0.0, f64::INFINITY, move |sim, t| {
        let (p, q) = keyframe_pose(&poses, t);
        sim.set_fixed_transform(&fix, p, q)
    });
    let c = cloth.contact.unwrap();
    sim.contact.set_friction(c, box_mesh.contact, 0.5).unwrap();
    sim.contact.set_friction(c, paddle_mesh.contact, 0.3).unwrap();
    let pin = PrescribedParams {
        stiffness: 1e6,
        ..Default::default()
    };
    for x in [-0.5, 0.5] {
        for y in [-0.5, 0.5] {
            sim.deformables
                .prescribed
                .add_in_box(
                    &sim.nodes,
                    cloth.nodes,
                    "cloth",
                    Vector3::new(x, y, 0.0),
                    Vector3::repeat(0.001),
                    true,
                    pin.clone(),
                )
                .unwrap();
        }
    }
    sim
}

#[test]
fn box_on_cloth_scene_matches_the_same_scene_built_in_rust() {
    let scene = load_scene_with(&repo_scene("rb_box_on_cloth.toml"), quiet).unwrap();
    let mut from_file = scene.simulation;
    let mut in_rust = box_on_cloth_in_rust(from_file.settings.clone());
    assert_eq!(from_file.settings, in_rust.settings);
    assert_eq!(body_bits(&from_file), body_bits(&in_rust));
    assert_eq!(bits(&from_file.nodes.x), bits(&in_rust.nodes.x));
    let describe = |c: &crate::contact::Contact| -> Vec<(String, f64, u32, u32)> {
        c.objects()
            .iter()
            .map(|o| (o.label.clone(), o.thickness_m, o.nodes.first, o.nodes.len))
            .collect()
    };
    assert_eq!(describe(&from_file.contact), describe(&in_rust.contact));
    for _ in 0..3 {
        from_file.step().unwrap();
        in_rust.step().unwrap();
    }
    assert!(
        in_rust.body_position(RigidBodyHandle { index: 0 }).z < 0.2 - 1e-3,
        "nothing moved"
    );
    assert_eq!(body_bits(&from_file), body_bits(&in_rust));
    assert_eq!(bits(&from_file.nodes.x), bits(&in_rust.nodes.x));
}

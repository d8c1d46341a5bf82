//! The built-in scenes' builders: the original Stark's scenes replicated, and this project's own
//! (contact, grasp and towel benchmarks).

use super::*;

/// The original's convergence settings: residual 1e-6 on the momentum-unit gradient (1e-6/dt N)
/// or a Newton step below 1 mm/s.
pub fn stark_tolerances(settings: &mut Settings) {
    settings.newton.residual_tolerance_n = 1e-6 / settings.time_step_s;
    settings.newton.step_tolerance_m_s = 1e-3;
}

/// The default scene (`stark run` without arguments): the original's hanging cloth, but with this
/// project's default convergence criterion (force residual below 1e-6 N, no step criterion).
pub fn default_scene(mut settings: Settings) -> Result<Simulation> {
    settings.name = "default".into();
    settings.time_step_s = 1.0 / 30.0;
    let mut sim = Simulation::new(settings)?;
    let cloth = sim.add_surface_grid("cloth", [1.0, 1.0], [32, 32], &SurfaceMaterial::cotton_fabric())?;
    let pin = PrescribedParams {
        stiffness: 1e6,
        ..Default::default()
    };
    for x in [0.5, -0.5] {
        sim.prescribe_in_box(
            cloth.nodes,
            Vector3::new(x, 0.5, 0.0),
            Vector3::repeat(0.001),
            pin.clone(),
        )?;
    }
    Ok(sim)
}

/// `hanging_cloth` of the original (`examples/main.cpp`): 1 m × 1 m cotton fabric, 32×32 quads,
/// the two corners at y = +0.5 prescribed (k = 1e6 N/m), no contact, dt = 1/30 s.
pub fn hanging_cloth(settings: Settings) -> Result<Simulation> {
    hanging_cloth_n(settings, 32, "hanging_cloth")
}

pub(super) fn hanging_cloth_n(mut settings: Settings, n: usize, name: &str) -> Result<Simulation> {
    settings.name = name.into();
    settings.time_step_s = 1.0 / 30.0;
    stark_tolerances(&mut settings);
    let mut sim = Simulation::new(settings)?;
    let cloth = sim.add_surface_grid("cloth", [1.0, 1.0], [n, n], &SurfaceMaterial::cotton_fabric())?;
    let pin = PrescribedParams {
        stiffness: 1e6,
        ..Default::default()
    };
    for x in [0.5, -0.5] {
        sim.prescribe_in_box(
            cloth.nodes,
            Vector3::new(x, 0.5, 0.0),
            Vector3::repeat(0.001),
            pin.clone(),
        )?;
    }
    Ok(sim)
}

/// `hanging_deformable_box` of the original: 0.5 m cube of soft rubber (E = 1e4 Pa), 10 cells per
/// side (2331 nodes, 12000 tets), two top corners at y = +0.25 prescribed (k = 1e7 N/m).
pub fn hanging_deformable_box(mut settings: Settings) -> Result<Simulation> {
    settings.name = "hanging_deformable_box".into();
    settings.time_step_s = 1.0 / 30.0;
    stark_tolerances(&mut settings);
    let mut sim = Simulation::new(settings)?;
    let mut material = VolumeMaterial::soft_rubber();
    material.strain.youngs_modulus = 1e4;
    let body = sim.add_volume_grid("box", [0.5, 0.5, 0.5], [10, 10, 10], &material)?;
    let pin = PrescribedParams {
        stiffness: 1e7,
        ..Default::default()
    };
    for x in [0.25, -0.25] {
        sim.prescribe_in_box(
            body.nodes,
            Vector3::new(x, 0.25, 0.25),
            Vector3::repeat(0.001),
            pin.clone(),
        )?;
    }
    Ok(sim)
}

/// A cotton cloth falling onto a fixed sphere (radius 0.25 m, 642 vertices): it drapes and comes
/// to rest; self-contact on, friction 0.5 against the sphere, contact thickness 2 mm, dt = 1/30 s,
/// the original's convergence criteria (as for all contact scenes).
pub fn cloth_on_sphere(mut settings: Settings) -> Result<Simulation> {
    settings.name = "cloth_on_sphere".into();
    settings.time_step_s = 1.0 / 30.0;
    stark_tolerances(&mut settings);
    settings.contact.default_thickness_m = Some(0.002);
    let mut sim = Simulation::new(settings)?;
    let mut cotton = SurfaceMaterial::cotton_fabric();
    cotton.contact_thickness_m = Some(0.002);
    let cloth = sim.add_surface_grid("cloth", [1.0, 1.0], [32, 32], &cotton)?;
    let mut sphere = meshes::sphere_mesh(0.25, 3);
    for v in &mut sphere.vertices {
        v.z -= 0.3;
    }
    let sphere = sim.add_prescribed_surface("sphere", &sphere.vertices, &sphere.elements, 0.002, 1e6)?;
    let cloth_contact = cloth.contact.expect("cloth has contact");
    sim.contact.set_friction(cloth_contact, sphere.contact, 0.5)?;
    Ok(sim)
}

/// `spinning_box_cloth`, the original's hello world (`benchmark-scenes.md` §6): a 0.4 m cotton
/// cloth (32×32) at z = 0 falls onto a 0.08 m box whose target is translated by
/// (0, 0, −0.08 − 0.1 sin t) and rotated by 90°·t about z. Contact thickness 2 mm, self-contact
/// on, no friction, dt = 1/30 s, 301 steps, the original's tolerances. As in the original, the box
/// is a 1 kg rigid body driven by a fix joint (k = 1e6 N/m, 1 mm / 1° tolerance).
pub fn spinning_box_cloth(mut settings: Settings) -> Result<Simulation> {
    settings.name = "spinning_box_cloth".into();
    settings.time_step_s = 1.0 / 30.0;
    stark_tolerances(&mut settings);
    settings.contact.default_thickness_m = Some(0.002);
    let mut sim = Simulation::new(settings)?;
    sim.add_surface_grid("cloth", [0.4, 0.4], [32, 32], &SurfaceMaterial::cotton_fabric())?;
    let (body, _) = rigid_box(
        &mut sim,
        "box",
        1.0,
        Vector3::repeat(0.08),
        Vector3::new(0.0, 0.0, -0.08),
        None,
    )?;
    let fix = sim.add_fix_joint("box_drive", body, JointParams::default())?;
    sim.add_time_event(0.0, f64::INFINITY, move |sim, t| {
        sim.set_fixed_transform_deg(
            &fix,
            Vector3::new(0.0, 0.0, -0.08 - 0.1 * t.sin()),
            90.0 * t,
            Vector3::z(),
        )
    });
    Ok(sim)
}

/// A rigid box of `mass_kg` and side lengths `size` (m), centred at `position` (m), with the
/// 8-vertex/12-triangle collision mesh of the original's `add_box`.
pub fn rigid_box(
    sim: &mut Simulation,
    label: &str,
    mass_kg: f64,
    size: Vector3<f64>,
    position: Vector3<f64>,
    thickness_m: Option<f64>,
) -> Result<(RigidBodyHandle, ContactHandle)> {
    let props = MassProperties::cuboid(mass_kg, size);
    let body = sim.add_rigid_body_with(label, &props, position, UnitQuaternion::identity())?;
    let mesh = meshes::box_mesh(size);
    let m = sim.add_rigid_collision_mesh(body, &mesh.vertices, &mesh.elements, thickness_m)?;
    Ok((body, m.contact))
}

/// `rb_constraints_point` of the original (`examples/rb_constraint_test_scenes.cpp`): ten 0.1 m,
/// 1 kg boxes in a row along x, box 0 fixed, box i joined to box i − 1 by a ball joint at
/// (0.05 + 0.1(i − 1), ∓0.05, ∓0.05) (− for odd i, + for even), so the chain folds down under
/// gravity. No contact; k = 1e6 N/m, tolerance 1 mm; dt = 1/30 s; the original's tolerances.
pub fn rb_point(mut settings: Settings) -> Result<Simulation> {
    settings.name = "rb_point".into();
    // A small system stiffened by rigid bodies (joints, contact on lever arms): one sparse
    // factorisation per Newton iteration beats block-Jacobi CG (~80 iterations per solve here).
    settings.newton.linear_solver = crate::solver::LinearSolver::Cholesky;
    settings.time_step_s = 1.0 / 30.0;
    stark_tolerances(&mut settings);
    let mut sim = Simulation::new(settings)?;
    let size = Vector3::repeat(0.1);
    let props = MassProperties::cuboid(1.0, size);
    let cube = meshes::box_mesh(size);
    let mut prev = sim.add_rigid_body_with("box0", &props, Vector3::zeros(), UnitQuaternion::identity())?;
    sim.add_rigid_output_mesh(prev, &cube.vertices, &cube.elements)?;
    sim.add_fix_joint("fix", prev, JointParams::default())?;
    for i in 1..10 {
        let body = sim.add_rigid_body_with(
            &format!("box{i}"),
            &props,
            Vector3::new(0.1 * i as f64, 0.0, 0.0),
            UnitQuaternion::identity(),
        )?;
        sim.add_rigid_output_mesh(body, &cube.vertices, &cube.elements)?;
        let s = if i % 2 == 1 { -0.05 } else { 0.05 };
        let p = Vector3::new(0.05 + (i - 1) as f64 * 0.1, s, s);
        sim.add_ball_joint(&format!("ball{i}"), Some(prev), body, p, JointParams::default())?;
        prev = body;
    }
    Ok(sim)
}

/// `deformable_and_rigid_collisions` of the original (`examples/main.cpp`): a 0.25 m soft-rubber
/// box (5³ cells, 1000 kg/m³, E = 1e4 Pa, thickness 0.25 mm) 1 cm above a fixed rigid floor
/// (2 × 2 × 0.1 m, thickness 2 mm) and a 0.1 m box (2³ cells, 1e4 kg/m³, E = 1e5 Pa, thickness
/// 0.1 mm) 1 cm above it, offset by (13, 7) mm; μ = 1 for all pairs, ε_v = 0.01 m/s; dt = 1/30 s.
pub fn deformable_and_rigid_collisions(mut settings: Settings) -> Result<Simulation> {
    settings.name = "deformable_and_rigid_collisions".into();
    // Block-Jacobi PCG, as the original: ~26 CG iterations per Newton iteration here, a quarter
    // less wall time than a sparse factorisation per iteration (BENCHMARKS.md, 2026-12-06).
    settings.time_step_s = 1.0 / 30.0;
    stark_tolerances(&mut settings);
    settings.contact.friction_stick_slide_threshold_m_s = 0.01;
    let mut sim = Simulation::new(settings)?;
    let (d1, d2, gap) = (0.25, 0.1, 0.01);
    let mut rubber = VolumeMaterial::soft_rubber();
    rubber.contact_thickness_m = Some(0.001 * d1);
    rubber.inertia.density = 1e3;
    let mut m1 = meshes::tet_grid(Vector3::zeros(), Vector3::repeat(d1), [5, 5, 5]);
    m1.vertices.iter_mut().for_each(|v| v.z += 0.5 * d1 + gap);
    let a = sim.add_volume("box_a", &m1.vertices, &m1.elements, &rubber)?;
    rubber.contact_thickness_m = Some(0.001 * d2);
    rubber.inertia.density = 1e4;
    rubber.strain.youngs_modulus = 1e5;
    let mut m2 = meshes::tet_grid(Vector3::zeros(), Vector3::repeat(d2), [2, 2, 2]);
    let shift = Vector3::new(0.13 * d2, 0.07 * d2, d1 + 0.5 * d2 + 2.0 * gap);
    m2.vertices.iter_mut().for_each(|v| *v += shift);
    let b = sim.add_volume("box_b", &m2.vertices, &m2.elements, &rubber)?;
    let d3 = 2.0;
    let (floor, floor_contact) = rigid_box(
        &mut sim,
        "floor",
        1.0,
        Vector3::new(d3, d3, 0.05 * d3),
        Vector3::new(0.0, 0.0, -0.025 * d3),
        Some(0.001 * d3),
    )?;
    sim.add_fix_joint("floor_fix", floor, JointParams::default())?;
    let (ca, cb) = (a.contact.expect("thickness"), b.contact.expect("thickness"));
    for (x, y) in [(floor_contact, ca), (floor_contact, cb), (ca, cb)] {
        sim.contact.set_friction(x, y, 1.0)?;
    }
    Ok(sim)
}

/// `simple_grasp` of the original (`examples/main.cpp`): a 0.2 m soft cube (5³ cells, 1 kg,
/// E = 2e3 Pa, elasticity only) between two rigid fingers (0.1 × 0.4 × 0.4 m, 1 kg) on a fixed
/// rigid hand (0.6 m cube); each finger is a prismatic press on the hand along x driven at 1 m/s
/// toward the cube with at most 5 N. No gravity until it ramps linearly to −10 m/s² over
/// t = 2–3 s. Finger friction μ = 1.05 (holds: 2 × 5 N × 1.05 > 10 N), 0.95 from t = 5 s
/// (slides). Thickness 1 mm, ε_v = 1e-3 m/s, dt = 1/30 s.
pub fn simple_grasp(settings: Settings) -> Result<Simulation> {
    simple_grasp_with(settings, 1.05, 0.95, 5.0)
}

/// [`simple_grasp`] with the friction `mu_hold` before and `mu_slide` from `slide_from_s`.
pub fn simple_grasp_with(mut settings: Settings, mu_hold: f64, mu_slide: f64, slide_from_s: f64) -> Result<Simulation> {
    settings.name = "simple_grasp".into();
    // Block-Jacobi PCG, as the original: ~19 CG iterations per Newton iteration here, a quarter
    // less wall time than a sparse factorisation per iteration (BENCHMARKS.md, 2026-12-06).
    settings.time_step_s = 1.0 / 30.0;
    settings.gravity_m_s2 = [0.0; 3];
    stark_tolerances(&mut settings);
    settings.contact.default_thickness_m = Some(0.001);
    settings.contact.friction_stick_slide_threshold_m_s = 1e-3;
    let mut sim = Simulation::new(settings)?;
    let (d, gap, mass, pressure_n) = (0.2, 0.02, 1.0, 10.0);
    let hd = d / 2.0;
    let mut rubber = VolumeMaterial::soft_rubber();
    rubber.inertia.density = mass / (d * d * d);
    rubber.strain.youngs_modulus = 2e3;
    rubber.strain.strain_limit = f64::INFINITY;
    rubber.strain.damping = 0.0;
    let object = sim.add_volume_grid("object", [d, d, d], [5, 5, 5], &rubber)?;
    let object_contact = object.contact.expect("default thickness");
    let (hand, hand_contact) = rigid_box(
        &mut sim,
        "hand",
        mass,
        Vector3::repeat(3.0 * d),
        Vector3::new(0.0, -(3.0 * hd + hd + gap), 0.0),
        None,
    )?;
    let finger_size = Vector3::new(0.5 * d, 2.0 * d, 2.0 * d);
    let x = hd + 0.5 * hd + gap;
    let (left, left_contact) = rigid_box(
        &mut sim,
        "left_finger",
        mass,
        finger_size,
        Vector3::new(-x, -gap, 0.0),
        None,
    )?;
    let (right, right_contact) = rigid_box(
        &mut sim,
        "right_finger",
        mass,
        finger_size,
        Vector3::new(x, -gap, 0.0),
        None,
    )?;
    sim.contact.disable_collision(hand_contact, left_contact)?;
    sim.contact.disable_collision(hand_contact, right_contact)?;
    sim.add_fix_joint("hand_fix", hand, JointParams::default())?;
    let params = JointParams::default();
    let f = 0.5 * pressure_n;
    sim.add_prismatic_press(
        "left_press",
        Some(hand),
        left,
        Vector3::zeros(),
        Vector3::x(),
        1.0,
        f,
        0.01,
        params,
    )?;
    sim.add_prismatic_press(
        "right_press",
        Some(hand),
        right,
        Vector3::zeros(),
        Vector3::x(),
        -1.0,
        f,
        0.01,
        params,
    )?;
    sim.contact.set_friction(left_contact, object_contact, mu_hold)?;
    sim.contact.set_friction(right_contact, object_contact, mu_hold)?;
    sim.add_time_event(2.0, 3.0, |sim, t| {
        sim.set_gravity(Vector3::new(0.0, 0.0, -10.0 * (t - 2.0)));
        Ok(())
    });
    sim.add_time_event(3.0, f64::INFINITY, |sim, _| {
        sim.set_gravity(Vector3::new(0.0, 0.0, -10.0));
        Ok(())
    });
    sim.add_time_event(slide_from_s, f64::INFINITY, move |sim, _| {
        sim.contact.set_friction(left_contact, object_contact, mu_slide)?;
        sim.contact.set_friction(right_contact, object_contact, mu_slide)
    });
    Ok(sim)
}

/// Stark's `blend(.., EaseInOut)`: cubic ease in and out from 0 to 1 over `[0, 1]`.
pub(super) fn ease_in_out(t: f64) -> f64 {
    let t = t.clamp(0.0, 1.0);
    if t < 0.5 {
        4.0 * t * t * t
    } else {
        1.0 - (2.0 - 2.0 * t).powi(3) / 2.0
    }
}

/// `boxes_on_cloth` of the original's Python examples: a 0.5 m cotton cloth (64×64, strain-limit
/// stiffness 1e7, inertial damping 1/s, strain damping 10) lies on a fixed rigid floor
/// (1 × 10 × 0.05 m); 24 rigid 0.08 m, 1 kg boxes stand on it in 8 layers of 3. Gravity ramps to
/// −9.81 m/s² over the first second, then the cloth's edge y = 0.25 is lifted 0.1 m (1–2 s,
/// ease in-out) and pulled 1 m along y (2–10 s). μ = 0.5 everywhere, thickness 0.5 mm,
/// ε_v = 0.01 m/s; dt = 1/30 s; residual 1e-6 (the original's step tolerance is 1e-6 m/s).
pub fn boxes_on_cloth(mut settings: Settings) -> Result<Simulation> {
    settings.name = "boxes_on_cloth".into();
    settings.time_step_s = 1.0 / 30.0;
    settings.gravity_m_s2 = [0.0; 3];
    settings.newton.residual_tolerance_n = 1e-6 / settings.time_step_s;
    settings.newton.step_tolerance_m_s = 1e-6;
    let thickness = 0.0005;
    settings.contact.default_thickness_m = Some(thickness);
    settings.contact.friction_stick_slide_threshold_m_s = 0.01;
    let mut sim = Simulation::new(settings)?;
    let (floor, floor_contact) = rigid_box(
        &mut sim,
        "floor",
        1.0,
        Vector3::new(1.0, 10.0, 0.05),
        Vector3::new(0.0, 4.0, -0.05 / 2.0 - thickness),
        None,
    )?;
    let fix = sim.add_fix_joint("floor_fix", floor, JointParams::default())?;
    sim.set_joint_stiffness(&fix, 1e8)?;
    let mut cotton = SurfaceMaterial::cotton_fabric();
    cotton.strain.strain_limit_stiffness = 1e7;
    cotton.inertia.damping = 1.0;
    cotton.strain.damping = 10.0;
    let s = 0.5;
    let mut grid = meshes::triangle_grid([0.0, 0.0], [s, s], [64, 64], 0.0);
    grid.vertices.iter_mut().for_each(|v| v.z += 2.0 * thickness);
    let cloth = sim.add_surface("cloth", &grid.vertices, &grid.elements, &cotton)?;
    let cloth_contact = cloth.contact.expect("default thickness");
    sim.contact.set_friction(floor_contact, cloth_contact, 0.5)?;
    let edge = sim.prescribe_in_box(
        cloth.nodes,
        Vector3::new(0.0, s / 2.0, 2.0 * thickness),
        Vector3::new(s, 0.001, s),
        PrescribedParams::default(),
    )?;
    let (mu, side) = (0.5, 0.08);
    let box_height = side + 2.0 * thickness;
    let box_base = side / 2.0 + 3.0 * thickness;
    let mut boxes: Vec<ContactHandle> = Vec::new();
    for i in 0..8 {
        for j in 0..3 {
            let y = if j == 1 { -side } else { -1.5 * side };
            let position = Vector3::new(
                -box_height / 2.0 + j as f64 * box_height,
                y,
                box_base + i as f64 * box_height,
            );
            let (_, c) = rigid_box(
                &mut sim,
                &format!("box{}", 3 * i + j),
                1.0,
                Vector3::repeat(side),
                position,
                None,
            )?;
            sim.contact.set_friction(c, cloth_contact, mu)?;
            sim.contact.set_friction(c, floor_contact, mu)?;
            for &other in &boxes {
                sim.contact.set_friction(c, other, mu)?;
            }
            boxes.push(c);
        }
    }
    let (lift_start, pull_start) = (1.0, 2.0);
    sim.add_time_event(0.0, lift_start, move |sim, t| {
        sim.set_gravity(Vector3::new(0.0, 0.0, -9.81 * t / lift_start));
        Ok(())
    });
    sim.add_time_event(lift_start, f64::INFINITY, move |sim, t| {
        sim.set_gravity(Vector3::new(0.0, 0.0, -9.81));
        let lift = 0.1 * ease_in_out((t - lift_start) / (pull_start - lift_start));
        let pull = if t > pull_start { (t - pull_start) / 8.0 } else { 0.0 };
        sim.deformables.prescribed.set_transform(
            edge,
            Vector3::new(0.0, pull.min(1.0), lift),
            nalgebra::Rotation3::identity(),
        )
    });
    Ok(sim)
}

/// `spinning_box_cloth` with the box as a prescribed surface: a kinematic obstacle following the
/// same motion (the previous form of the scene, before rigid bodies).
pub fn spinning_box_cloth_prescribed(mut settings: Settings) -> Result<Simulation> {
    settings.name = "spinning_box_cloth_prescribed".into();
    settings.time_step_s = 1.0 / 30.0;
    stark_tolerances(&mut settings);
    settings.contact.default_thickness_m = Some(0.002);
    let mut sim = Simulation::new(settings)?;
    sim.add_surface_grid("cloth", [0.4, 0.4], [32, 32], &SurfaceMaterial::cotton_fabric())?;
    let mut cube = meshes::box_mesh(Vector3::repeat(0.08));
    for v in &mut cube.vertices {
        v.z -= 0.08;
    }
    let thickness = sim.settings.contact.default_thickness_m.unwrap_or(0.002);
    let obstacle = sim.add_prescribed_surface("box", &cube.vertices, &cube.elements, thickness, 1e6)?;
    let prescribed = obstacle.prescribed;
    sim.add_time_event(0.0, f64::INFINITY, move |sim, t| {
        sim.deformables.prescribed.set_transform_deg(
            prescribed,
            Vector3::new(0.0, 0.0, -0.1 * t.sin()),
            90.0 * t,
            Vector3::z(),
        )
    });
    Ok(sim)
}

/// `twisting_cloth` of the original (`benchmark-scenes.md` §7): a 0.5 m cotton cloth (n×n quads,
/// elasticity only: no strain limit or damping) in the XZ plane, its edges x = ±0.25 prescribed
/// (k = 1e3 N/m) and rotated ±90°/s about X; self-friction μ = 1, thickness 1 mm, no gravity,
/// dt = 1/30 s, 151 steps, the original's tolerances.
pub(super) fn twisting_cloth_n(mut settings: Settings, n: usize, name: &str) -> Result<Simulation> {
    settings.name = name.into();
    settings.time_step_s = 1.0 / 30.0;
    settings.gravity_m_s2 = [0.0; 3];
    stark_tolerances(&mut settings);
    settings.contact.default_thickness_m = Some(0.001);
    // Thousands of light self-contact pairs: the Gauss–Newton barrier Hessian needs as many
    // Newton iterations here as the projected one (4.9 vs 5.2 per step) at a third of the cost.
    settings.contact.hessian = crate::contact::PairHessian::GaussNewton;
    let mut sim = Simulation::new(settings)?;
    let mut cotton = SurfaceMaterial::cotton_fabric();
    cotton.strain.damping = 0.0;
    cotton.strain.strain_limit = f64::INFINITY;
    let mut grid = meshes::triangle_grid([0.0, 0.0], [0.5, 0.5], [n, n], 0.0);
    for v in &mut grid.vertices {
        *v = Vector3::new(v.x, -v.z, v.y); // 90° about X
    }
    let cloth = sim.add_surface("cloth", &grid.vertices, &grid.elements, &cotton)?;
    let contact = cloth.contact.expect("the default thickness gives the cloth contact");
    sim.contact.set_friction(contact, contact, 1.0)?;
    for (x, sign) in [(-0.25, 1.0), (0.25, -1.0)] {
        let edge = sim.prescribe_in_box(
            cloth.nodes,
            Vector3::new(x, 0.0, 0.0),
            Vector3::new(0.001, 0.5, 0.5),
            PrescribedParams::default(),
        )?;
        sim.add_time_event(0.0, f64::INFINITY, move |sim, t| {
            sim.deformables
                .prescribed
                .set_transform_deg(edge, Vector3::zeros(), sign * 90.0 * t, Vector3::x())
        });
    }
    Ok(sim)
}

/// Four soft rubber cubes (0.1 m, E = 1e5 Pa, 3×3×3 hexes each) stacked 5 mm apart, each turned
/// 0.3 rad from the one below, above a floor (a kinematic 2 m square), falling under gravity: contact
/// between the cubes and with the floor, friction 0.5 everywhere, thickness 1 mm, dt = 1/60 s.
pub fn soft_cubes(mut settings: Settings) -> Result<Simulation> {
    settings.name = "soft_cubes".into();
    settings.time_step_s = 1.0 / 60.0;
    stark_tolerances(&mut settings);
    settings.contact.default_thickness_m = Some(0.001);
    let mut sim = Simulation::new(settings)?;
    let floor = meshes::triangle_grid([0.0, 0.0], [2.0, 2.0], [1, 1], 0.0);
    let floor = sim.add_fixed_surface("floor", &floor.vertices, &floor.elements, 0.001)?;
    let mut rubber = VolumeMaterial::soft_rubber();
    rubber.strain.youngs_modulus = 1e5;
    let side = 0.1;
    let mut contacts = vec![floor.contact];
    for k in 0..4 {
        let mut cube = meshes::tet_grid(Vector3::zeros(), Vector3::repeat(side), [3, 3, 3]);
        // Each cube turned 0.3 rad from the one below, so edges cross faces at general angles.
        let angle = 0.3 * k as f64;
        let (sin, cos) = angle.sin_cos();
        let center = Vector3::new(0.0, 0.0, 0.005 + side / 2.0 + (side + 0.005) * k as f64);
        for v in &mut cube.vertices {
            *v = Vector3::new(cos * v.x - sin * v.y, sin * v.x + cos * v.y, v.z) + center;
        }
        let body = sim.add_volume(&format!("cube{k}"), &cube.vertices, &cube.elements, &rubber)?;
        let contact = body.contact.expect("the default thickness gives the cube contact");
        for &other in &contacts {
            sim.contact.set_friction(contact, other, 0.5)?;
        }
        contacts.push(contact);
    }
    Ok(sim)
}

/// A small stiff cube (0.05 m, E = 1e7 Pa, 1000 kg/m³) shot at 50 m/s into a 1 m cotton cloth
/// (32×32) pinned at its four corners, dt = 1/30 s: the cube moves 1.7 m per step, 33 times its
/// size, so only continuous collision detection keeps it from passing through. Thickness 1 mm.
pub fn tunneling(mut settings: Settings) -> Result<Simulation> {
    settings.name = "tunneling".into();
    settings.time_step_s = 1.0 / 30.0;
    stark_tolerances(&mut settings);
    // A stiff cube pressed by large barrier forces is badly conditioned for CG; the problem is
    // small, so factorise.
    settings.newton.linear_solver = crate::solver::LinearSolver::Cholesky;
    settings.contact.default_thickness_m = Some(0.001);
    let mut sim = Simulation::new(settings)?;
    let cloth = sim.add_surface_grid("cloth", [1.0, 1.0], [32, 32], &SurfaceMaterial::cotton_fabric())?;
    let pin = PrescribedParams {
        stiffness: 1e6,
        ..Default::default()
    };
    for (x, y) in [(0.5, 0.5), (-0.5, 0.5), (0.5, -0.5), (-0.5, -0.5)] {
        sim.prescribe_in_box(
            cloth.nodes,
            Vector3::new(x, y, 0.0),
            Vector3::repeat(0.001),
            pin.clone(),
        )?;
    }
    let mut steel_like = VolumeMaterial::soft_rubber();
    steel_like.strain.youngs_modulus = 1e7;
    let cube = meshes::tet_grid(Vector3::new(0.0, 0.0, 0.1), Vector3::repeat(0.05), [2, 2, 2]);
    let body = sim.add_volume("cube", &cube.vertices, &cube.elements, &steel_like)?;
    sim.set_velocity(body.nodes, Vector3::new(0.0, 0.0, -50.0));
    Ok(sim)
}

/// Magnet strength `k` of `magnetic_deformables`, N·m² (per node: the force is `k/r²`). At 0.1 m
/// a node feels about twice its weight.
pub const MAGNET_STRENGTH_N_M2: f64 = 1e-3;
/// Regularisation length of the magnet potential, m: `−k/√(r² + ε²)` stays finite at the magnet.
pub const MAGNET_SOFTENING_M: f64 = 0.01;

/// The magnet's height above the floor at time `t_s`, m: at rest 0.6 m, lowered to 0.15 m over
/// 1.5–3 s, held, raised back over 4.5–6 s (the original's script).
pub fn magnet_height_m(t_s: f64) -> f64 {
    let (high, low) = (0.6, 0.15);
    let ramp = |t0: f64, t1: f64| ((t_s - t0) / (t1 - t0)).clamp(0.0, 1.0);
    high + (low - high) * ramp(1.5, 3.0) - (low - high) * ramp(4.5, 6.0)
}

/// The magnet potential of one node at `x` with parameters `[k, ε, m]`: `−k/√(‖x − m‖² + ε²)` (J).
pub fn magnet_energy<S: crate::energy::Scalar>(x: &crate::energy::Vec3<S>, p: &[S]) -> S {
    let r = *x - crate::energy::Vec3::new(p[2], p[3], p[4]);
    -p[0] / (r.norm_sq() + p[1] * p[1]).sqrt()
}

/// `magnetic_deformables` with `n × n` cubes (0.05 m, E = 2e4 Pa, 2×2×2 hexes each, 0.1 m
/// apart) on a floor, friction μ 0.5 between all pairs, contact thickness 5 mm (the original's;
/// d̂ between two objects 1 cm). Every cube node carries a user energy (the JIT path) pulling it
/// to the magnet, which a time event moves by [`magnet_height_m`].
pub fn magnetic_deformables_n(mut settings: Settings, n: usize, name: &str) -> Result<Simulation> {
    use crate::energy::{trace_element, Node};
    settings.name = name.into();
    settings.time_step_s = 1.0 / 60.0;
    stark_tolerances(&mut settings);
    settings.contact.default_thickness_m = Some(0.005);
    let mut sim = Simulation::new(settings)?;
    let floor = meshes::triangle_grid([0.0, 0.0], [2.0, 2.0], [1, 1], 0.0);
    let floor = sim.add_prescribed_surface("floor", &floor.vertices, &floor.elements, 0.005, 1e6)?;
    let mut rubber = VolumeMaterial::soft_rubber();
    rubber.strain.youngs_modulus = 2e4;
    let side = 0.05;
    let spacing = 0.1;
    let mut contacts = vec![floor.contact];
    let mut magnet_nodes = Vec::new();
    for i in 0..n {
        for j in 0..n {
            let center = Vector3::new(
                (i as f64 - (n as f64 - 1.0) / 2.0) * spacing,
                (j as f64 - (n as f64 - 1.0) / 2.0) * spacing,
                0.011 + side / 2.0,
            );
            let cube = meshes::tet_grid(center, Vector3::repeat(side), [2, 2, 2]);
            let body = sim.add_volume(&format!("cube{}", i * n + j), &cube.vertices, &cube.elements, &rubber)?;
            let contact = body.contact.expect("the default thickness gives the cube contact");
            for &other in &contacts {
                sim.contact.set_friction(contact, other, 0.5)?;
            }
            contacts.push(contact);
            magnet_nodes.extend(body.nodes.range().map(|k| vec![Node::Point(k as u32)]));
        }
    }
    let traced = trace_element(1, 5, |a| Ok(magnet_energy(&a.x[0], &a.p)))?;
    let names = ["k", "softening_m", "mx", "my", "mz"].map(String::from).to_vec();
    let params = [MAGNET_STRENGTH_N_M2, MAGNET_SOFTENING_M, 0.0, 0.0, magnet_height_m(0.0)];
    let magnet = sim.add_user_energy("magnet", &magnet_nodes, names, &params, traced)?;
    sim.add_time_event(0.0, f64::INFINITY, move |sim, t| {
        sim.set_user_energy_param(magnet, "mz", &[magnet_height_m(t)])
    });
    Ok(sim)
}

/// Simulated duration of `towel_box`, s: 10 steps, in which the folded layers land on each
/// other and on the floor (9k active pairs on average, 34k at the end) and the barrier stiffness
/// adapts; longer runs (`stark run --scene towel_box --duration 6`) reach the settled state.
pub const TOWEL_BOX_DURATION_S: f64 = 0.05;

/// The towel benchmark (issue 16): the paper's towel mesh (the original's `towel_flat.obj` as
/// rest shape, `towel_2folds.obj` as initial positions: 5757 nodes, 11200 triangles, four layers
/// stacked where folded) lying on a fixed floor, a 3 kg rigid box (0.35 × 0.35 × 0.07 m) resting
/// on part of it. As in the paper's robot experiment: d̂ = 3.25 mm (contact thickness 1.625 mm
/// per side), dt = 5 ms, residual 1e-6 N; Neo-Hookean membrane E = 1.5e4 Pa at h = 3.25 mm
/// (E·h ≈ 50 N/m), ν = 0.3, bending 5e-6, 0.5 kg/m²; friction towel–towel 0.4, towel–floor 1.0,
/// box–towel 0.4. The floor is a box fixed in the world whose top is `d̂` below the towel's
/// lowest vertex, so the towel drops onto it within the first steps.
pub fn towel_box(mut settings: Settings) -> Result<Simulation> {
    let dhat = 3.25e-3;
    let thickness = dhat / 2.0;
    settings.name = "towel_box".into();
    settings.time_step_s = 0.005;
    settings.newton.residual_tolerance_n = 1e-6;
    settings.contact.default_thickness_m = Some(thickness);
    // The suite's configuration 3: folded twice.
    let (
        meshes::Mesh {
            vertices: rest,
            elements: triangles,
        },
        folded,
    ) = kobuki_towel::towel_meshes(3)?;
    let mut sim = Simulation::new(settings)?;
    let h = 3.25e-3;
    let e = 1.5e4;
    let towel_material = SurfaceMaterial {
        inertia: crate::deformables::InertiaParams {
            density: 0.5,
            damping: 0.1,
            quasistatic: false,
        },
        strain: crate::deformables::TriangleStrainParams {
            thickness_m: h,
            youngs_modulus: e,
            poissons_ratio: 0.3,
            damping: 0.1 * h * e,
            ..Default::default()
        },
        bending: crate::presets::Bending::Flat(crate::deformables::FlatBendingParams {
            stiffness: 5e-6,
            damping: 1e-7,
        }),
        contact_thickness_m: Some(thickness),
    };
    let towel = sim.add_surface("towel", &rest, &triangles, &towel_material)?;
    // The rest shape is the flat grid; the towel starts folded.
    for (x, p) in sim.nodes.x[towel.nodes.range()].iter_mut().zip(&folded) {
        *x = *p;
    }
    let z_min = folded.iter().map(|p| p.z).fold(f64::INFINITY, f64::min);
    let floor_size = Vector3::new(1.2, 0.8, 0.05);
    let mut floor = meshes::box_mesh(floor_size);
    let (x_mid, y_mid) = (0.0, 0.175);
    for v in &mut floor.vertices {
        *v += Vector3::new(x_mid, y_mid, z_min - dhat - floor_size.z / 2.0);
    }
    let floor = sim.add_fixed_surface("floor", &floor.vertices, &floor.elements, thickness)?;
    let towel_contact = towel.contact.expect("towel has a contact thickness");
    sim.contact.set_friction(towel_contact, towel_contact, 0.4)?;
    sim.contact.set_friction(towel_contact, floor.contact, 1.0)?;
    // The box rests on the right half of the folded towel, a gap of d̂ above its highest vertex
    // under the box's footprint.
    let box_size = Vector3::new(0.35, 0.35, 0.07);
    let box_xy = [0.15, y_mid];
    let under = folded
        .iter()
        .filter(|p| (p.x - box_xy[0]).abs() <= box_size.x / 2.0 && (p.y - box_xy[1]).abs() <= box_size.y / 2.0)
        .map(|p| p.z)
        .fold(z_min, f64::max);
    let (_, box_contact) = rigid_box(
        &mut sim,
        "box",
        3.0,
        box_size,
        Vector3::new(box_xy[0], box_xy[1], under + dhat + box_size.z / 2.0),
        Some(thickness),
    )?;
    sim.contact.set_friction(box_contact, towel_contact, 0.4)?;
    Ok(sim)
}

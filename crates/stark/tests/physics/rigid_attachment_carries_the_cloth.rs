//! Deformable–rigid attachment: a 0.3 m cotton cloth (12×12 quads, 0.2 kg/m², so 18 g) hangs
//! from a 1 kg rigid bar, its top row glued to the bar (`attach_to_body_by_distance`, within
//! 1 mm of the bar's mesh), the bar held by a fix joint. Gravity 9.81 m/s²; the cloth's inertial
//! damping (1/s) lets it settle. After 3 s every glued node is within its 0.1 mm tolerance of its
//! body point (the penalty hardens as needed), and the fix joint carries the bar and the cloth:
//! its force on the bar is `(1 kg + 18 g)·g` upwards within 0.5% (the rest of the cloth's
//! swinging), while a free bar would have fallen.

use nalgebra::{UnitQuaternion, Vector3};
use stark::deformables::AttachmentParams;
use stark::presets::{meshes, SurfaceMaterial};
use stark::rigidbodies::joints::JointParams;
use stark::rigidbodies::MassProperties;
use stark::{Settings, Simulation};

#[test]
fn rigid_attachment_carries_the_cloth() {
    let mut settings = Settings::default();
    settings.output.frames = false;
    settings.output.step_log = false;
    settings.time_step_s = 1.0 / 60.0;
    let mut sim = Simulation::new(settings).unwrap();
    let bar_size = Vector3::new(0.4, 0.02, 0.02);
    let bar = sim
        .add_rigid_body_with(
            "bar",
            &MassProperties::cuboid(1.0, bar_size),
            Vector3::new(0.0, 0.0, 0.01),
            UnitQuaternion::identity(),
        )
        .unwrap();
    let bar_mesh = meshes::box_mesh(bar_size);
    let mesh = sim
        .add_rigid_collision_mesh(bar, &bar_mesh.vertices, &bar_mesh.elements, Some(1e-3))
        .unwrap();
    let fix = sim.add_fix_joint("bar_fix", bar, JointParams::default()).unwrap();
    // The cloth in the xz plane below the bar, its top edge touching the bar's bottom face.
    let mut grid = meshes::triangle_grid([0.0, 0.0], [0.3, 0.3], [12, 12], 0.0);
    for v in &mut grid.vertices {
        *v = Vector3::new(v.x, 0.0, v.y - 0.15);
    }
    let mut cotton = SurfaceMaterial::cotton_fabric();
    cotton.inertia.damping = 1.0;
    let cloth = sim
        .add_surface("cloth", &grid.vertices, &grid.elements, &cotton)
        .unwrap();
    let cloth_mass: f64 = 0.2 * 0.3 * 0.3;
    let params = AttachmentParams {
        stiffness: 1e4,
        tolerance_m: 1e-4,
    };
    let (glue, n) = sim
        .attach_to_body_by_distance("glue", &mesh, &bar_mesh.elements, cloth.nodes, 1e-3, params)
        .unwrap();
    assert_eq!(n, 13, "the top row of the cloth is glued");
    while sim.time() < 3.0 - 1e-9 {
        sim.step().unwrap();
    }
    let state = sim.joint_state(&fix);
    let expected = (1.0 + cloth_mass) * 9.81;
    let force = Vector3::from(state.force_on_b_n);
    let stiffness = sim.rigid_bodies.attachments.potential.params(glue).unwrap().stiffness;
    println!(
        "fix joint force on the bar {force:?} N (expected +{expected:.4} N in z), glue stiffness {stiffness:.3e} N/m, \
         bar moved {:.2e} m",
        (sim.body_position(bar) - Vector3::new(0.0, 0.0, 0.01)).norm()
    );
    assert!(
        (force.z - expected).abs() < 0.005 * expected,
        "{} vs {expected}",
        force.z
    );
    assert!(force.x.abs() < 0.01 && force.y.abs() < 0.01);
    // Every glued node is where it was glued, relative to the bar.
    let top: Vec<usize> = (0..cloth.nodes.len as usize)
        .filter(|&i| grid.vertices[i].z.abs() < 1e-9)
        .collect();
    for &i in &top {
        let x = sim.positions(cloth.nodes)[i];
        let local = sim.body_point_to_local(bar, &x);
        let original = grid.vertices[i] - Vector3::new(0.0, 0.0, 0.01);
        assert!(
            (local - original).norm() < 1e-4,
            "node {i} drifted {} m from its glue point",
            (local - original).norm()
        );
    }
}

//! A floor fixed in the world (`add_fixed_surface`) carries a cloth and a rigid box without
//! moving and without unknowns of its own.
//!
//! Setup: a fixed 2-triangle floor at z = 0 (its diagonal far from the objects), a 0.3 m cotton
//! square (8 × 8 quads, 18 g) 2 mm above it and a 1 kg rigid 0.1 m cube 1 mm above it beside the
//! cloth, contact thickness 1 mm, μ = 0.5 with the floor; 1 s at dt = 1e-2 s, every step checked
//! with the exact intersection test.
//!
//! Asserted: the floor's nodes keep their positions bit for bit and have zero velocity; the
//! Newton solve's unknowns are the cloth's nodes and the cube's six; at the end the cube is at
//! rest and the floor's contact forces carry the weight of both (the floor pushes up with
//! (m_cube + m_cloth)·g to 0.1%, and sideways with nothing).
//!
//! Runtime: < 1 s.

use super::checks::{step_checked, ValidityTotals};
use nalgebra::{UnitQuaternion, Vector3};
use stark::presets::SurfaceMaterial;
use stark::{Settings, Simulation};

#[test]
fn fixed_floor_carries_the_weight() {
    let mut settings = Settings::default();
    settings.output.frames = false;
    settings.output.step_log = false;
    settings.time_step_s = 1e-2;
    settings.contact.default_thickness_m = Some(1e-3);
    let g = Vector3::from(settings.gravity_m_s2).norm();
    let mut sim = Simulation::new(settings).unwrap();
    let floor_vertices = [
        Vector3::new(-1.0, -5.0, 0.0),
        Vector3::new(9.0, -5.0, 0.0),
        Vector3::new(9.0, 5.0, 0.0),
        Vector3::new(-1.0, 5.0, 0.0),
    ];
    let floor = sim
        .add_fixed_surface("floor", &floor_vertices, &[[0, 1, 2], [0, 2, 3]], 1e-3)
        .unwrap();
    let cloth = sim
        .add_surface_grid("cloth", [0.3, 0.3], [8, 8], &SurfaceMaterial::cotton_fabric())
        .unwrap();
    for x in &mut sim.nodes.x[cloth.nodes.range()] {
        *x += Vector3::new(0.0, 0.0, 0.002);
    }
    let cloth_mass_kg = 0.3 * 0.3 * SurfaceMaterial::cotton_fabric().inertia.density;
    let cube_mass_kg = 1.0;
    let cube = sim
        .add_box(
            "cube",
            cube_mass_kg,
            Vector3::repeat(0.1),
            Vector3::new(0.5, 0.0, 0.051),
            UnitQuaternion::identity(),
            None,
        )
        .unwrap();
    sim.contact
        .set_friction(floor.contact, cloth.contact.unwrap(), 0.5)
        .unwrap();
    sim.contact.set_friction(floor.contact, cube.mesh.contact, 0.5).unwrap();
    let floor_start: Vec<Vector3<f64>> = sim.nodes.x[floor.nodes.range()].to_vec();
    let mut totals = ValidityTotals::default();
    while sim.time() < 1.0 - 1e-9 {
        step_checked(&mut sim, "fixed floor", &mut totals);
        assert_eq!(&sim.nodes.x[floor.nodes.range()], &floor_start[..], "the floor moved");
        assert!(sim.nodes.v[floor.nodes.range()].iter().all(|v| *v == Vector3::zeros()));
    }
    assert_eq!(sim.summary().unknowns, 3 * cloth.nodes.len as usize + 6);
    let speed = sim.body_velocity(cube.body).norm();
    assert!(speed < 1e-6, "the cube still moves at {speed:.2e} m/s");
    let (normal, friction) = sim.contact.solve_forces(&sim.nodes.x);
    let on_floor: Vector3<f64> = floor.nodes.range().map(|i| normal[i] + friction[i]).sum();
    let weight_n = (cube_mass_kg + cloth_mass_kg) * g;
    println!("floor carries {on_floor:?} N against the weight {weight_n:.6} N");
    // The floor's reaction on the objects is −on_floor: up by the weight.
    assert!(
        (-on_floor.z - weight_n).abs() < 1e-3 * weight_n,
        "{on_floor:?} N against {weight_n} N"
    );
    assert!(on_floor.xy().norm() < 1e-3 * weight_n, "sideways {on_floor:?} N");
}

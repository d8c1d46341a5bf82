//! The README's rigid-body example: a link on a hinge, released horizontally.
use nalgebra::{UnitQuaternion, Vector3};
use stark::presets::meshes::box_mesh;
use stark::rigidbodies::joints::JointParams;
use stark::rigidbodies::MassProperties;
use stark::{Settings, Simulation};

fn main() -> stark::Result<()> {
    let mut settings = Settings::default();
    settings.name = "pendulum".into();
    settings.time_step_s = 0.01;
    let mut sim = Simulation::new(settings)?;
    // A 20 cm, 0.2 kg link with its centre of mass 10 cm from a hinge at the origin (axis y).
    let size = Vector3::new(0.2, 0.03, 0.03);
    let props = MassProperties::cuboid(0.2, size);
    let link = sim.add_rigid_body_with("link", &props, Vector3::new(0.1, 0.0, 0.0), UnitQuaternion::identity())?;
    let mesh = box_mesh(size); // body-frame vertices, centred at the centre of mass
    sim.add_rigid_output_mesh(link, &mesh.vertices, &mesh.elements)?; // or add_rigid_collision_mesh for contact
    let hinge = sim.add_hinge_joint(
        "pivot",
        None,
        link,
        Vector3::zeros(),
        Vector3::y(),
        JointParams::default(),
    )?;
    sim.run(0.5)?; // frames, pendulum.steps/bodies/joints.jsonl in output/
    let state = sim.joint_state(&hinge);
    println!(
        "angle {:.1}°, hinge force on the link {:.2?} N, violation {:.1e} m",
        state.coordinate.unwrap_or(0.0).to_degrees(),
        state.force_on_b_n,
        state.violation_m
    );
    Ok(())
}

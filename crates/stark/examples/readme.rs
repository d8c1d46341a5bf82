//! The README's minimal example.
use nalgebra::Vector3;
use stark::deformables::PrescribedParams;
use stark::presets::SurfaceMaterial;
use stark::{Settings, Simulation};

fn main() -> stark::Result<()> {
    let mut settings = Settings::default(); // dt 1/30 s, residual 1e-6 N, frames at 30 fps
    settings.output.directory = "output/cloth".into();
    let mut sim = Simulation::new(settings)?;
    let cloth = sim.add_surface_grid("cloth", [1.0, 1.0], [32, 32], &SurfaceMaterial::cotton_fabric())?;
    let pin = PrescribedParams {
        stiffness: 1e6,
        ..Default::default()
    };
    for x in [-0.5, 0.5] {
        sim.prescribe_in_box(
            cloth.nodes,
            Vector3::new(x, 0.5, 0.0),
            Vector3::repeat(1e-3),
            pin.clone(),
        )?;
    }
    let summary = sim.run(2.0)?;
    println!(
        "{} steps, {:.2} Newton iterations per step",
        summary.steps, summary.newton_iterations_per_step
    );
    Ok(())
}

//! Built-in scenes, including exact replicas of the original Stark's shipped scenes
//! (`reference/benchmark-scenes.md`) used for validation and benchmarks.

use crate::deformables::PrescribedParams;
use crate::error::{Result, StarkError};
use crate::presets::{meshes, SurfaceMaterial, VolumeMaterial};
use crate::simulation::Simulation;
use crate::solver::Settings;
use nalgebra::Vector3;

/// A built-in scene.
pub struct BuiltinScene {
    /// Name (`stark run --scene NAME`).
    pub name: &'static str,
    /// One-line description.
    pub description: &'static str,
    /// Simulated duration, s.
    pub duration_s: f64,
    /// Builds the simulation from base settings (output directory, threads).
    pub build: fn(Settings) -> Result<Simulation>,
}

/// Every built-in scene.
pub fn builtin_scenes() -> Vec<BuiltinScene> {
    vec![
        BuiltinScene {
            name: "default",
            description: "1 m cotton cloth, 32×32, hanging from two corners for 3 s, every step converged to 1e-6 N",
            duration_s: 3.0,
            build: default_scene,
        },
        BuiltinScene {
            name: "hanging_cloth",
            description:
                "Original Stark scene: 1 m cotton cloth, 32×32, hanging from two corners (151 steps of 1/30 s)",
            duration_s: 151.0 / 30.0,
            build: hanging_cloth,
        },
        BuiltinScene {
            name: "hanging_deformable_box",
            description:
                "Original Stark scene: 0.5 m soft-rubber box, 10³ cells (12000 tets), hanging from two corners",
            duration_s: 151.0 / 30.0,
            build: hanging_deformable_box,
        },
        BuiltinScene {
            name: "hanging_cloth_64",
            description: "hanging_cloth at 64×64 quads (benchmark)",
            duration_s: 151.0 / 30.0,
            build: |s| hanging_cloth_n(s, 64, "hanging_cloth_64"),
        },
        BuiltinScene {
            name: "hanging_cloth_128",
            description: "hanging_cloth at 128×128 quads (benchmark)",
            duration_s: 151.0 / 30.0,
            build: |s| hanging_cloth_n(s, 128, "hanging_cloth_128"),
        },
        BuiltinScene {
            name: "cloth_on_sphere",
            description:
                "1 m cotton cloth, 32×32, dropped on a kinematic sphere of radius 0.25 m (contact, self-contact)",
            duration_s: 3.0,
            build: cloth_on_sphere,
        },
    ]
}

/// The built-in scene called `name`.
pub fn find_scene(name: &str) -> Result<BuiltinScene> {
    builtin_scenes().into_iter().find(|s| s.name == name).ok_or_else(|| {
        let names: Vec<_> = builtin_scenes().iter().map(|s| s.name).collect();
        StarkError::InvalidInput(format!(
            "unknown scene '{name}' (built-in scenes: {})",
            names.join(", ")
        ))
    })
}

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

fn hanging_cloth_n(mut settings: Settings, n: usize, name: &str) -> Result<Simulation> {
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

/// A cotton cloth falling onto a fixed sphere: drape with self-contact, no friction.
pub fn cloth_on_sphere(mut settings: Settings) -> Result<Simulation> {
    settings.name = "cloth_on_sphere".into();
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

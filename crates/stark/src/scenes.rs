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
        BuiltinScene {
            name: "spinning_box_cloth",
            description:
                "The original's hello world: 0.4 m cloth (32×32) falls on a spinning, bobbing box (self-contact)",
            duration_s: 301.0 / 30.0,
            build: spinning_box_cloth,
        },
        BuiltinScene {
            name: "twisting_cloth",
            description:
                "The original's twisting cloth: 0.5 m cloth (32×32), edges twisted ±90°/s, self-friction μ = 1",
            duration_s: 151.0 / 30.0,
            build: |s| twisting_cloth_n(s, 32, "twisting_cloth"),
        },
        BuiltinScene {
            name: "twisting_cloth_64",
            description: "twisting_cloth at 64×64",
            duration_s: 151.0 / 30.0,
            build: |s| twisting_cloth_n(s, 64, "twisting_cloth_64"),
        },
        BuiltinScene {
            name: "soft_cubes",
            description: "A stack of four soft rubber cubes falling on a floor (contact, friction 0.5 everywhere)",
            duration_s: 2.0,
            build: soft_cubes,
        },
        BuiltinScene {
            name: "tunneling",
            description: "A small stiff cube at 50 m/s into a pinned cloth at dt = 1/30 s: CCD must stop it",
            duration_s: 0.5,
            build: tunneling,
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
/// on, no friction, dt = 1/30 s, 301 steps, the original's tolerances. The original drives a rigid
/// box with a fix constraint; here the box is a kinematic surface (prescribed positions, k = 1e6
/// N/m) following the same motion.
pub fn spinning_box_cloth(mut settings: Settings) -> Result<Simulation> {
    settings.name = "spinning_box_cloth".into();
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
fn twisting_cloth_n(mut settings: Settings, n: usize, name: &str) -> Result<Simulation> {
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
    let floor = sim.add_prescribed_surface("floor", &floor.vertices, &floor.elements, 0.001, 1e6)?;
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

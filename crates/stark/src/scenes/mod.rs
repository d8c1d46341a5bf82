//! Built-in scenes, including exact replicas of the original Stark's shipped scenes
//! (`reference/benchmark-scenes.md`) used for validation and benchmarks.

mod builders;
pub mod franka_cup;
pub mod kobuki_towel;
pub mod robot_towel_outcome;

use crate::contact::ContactHandle;
use crate::deformables::PrescribedParams;
use crate::error::{Result, StarkError};
use crate::presets::{meshes, SurfaceMaterial, VolumeMaterial};
use crate::rigidbodies::joints::JointParams;
use crate::rigidbodies::{MassProperties, RigidBodyHandle};
use crate::settings::Settings;
use crate::simulation::Simulation;
use nalgebra::{UnitQuaternion, Vector3};

pub use builders::*;
use builders::{hanging_cloth_n, twisting_cloth_n};

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

/// The 16 runs of the paper's robot–towel suite, with the parameter set `original`, then with
/// `paper` (names ending in `_paper`).
macro_rules! kobuki_towel_scenes {
    ($(($floor:ident, $floor_name:literal, $c:literal, $what:literal)),* $(,)?) => {
        [$(kobuki_towel_scenes!(
            @one $floor, $c, Original,
            concat!("kobuki_towel_", $floor_name, "_", $c),
            concat!(
                "The paper's experiment: the Kobuki robot drives into a towel (", $what, ") on ",
                $floor_name, ", 6 s; classified P/O/S"
            )
        ),)*
        $(kobuki_towel_scenes!(
            @one $floor, $c, Paper,
            concat!("kobuki_towel_", $floor_name, "_", $c, "_paper"),
            concat!("kobuki_towel_", $floor_name, "_", $c, " with the parameters the paper's text states")
        )),*]
    };
    (@one $floor:ident, $c:literal, $params:ident, $name:expr, $description:expr) => {
        BuiltinScene {
            name: $name,
            description: $description,
            duration_s: kobuki_towel::DURATION_S,
            build: |s| {
                kobuki_towel::builtin(
                    s,
                    kobuki_towel::Case {
                        floor: kobuki_towel::Floor::$floor,
                        configuration: $c,
                        params: kobuki_towel::ParamSet::$params,
                    },
                )
            },
        }
    };
}

/// Every built-in scene.
pub fn builtin_scenes() -> Vec<BuiltinScene> {
    let mut scenes = builtin_scenes_without_suites();
    scenes.extend(kobuki_towel_scenes![
        (Carpet, "carpet", 1, "flat"),
        (Carpet, "carpet", 2, "1 fold"),
        (Carpet, "carpet", 3, "2 folds"),
        (Carpet, "carpet", 4, "3 folds, folded side"),
        (Carpet, "carpet", 5, "3 folds, open side"),
        (Carpet, "carpet", 6, "rolled, rolled side"),
        (Carpet, "carpet", 7, "rolled, open side"),
        (Carpet, "carpet", 8, "rolled sideways"),
        (Polished, "polished", 1, "flat"),
        (Polished, "polished", 2, "1 fold"),
        (Polished, "polished", 3, "2 folds"),
        (Polished, "polished", 4, "3 folds, folded side"),
        (Polished, "polished", 5, "3 folds, open side"),
        (Polished, "polished", 6, "rolled, rolled side"),
        (Polished, "polished", 7, "rolled, open side"),
        (Polished, "polished", 8, "rolled sideways"),
    ]);
    scenes
}

fn builtin_scenes_without_suites() -> Vec<BuiltinScene> {
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
            name: "hanging_cloth_256",
            description: "hanging_cloth at 256×256 quads (the scaling benchmark's 200k unknowns; not in `stark bench`'s default list)",
            duration_s: 151.0 / 30.0,
            build: |s| hanging_cloth_n(s, 256, "hanging_cloth_256"),
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
            name: "spinning_box_cloth_prescribed",
            description: "spinning_box_cloth with the box as a prescribed (kinematic) surface instead of a rigid body",
            duration_s: 301.0 / 30.0,
            build: spinning_box_cloth_prescribed,
        },
        BuiltinScene {
            name: "rb_point",
            description: "Original Stark scene: a chain of 10 rigid boxes joined by ball joints, the first one fixed",
            duration_s: 151.0 / 30.0,
            build: rb_point,
        },
        BuiltinScene {
            name: "deformable_and_rigid_collisions",
            description: "Original Stark scene: two soft boxes stacked on a fixed rigid floor, friction μ = 1",
            duration_s: 151.0 / 30.0,
            build: deformable_and_rigid_collisions,
        },
        BuiltinScene {
            name: "simple_grasp",
            description:
                "Original Stark scene: a 1 kg soft cube squeezed by two prismatic-press fingers (5 N each); μ 1.05, then 0.95 from t = 5 s",
            duration_s: 211.0 / 30.0,
            build: simple_grasp,
        },
        BuiltinScene {
            name: "boxes_on_cloth",
            description: "The original's Python example: 24 rigid boxes on a 64×64 cloth on a rigid floor; the cloth edge is lifted and pulled",
            duration_s: 10.0,
            build: boxes_on_cloth,
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
            name: "magnetic_deformables",
            description: "The original's magnetic_deformables_implicit: 64 soft cubes on a floor (μ 0.5) pulled by a scripted magnet, a user energy −k/‖x − m‖ on every node compiled at run time",
            duration_s: 7.0,
            build: |s| magnetic_deformables_n(s, 8, "magnetic_deformables"),
        },
        BuiltinScene {
            name: "tunneling",
            description: "A small stiff cube at 50 m/s into a pinned cloth at dt = 1/30 s: CCD must stop it",
            duration_s: 0.5,
            build: tunneling,
        },
        BuiltinScene {
            name: "franka_cup",
            description: "The paper's grasp: a Franka hand holds a PET cup (5 N, μ 0.5) while 14 g steel balls are poured in, one every 0.2 s, until it slips",
            duration_s: franka_cup::DURATION_S,
            build: franka_cup_scene,
        },
        BuiltinScene {
            name: "franka_cup_pet",
            description: "franka_cup with the bending stiffness of a real 0.3 mm PET sheet (4.7e-3 N·m instead of 1e-4): the tapered wall as a wedge, without the pads' indentation",
            duration_s: franka_cup::DURATION_S,
            build: |s| franka_cup_variant(s, "franka_cup_pet", franka_cup::PET_BENDING_N_M, Default::default()),
        },
        BuiltinScene {
            name: "franka_cup_straight",
            description: "franka_cup with a straight wall (radius 27 mm top and bottom): the pads' indentation without the wedge",
            duration_s: franka_cup::DURATION_S,
            build: |s| franka_cup_variant(s, "franka_cup_straight", franka_cup::CUP_BENDING_N_M, straight_cup()),
        },
        BuiltinScene {
            name: "franka_rigid_box",
            description: "The check of franka_cup: a rigid 50 g box in the same hand, pulled down by a force growing at 1 N/s, slips at μ·ΣN",
            duration_s: 4.0,
            build: franka_box_scene,
        },
        BuiltinScene {
            name: "towel_box",
            description: "The paper's towel (5757 nodes, folded twice) on a fixed floor under a 3 kg rigid box: dense self-contact, d̂ = 3.25 mm, dt = 5 ms, residual 1e-6 N",
            duration_s: TOWEL_BOX_DURATION_S,
            build: towel_box,
        },
    ]
}

/// The built-in `franka_cup` (see [`franka_cup`]).
pub fn franka_cup_scene(settings: Settings) -> Result<Simulation> {
    let shape = crate::presets::meshes::CupShape::default();
    franka_cup_variant(settings, "franka_cup", franka_cup::CUP_BENDING_N_M, shape)
}

/// [`franka_cup`] with another cup: bending stiffness (N·m) and shape. The variants separate the
/// wedge of the tapered wall from the pads' indentation of a soft one.
pub fn franka_cup_variant(
    mut settings: Settings,
    name: &str,
    bending_n_m: f64,
    shape: crate::presets::meshes::CupShape,
) -> Result<Simulation> {
    settings.name = name.into();
    settings.time_step_s = 0.005;
    settings.newton.residual_tolerance_n = 1e-6;
    let options = franka_cup::FrankaCupOptions {
        held: franka_cup::Held::Cup(shape),
        cup_bending_n_m: bending_n_m,
        ..Default::default()
    };
    Ok(franka_cup::build(settings, options)?.0)
}

/// A cup with a straight wall: the default's rim radius top and bottom.
fn straight_cup() -> crate::presets::meshes::CupShape {
    let mut shape = crate::presets::meshes::CupShape::default();
    shape.bottom_radius_m = shape.rim_radius_m;
    shape
}

/// The built-in `franka_rigid_box`: [`franka_cup`] with a rigid box pulled down instead of the cup.
pub fn franka_box_scene(mut settings: Settings) -> Result<Simulation> {
    settings.name = "franka_rigid_box".into();
    settings.time_step_s = 0.005;
    settings.newton.residual_tolerance_n = 1e-6;
    let options = franka_cup::FrankaCupOptions {
        held: franka_cup::Held::RigidBox {
            size_m: [0.04, 0.05, 0.06],
            mass_kg: 0.05,
            pull_rate_n_s: 1.0,
        },
        ..Default::default()
    };
    Ok(franka_cup::build(settings, options)?.0)
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn towel_box_builds_from_the_shipped_meshes_and_takes_a_step() {
        let mut settings = Settings::default();
        settings.output.frames = false;
        settings.output.step_log = false;
        settings.threads = 1;
        let mut sim = towel_box(settings).unwrap();
        let towel = sim.deformables.set_by_label("towel").unwrap();
        assert_eq!(towel.len, 5757);
        // Starts folded (four layers up to 46 mm), not on its flat rest shape.
        let top = sim.positions(towel).iter().map(|p| p.z).fold(f64::MIN, f64::max);
        assert!((top - 0.0457).abs() < 1e-3, "{top}");
        sim.step().unwrap();
        assert!(sim.positions(towel).iter().all(|p| p.iter().all(|c| c.is_finite())));
    }
}

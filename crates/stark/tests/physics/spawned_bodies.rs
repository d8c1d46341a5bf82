//! Objects added during a run ([`Simulation::add_spawn`]): three 1 cm balls spawned at t = 0.1,
//! 0.2 and 0.3 s above a kinematic floor fall, land and come to rest on it, with ball–floor and
//! ball–ball friction set by the spawns; a 4 cm cotton cloth (a deformable) spawned at 0.15 s
//! falls beside them and lies on the floor. Every accepted step is checked with the exact
//! intersection test; a ball exists from its spawn time on (before it, the simulation has fewer
//! bodies; right after, it sits where it was spawned); a ball falls for its own time only.
//!
//! A run checkpointed at t = 0.25 s (two balls spawned) and continued in a freshly built
//! simulation (the spawns added again, not fired) repeats the uninterrupted run bit for bit: the
//! restore fires the two spawns due by then before it restores the state. The frames' `.pvd`
//! lists a ball from its spawn on. A spawn into an occupied place stops the run with an error
//! naming the spawn.

use nalgebra::{UnitQuaternion, Vector3};
use stark::{Settings, Simulation};
use std::path::Path;

const RADIUS_M: f64 = 0.005;
const THICKNESS_M: f64 = 5e-4;
const SPAWN_TIMES_S: [f64; 3] = [0.1, 0.2, 0.3];

fn ball_position(k: usize) -> Vector3<f64> {
    // Side by side, 5 cm above the floor.
    Vector3::new(0.03 * k as f64, 0.0, 0.05)
}

fn build(out: &Path, frames: bool) -> Simulation {
    let mut settings = Settings::default();
    settings.output.directory = out.to_path_buf();
    settings.output.frames = frames;
    settings.output.fps = 20.0;
    settings.output.step_log = false;
    settings.time_step_s = 0.01;
    settings.contact.default_thickness_m = Some(THICKNESS_M);
    let mut sim = Simulation::new(settings).unwrap();
    let floor = [
        Vector3::new(-0.1, -0.1, 0.0),
        Vector3::new(0.2, -0.1, 0.0),
        Vector3::new(0.2, 0.1, 0.0),
        Vector3::new(-0.1, 0.1, 0.0),
    ];
    sim.add_prescribed_surface("floor", &floor, &[[0, 1, 2], [0, 2, 3]], THICKNESS_M, 1e7)
        .unwrap();
    sim.add_spawn(0.15, "cloth", |sim| {
        let grid = stark::presets::meshes::triangle_grid([-0.05, 0.0], [0.04, 0.04], [4, 4], 0.02);
        let mut cotton = stark::presets::SurfaceMaterial::cotton_fabric();
        cotton.contact_thickness_m = Some(THICKNESS_M);
        let cloth = sim.add_surface("cloth", &grid.vertices, &grid.elements, &cotton)?;
        let floor = sim.contact.object_by_label("floor").expect("the floor is there");
        sim.contact
            .set_friction(cloth.contact.expect("it has a thickness"), floor, 0.5)
    })
    .unwrap();
    for (k, &t) in SPAWN_TIMES_S.iter().enumerate() {
        sim.add_spawn(t, &format!("ball {k}"), move |sim| {
            let label = format!("ball{k}");
            let b = sim.add_sphere(
                &label,
                0.004,
                RADIUS_M,
                2,
                ball_position(k),
                UnitQuaternion::identity(),
                None,
            )?;
            let mine = b.mesh.contact;
            let floor = sim.contact.object_by_label("floor").expect("the floor is there");
            sim.contact.set_friction(mine, floor, 0.5)?;
            for j in 0..k {
                let other = sim
                    .contact
                    .object_by_label(&format!("ball{j}"))
                    .expect("spawned before");
                sim.contact.set_friction(mine, other, 0.3)?;
            }
            Ok(())
        })
        .unwrap();
    }
    sim
}

fn step_to(sim: &mut Simulation, t_end: f64) {
    while sim.time() < t_end - 1e-9 {
        super::checks::step_checked(sim, "spawned balls", &mut super::checks::ValidityTotals::default());
        // Ball k exists exactly from its spawn time on.
        let spawned = SPAWN_TIMES_S.iter().filter(|&&t| sim.time() >= t - 1e-9).count();
        assert_eq!(sim.num_rigid_bodies(), spawned, "t = {}", sim.time());
    }
}

fn bits(v: &[Vector3<f64>]) -> Vec<[u64; 3]> {
    v.iter()
        .map(|p| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
        .collect()
}

#[test]
fn spawned_balls_fall_rest_and_resume_bit_identically() {
    let dir = std::env::temp_dir().join(format!("stark_spawn_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let mut full = build(&dir.join("full"), true);
    step_to(&mut full, 0.1);
    // Spawned at the end of the step reaching 0.1 s, where it was placed, at rest.
    let b0 = full.rigid_bodies.by_label("ball0").unwrap();
    assert_eq!(full.body_position(b0), ball_position(0));
    step_to(&mut full, 0.25);
    let ball1_at_025 = full.body_position(full.rigid_bodies.by_label("ball1").unwrap());
    // Ball 1 has fallen for 0.05 s: about g·t²/2 = 12 mm (backward Euler: a little more).
    let fallen = ball_position(1).z - ball1_at_025.z;
    assert!((0.011..0.016).contains(&fallen), "ball 1 fell {fallen} m in 0.05 s");
    full.save_checkpoint(dir.join("at_025.ckpt")).unwrap();
    step_to(&mut full, 0.8);
    for k in 0..3 {
        let b = full.rigid_bodies.by_label(&format!("ball{k}")).unwrap();
        let (z, v) = (full.body_position(b).z, full.body_velocity(b).norm());
        assert!(
            (RADIUS_M * 0.98..RADIUS_M + 2.0 * THICKNESS_M).contains(&z) && v < 1e-3,
            "ball {k} at rest on the floor: z = {z}, |v| = {v}"
        );
    }
    let cloth = full.deformables.set_by_label("cloth").unwrap();
    let top = full
        .positions(cloth)
        .iter()
        .map(|p| p.z)
        .fold(f64::NEG_INFINITY, f64::max);
    assert!(
        (0.0..2e-3).contains(&top),
        "the cloth lies on the floor: top at {top} m"
    );
    // The frames list a ball from its spawn on: ball 2 (t = 0.3 s) is not in the frames at
    // 0, 0.05, ..., 0.25 s, and is in every frame after.
    let pvd = std::fs::read_to_string(dir.join("full").join(format!("{}.pvd", full.settings.name))).unwrap();
    let ball2_frames = pvd.lines().filter(|l| l.contains("ball2_")).count();
    let frames = full.summary().frames;
    assert_eq!(
        ball2_frames,
        frames - 6,
        "ball 2 listed in {ball2_frames} of {frames} frames"
    );

    let mut resumed = build(&dir.join("resumed"), false);
    resumed.restore_checkpoint(dir.join("at_025.ckpt")).unwrap();
    assert_eq!(resumed.num_rigid_bodies(), 2);
    step_to(&mut resumed, 0.8);
    assert_eq!(resumed.time().to_bits(), full.time().to_bits());
    assert_eq!(bits(&resumed.nodes.x), bits(&full.nodes.x));
    assert_eq!(bits(&resumed.bodies.position), bits(&full.bodies.position));
    assert_eq!(bits(&resumed.bodies.velocity), bits(&full.bodies.velocity));
    assert_eq!(resumed.summary().newton_iterations, full.summary().newton_iterations);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_spawn_into_an_occupied_place_is_an_error_naming_it() {
    let dir = std::env::temp_dir().join(format!("stark_spawn_bad_{}", std::process::id()));
    let mut sim = build(&dir, false);
    // A second ball where ball 0 will be.
    sim.add_spawn(0.15, "intruder", |sim| {
        sim.add_sphere(
            "intruder",
            0.004,
            RADIUS_M,
            2,
            ball_position(0) + Vector3::new(0.002, 0.0, -0.01),
            UnitQuaternion::identity(),
            None,
        )
        .map(|_| ())
    })
    .unwrap();
    let mut error = None;
    while sim.time() < 0.3 {
        if let Err(e) = sim.step() {
            error = Some(e.to_string());
            break;
        }
    }
    let error = error.expect("the intruding spawn fails");
    assert!(
        error.contains("spawn 'intruder' at t = 0.15 s") && error.contains("intersect"),
        "{error}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

//! A stack of five rigid boxes on a floor stays at rest.
//!
//! SETUP-DOC

use super::checks::{step_checked, ValidityTotals};
use nalgebra::{UnitQuaternion, Vector3};
use stark::{Settings, Simulation};

const N_BOXES: usize = 5;
const SIDE_M: f64 = 0.1;
const THICKNESS_M: f64 = 1e-3;
const GAP_M: f64 = 1e-3;

fn yaw(i: usize) -> UnitQuaternion<f64> {
    UnitQuaternion::from_axis_angle(
        &Vector3::z_axis(),
        if i % 2 == 1 { std::f64::consts::FRAC_PI_4 } else { 0.0 },
    )
}

fn run_stack(dt: f64, duration_s: f64) {
    let mut settings = Settings::default();
    settings.output.frames = false;
    settings.output.step_log = false;
    settings.time_step_s = dt;
    settings.contact.default_thickness_m = Some(THICKNESS_M);
    let mut sim = Simulation::new(settings).unwrap();
    let floor_vertices = [
        Vector3::new(-1.0, -5.0, 0.0),
        Vector3::new(9.0, -5.0, 0.0),
        Vector3::new(9.0, 5.0, 0.0),
        Vector3::new(-1.0, 5.0, 0.0),
    ];
    let floor = sim
        .add_prescribed_surface("floor", &floor_vertices, &[[0, 1, 2], [0, 2, 3]], THICKNESS_M, 1e7)
        .unwrap();
    let mut boxes = Vec::new();
    for i in 0..N_BOXES {
        let z = GAP_M + 0.5 * SIDE_M + i as f64 * (SIDE_M + GAP_M);
        let b = sim
            .add_box(
                &format!("box{i}"),
                1.0,
                Vector3::repeat(SIDE_M),
                Vector3::new(0.0, 0.0, z),
                yaw(i),
                None,
            )
            .unwrap();
        boxes.push(b);
    }
    let mut contacts = vec![floor.contact];
    contacts.extend(boxes.iter().map(|b| b.mesh.contact));
    for w in contacts.windows(2) {
        sim.contact.set_friction(w[0], w[1], 0.5).unwrap();
    }
    let start: Vec<Vector3<f64>> = boxes.iter().map(|b| sim.body_position(b.body)).collect();
    let mut totals = ValidityTotals::default();
    let mut max_lateral: f64 = 0.0;
    let mut max_rotation: f64 = 0.0;
    let mut max_sink: f64 = 0.0;
    let mut settled: Option<Vec<Vector3<f64>>> = None;
    let mut max_drift: f64 = 0.0;
    let mut iters = 0;
    while sim.time() < duration_s - 1e-9 {
        let r = step_checked(&mut sim, "rigid stack", &mut totals);
        iters += r.newton_iterations;
        for (i, b) in boxes.iter().enumerate() {
            let p = sim.body_position(b.body);
            max_lateral = max_lateral.max((p - start[i]).xy().norm());
            max_sink = max_sink.max(start[i].z - p.z);
            max_rotation = max_rotation.max(sim.body_orientation(b.body).angle_to(&yaw(i)));
            if let Some(s) = &settled {
                max_drift = max_drift.max((p - s[i]).norm());
            }
        }
        if settled.is_none() && sim.time() >= 1.0 - 1e-9 {
            settled = Some(boxes.iter().map(|b| sim.body_position(b.body)).collect());
        }
    }
    let speed = boxes
        .iter()
        .map(|b| sim.body_velocity(b.body).norm())
        .fold(0.0, f64::max);
    println!(
        "stack dt {dt}: lateral {max_lateral:.2e} m, sink {max_sink:.2e} m, rotation {max_rotation:.2e} rad, drift after 1 s {max_drift:.2e} m, speed {speed:.2e} m/s, {:.2} Newton it/step, failed {}, κ {:.3e}, min d {:.3e}",
        iters as f64 / totals.steps as f64,
        sim.summary().failed_steps,
        sim.contact.stiffness(),
        sim.contact.stats.min_distance_m
    );
    println!("stack dt {dt}: {}", totals.summary());
    println!("times {:?}", sim.summary().times);
    for b in &boxes {
        let q = sim.body_orientation(b.body);
        println!(
            "  box at {:?} axis {:?} angle {:.3e}",
            sim.body_position(b.body),
            q.axis(),
            q.angle()
        );
    }
}

#[test]
fn stack_of_rigid_boxes_stays_at_rest() {
    for dt in [1.0 / 30.0, 1e-2] {
        run_stack(dt, 10.0);
    }
}

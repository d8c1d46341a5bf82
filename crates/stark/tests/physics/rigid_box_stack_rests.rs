//! A stack of five rigid boxes on a floor stays at rest.
//!
//! Setup: five rigid 0.1 m cubes of 1 kg (`add_box`, contact thickness 1 mm, so `d̂` = 2 mm
//! between touching objects) stacked with 1 mm gaps on a kinematic floor (a prescribed 2-triangle
//! square whose diagonal is far from the stack), μ = 0.5 between neighbours (default ε_v =
//! 0.01 m/s), default Newton settings (residual 1e-6 N). Every other cube is turned by 45° about
//! the vertical (see below). 10 s at dt = 1/30 s and at dt = 1e-2 s; every accepted step is
//! checked with the exact intersection test, and the line-search validity test of rigid contact
//! is on (it ran on ~1.5 trial states per step, rejected none, and took 5–8% of the run time).
//!
//! Measured (dt = 1/30 s | 1e-2 s), asserted bound in brackets: largest horizontal displacement
//! of any centre of mass 4.7e-9 | 5.8e-9 m [1e-6], largest rotation 9.6e-9 | 1.3e-8 rad [1e-6],
//! largest displacement after the first second 2.5e-9 | 3.5e-9 m [1e-6], final speed 2.9e-10 |
//! 3.5e-10 m/s [1e-6]; the stack settles into the barrier by 3.8 | 0.6 mm in total (5 gaps of
//! 1 mm; the barrier stiffness `m̄/dt²` is 9× lower at the larger step, so the gaps close more,
//! to 41 | 455 µm at the bottom); 0.5 Newton iterations per step (most steps are solved by the
//! initial guess).
//!
//! Why the 45° turns: IPC's barrier is a sum over point–triangle and edge–edge pairs, and where a
//! vertex of one mesh lies over an edge of the other, several pairs (the point with both
//! triangles of the edge, with the edge itself, and the edges ending at the vertex) all act at the
//! same distance; moving the vertex off the edge by more than ~`d̂` removes some of them. The
//! energy has ridges of the height of a pair's barrier energy along the other mesh's edges, which
//! deformables hardly feel but which a rigid body integrates into net forces and torques. Aligned
//! identical cubes put every corner over a corner and the face diagonals on top of each other: in
//! this setup the aligned stack slides up to 1.4 cm sideways and twists by up to 0.08 rad in 10 s
//! (the equilibrium is a ridge top, and friction at ε_v = 0.01 m/s creeps under the torque). A
//! single frictionless cube resting across the floor's diagonal (corners on the seam) is spun up
//! to 1 rad/s about the vertical in its first step. With the 45° turns, neighbours touch only
//! where edges cross away from vertices, which keeps all pairs' normals vertical.
//!
//! Runtime: ~2 s (dt = 1/30 s) and ~5 s (dt = 1e-2 s).

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
        "stack dt {dt}: lateral {max_lateral:.2e} m, sink {max_sink:.2e} m, rotation {max_rotation:.2e} rad, \
         drift after 1 s {max_drift:.2e} m, speed {speed:.2e} m/s, {:.2} Newton it/step, κ {:.3e} N/m, \
         smallest gap {:.3e} m",
        iters as f64 / totals.steps as f64,
        sim.contact.stiffness(),
        sim.contact.stats.min_distance_m
    );
    println!("stack dt {dt}: {}", totals.summary());
    assert_eq!(sim.summary().failed_steps, 0, "dt {dt}: failed steps");
    assert!(totals.checks > 0, "dt {dt}: the validity test never ran");
    assert!(
        max_lateral < 1e-6,
        "dt {dt}: a box moved sideways by {max_lateral:.2e} m"
    );
    assert!(max_rotation < 1e-6, "dt {dt}: a box turned by {max_rotation:.2e} rad");
    assert!(
        max_drift < 1e-6,
        "dt {dt}: a box moved {max_drift:.2e} m after settling"
    );
    assert!(speed < 1e-6, "dt {dt}: a box still moves at {speed:.2e} m/s");
    // Each gap settles inside the barrier's range: never more than the initial gaps in total.
    assert!(
        max_sink > 0.0 && max_sink < N_BOXES as f64 * GAP_M,
        "dt {dt}: sink {max_sink:.2e} m"
    );
}

#[test]
fn stack_of_rigid_boxes_stays_at_rest() {
    for dt in [1.0 / 30.0, 1e-2] {
        run_stack(dt, 10.0);
    }
}

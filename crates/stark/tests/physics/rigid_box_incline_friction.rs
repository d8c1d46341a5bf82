//! Coulomb friction on a rigid box: it sticks when `tan θ < μ` and slides when `tan θ > μ` with
//! `a = g (sin θ − μ cos θ)`.
//!
//! The rigid-body counterpart of `incline_friction.rs` (same floor, same numbers), which checks
//! friction through the kinematic map: contact pairs between the box's mesh vertices (rigid nodes,
//! 6 DOFs per body) and the floor's triangles, their lagged normal forces and tangents, and the
//! friction torques that the map turns into angular velocity.
//!
//! Setup: a 0.1 m rigid cube of 1 kg (`add_box`, 8-vertex mesh, contact thickness 1 mm) rests
//! 1 mm above a kinematic floor (prescribed 2-triangle square, thickness 1 mm, so `d̂` = 2 mm),
//! μ = 0.5, ε_v = 1e-4 m/s, dt = 0.01 s, Newton to 1e-6 N. There is no fixed rigid body, so the
//! floor is a prescribed surface, and the incline is emulated by tilting gravity by θ after 0.3 s
//! of settling, as in `incline_friction.rs`; the centre of mass is followed for 1 s. Every step is
//! checked with the exact intersection test; the box's 4 bottom corners meet the floor as
//! point–triangle pairs.
//!
//! - Sticking, `tan θ = 0.8 μ`: the smoothed friction holds a load `r μλ` with a slip of
//!   `(1 − √(1 − r)) ε_v dt` per step (see `incline_friction.rs`), the same for each corner of a
//!   rigid box. Measured: 0.20 mm in 1 s (sliding freely: 1.8 m), creep 5.5279e-5 m/s against the
//!   model's 5.5279e-5 m/s (asserted: < 1 mm, creep within 10%).
//! - Sliding, `tan θ = 1.25 μ` (θ = 32.0°): a = 1.039858 m/s² against g(sin θ − μ cos θ) =
//!   1.039858 m/s², relative error −3e-8 (asserted 3%). A rigid box has no elastic wobble, so
//!   the fit is exact up to the solver tolerance.
//!
//! Both with 1 and 3 friction iterations. The box pitches forward by 3–4 mrad (about y): the
//! friction force acts at the floor, 5 cm below the centre of mass, and its moment is balanced by
//! more barrier force under the front corners, which the barrier (stiffness `m̄/dt²`, gaps
//! ~1 mm of `d̂` = 2 mm) provides by letting them come ~0.3 mm closer than the back ones; asserted
//! below 1e-2 rad (the box does not tip: `tan θ` < half-width/half-height = 1).
//!
//! The line-search validity test (edge–triangle intersections of trial states with rigid
//! primitives) ran on 250–380 trial states per run, rejected none, and took 1–2% of the run time.
//!
//! Runtime: ~0.3–0.6 s per simulation, ~1 s for the file.

use super::checks::{step_checked, ValidityTotals};
use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use stark::solver::LinearSolver;
use stark::{Settings, Simulation};

const G_M_S2: f64 = 9.81;
const MU: f64 = 0.5;
const SIDE_M: f64 = 0.1;
const MASS_KG: f64 = 1.0;
const THICKNESS_M: f64 = 1e-3;
const INITIAL_GAP_M: f64 = 1e-3;
const DT_S: f64 = 0.01;
const EPS_V_M_S: f64 = 1e-4;
const SETTLE_S: f64 = 0.3;
const DURATION_S: f64 = 1.0;

/// Displacements along the slope since the tilt (time, m), and the largest rotation (rad).
fn slide_box(tan_theta: f64, friction_iterations: usize) -> (Vec<(f64, f64)>, f64) {
    let mut settings = Settings::default();
    settings.output.frames = false;
    settings.output.step_log = false;
    settings.threads = 1;
    settings.time_step_s = DT_S;
    settings.newton.linear_solver = LinearSolver::Cholesky;
    settings.newton.residual_tolerance_n = 1e-6;
    settings.contact.friction_stick_slide_threshold_m_s = EPS_V_M_S;
    settings.contact.friction_iterations = friction_iterations;
    settings.gravity_m_s2 = [0.0, 0.0, -G_M_S2];
    let mut sim = Simulation::new(settings).unwrap();
    let cube = sim
        .add_box(
            "box",
            MASS_KG,
            Vector3::repeat(SIDE_M),
            Vector3::zeros(),
            UnitQuaternion::identity(),
            Some(THICKNESS_M),
        )
        .unwrap();
    let z = -0.5 * SIDE_M - INITIAL_GAP_M;
    let floor_vertices = [
        Vector3::new(-1.0, -5.0, z),
        Vector3::new(9.0, -5.0, z),
        Vector3::new(9.0, 5.0, z),
        Vector3::new(-1.0, 5.0, z),
    ];
    let floor = sim
        .add_prescribed_surface("floor", &floor_vertices, &[[0, 1, 2], [0, 2, 3]], THICKNESS_M, 1e7)
        .unwrap();
    sim.contact.set_friction(cube.mesh.contact, floor.contact, MU).unwrap();
    let mut totals = ValidityTotals::default();
    let what = format!("rigid box, tan θ = {tan_theta}");
    let mut step = |sim: &mut Simulation| {
        let r = step_checked(sim, &what, &mut totals);
        assert_eq!(r.failed_attempts, 0, "step {} failed: {:?}", r.step, r.failure_reasons);
        assert!(
            r.contact.unwrap().friction_pairs > 0,
            "t = {}: the box lost contact",
            sim.time()
        );
    };
    while sim.time() < SETTLE_S - 1e-9 {
        step(&mut sim);
    }
    let theta = tan_theta.atan();
    sim.set_gravity(G_M_S2 * Vector3::new(theta.sin(), 0.0, -theta.cos()));
    let (t0, c0) = (sim.time(), sim.body_position(cube.body));
    let mut samples = vec![(0.0, 0.0)];
    let mut rotation: f64 = 0.0;
    while sim.time() < t0 + DURATION_S - 1e-9 {
        step(&mut sim);
        samples.push((sim.time() - t0, sim.body_position(cube.body).x - c0.x));
        rotation = rotation.max(sim.body_orientation(cube.body).angle());
    }
    println!("{what}: {}", totals.summary());
    (samples, rotation)
}

fn at(samples: &[(f64, f64)], t: f64) -> f64 {
    samples.iter().find(|s| (s.0 - t).abs() < 1e-6).expect("sample").1
}

/// Least-squares parabola through the samples in `[from, to]`; returns `2 c₂`.
fn fitted_acceleration(samples: &[(f64, f64)], from: f64, to: f64) -> f64 {
    let w: Vec<(f64, f64)> = samples
        .iter()
        .copied()
        .filter(|s| s.0 >= from - 1e-9 && s.0 <= to + 1e-9)
        .collect();
    let mean_t = w.iter().map(|s| s.0).sum::<f64>() / w.len() as f64;
    let mut normal = Matrix3::<f64>::zeros();
    let mut rhs = Vector3::<f64>::zeros();
    for &(t, x) in &w {
        let tau = t - mean_t;
        let p = Vector3::new(1.0, tau, tau * tau);
        normal += p * p.transpose();
        rhs += p * x;
    }
    2.0 * normal.lu().solve(&rhs).expect("enough samples")[2]
}

#[test]
fn rigid_box_sticks_below_the_friction_angle() {
    let ratio = 0.8;
    let theta = (ratio * MU).atan();
    let free_slide_m = 0.5 * G_M_S2 * theta.sin() * DURATION_S * DURATION_S;
    let creep_model = (1.0 - (1.0 - ratio).sqrt()) * EPS_V_M_S;
    for iterations in [1, 3] {
        let (trace, rotation) = slide_box(ratio * MU, iterations);
        let displacement = at(&trace, DURATION_S);
        let creep = (at(&trace, DURATION_S) - at(&trace, 0.5)) / (DURATION_S - 0.5);
        println!(
            "rigid stick (tan θ = {ratio} μ, {iterations} friction iteration(s)): displacement {displacement:.3e} m \
             (frictionless {free_slide_m:.2} m), creep {creep:.4e} m/s (model {creep_model:.4e} m/s), \
             rotation {rotation:.2e} rad"
        );
        assert!(displacement.abs() < 1e-3, "{iterations}: moved {displacement:.3e} m");
        assert!(
            creep > 0.0 && (creep / creep_model - 1.0).abs() < 0.1,
            "{iterations}: creep {creep:.4e} m/s, model {creep_model:.4e} m/s"
        );
        assert!(rotation < 1e-2, "{iterations}: the box rotated by {rotation:.2e} rad");
    }
}

#[test]
fn rigid_box_slides_above_the_friction_angle_at_the_coulomb_acceleration() {
    let ratio = 1.25;
    let theta = (ratio * MU).atan();
    let analytic = G_M_S2 * (theta.sin() - MU * theta.cos());
    for iterations in [1, 3] {
        let (trace, rotation) = slide_box(ratio * MU, iterations);
        let measured = fitted_acceleration(&trace, 0.2, DURATION_S);
        let error = measured / analytic - 1.0;
        println!(
            "rigid slide (tan θ = {ratio} μ, θ = {:.2}°, {iterations} friction iteration(s)): a = {measured:.6} m/s² vs \
             {analytic:.6} m/s², relative error {error:+.2e}, rotation {rotation:.2e} rad",
            theta.to_degrees()
        );
        assert!(
            error.abs() < 0.03,
            "{iterations}: a = {measured:.5}, expected {analytic:.5} ({:+.2}%)",
            100.0 * error
        );
        assert!(rotation < 1e-2, "{iterations}: the box rotated by {rotation:.2e} rad");
    }
}

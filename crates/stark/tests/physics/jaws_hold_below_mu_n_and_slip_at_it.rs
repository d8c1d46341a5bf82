//! Force-limited jaws hold a box while its load stays below μ·ΣN and let it slip at μ·ΣN, with
//! the default contact settings (automatic barrier stiffness, ε_v = 1e-4 m/s, dt = 1/30 s).
//!
//! Two rigid jaws (pads of 0.02 × 0.1 × 0.1 m, 0.5 kg) on prismatic presses to the world close along x
//! at 2 cm/s with at most F = 10 N each on a rigid 1 kg cube of 0.1 m (contact thickness 1 mm,
//! d̂ = 2 mm, μ = 0.5 between jaws and cube). No gravity for the first 0.5 s: the presses stall
//! against the cube at F. Then gravity, which the presses' joints carry for the jaws, loads the
//! cube: it ramps to 90% of the critical `g_c = μ·ΣN/m` over 1 s, stays there 1 s, and ramps on
//! by `g_c/4` per second. Checks:
//! - Holding at 0.9 μ·ΣN the cube creeps less than 1 mm in the 1 s (smoothed friction creeps
//!   at `(1 − √(1 − 0.9))·ε_v` ≈ 0.07 mm/s).
//! - It slips (falls faster than 1 mm/s, 10 ε_v) when its weight reaches μ·ΣN within 5%, ΣN
//!   the normal (barrier) forces on the cube at the start of that step, from which friction is
//!   lagged. The ramp adds 0.8% of `g_c` per step.
//!
//! Measured: creep 0.069 mm in the 1 s; slip at m·g = 0.976 μΣN (ΣN = 19.48 N).
//!
//! Noticed, left for later: ΣN is 20.00 N after closing but drops to 19.48 N (−2.6%) as the
//! vertical load builds, while the presses report 2 × 10 N throughout. With pads larger than the
//! faces (0.12 m) the barrier forces where the two meshes' diagonals cross put a yaw torque on
//! the cube (−1.8e-3 N·m at 0.9 μΣN), which the smoothed friction lets it creep in (1e-4
//! rad/s), and it slips early, at 0.94 μΣN. With ε_v = 1e-3 m/s (and slip detected at 1 cm/s)
//! the cube slips at 0.81 of the presses' μ·2F (ΣN then measured 18.96 N): one reason the default
//! is 1e-4 m/s.
//! - Every accepted state is checked for intersections (exact test).
//!
//! Command: `cargo test --release -p stark --test physics jaws_hold -- --nocapture`.

use super::checks::{step_checked, ValidityTotals};
use nalgebra::{UnitQuaternion, Vector3};
use stark::rigidbodies::joints::JointParams;
use stark::{Settings, Simulation};

const MU: f64 = 0.5;
const PRESS_FORCE_N: f64 = 10.0;
const CUBE_MASS_KG: f64 = 1.0;
const THICKNESS_M: f64 = 1e-3;

#[test]
fn jaws_hold_below_mu_n_and_slip_at_it() {
    let mut settings = Settings::default();
    settings.output.frames = false;
    settings.output.step_log = false;
    settings.gravity_m_s2 = [0.0; 3];
    let mut sim = Simulation::new(settings).unwrap();
    let side = 0.1;
    let cube = sim
        .add_box(
            "cube",
            CUBE_MASS_KG,
            Vector3::repeat(side),
            Vector3::zeros(),
            UnitQuaternion::identity(),
            Some(THICKNESS_M),
        )
        .unwrap();
    // Pads the size of the cube's faces (see the module documentation for larger ones).
    let jaw_size = Vector3::new(0.02, side, side);
    let mut presses = vec![];
    for sign in [-1.0, 1.0] {
        // Surfaces 3 mm apart, beyond d̂.
        let x = sign * (0.5 * side + 0.003 + 0.5 * jaw_size.x);
        let label = if sign < 0.0 { "left" } else { "right" };
        let jaw = sim
            .add_box(
                label,
                0.5,
                jaw_size,
                Vector3::new(x, 0.0, 0.0),
                UnitQuaternion::identity(),
                Some(THICKNESS_M),
            )
            .unwrap();
        sim.contact
            .set_friction(jaw.mesh.contact, cube.mesh.contact, MU)
            .unwrap();
        let press = sim
            .add_prismatic_press(
                &format!("{label}_press"),
                None,
                jaw.body,
                Vector3::new(x, 0.0, 0.0),
                Vector3::new(-sign, 0.0, 0.0),
                0.02,
                PRESS_FORCE_N,
                0.01,
                JointParams::default(),
            )
            .unwrap();
        presses.push(press);
    }
    let eps_v = sim.settings.contact.friction_stick_slide_threshold_m_s;
    let mut totals = ValidityTotals::default();
    while sim.time() < 0.5 - 1e-9 {
        step_checked(&mut sim, "jaws", &mut totals);
    }
    let press_sum = |sim: &Simulation| -> f64 { presses.iter().map(|p| sim.joint_state(p).driver_effort.abs()).sum() };
    // ΣN: the normal (barrier) forces on the cube's nodes, both faces.
    let normal_sum = |sim: &mut Simulation| -> f64 {
        let x = sim.nodes.x.clone();
        let f = sim.contact.barrier_forces(&x);
        cube.mesh.nodes.range().map(|i| f[i].x.abs()).sum()
    };
    let (press_n, squeeze_n) = (press_sum(&sim), normal_sum(&mut sim));
    let g_c = MU * squeeze_n / CUBE_MASS_KG;
    let gravity_at = |t: f64| -> f64 {
        let t = t - 0.5;
        if t < 1.0 {
            0.9 * g_c * t
        } else if t < 2.0 {
            0.9 * g_c
        } else {
            g_c * (0.9 + 0.25 * (t - 2.0))
        }
    };
    let (mut z_hold0, mut z_hold1) = (f64::NAN, f64::NAN);
    let mut slip: Option<(f64, f64, f64)> = None;
    // ΣN at the start of the step (the end of the previous one): friction is lagged from it.
    let mut n_before = squeeze_n;
    while slip.is_none() && sim.time() < 3.5 {
        // Gravity over the coming step: backward Euler applies the value at its end.
        let t_end = sim.time() + sim.dt();
        sim.set_gravity(Vector3::new(0.0, 0.0, -gravity_at(t_end)));
        step_checked(&mut sim, "jaws", &mut totals);
        let t = sim.time();
        let z = sim.body_position(cube.body).z;
        if z_hold0.is_nan() && t > 1.5 - 1e-6 {
            z_hold0 = z;
        }
        if z_hold1.is_nan() && t > 2.5 - 1e-6 {
            z_hold1 = z;
        }
        if sim.body_velocity(cube.body).z < -10.0 * eps_v {
            slip = Some((t, gravity_at(t), n_before));
        }
        n_before = normal_sum(&mut sim);
    }
    let creep_m = (z_hold1 - z_hold0).abs();
    let (t_slip, g_slip, n_slip) = slip.expect("the cube never slipped");
    let ratio = CUBE_MASS_KG * g_slip / (MU * n_slip);
    eprintln!(
        "jaws: presses {press_n:.4} N, ΣN {squeeze_n:.4} N after closing; creep at 0.9 μΣN {:.4} mm in 1 s; \
         slip at t = {t_slip:.3} s, m·g = {:.4} N vs μ·ΣN = {:.4} N (ratio {ratio:.4}); {}",
        1e3 * creep_m,
        CUBE_MASS_KG * g_slip,
        MU * n_slip,
        totals.summary()
    );
    assert!(
        (press_n - 2.0 * PRESS_FORCE_N).abs() < 0.01 * PRESS_FORCE_N,
        "the presses push with {press_n} N, not 2 × {PRESS_FORCE_N} N"
    );
    assert!(
        (squeeze_n / press_n - 1.0).abs() < 0.05,
        "ΣN {squeeze_n} N vs the presses' {press_n} N"
    );
    assert!(creep_m < 1e-3, "the cube crept {creep_m} m at 0.9 μΣN");
    assert!((ratio - 1.0).abs() < 0.05, "slip at {ratio} × μΣN");
}

//! `simple_grasp` (the original's scene): a 1 kg soft cube held between two rigid fingers, each a
//! prismatic press pushing with at most 5 N, under gravity ramped to 10 m/s² over t = 2–3 s. The
//! friction force available is `2·μ·5 N`, so the grasp holds iff `μ > m·g/(2·5 N) = 1`.
//!
//! The scene runs with μ = 1.05 and then μ = 0.95, as in the original, but switches at t = 6 s
//! instead of 5 s: the cube, very soft (E = 2 kPa), sags about 16 mm under its weight and settles
//! until t ≈ 3.4 s, so the holding slip is measured over the 2 s from t = 3.5 s to 5.5 s, and the
//! sliding over t = 6–8 s. Slip is the cube's centroid motion along z (the fingers cannot move
//! vertically).
//!
//! The smoothed friction model sticks only approximately: holding a load ratio `r = mg/(2μF)` =
//! 0.952 takes a slip of `(1 − √(1 − r))·ε_v` per unit time (see incline_friction.rs), 0.78 mm/s
//! at the scene's ε_v = 1e-3 m/s, i.e. 1.6 mm over 2 s (measured 1.2 mm with the cube's own
//! settling). The claim "slips under 1 mm over 2 s" is checked at ε_v = 1e-4 m/s, where the model
//! predicts 0.16 mm, with Newton converged to a force residual of 1e-6 N (the original's step
//! criterion, 1 mm/s, is coarser than the creep being measured). Sliding at μ = 0.95 the cube accelerates at `g − 2μF/m` = 0.5 m/s², about
//! 1 m in 2 s. Every accepted state is checked for intersections (exact test) and inverted tets.

use stark::scenes::simple_grasp_with;
use stark::{Settings, Simulation};

fn centroid_z(sim: &Simulation) -> f64 {
    let obj = sim.deformables.set_by_label("object").unwrap();
    let x = sim.positions(obj);
    x.iter().map(|p| p.z).sum::<f64>() / x.len() as f64
}

#[test]
fn grasp_holds_above_mu_one_and_slides_below() {
    let mut settings = Settings::default();
    settings.output.frames = false;
    settings.output.step_log = false;
    let mut sim = simple_grasp_with(settings, 1.05, 0.95, 6.0).unwrap();
    sim.settings.contact.friction_stick_slide_threshold_m_s = 1e-4;
    // The original's step criterion (‖Δv‖ < 1 mm/s) is coarser than this creep: converge on the
    // force residual instead.
    sim.settings.newton.step_tolerance_m_s = 0.0;
    sim.settings.newton.residual_tolerance_n = 1e-6;
    let (mut z_hold0, mut z_hold1, mut z_slide0) = (f64::NAN, f64::NAN, f64::NAN);
    while sim.time() < 8.0 - 1e-9 {
        sim.step().unwrap();
        let crossings = sim.contact.find_intersections(&sim.nodes.x);
        assert!(
            crossings.is_empty(),
            "intersection at t = {:.3}: {:?}",
            sim.time(),
            &crossings[..1]
        );
        assert_eq!(sim.deformables.tets.potential.count_inverted(&sim.nodes.x), 0);
        let t = sim.time();
        // The first state at or after each time (dt = 1/30 s does not hit them exactly).
        for (at, z) in [(3.5, &mut z_hold0), (5.5, &mut z_hold1), (6.0, &mut z_slide0)] {
            if z.is_nan() && t > at - 1e-6 {
                *z = centroid_z(&sim);
            }
        }
    }
    let hold_slip = (z_hold0 - z_hold1).abs();
    let slide = z_slide0 - centroid_z(&sim);
    eprintln!(
        "slip 3.5–5.5 s at μ = 1.05: {:.3} mm; slide 6–8 s at μ = 0.95: {:.3} m",
        1e3 * hold_slip,
        slide
    );
    assert!(hold_slip < 1e-3, "the grasp slipped {hold_slip} m at μ = 1.05");
    assert!(slide > 0.01, "the cube slid only {slide} m at μ = 0.95");
}

//! The default scene (hanging cotton cloth) converges every step to a force residual below
//! 1e-6 N by the residual criterion alone, with no failed or retried step.

use stark::scenes::find_scene;
use stark::solver::ConvergedBy;
use stark::Settings;

#[test]
fn default_scene_converges_to_tolerance() {
    let scene = find_scene("default").unwrap();
    let mut settings = Settings::default();
    settings.output.frames = false;
    settings.output.step_log = false;
    let mut sim = (scene.build)(settings).unwrap();
    assert_eq!(sim.settings.newton.residual_tolerance_n, 1e-6);
    assert_eq!(sim.settings.newton.step_tolerance_m_s, 0.0);
    let mut worst: f64 = 0.0;
    while sim.time() < scene.duration_s - 1e-9 {
        let r = sim.step().unwrap();
        assert_eq!(
            r.converged_by,
            ConvergedBy::Residual,
            "step {} at t = {}",
            r.step,
            r.time_s
        );
        assert!(r.residual_n < 1e-6, "step {}: residual {} N", r.step, r.residual_n);
        assert_eq!(r.failed_attempts, 0);
        worst = worst.max(r.residual_n);
    }
    let s = sim.summary();
    assert_eq!(s.steps, 90);
    println!(
        "default scene: {} steps, {:.2} Newton/step, worst residual {worst:.2e} N",
        s.steps, s.newton_iterations_per_step
    );
}

//! The same input gives bit-identical results, whatever the number of threads.

use stark::scenes::find_scene;
use stark::Settings;

fn run(threads: usize) -> Vec<nalgebra::Vector3<f64>> {
    let scene = find_scene("hanging_cloth").unwrap();
    let mut settings = Settings::default();
    settings.output.frames = false;
    settings.output.step_log = false;
    settings.threads = threads;
    let mut sim = (scene.build)(settings).unwrap();
    for _ in 0..15 {
        sim.step().unwrap();
    }
    sim.nodes.x.clone()
}

#[test]
fn results_are_deterministic() {
    let a = run(1);
    let b = run(2);
    let c = run(2);
    assert!(a == b && b == c, "positions differ between runs");
}

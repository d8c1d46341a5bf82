//! The same input gives bit-identical results, whatever the number of threads.

use stark::scenes::find_scene;
use stark::solver::LinearSolver;
use stark::Settings;

fn run(threads: usize) -> Vec<nalgebra::Vector3<f64>> {
    run_with("hanging_cloth", threads, LinearSolver::Pcg)
}

fn run_with(scene: &str, threads: usize, linear_solver: LinearSolver) -> Vec<nalgebra::Vector3<f64>> {
    let scene = find_scene(scene).unwrap();
    let mut settings = Settings::default();
    settings.newton.linear_solver = linear_solver;
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

/// The multigrid preconditioner (a hierarchy built from the matrix in parallel) as well; and it
/// solves the same steps: on the default scene (the hanging cloth with every step solved to a
/// force residual of 1e-6 N, no step-size criterion, whose 1e-3 m/s would let the solvers' end
/// points differ by up to ~3e-5 m a step), its positions after 15 steps agree with the sparse
/// Cholesky solver's to a few micrometres at most, as block-Jacobi CG's do (1e-7 m and 1e-6 m:
/// the iterative solvers stop at a forcing tolerance, so none agrees bit for bit).
#[test]
fn multigrid_results_are_deterministic_and_agree_with_the_direct_solver() {
    let amg = run_with("default", 1, LinearSolver::Amg);
    assert!(
        amg == run_with("default", 2, LinearSolver::Amg),
        "positions differ between thread counts"
    );
    let direct = run_with("default", 2, LinearSolver::Cholesky);
    let distance =
        |a: &[nalgebra::Vector3<f64>]| a.iter().zip(&direct).map(|(p, q)| (p - q).amax()).fold(0.0, f64::max);
    let (amg_m, block_jacobi_m) = (distance(&amg), distance(&run_with("default", 2, LinearSolver::Pcg)));
    assert!(
        amg_m < 5e-6 && block_jacobi_m < 5e-6,
        "multigrid {amg_m:.3e} m, block-Jacobi CG {block_jacobi_m:.3e} m from the direct solver's positions"
    );
}

/// Contact on rigid bodies as well: its pairs share the bodies' DOF blocks, so their chunks fall
/// in small colours and the serial group (evaluated in parallel batches, added in order), and
/// IPC's stiffness balance evaluates them in parallel.
#[test]
fn rigid_body_contact_results_are_deterministic() {
    let run = |threads: usize| {
        let scene = find_scene("boxes_on_cloth").unwrap();
        let mut settings = Settings::default();
        settings.output.frames = false;
        settings.output.step_log = false;
        settings.threads = threads;
        let mut sim = (scene.build)(settings).unwrap();
        while sim.time() < 0.25 {
            sim.step().unwrap();
        }
        (
            sim.nodes.x.clone(),
            sim.bodies.position.clone(),
            sim.bodies.orientation.clone(),
        )
    };
    let a = run(1);
    let b = run(2);
    assert!(a == b, "states differ between thread counts");
}

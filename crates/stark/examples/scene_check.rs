//! Runs a built-in scene and prints per-step statistics and the final-state figures.
use stark::scenes::find_scene;
use stark::Settings;

fn main() {
    let name = std::env::args().nth(1).unwrap_or_else(|| "hanging_cloth".into());
    let threads: usize = std::env::args().nth(2).map(|s| s.parse().unwrap()).unwrap_or(1);
    let scene = find_scene(&name).unwrap();
    let mut settings = Settings::default();
    settings.threads = threads;
    settings.output.frames = false;
    settings.output.directory = "/tmp/stark_out".into();
    let mut sim = (scene.build)(settings).unwrap();
    if std::env::var("STARK_CHOLESKY").is_ok() {
        sim.settings.newton.linear_solver = stark::solver::LinearSolver::Cholesky;
    }
    if std::env::var("STARK_PROJECT_ALWAYS").is_ok() {
        sim.settings.newton.projection = stark::solver::Projection::Always;
    }
    if std::env::var("STARK_TOL").is_ok() {
        stark::scenes::stark_tolerances(&mut sim.settings);
    }
    if std::env::var("STARK_GN").is_ok() {
        sim.settings.contact.hessian = stark::contact::PairHessian::GaussNewton;
    }
    if let Ok(k) = std::env::var("STARK_KAPPA") {
        sim.settings.contact.stiffness = Some(k.parse().unwrap());
    }
    if let Ok(b) = std::env::var("STARK_CUBIC") {
        sim.settings.contact.barrier = stark::contact::BarrierKind::Cubic;
        sim.settings.contact.stiffness = Some(b.parse().unwrap());
    }
    if let Some(eta) = std::env::args().nth(3) {
        sim.settings.newton.cg_relative_tolerance = eta.parse().unwrap();
    }
    let mut iters = Vec::new();
    let (mut ls, mut projected) = (0, 0);
    let t = std::time::Instant::now();
    let max_steps: usize = std::env::args()
        .nth(4)
        .map(|s| s.parse().unwrap())
        .unwrap_or(usize::MAX);
    while sim.time() < scene.duration_s - 1e-3 * sim.dt() && iters.len() < max_steps {
        let r = sim.step().unwrap();
        if !r.failure_reasons.is_empty() || std::env::var("STARK_STEPS").is_ok() {
            println!(
                "step {} t {:.4} dt {:.2e} its {} wall {:.2}s contact {:?} failures {:?}",
                r.step, r.time_s, r.dt_s, r.newton_iterations, r.wall_time_s, r.contact, r.failure_reasons
            );
        }
        iters.push(r.newton_iterations);
        ls += r.line_search_evaluations;
        projected += r.projected as usize;
    }
    let s = sim.summary();
    println!(
        "{} steps, {:.3} s wall, newton {} ({:.2}/step), cg {}, max residual {:.3e} N",
        s.steps,
        t.elapsed().as_secs_f64(),
        s.newton_iterations,
        s.newton_iterations_per_step,
        s.cg_iterations,
        s.max_residual_n
    );
    println!("times: {:?}", s.times);
    println!("assembly (evaluate, gather) {:?}", sim.assembly_timing());
    println!("line-search evaluations {ls}, steps with projection {projected}");
    println!("iterations: {:?}", &iters[..iters.len().min(40)]);
    let x = &sim.nodes.x;
    let n = x.len() as f64;
    let c = x.iter().fold(nalgebra::Vector3::zeros(), |a, p| a + p) / n;
    let minz = x.iter().map(|p| p.z).fold(f64::INFINITY, f64::min);
    let maxz = x.iter().map(|p| p.z).fold(f64::NEG_INFINITY, f64::max);
    let (minx, maxx) = (
        x.iter().map(|p| p.x).fold(f64::INFINITY, f64::min),
        x.iter().map(|p| p.x).fold(f64::NEG_INFINITY, f64::max),
    );
    println!(
        "centroid ({:.4}, {:.4}, {:.4}), z [{:.4}, {:.4}], x [{:.4}, {:.4}]",
        c.x, c.y, c.z, minz, maxz, minx, maxx
    );
}

//! Runs a scene file and prints the run summary (until the `stark` command runs scene files).
//!
//! `cargo run --release -p stark --example run_scene_file -- scenes/default.toml [threads] [out]`
use stark::io::load_scene_with;

fn main() {
    let mut args = std::env::args().skip(1);
    let Some(path) = args.next() else {
        eprintln!("usage: run_scene_file SCENE.toml [threads] [output directory]");
        std::process::exit(2);
    };
    let threads: Option<usize> = args.next().map(|s| s.parse().expect("threads: a number"));
    let out = args.next();
    let scene = load_scene_with(std::path::Path::new(&path), |s| {
        if let Some(t) = threads {
            s.threads = t;
        }
        match &out {
            Some(dir) => s.output.directory = dir.into(),
            None => {
                s.output.frames = false;
                s.output.step_log = false;
            }
        }
    });
    let mut scene = match scene {
        Ok(s) => s,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(1);
        }
    };
    println!(
        "scene '{}': {} nodes, {} s",
        scene.name,
        scene.simulation.nodes.len(),
        scene.duration_s
    );
    match scene.simulation.run(scene.duration_s) {
        Ok(s) => println!(
            "{} steps ({} failed, {} hardening retries), {:.2} Newton iterations/step, max residual {:.3e} N, {} by step size, {:.2} s wall",
            s.steps,
            s.failed_steps,
            s.hardening_retries,
            s.newton_iterations_per_step,
            s.max_residual_n,
            s.steps_converged_by_step_size,
            s.wall_time_s
        ),
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(1);
        }
    }
}

//! `stark`: run scenes and benchmarks from the command line.

use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use stark::rigidbodies::joints::{Measure, Primitive};
use stark::scenes::{builtin_scenes, find_scene};
use stark::{RunSummary, Settings, Simulation};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "stark",
    version,
    about = "Strongly coupled simulation of rigid and deformable bodies with frictional contact"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a scene file, a built-in scene (--scene), or the default scene.
    Run {
        /// Scene file (TOML or JSON). Without it, the built-in `default` scene runs.
        scene_file: Option<PathBuf>,
        /// Run a built-in scene by name (see `stark list`).
        #[arg(long, conflicts_with = "scene_file")]
        scene: Option<String>,
        /// Output directory for frames and logs.
        #[arg(long, default_value = "output")]
        out: PathBuf,
        /// Simulated duration in seconds (default: the scene's).
        #[arg(long)]
        duration: Option<f64>,
        /// Write the run summary as JSON to this file.
        #[arg(long)]
        summary_json: Option<PathBuf>,
        /// Worker threads (0 = all cores).
        #[arg(long, default_value_t = 0)]
        threads: usize,
        /// Do not write VTK frames.
        #[arg(long)]
        no_frames: bool,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
        /// After every step, check independently that no contact edge crosses a contact triangle
        /// and count inverted tetrahedra; the run fails at the first intersection.
        #[arg(long)]
        check: bool,
    },
    /// List the built-in scenes.
    List,
    /// Run the benchmark scenes and report time per simulated second.
    Bench {
        /// Scenes to run (default: all benchmark scenes).
        #[arg(long, value_delimiter = ',')]
        scenes: Vec<String>,
        /// Thread counts to run each scene with.
        #[arg(long, value_delimiter = ',', default_value = "1,2")]
        threads: Vec<usize>,
        /// Write the results as JSON to this file.
        #[arg(long)]
        json: Option<PathBuf>,
    },
}

fn base_settings(out: PathBuf, threads: usize, frames: bool) -> Settings {
    let mut s = Settings::default();
    s.output.directory = out;
    s.threads = threads;
    s.output.frames = frames;
    s
}

/// What `--check` saw over a run.
#[derive(Default)]
struct CheckReport {
    /// States checked: the initial one and the one after each step.
    steps_checked: u64,
    most_inverted_tets: usize,
    steps_with_inverted_tets: u64,
}

/// The independent per-step check of `stark run --check`: an exact edge–triangle intersection
/// test over all contact surfaces (not the solver's CCD) and the sign of every tet's volume.
fn check_step(sim: &Simulation, report: &mut CheckReport) -> stark::Result<()> {
    let check = sim.state_check();
    let crossings = &check.intersections;
    if !crossings.is_empty() {
        return Err(stark::StarkError::InvalidInput(format!(
            "--check: {} intersection(s) at t = {:.6} s, e.g. {}",
            crossings.len(),
            sim.time(),
            crossings[..crossings.len().min(3)].join("; ")
        )));
    }
    let inverted = check.inverted_tets;
    report.steps_checked += 1;
    report.most_inverted_tets = report.most_inverted_tets.max(inverted);
    report.steps_with_inverted_tets += u64::from(inverted > 0);
    Ok(())
}

fn run_with_progress(
    sim: &mut Simulation,
    duration: f64,
    quiet: bool,
    mut check: Option<&mut CheckReport>,
) -> stark::Result<RunSummary> {
    let bar = if quiet {
        ProgressBar::hidden()
    } else {
        let bar = ProgressBar::new((duration * 1000.0).round() as u64);
        bar.set_style(
            ProgressStyle::with_template("{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} ms simulated  {msg}")
                .expect("valid template"),
        );
        bar
    };
    let start = sim.time();
    let result = sim.run_with(duration, |s| {
        bar.set_position(((s.time() - start) * 1000.0).round() as u64);
        let sum = s.summary();
        bar.set_message(format!(
            "step {} · {:.2} Newton/step",
            sum.steps, sum.newton_iterations_per_step
        ));
        match check.as_deref_mut() {
            Some(report) => check_step(s, report),
            None => Ok(()),
        }
    });
    bar.finish_and_clear();
    result
}

/// Most joints listed in the summary.
const MAX_JOINTS_SHOWN: usize = 12;

/// The rigid-body part of the summary: counts, largest joint violations and each joint's state
/// at the end.
fn print_rigid_summary(sim: &Simulation, s: &RunSummary) {
    if s.rigid_bodies == 0 {
        return;
    }
    println!(
        "rigid bodies          {} bodies, {} joints (largest violation {:.2e} m, {:.2e}°)",
        s.rigid_bodies,
        s.joints,
        s.max_joint_violation_m,
        s.max_joint_violation_rad.to_degrees()
    );
    let joints = &sim.rigid_bodies.named_joints;
    if joints.is_empty() {
        return;
    }
    println!(
        "  {:<22} {:>12} {:>14} {:>14} {:>10} {:>9}",
        "joint at the end", "coordinate", "rate", "driver effort", "violation", "angle"
    );
    let elements = &sim.rigid_bodies.joints.potential.elements;
    for (h, (label, state)) in joints.iter().zip(sim.joint_states()).take(MAX_JOINTS_SHOWN) {
        let (coordinate, rate) = match (h.measure, state.coordinate, state.coordinate_rate) {
            (Some(Measure::Angle { .. }), Some(c), Some(r)) => {
                (format!("{:.2}°", c.to_degrees()), format!("{:.2}°/s", r.to_degrees()))
            }
            (Some(Measure::Position { .. }), Some(c), Some(r)) => (format!("{c:.4} m"), format!("{r:.4} m/s")),
            _ => ("-".into(), "-".into()),
        };
        let effort = match h.driver.and_then(|d| elements.get(d as usize)) {
            Some(d) if matches!(d.primitive, Primitive::AngularVelocity { .. }) => {
                format!("{:.4} N·m", state.driver_effort)
            }
            Some(_) => format!("{:.4} N", state.driver_effort),
            None => "-".into(),
        };
        println!(
            "  {:<22} {:>12} {:>14} {:>14} {:>8.1e} m {:>8.1e}°",
            label,
            coordinate,
            rate,
            effort,
            state.violation_m,
            state.violation_rad.to_degrees()
        );
    }
    if joints.len() > MAX_JOINTS_SHOWN {
        println!(
            "  ... and {} more (all of them, every step: the joint log)",
            joints.len() - MAX_JOINTS_SHOWN
        );
    }
}

fn print_summary(s: &RunSummary, out: &std::path::Path) {
    println!("scene                 {}", s.scene);
    println!(
        "simulated time        {:.4} s in {} steps ({} failed attempts, {} hardening retries)",
        s.simulated_time_s, s.steps, s.failed_steps, s.hardening_retries
    );
    println!(
        "Newton iterations     {} ({:.2} per step), {} CG iterations",
        s.newton_iterations, s.newton_iterations_per_step, s.cg_iterations
    );
    println!(
        "largest residual      {:.3e} N ({} steps ended by the step-size criterion)",
        s.max_residual_n, s.steps_converged_by_step_size
    );
    println!(
        "wall time             {:.3} s ({:.3} s per simulated second)",
        s.wall_time_s, s.wall_time_per_simulated_s
    );
    let t = &s.times;
    let total = t.total_s().max(1e-12);
    println!(
        "time per phase        evaluation {:.0}%, linear solve {:.0}%, line search {:.0}%, contact detection {:.0}%, \
         CCD {:.0}%",
        100.0 * t.evaluation_s / total,
        100.0 * t.linear_solve_s / total,
        100.0 * t.line_search_s / total,
        100.0 * t.prepare_s / total,
        100.0 * t.ccd_s / total
    );
    if s.max_active_pairs > 0 {
        println!(
            "contact               {:.0} active pairs on average, {} at most",
            s.mean_active_pairs, s.max_active_pairs
        );
    }
    println!("output                {} frames in {}", s.frames, out.display());
}

/// The logs the run wrote.
fn print_logs(sim: &Simulation) {
    let o = &sim.settings.output;
    if !o.step_log {
        return;
    }
    let name = &sim.settings.name;
    let mut logs = vec![format!("{name}.steps.jsonl")];
    if o.bodies_log && sim.num_rigid_bodies() > 0 {
        logs.push(format!("{name}.bodies.jsonl"));
    }
    if o.joints_log && !sim.rigid_bodies.named_joints.is_empty() {
        logs.push(format!("{name}.joints.jsonl"));
    }
    println!("logs                  {}", logs.join(", "));
}

fn run(
    scene_file: Option<PathBuf>,
    scene: Option<String>,
    out: PathBuf,
    duration: Option<f64>,
    summary_json: Option<PathBuf>,
    threads: usize,
    frames: bool,
    quiet: bool,
    check: bool,
) -> stark::Result<()> {
    let settings = base_settings(out.clone(), threads, frames);
    let (mut sim, scene_duration) = match (scene_file, scene) {
        (Some(path), _) => {
            let loaded = stark::io::scene::load_scene_with(&path, |s| {
                s.output.directory = out.clone();
                s.threads = threads;
                s.output.frames &= frames;
            })?;
            (loaded.simulation, loaded.duration_s)
        }
        (None, name) => {
            let scene = find_scene(name.as_deref().unwrap_or("default"))?;
            ((scene.build)(settings)?, scene.duration_s)
        }
    };
    let duration = duration.unwrap_or(scene_duration);
    if !(duration > 0.0 && duration.is_finite()) {
        return Err(stark::StarkError::InvalidInput(format!(
            "--duration must be positive, got {duration}"
        )));
    }
    let mut check_report = CheckReport::default();
    let summary = run_with_progress(&mut sim, duration, quiet, check.then_some(&mut check_report))?;
    if check {
        // The callback runs before each step; this checks the state after the last one.
        check_step(&sim, &mut check_report)?;
    }
    print_summary(&summary, &out);
    if check {
        println!(
            "check                 no intersection in any of {} states (the initial one and after each step); \
             inverted tets: {} at most, in {} states",
            check_report.steps_checked, check_report.most_inverted_tets, check_report.steps_with_inverted_tets
        );
    }
    print_logs(&sim);
    print_rigid_summary(&sim, &summary);
    if let Some(path) = summary_json {
        let text = serde_json::to_string_pretty(&summary).expect("serialisable summary");
        std::fs::write(&path, text).map_err(|e| stark::StarkError::Output {
            path: path.display().to_string(),
            source: e,
        })?;
    }
    Ok(())
}

/// The original Stark's wall time on this machine kind at 1 thread (reference/benchmark-scenes.md).
fn original_wall_s(scene: &str) -> Option<f64> {
    match scene {
        "hanging_cloth" => Some(6.5),
        "hanging_deformable_box" => Some(11.6),
        "spinning_box_cloth" => Some(190.0),
        "twisting_cloth" => Some(38.1),
        "rb_point" => Some(0.25),
        "deformable_and_rigid_collisions" => Some(3.1),
        "simple_grasp" => Some(3.0),
        _ => None,
    }
}

fn bench(scenes: Vec<String>, threads: Vec<usize>, json: Option<PathBuf>) -> stark::Result<()> {
    let names: Vec<String> = if scenes.is_empty() {
        vec![
            "hanging_cloth".into(),
            "hanging_deformable_box".into(),
            "hanging_cloth_64".into(),
            "hanging_cloth_128".into(),
            "rb_point".into(),
            "deformable_and_rigid_collisions".into(),
            "simple_grasp".into(),
            "spinning_box_cloth".into(),
            "twisting_cloth".into(),
            "twisting_cloth_64".into(),
        ]
    } else {
        scenes
    };
    println!(
        "{:<22} {:>3} {:>6} {:>9} {:>9} {:>9} {:>7} {:>6} {:>6} {:>5} {:>5} {:>6} {:>5} {:>9}",
        "scene",
        "thr",
        "steps",
        "wall [s]",
        "s/sim. s",
        "Newton/st",
        "CG/Newt",
        "pairs",
        "detect%",
        "ccd%",
        "eval%",
        "solve%",
        "ls%",
        "original"
    );
    let mut results = Vec::new();
    for name in &names {
        let scene = find_scene(name)?;
        for &t in &threads {
            let dir = std::env::temp_dir().join(format!("stark-bench-{}", std::process::id()));
            let mut settings = base_settings(dir, t, false);
            settings.output.step_log = false;
            let mut sim = (scene.build)(settings)?;
            let s = sim.run(scene.duration_s)?;
            let tt = &s.times;
            let total = tt.total_s().max(1e-12);
            let original = original_wall_s(name)
                .map(|w| format!("{w:.1} s"))
                .unwrap_or_else(|| "-".into());
            println!(
                "{:<22} {:>3} {:>6} {:>9.2} {:>9.3} {:>9.2} {:>7.1} {:>6.0} {:>7.0} {:>5.0} {:>5.0} {:>6.0} {:>5.0} {:>9}",
                name,
                t,
                s.steps,
                s.wall_time_s,
                s.wall_time_per_simulated_s,
                s.newton_iterations_per_step,
                s.cg_iterations as f64 / s.newton_iterations.max(1) as f64,
                s.mean_active_pairs,
                100.0 * tt.prepare_s / total,
                100.0 * tt.ccd_s / total,
                100.0 * tt.evaluation_s / total,
                100.0 * tt.linear_solve_s / total,
                100.0 * tt.line_search_s / total,
                original
            );
            results.push(serde_json::json!({ "scene": name, "threads": t, "summary": s, "original_wall_s": original_wall_s(name) }));
        }
    }
    if let Some(path) = json {
        let text = serde_json::to_string_pretty(&results).expect("serialisable");
        std::fs::write(&path, text).map_err(|e| stark::StarkError::Output {
            path: path.display().to_string(),
            source: e,
        })?;
    }
    Ok(())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run {
            scene_file,
            scene,
            out,
            duration,
            summary_json,
            threads,
            no_frames,
            quiet,
            check,
        } => run(
            scene_file,
            scene,
            out,
            duration,
            summary_json,
            threads,
            !no_frames,
            quiet,
            check,
        ),
        Command::List => {
            for s in builtin_scenes() {
                println!("{:<26} {:>6.2} s  {}", s.name, s.duration_s, s.description);
            }
            Ok(())
        }
        Command::Bench { scenes, threads, json } => bench(scenes, threads, json),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

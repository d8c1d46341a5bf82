//! `stark`: run scenes and benchmarks from the command line.

use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use stark::io::SceneOrigin;
use stark::rigidbodies::joints::{Measure, Primitive};
use stark::scenes::{builtin_scenes, find_scene};
use stark::solver::FrameFormat;
use stark::{RunSummary, Settings, Simulation};
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};

mod bench;
mod grasp;
mod plot;
mod summary;
mod sweep;
mod view;

use bench::bench;
use summary::{print_logs, print_rigid_summary, print_robot_towel_outcome, print_summary};

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
    /// Run scene files, a built-in scene (--scene), or the default scene.
    Run {
        /// Scene files (TOML or JSON), run one after the other. Without any, the built-in
        /// `default` scene runs.
        scene_files: Vec<PathBuf>,
        /// Run a built-in scene by name (see `stark list`).
        #[arg(long, conflicts_with = "scene_files")]
        scene: Option<String>,
        /// Override a scene-file field, `key.path=value` (repeatable), e.g.
        /// `--set settings.time_step_s=0.01` or `--set surface.cloth.material.strain.youngs_modulus=1e5`.
        /// Built-in scenes take `settings.*` keys.
        #[arg(long = "set", value_name = "KEY.PATH=VALUE")]
        set: Vec<String>,
        /// Output directory for frames and logs (with several scene files, one subdirectory per
        /// scene).
        #[arg(long, default_value = "output")]
        out: PathBuf,
        /// Simulated duration in seconds (default: the scene's); the last step is shortened to
        /// land on it.
        #[arg(long)]
        duration: Option<f64>,
        #[command(flatten)]
        opts: RunOptions,
        /// Write the run summary as JSON to this file (an array with several scene files).
        #[arg(long)]
        summary_json: Option<PathBuf>,
        /// Do not write frames.
        #[arg(long)]
        no_frames: bool,
        /// Write legacy VTK frames (velocity only) instead of VTU with fields and a .pvd series.
        #[arg(long)]
        legacy_vtk: bool,
    },
    /// Continue a run from a checkpoint (written by `--checkpoint-every` or on Ctrl-C).
    Resume {
        /// The checkpoint file (`<out>/<scene>.ckpt`).
        checkpoint: PathBuf,
        /// Simulated time to add, s (default: what remains of the scene's duration).
        #[arg(long)]
        duration: Option<f64>,
        /// Output directory (default: the one of the run that wrote the checkpoint).
        #[arg(long)]
        out: Option<PathBuf>,
        #[command(flatten)]
        opts: RunOptions,
        /// Write the run summary as JSON to this file.
        #[arg(long)]
        summary_json: Option<PathBuf>,
    },
    /// Run a sweep file: a base scene and a grid of values, as independent processes, resumable
    /// (finished cases are skipped, interrupted ones continue from their checkpoints); ends
    /// with a summary. See `sweeps/` for examples.
    Sweep {
        /// The sweep file (TOML).
        file: PathBuf,
        /// Only write the summary of the cases finished so far (runs nothing).
        #[arg(long)]
        summary_only: bool,
    },
    /// List the built-in scenes.
    List,
    /// Plot series of step, body or joint logs (`*.steps.jsonl`, `*.bodies.jsonl`,
    /// `*.joints.jsonl`) against time into a PNG.
    Plot {
        /// Log files.
        #[arg(required = true)]
        logs: Vec<PathBuf>,
        /// Series to plot: a key path into each line, e.g. `newton_iterations`,
        /// `contact.active_pairs`, `joints.motor.driver_effort`, `bodies.wheel.position_m.2`
        /// (default: a few useful ones per kind of log). A key ending in a table or array plots
        /// every number below it.
        #[arg(long, num_args = 1..)]
        series: Vec<String>,
        /// Output file (default: the first log's name with .png).
        #[arg(short = 'o', long)]
        output: Option<PathBuf>,
    },
    /// Write a self-contained HTML viewer (frames packed in, no network needed) of a run's
    /// output directory.
    View {
        /// The run's output directory.
        output_dir: PathBuf,
        /// The HTML file (default: `<output_dir>/<scene>.html`).
        #[arg(short = 'o', long)]
        output: Option<PathBuf>,
    },
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
        /// The original Stark's wall times at 1 thread, measured on this machine in the same
        /// sitting: a JSON object `{ "scene": seconds }`; the table then shows them and the
        /// speed-up.
        #[arg(long)]
        original: Option<PathBuf>,
    },
}

/// Options shared by `run` and `resume`.
#[derive(clap::Args, Clone)]
struct RunOptions {
    /// Worker threads (0 = all cores).
    #[arg(long, default_value_t = 0)]
    threads: usize,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
    /// Write a checkpoint (`<out>/<scene>.ckpt`, replaced each time) every S simulated seconds
    /// and at the end; one is written on Ctrl-C in any case.
    #[arg(long, value_name = "S")]
    checkpoint_every: Option<f64>,
    /// Do not write the summary plot `<out>/<scene>.summary.png`.
    #[arg(long)]
    no_plot: bool,
    /// After every step, check independently that no contact edge crosses a contact triangle
    /// and count inverted tetrahedra; the run fails at the first intersection.
    #[arg(long)]
    check: bool,
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

/// Set by the first Ctrl-C: the run stops after the step in progress.
static INTERRUPTED: AtomicBool = AtomicBool::new(false);

/// The first Ctrl-C (SIGINT) asks the run to stop after the current step (logs flushed, a
/// checkpoint written, the summary printed, exit status 130); a second one exits at once.
fn install_interrupt_handler() -> stark::Result<()> {
    ctrlc::set_handler(|| {
        if INTERRUPTED.swap(true, Ordering::SeqCst) {
            std::process::exit(EXIT_INTERRUPTED.into());
        }
    })
    .map_err(|e| stark::StarkError::InvalidInput(format!("cannot install the Ctrl-C handler: {e}")))
}

/// Exit status after Ctrl-C (128 + SIGINT, as shells report it).
const EXIT_INTERRUPTED: u8 = 130;

/// Where `stark run` writes a scene's checkpoint.
fn checkpoint_path(sim: &Simulation) -> PathBuf {
    sim.settings
        .output
        .directory
        .join(format!("{}.ckpt", sim.settings.name))
}

/// How a run ended.
struct RunEnd {
    summary: RunSummary,
    interrupted: bool,
    checkpoint: Option<PathBuf>,
}

fn run_with_progress(
    sim: &mut Simulation,
    duration: f64,
    opts: &RunOptions,
    mut check: Option<&mut CheckReport>,
    mut grasp: Option<&mut grasp::GraspRun>,
) -> stark::Result<RunEnd> {
    if let Some(every) = opts.checkpoint_every {
        if !(every > 0.0 && every.is_finite()) {
            return Err(stark::StarkError::InvalidInput(format!(
                "--checkpoint-every must be a positive number of seconds, got {every}"
            )));
        }
    }
    let bar = if opts.quiet {
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
    let ckpt = checkpoint_path(sim);
    let mut next_checkpoint = opts.checkpoint_every.map(|every| start + every);
    let result = sim.run_with(duration, |s| {
        if INTERRUPTED.load(Ordering::SeqCst) {
            return Err(stark::StarkError::Interrupted { time_s: s.time() });
        }
        if let (Some(next), Some(every)) = (next_checkpoint.as_mut(), opts.checkpoint_every) {
            // Checkpoints are taken between steps, at the first step boundary past each mark.
            if s.time() >= *next - 1e-9 * every {
                s.save_checkpoint(&ckpt)?;
                while *next <= s.time() + 1e-9 * every {
                    *next += every;
                }
            }
        }
        bar.set_position(((s.time() - start) * 1000.0).round() as u64);
        let sum = s.summary();
        bar.set_message(format!(
            "step {} · {:.2} Newton/step",
            sum.steps, sum.newton_iterations_per_step
        ));
        if let Some(g) = grasp.as_deref_mut() {
            g.after_step(s);
        }
        match check.as_deref_mut() {
            Some(report) => check_step(s, report),
            None => Ok(()),
        }
    });
    bar.finish_and_clear();
    match result {
        Ok(summary) => {
            let checkpoint = if opts.checkpoint_every.is_some() {
                sim.save_checkpoint(&ckpt)?;
                Some(ckpt)
            } else {
                None
            };
            Ok(RunEnd {
                summary,
                interrupted: false,
                checkpoint,
            })
        }
        Err(stark::StarkError::Interrupted { .. }) => {
            sim.save_checkpoint(&ckpt)?;
            Ok(RunEnd {
                summary: sim.summary().clone(),
                interrupted: true,
                checkpoint: Some(ckpt),
            })
        }
        Err(e) => Err(e),
    }
}

/// Apply `settings.*` overrides to a built simulation's settings (built-in scenes are code, so
/// only their settings can be overridden).
fn override_settings(sim: &mut Simulation, overrides: &[String]) -> stark::Result<()> {
    if overrides.is_empty() {
        return Ok(());
    }
    let bad = |m: String| stark::StarkError::InvalidInput(m);
    let table = toml::Table::try_from(&sim.settings).map_err(|e| bad(format!("cannot write the settings: {e}")))?;
    let mut doc = toml::Table::new();
    doc.insert("settings".into(), toml::Value::Table(table));
    for o in overrides {
        if !o.trim_start().starts_with("settings.") {
            return Err(bad(format!(
                "--set {o}: a built-in scene is built by code; only its `settings.*` can be set (scene files take any field)"
            )));
        }
        stark::io::scene::apply_override(&mut doc, o).map_err(|m| bad(format!("--set {o}: {m}")))?;
    }
    let value = doc.remove("settings").expect("inserted above");
    let threads = sim.settings.threads;
    let mut settings: Settings = value
        .try_into()
        .map_err(|e: toml::de::Error| bad(format!("--set: {}", e.message().trim_end())))?;
    settings.threads = threads; // the thread pool is already built
    settings.validate()?;
    sim.settings = settings;
    Ok(())
}

/// Everything `stark run` does after a simulation is built: run it, print its summary, logs and
/// joints, write the summary plot and JSON. Returns the summary and whether Ctrl-C stopped it.
fn run_built(sim: &mut Simulation, duration: f64, opts: &RunOptions, check: bool) -> stark::Result<(RunSummary, bool)> {
    if !(duration > 0.0 && duration.is_finite()) {
        return Err(stark::StarkError::InvalidInput(format!(
            "--duration must be positive, got {duration}"
        )));
    }
    let out = sim.settings.output.directory.clone();
    let mut check_report = CheckReport::default();
    let mut grasp = grasp::GraspRun::find(sim);
    let end =
        sim.in_pool(|sim| run_with_progress(sim, duration, opts, check.then_some(&mut check_report), grasp.as_mut()))?;
    if let Some(g) = grasp.as_mut() {
        // The callback runs before each step; this watches the state after the last one.
        g.after_step(sim);
    }
    if check && !end.interrupted {
        // The callback runs before each step; this checks the state after the last one.
        check_step(sim, &mut check_report)?;
    }
    let summary = end.summary;
    print_summary(&summary, &out);
    if check {
        println!(
            "check                 no intersection in any of {} states (the initial one and after each step); \
             inverted tets: {} at most, in {} states",
            check_report.steps_checked, check_report.most_inverted_tets, check_report.steps_with_inverted_tets
        );
    }
    print_logs(sim);
    print_rigid_summary(sim, &summary);
    print_robot_towel_outcome(sim);
    if let Some(g) = &grasp {
        g.report(sim);
    }
    if !opts.no_plot && sim.settings.output.step_log {
        let log = out.join(format!("{}.steps.jsonl", sim.settings.name));
        let png = out.join(format!("{}.summary.png", sim.settings.name));
        match plot::summary_plot(&log, &png) {
            Ok(()) => println!("summary plot          {}", png.display()),
            Err(e) => eprintln!("warning: no summary plot: {e}"),
        }
    }
    if let Some(path) = &end.checkpoint {
        println!(
            "checkpoint            {} (t = {:.4} s; continue with `stark resume {}`)",
            path.display(),
            sim.time(),
            path.display()
        );
    }
    if end.interrupted {
        println!(
            "interrupted           at t = {:.4} s after the step in progress; every log is complete",
            sim.time()
        );
    }
    Ok((summary, end.interrupted))
}

fn write_summary_json(path: &std::path::Path, value: &impl serde::Serialize) -> stark::Result<()> {
    let text = serde_json::to_string_pretty(value).expect("serialisable summary");
    std::fs::write(path, text).map_err(|e| stark::StarkError::Output {
        path: path.display().to_string(),
        source: e,
    })
}

fn run(
    scene_files: Vec<PathBuf>,
    scene: Option<String>,
    set: Vec<String>,
    out: PathBuf,
    duration: Option<f64>,
    opts: RunOptions,
    summary_json: Option<PathBuf>,
    frames: bool,
    legacy_vtk: bool,
) -> stark::Result<ExitCode> {
    install_interrupt_handler()?;
    let format = if legacy_vtk {
        FrameFormat::LegacyVtk
    } else {
        FrameFormat::Vtu
    };
    let mut summaries = Vec::new();
    let several = scene_files.len() > 1;
    // Scene files, or one built-in scene.
    let jobs: Vec<Option<PathBuf>> = if scene_files.is_empty() {
        vec![None]
    } else {
        scene_files.into_iter().map(Some).collect()
    };
    for job in jobs {
        let (mut sim, scene_duration) = match job {
            Some(path) => {
                let stem = path
                    .file_stem()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_default();
                let dir = if several { out.join(&stem) } else { out.clone() };
                let loaded = stark::io::scene::load_scene_with_overrides(&path, &set, |s| {
                    s.output.directory = dir.clone();
                    s.threads = opts.threads;
                    s.output.frames &= frames;
                    s.output.frame_format = format;
                })?;
                (loaded.simulation, loaded.duration_s)
            }
            None => {
                let name = scene.as_deref().unwrap_or("default");
                let found = find_scene(name)?;
                let mut settings = base_settings(out.clone(), opts.threads, frames);
                settings.output.frame_format = format;
                let mut sim = (found.build)(settings)?;
                override_settings(&mut sim, &set)?;
                sim.set_scene_origin(SceneOrigin::Builtin { name: name.to_string() });
                (sim, found.duration_s)
            }
        };
        if several {
            println!("== {}", sim.settings.name);
        }
        let (summary, interrupted) = run_built(&mut sim, duration.unwrap_or(scene_duration), &opts, opts.check)?;
        summaries.push(summary);
        if interrupted {
            break;
        }
    }
    if let Some(path) = summary_json {
        if summaries.len() == 1 {
            write_summary_json(&path, &summaries[0])?;
        } else {
            write_summary_json(&path, &summaries)?;
        }
    }
    Ok(if INTERRUPTED.load(Ordering::SeqCst) {
        ExitCode::from(EXIT_INTERRUPTED)
    } else {
        ExitCode::SUCCESS
    })
}

fn resume(
    checkpoint: PathBuf,
    duration: Option<f64>,
    out: Option<PathBuf>,
    opts: RunOptions,
    summary_json: Option<PathBuf>,
) -> stark::Result<ExitCode> {
    install_interrupt_handler()?;
    let header = stark::io::read_checkpoint_header(&checkpoint)?;
    let out = out.unwrap_or_else(|| header.output_directory.clone());
    let (mut sim, scene_duration) = match &header.origin {
        SceneOrigin::Builtin { name } => {
            let found = find_scene(name)?;
            let mut sim = (found.build)(base_settings(out.clone(), opts.threads, true))?;
            sim.set_scene_origin(header.origin.clone());
            (sim, found.duration_s)
        }
        SceneOrigin::File { path, overrides } => {
            let loaded = stark::io::scene::load_scene_with_overrides(path, overrides, |s| {
                s.output.directory = out.clone();
                s.threads = opts.threads;
            })?;
            (loaded.simulation, loaded.duration_s)
        }
        SceneOrigin::Program => {
            return Err(stark::StarkError::Checkpoint {
                path: checkpoint.display().to_string(),
                message: "it was written by a program that built its scene in code: rebuild the scene there and \
                          call restore_checkpoint"
                    .into(),
            })
        }
    };
    sim.restore_checkpoint(&checkpoint)?;
    let remaining = scene_duration - sim.time();
    let duration = match duration {
        Some(d) => d,
        None if remaining > 1e-9 => remaining,
        None => {
            return Err(stark::StarkError::InvalidInput(format!(
                "the checkpoint is at t = {:.4} s, the end of the scene's {scene_duration} s: give --duration to go on",
                sim.time()
            )))
        }
    };
    println!(
        "resuming              {} at t = {:.4} s (step {})",
        header.scene, header.time_s, header.steps
    );
    let (summary, interrupted) = run_built(&mut sim, duration, &opts, opts.check)?;
    if let Some(path) = summary_json {
        write_summary_json(&path, &summary)?;
    }
    Ok(if interrupted {
        ExitCode::from(EXIT_INTERRUPTED)
    } else {
        ExitCode::SUCCESS
    })
}

/// `stark list`: name, duration and description in aligned columns.
fn list() {
    let scenes = builtin_scenes();
    let name_w = scenes
        .iter()
        .map(|s| s.name.len())
        .max()
        .unwrap_or(0)
        .max("scene".len());
    let durations: Vec<String> = scenes.iter().map(|s| format!("{:.2} s", s.duration_s)).collect();
    let dur_w = durations
        .iter()
        .map(|d| d.len())
        .max()
        .unwrap_or(0)
        .max("duration".len());
    println!("{:<name_w$}  {:>dur_w$}  description", "scene", "duration");
    for (s, d) in scenes.iter().zip(&durations) {
        println!("{:<name_w$}  {:>dur_w$}  {}", s.name, d, s.description);
    }
}

/// glibc hands blocks above its mmap threshold back to the system when they are freed, and the
/// next allocation of that size faults its pages in again, zeroed (1–2 µs per 4 KiB page here):
/// a multigrid set-up at every step allocates and frees tens of MB. Blocks up to the threshold's
/// ceiling (32 MiB) come from the heap instead, which keeps freed memory for reuse.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
fn keep_freed_memory() {
    // SAFETY: `mallopt` only sets the allocator's parameters; it runs before any other thread
    // starts.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 32 << 20);
        libc::mallopt(libc::M_TRIM_THRESHOLD, 1 << 30);
    }
}

fn main() -> ExitCode {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    keep_freed_memory();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run {
            scene_files,
            scene,
            set,
            out,
            duration,
            opts,
            summary_json,
            no_frames,
            legacy_vtk,
        } => run(
            scene_files,
            scene,
            set,
            out,
            duration,
            opts,
            summary_json,
            !no_frames,
            legacy_vtk,
        ),
        Command::Resume {
            checkpoint,
            duration,
            out,
            opts,
            summary_json,
        } => resume(checkpoint, duration, out, opts, summary_json),
        Command::Sweep { file, summary_only } => {
            sweep::sweep(&file, summary_only).map(|ok| if ok { ExitCode::SUCCESS } else { ExitCode::FAILURE })
        }
        Command::List => {
            list();
            Ok(ExitCode::SUCCESS)
        }
        Command::Plot { logs, series, output } => plot::plot_logs(&logs, &series, output.as_deref()).map(|path| {
            println!("{}", path.display());
            ExitCode::SUCCESS
        }),
        Command::View { output_dir, output } => view::write_viewer(&output_dir, output.as_deref()).map(|path| {
            println!("{}", path.display());
            ExitCode::SUCCESS
        }),
        Command::Bench {
            scenes,
            threads,
            json,
            original,
        } => bench(scenes, threads, json, original).map(|()| ExitCode::SUCCESS),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

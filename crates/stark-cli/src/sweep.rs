//! `stark sweep FILE`: a set of runs (a base scene and a grid of values) as independent processes,
//! `jobs` at a time with `threads` each, resumable: a case whose result file exists is skipped,
//! and a case with a checkpoint continues from it. Ends with a summary (markdown, JSON and a PNG
//! grid of the cases' final-state pictures). Every case runs with `--check` (an independent
//! intersection and inversion test after each step).
//!
//! A sweep file (TOML):
//!
//! ```toml
//! scene = "kobuki_towel_{floor}_{configuration}"   # a built-in scene, {names} from the grid
//! # or: scene_file = "scenes/franka_box.toml"       # relative to the sweep file
//! out = "output/sweeps/kobuki_towel"                # runs (frames, logs, checkpoints)
//! results = "docs/validation/kobuki_towel"          # one small JSON per finished case
//! jobs = 2
//! threads = 1
//! checkpoint_every_s = 0.25
//! # duration_s = 0.3                                # default: the scene's
//! [grid]
//! floor = ["carpet", "polished"]                    # a name used in `scene`
//! configuration = [1, 2, 3, 4, 5, 6, 7, 8]
//! # "settings.time_step_s" = [0.01, 0.005]          # a dotted key is a `--set` override
//! ```
//!
//! Relative paths are taken from the sweep file's folder. Cases are every combination of the
//! grid's values, its keys in alphabetical order, the first varying slowest.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};

/// A sweep file.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SweepFile {
    scene: Option<String>,
    scene_file: Option<PathBuf>,
    out: PathBuf,
    results: PathBuf,
    #[serde(default = "one")]
    jobs: usize,
    #[serde(default = "one")]
    threads: usize,
    #[serde(default = "quarter")]
    checkpoint_every_s: f64,
    duration_s: Option<f64>,
    #[serde(default)]
    grid: BTreeMap<String, Vec<toml::Value>>,
}

fn one() -> usize {
    1
}
fn quarter() -> f64 {
    0.25
}

/// One run of a sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct Case {
    /// Its name (the folder of its run and its result file's stem).
    pub name: String,
    /// Built-in scene name, or the scene file.
    pub scene: SceneRef,
    /// `--set` overrides.
    pub overrides: Vec<String>,
}

/// What a case runs.
#[derive(Clone, Debug, PartialEq)]
pub enum SceneRef {
    /// A built-in scene.
    Builtin(String),
    /// A scene file.
    File(PathBuf),
}

/// The result file of a finished case.
#[derive(Debug, Serialize, Deserialize)]
pub struct CaseResult {
    /// Case name.
    pub case: String,
    /// The run's summary (as `stark run --summary-json` writes it).
    pub summary: serde_json::Value,
    /// The outcome of a robot–towel run: `{outcome, reason, ...}`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub outcome: Option<serde_json::Value>,
    /// The lab's outcome of a robot–towel case (Table I).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lab_outcome: Option<char>,
    /// Every step was checked for intersections and inverted elements (`stark run --check`; a
    /// failed check fails the case).
    #[serde(default)]
    pub checked_every_step: bool,
}

fn bad(m: String) -> stark::StarkError {
    stark::StarkError::InvalidInput(m)
}

fn value_text(v: &toml::Value) -> String {
    match v {
        toml::Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

/// The cases of a sweep file: every combination of the grid's values, its keys taken in
/// alphabetical order with the first varying slowest.
pub fn cases(file: &Path) -> stark::Result<(Vec<Case>, SweepPlan)> {
    let text = std::fs::read_to_string(file).map_err(|e| bad(format!("{}: {e}", file.display())))?;
    let s: SweepFile = toml::from_str(&text).map_err(|e| bad(format!("{}: {e}", file.display())))?;
    let dir = file.parent().unwrap_or(Path::new("."));
    let base = match (&s.scene, &s.scene_file) {
        (Some(name), None) => SceneRef::Builtin(name.clone()),
        (None, Some(path)) => SceneRef::File(dir.join(path)),
        _ => {
            return Err(bad(format!(
                "{}: give exactly one of `scene` (a built-in scene) and `scene_file`",
                file.display()
            )))
        }
    };
    if s.jobs == 0 || !(s.checkpoint_every_s > 0.0) {
        return Err(bad(format!(
            "{}: `jobs` must be at least 1 and `checkpoint_every_s` positive",
            file.display()
        )));
    }
    for (key, values) in &s.grid {
        if values.is_empty() {
            return Err(bad(format!("{}: grid `{key}` has no values", file.display())));
        }
    }
    // The cartesian product of the grid.
    let mut combos: Vec<Vec<(String, String)>> = vec![Vec::new()];
    for (key, values) in &s.grid {
        combos = combos
            .into_iter()
            .flat_map(|c| {
                values.iter().map(move |v| {
                    let mut c = c.clone();
                    c.push((key.clone(), value_text(v)));
                    c
                })
            })
            .collect();
    }
    let mut out = Vec::new();
    for combo in combos {
        let mut scene = base.clone();
        let mut overrides = Vec::new();
        let mut name_parts = Vec::new();
        for (key, value) in &combo {
            if key.contains('.') {
                overrides.push(format!("{key}={value}"));
                name_parts.push(format!("{}={value}", key.rsplit('.').next().unwrap_or(key)));
            } else if let SceneRef::Builtin(n) = &mut scene {
                let slot = format!("{{{key}}}");
                if !n.contains(&slot) {
                    return Err(bad(format!(
                        "{}: grid `{key}` is neither used in `scene` as {slot} nor a dotted `--set` key",
                        file.display()
                    )));
                }
                *n = n.replace(&slot, value);
            } else {
                return Err(bad(format!(
                    "{}: grid `{key}`: a scene file's grid keys are `--set` paths (with a dot)",
                    file.display()
                )));
            }
        }
        let stem = match &scene {
            SceneRef::Builtin(n) => n.clone(),
            SceneRef::File(p) => p
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default(),
        };
        let name = match (&scene, name_parts.is_empty()) {
            (_, true) => stem,
            _ => format!("{stem}__{}", name_parts.join("_")),
        };
        out.push(Case { name, scene, overrides });
    }
    Ok((
        out,
        SweepPlan {
            out: dir.join(&s.out),
            results: dir.join(&s.results),
            jobs: s.jobs,
            threads: s.threads,
            checkpoint_every_s: s.checkpoint_every_s,
            duration_s: s.duration_s,
            grid_rows: s.grid.values().last().map_or(1, Vec::len),
        },
    ))
}

/// How a sweep runs.
#[derive(Clone, Debug)]
pub struct SweepPlan {
    out: PathBuf,
    results: PathBuf,
    jobs: usize,
    threads: usize,
    checkpoint_every_s: f64,
    duration_s: Option<f64>,
    /// Rows of the picture grid: the values of the fastest-varying grid key (the floors of the
    /// robot–towel suite); the other keys run along the columns.
    grid_rows: usize,
}

impl SweepPlan {
    fn result_path(&self, case: &Case) -> PathBuf {
        self.results.join(format!("{}.json", case.name))
    }
    fn run_dir(&self, case: &Case) -> PathBuf {
        self.out.join(&case.name)
    }
}

/// The checkpoint a case's run left in `run_dir`, if any.
fn checkpoint(case: &Case, run_dir: &Path) -> Option<PathBuf> {
    scene_name(case, run_dir)
        .map(|n| run_dir.join(format!("{n}.ckpt")))
        .filter(|c| c.exists())
}

/// The scene name a case's run writes its files under.
fn scene_name(case: &Case, run_dir: &Path) -> Option<String> {
    match &case.scene {
        SceneRef::Builtin(n) => Some(n.clone()),
        // A scene file names its run in `settings.name`: find the checkpoint or summary it left.
        SceneRef::File(_) => std::fs::read_dir(run_dir).ok()?.flatten().find_map(|e| {
            let n = e.file_name().to_string_lossy().into_owned();
            n.strip_suffix(".ckpt").map(str::to_string)
        }),
    }
}

fn spawn(case: &Case, plan: &SweepPlan) -> stark::Result<Child> {
    let exe = std::env::current_exe().map_err(|e| bad(format!("cannot find the stark executable: {e}")))?;
    let dir = plan.run_dir(case);
    std::fs::create_dir_all(&dir).map_err(|e| bad(format!("{}: {e}", dir.display())))?;
    let mut cmd = Command::new(exe);
    // A checkpoint this build cannot read (another format version, a damaged file) cannot be
    // continued: the case starts afresh (its run overwrites the checkpoint) instead of stopping
    // the sweep.
    let resumable = checkpoint(case, &dir).and_then(|ckpt| match stark::io::read_checkpoint_header(&ckpt) {
        Ok(header) => Some((ckpt, header)),
        Err(e) => {
            eprintln!("{}: {e}; the case starts afresh", case.name);
            None
        }
    });
    match resumable {
        Some((ckpt, header)) => {
            cmd.arg("resume").arg(&ckpt);
            if let Some(d) = plan.duration_s {
                // `resume` continues to the scene's duration by default; the sweep's is shorter.
                cmd.arg("--duration").arg((d - header.time_s).to_string());
            }
        }
        None => {
            cmd.arg("run");
            match &case.scene {
                SceneRef::Builtin(n) => {
                    cmd.arg("--scene").arg(n);
                }
                SceneRef::File(p) => {
                    cmd.arg(p);
                }
            }
            for o in &case.overrides {
                cmd.arg("--set").arg(o);
            }
            cmd.arg("--out").arg(&dir);
            if let Some(d) = plan.duration_s {
                cmd.arg("--duration").arg(d.to_string());
            }
        }
    }
    // Every step checked for intersections and inverted elements, independently of the solver.
    cmd.arg("--check")
        .arg("--threads")
        .arg(plan.threads.to_string())
        .arg("--quiet")
        .arg("--checkpoint-every")
        .arg(plan.checkpoint_every_s.to_string())
        .arg("--summary-json")
        .arg(dir.join("summary.json"))
        .stdout(
            std::fs::File::create(dir.join("stdout.txt"))
                .map(Stdio::from)
                .unwrap_or(Stdio::null()),
        )
        .stderr(
            std::fs::File::create(dir.join("stderr.txt"))
                .map(Stdio::from)
                .unwrap_or(Stdio::null()),
        );
    cmd.spawn()
        .map_err(|e| bad(format!("cannot start case {}: {e}", case.name)))
}

/// Collect a finished case's result into its result file.
fn collect(case: &Case, plan: &SweepPlan) -> stark::Result<CaseResult> {
    let dir = plan.run_dir(case);
    let summary_path = dir.join("summary.json");
    let text = std::fs::read_to_string(&summary_path).map_err(|e| bad(format!("{}: {e}", summary_path.display())))?;
    let summary: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| bad(format!("{}: {e}", summary_path.display())))?;
    let summary = match summary {
        serde_json::Value::Array(mut a) if !a.is_empty() => a.remove(0),
        other => other,
    };
    let name = summary["scene"].as_str().unwrap_or(&case.name).to_string();
    let probe = dir.join(format!("{name}.{}.jsonl", stark::scenes::kobuki_towel::PROBE));
    let outcome = if probe.exists() {
        let c = stark::scenes::kobuki_towel::classify_log(&probe)?;
        Some(serde_json::to_value(c).expect("serialisable"))
    } else {
        None
    };
    let lab_outcome = stark::scenes::kobuki_towel::Case::from_name(&name).map(|c| c.lab_outcome());
    let result = CaseResult {
        case: case.name.clone(),
        summary,
        outcome,
        lab_outcome,
        checked_every_step: true,
    };
    std::fs::create_dir_all(&plan.results).map_err(|e| bad(format!("{}: {e}", plan.results.display())))?;
    // The run's pictures go with its result (small PNGs, meant to be committed).
    for kind in ["motors", "final"] {
        let png = dir.join(format!("{name}.{kind}.png"));
        if png.exists() {
            let to = plan.results.join(format!("{}.{kind}.png", case.name));
            std::fs::copy(&png, &to).map_err(|e| bad(format!("{}: {e}", to.display())))?;
        }
    }
    let path = plan.result_path(case);
    let text = serde_json::to_string_pretty(&result).expect("serialisable");
    std::fs::write(&path, text + "\n").map_err(|e| bad(format!("{}: {e}", path.display())))?;
    Ok(result)
}

/// Run a sweep file: every case not finished yet, `jobs` at a time, the summary rewritten after
/// each (only the summary with `summary_only`).
pub fn sweep(file: &Path, summary_only: bool) -> stark::Result<bool> {
    let (cases, plan) = cases(file)?;
    if summary_only {
        write_summary(&cases, &plan)?;
        return Ok(true);
    }
    let todo: Vec<&Case> = cases.iter().filter(|c| !plan.result_path(c).exists()).collect();
    println!(
        "sweep                 {} cases, {} finished, {} to run ({} jobs × {} threads)",
        cases.len(),
        cases.len() - todo.len(),
        todo.len(),
        plan.jobs,
        plan.threads
    );
    // A case whose checkpoint is already at the end only needs collecting.
    let mut todo = todo;
    let mut k = 0;
    while k < todo.len() {
        let case = todo[k];
        let dir = plan.run_dir(case);
        let finished = checkpoint(case, &dir)
            .and_then(|c| stark::io::read_checkpoint_header(&c).ok())
            .zip(plan.duration_s)
            .is_some_and(|(h, d)| h.time_s >= d - 1e-9);
        if finished && dir.join("summary.json").exists() {
            collect(case, &plan)?;
            todo.remove(k);
        } else {
            k += 1;
        }
    }
    let mut queue = todo.into_iter();
    let mut running: Vec<(&Case, Child, std::time::Instant)> = Vec::new();
    let mut failed = Vec::new();
    loop {
        while running.len() < plan.jobs {
            let Some(case) = queue.next() else { break };
            println!("start                 {}", case.name);
            running.push((case, spawn(case, &plan)?, std::time::Instant::now()));
        }
        if running.is_empty() {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(200));
        let mut k = 0;
        while k < running.len() {
            let status = running[k]
                .1
                .try_wait()
                .map_err(|e| bad(format!("case {}: {e}", running[k].0.name)))?;
            let Some(status) = status else {
                k += 1;
                continue;
            };
            let (case, _, started) = running.swap_remove(k);
            let wall = started.elapsed().as_secs_f64();
            if status.success() && plan.run_dir(case).join("summary.json").exists() {
                let r = collect(case, &plan)?;
                let interrupted = r.summary["simulated_time_s"].as_f64().unwrap_or(0.0) <= 0.0;
                let outcome = r
                    .outcome
                    .as_ref()
                    .and_then(|o| o["outcome"].as_str())
                    .map(|o| format!(", outcome {o}"))
                    .unwrap_or_default();
                println!(
                    "done                  {} in {wall:.0} s{outcome}{}",
                    case.name,
                    if interrupted { " (nothing simulated)" } else { "" }
                );
                // The results folder stays complete while the sweep goes on (a session may end
                // before the sweep does).
                write_summary(&cases, &plan)?;
            } else {
                println!(
                    "failed                {} (exit {status}; see {})",
                    case.name,
                    plan.run_dir(case).join("stderr.txt").display()
                );
                failed.push(case.name.clone());
            }
        }
    }
    write_summary(&cases, &plan)?;
    Ok(failed.is_empty())
}

/// `summary.md` and `summary.json` in the results folder: every finished case.
fn write_summary(cases: &[Case], plan: &SweepPlan) -> stark::Result<()> {
    let mut results = Vec::new();
    for c in cases {
        let path = plan.result_path(c);
        if let Ok(text) = std::fs::read_to_string(&path) {
            let r: CaseResult = serde_json::from_str(&text).map_err(|e| bad(format!("{}: {e}", path.display())))?;
            results.push(r);
        }
    }
    let mut md = String::from(
        "| case | outcome | lab | original Stark | simulated [s] | wall [s] | steps | Newton/step | failed attempts | largest residual [N] | `--check` every step |\n\
         |---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in &results {
        let s = &r.summary;
        let outcome = r.outcome.as_ref().and_then(|o| o["outcome"].as_str()).unwrap_or("–");
        let paper = s["scene"]
            .as_str()
            .and_then(stark::scenes::kobuki_towel::Case::from_name)
            .map(|c| String::from(c.paper_simulation_outcome()))
            .unwrap_or_else(|| "–".into());
        md.push_str(&format!(
            "| {} | {} | {} | {} | {:.3} | {:.0} | {} | {:.2} | {} | {:.1e} | {} |\n",
            r.case,
            outcome,
            r.lab_outcome.map(String::from).unwrap_or_else(|| "–".into()),
            paper,
            s["simulated_time_s"].as_f64().unwrap_or(f64::NAN),
            s["wall_time_s"].as_f64().unwrap_or(f64::NAN),
            s["steps"].as_u64().unwrap_or(0),
            s["newton_iterations_per_step"].as_f64().unwrap_or(f64::NAN),
            s["failed_steps"].as_u64().unwrap_or(0),
            s["max_residual_n"].as_f64().unwrap_or(f64::NAN),
            if r.checked_every_step { "yes" } else { "no" },
        ));
    }
    std::fs::create_dir_all(&plan.results).map_err(|e| bad(format!("{}: {e}", plan.results.display())))?;
    let grid_name = "summary.final.png";
    if picture_grid(cases, plan, &results, &plan.results.join(grid_name))? {
        md.push_str(&format!("\n![final states]({grid_name})\n"));
    }
    let md_path = plan.results.join("summary.md");
    std::fs::write(&md_path, &md).map_err(|e| bad(format!("{}: {e}", md_path.display())))?;
    let json_path = plan.results.join("summary.json");
    let json = serde_json::to_string_pretty(&results).expect("serialisable");
    std::fs::write(&json_path, json + "\n").map_err(|e| bad(format!("{}: {e}", json_path.display())))?;
    println!(
        "summary               {} of {} cases finished: {}",
        results.len(),
        cases.len(),
        md_path.display()
    );
    Ok(())
}

/// Width of one case's picture in the grid, px.
const TILE_WIDTH_PX: u32 = 320;
/// Height of the label band above each picture, px.
const LABEL_HEIGHT_PX: u32 = 44;

/// The finished cases' final-state pictures side by side, `plan.grid_rows` rows (the fastest-
/// varying grid key) and the other keys along the columns, each labelled with its case and
/// outcomes; a case not finished yet is an empty tile. Returns false when no case has a picture.
fn picture_grid(cases: &[Case], plan: &SweepPlan, results: &[CaseResult], png: &Path) -> stark::Result<bool> {
    use image::{imageops, Rgb, RgbImage};
    use plotters::prelude::*;
    let picture = |c: &Case| plan.results.join(format!("{}.final.png", c.name));
    let pictures: Vec<Option<RgbImage>> = cases
        .iter()
        .map(|c| image::open(picture(c)).ok().map(|i| i.to_rgb8()))
        .collect();
    let Some(first) = pictures.iter().flatten().next() else {
        return Ok(false);
    };
    let tile_h = (f64::from(first.height()) * f64::from(TILE_WIDTH_PX) / f64::from(first.width())).round() as u32;
    let rows = plan.grid_rows.max(1);
    let columns = cases.len().div_ceil(rows);
    let (width, height) = (TILE_WIDTH_PX * columns as u32, (tile_h + LABEL_HEIGHT_PX) * rows as u32);
    let mut canvas = RgbImage::from_pixel(width, height, Rgb([255, 255, 255]));
    let at = |i: usize| {
        let (row, column) = (i % rows, i / rows);
        (TILE_WIDTH_PX * column as u32, (tile_h + LABEL_HEIGHT_PX) * row as u32)
    };
    for (i, p) in pictures.iter().enumerate() {
        if let Some(p) = p {
            let thumb = imageops::resize(p, TILE_WIDTH_PX, tile_h, imageops::FilterType::Triangle);
            let (x, y) = at(i);
            imageops::replace(&mut canvas, &thumb, i64::from(x), i64::from(y + LABEL_HEIGHT_PX));
        }
    }
    crate::plot::register_font();
    {
        let buffer: &mut [u8] = &mut canvas;
        let root = BitMapBackend::with_buffer(buffer, (width, height)).into_drawing_area();
        let draw_err = |e: DrawingAreaErrorKind<_>| bad(format!("{}: {e}", png.display()));
        for (i, case) in cases.iter().enumerate() {
            let (x, y) = at(i);
            let r = results.iter().find(|r| r.case == case.name);
            let outcome = r
                .and_then(|r| r.outcome.as_ref())
                .and_then(|o| o["outcome"].as_str())
                .map(|o| format!("outcome {o}"));
            let lab = r.and_then(|r| r.lab_outcome).map(|l| format!("lab {l}"));
            let second = match (r, outcome, lab) {
                (None, ..) => "not finished".to_string(),
                (Some(_), o, l) => [o, l].into_iter().flatten().collect::<Vec<_>>().join(", "),
            };
            let x = x as i32 + 6;
            root.draw_text(
                &case.name,
                &("sans-serif", 15).into_font().color(&BLACK),
                (x, y as i32 + 4),
            )
            .map_err(draw_err)?;
            root.draw_text(
                &second,
                &("sans-serif", 15).into_font().color(&BLACK),
                (x, y as i32 + 23),
            )
            .map_err(draw_err)?;
        }
        root.present().map_err(draw_err)?;
    }
    canvas.save(png).map_err(|e| bad(format!("{}: {e}", png.display())))?;
    Ok(true)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(dir: &Path, text: &str) -> PathBuf {
        let p = dir.join("sweep.toml");
        std::fs::write(&p, text).unwrap();
        p
    }

    /// A sweep over the robot–towel cases: both floors, `configurations` (a TOML array), and
    /// `extra` grid lines.
    fn towel_sweep(dir: &Path, configurations: &str, extra: &str) -> PathBuf {
        write(
            dir,
            &format!(
                "scene = \"kobuki_towel_{{floor}}_{{configuration}}\"\nout = \"runs\"\nresults = \"results\"\n\
                 [grid]\nfloor = [\"carpet\", \"polished\"]\nconfiguration = {configurations}\n{extra}\n"
            ),
        )
    }

    #[test]
    fn the_grid_fills_the_scene_name_and_sets_overrides() {
        let dir = tempfile::tempdir().unwrap();
        let f = towel_sweep(dir.path(), "[1, 2]", "\"settings.time_step_s\" = [0.01]");
        let (cases, plan) = cases(&f).unwrap();
        let names: Vec<_> = cases.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "kobuki_towel_carpet_1__time_step_s=0.01",
                "kobuki_towel_polished_1__time_step_s=0.01",
                "kobuki_towel_carpet_2__time_step_s=0.01",
                "kobuki_towel_polished_2__time_step_s=0.01"
            ]
        );
        assert_eq!(cases[0].scene, SceneRef::Builtin("kobuki_towel_carpet_1".into()));
        assert_eq!(cases[0].overrides, ["settings.time_step_s=0.01"]);
        assert_eq!(plan.out, dir.path().join("runs"));
    }

    #[test]
    fn bad_sweep_files_say_what_is_wrong() {
        let dir = tempfile::tempdir().unwrap();
        let err = |text: &str| cases(&write(dir.path(), text)).unwrap_err().to_string();
        assert!(err("out = \"a\"\nresults = \"b\"").contains("exactly one of `scene`"));
        let e = err("scene = \"x_{a}\"\nout = \"a\"\nresults = \"b\"\n[grid]\nb = [1]");
        assert!(e.contains("grid `b`"), "{e}");
        let e = err("scene = \"x\"\nout = \"a\"\nresults = \"b\"\njobs = 0");
        assert!(e.contains("jobs"), "{e}");
        let e = err("scene = \"x\"\nout = \"a\"\nresults = \"b\"\ntypo = 1");
        assert!(e.contains("typo"), "{e}");
    }

    #[test]
    fn the_summary_tiles_the_final_pictures_by_the_grid() {
        let dir = tempfile::tempdir().unwrap();
        let f = towel_sweep(dir.path(), "[1, 2, 3]", "");
        let (cases, plan) = cases(&f).unwrap();
        std::fs::create_dir_all(&plan.results).unwrap();
        // One finished case with a 100 × 150 picture; the others not finished.
        let done = &cases[1];
        image::RgbImage::from_pixel(100, 150, image::Rgb([200, 0, 0]))
            .save(plan.results.join(format!("{}.final.png", done.name)))
            .unwrap();
        let result = CaseResult {
            case: done.name.clone(),
            summary: serde_json::json!({"scene": done.name, "simulated_time_s": 6.0}),
            outcome: Some(serde_json::json!({"outcome": "O"})),
            lab_outcome: Some('O'),
            checked_every_step: true,
        };
        std::fs::write(plan.result_path(done), serde_json::to_string(&result).unwrap()).unwrap();
        write_summary(&cases, &plan).unwrap();

        let grid = image::open(plan.results.join("summary.final.png")).unwrap().to_rgb8();
        // Floors along the rows, configurations along the columns.
        let tile_h = 150 * TILE_WIDTH_PX / 100;
        assert_eq!(grid.dimensions(), (3 * TILE_WIDTH_PX, 2 * (tile_h + LABEL_HEIGHT_PX)));
        // cases[1] is polished_1: second row, first column.
        assert_eq!(done.name, "kobuki_towel_polished_1");
        let centre = |row: u32, column: u32| {
            *grid.get_pixel(
                column * TILE_WIDTH_PX + TILE_WIDTH_PX / 2,
                row * (tile_h + LABEL_HEIGHT_PX) + LABEL_HEIGHT_PX + tile_h / 2,
            )
        };
        assert_eq!(centre(1, 0), image::Rgb([200, 0, 0]));
        assert_eq!(centre(0, 0), image::Rgb([255, 255, 255]));
        let md = std::fs::read_to_string(plan.results.join("summary.md")).unwrap();
        assert!(md.contains("| kobuki_towel_polished_1 | O | O | O |"), "{md}");
        assert!(md.contains("summary.final.png"), "{md}");
    }
}

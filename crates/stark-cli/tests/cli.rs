//! The `stark` command as a user runs it: exact durations, several scene files, `--set`,
//! aligned `list`, Ctrl-C (SIGINT) with summary, complete logs and a checkpoint that resumes.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn stark() -> Command {
    Command::new(env!("CARGO_BIN_EXE_stark"))
}

fn scene(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes").join(name)
}

fn ok(out: Output) -> String {
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "stark failed: {}\n{stdout}{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    stdout
}

/// A sweep file `sweep.toml` with `toml` in `dir`.
fn write_sweep(dir: &Path, toml: &str) -> std::path::PathBuf {
    let file = dir.join("sweep.toml");
    std::fs::write(&file, toml).unwrap();
    file
}

/// The result JSON a sweep wrote for `case` in `results`.
fn case_result(results: &Path, case: &str) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(results.join(format!("{case}.json"))).unwrap()).unwrap()
}

fn log_lines(path: &Path) -> Vec<serde_json::Value> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

#[test]
fn duration_lands_exactly_and_several_scenes_run_with_overrides() {
    let dir = tempfile::tempdir().unwrap();
    let out = ok(stark()
        .args([
            "run",
            "--quiet",
            "--no-plot",
            "--duration",
            "0.25",
            "--set",
            "settings.output.fps=10",
        ])
        .arg(scene("default.toml"))
        .arg(scene("rb_pendulum_chain.toml"))
        .arg("--out")
        .arg(dir.path())
        .output()
        .unwrap());
    assert!(
        out.contains("== default") && out.contains("== rb_pendulum_chain"),
        "{out}"
    );
    for (name, dt) in [("default", 1.0 / 30.0), ("rb_pendulum_chain", 0.01)] {
        let lines = log_lines(&dir.path().join(name).join(format!("{name}.steps.jsonl")));
        let last = lines.last().unwrap();
        // To the rounding of the summed steps (25 × 0.01 s is 0.25000000000000006).
        let t = last["time_s"].as_f64().unwrap();
        assert!((t - 0.25).abs() < 1e-15, "{name} ends at {t}, not at 0.25 s");
        let full = lines
            .iter()
            .filter(|l| (l["dt_s"].as_f64().unwrap() - dt).abs() < 1e-12)
            .count();
        assert!(full >= lines.len() - 1, "{name}: only the last step may be shortened");
    }
    // 0.25 s = 7 steps of 1/30 s and one of 1/60 s, which ends on 0.25 to the bit.
    let default_log = log_lines(&dir.path().join("default/default.steps.jsonl"));
    assert_eq!(default_log.len(), 8);
    assert_eq!(default_log[7]["time_s"].as_f64().unwrap(), 0.25);
    assert!((default_log[7]["dt_s"].as_f64().unwrap() - 1.0 / 60.0).abs() < 1e-12);

    let bad = stark()
        .args(["run", "--quiet", "--set", "surface.sheet.material=cotton_fabric"])
        .arg(scene("default.toml"))
        .output()
        .unwrap();
    assert!(!bad.status.success());
    let e = String::from_utf8_lossy(&bad.stderr);
    assert!(e.contains("no entry named 'sheet'") && e.contains("cloth"), "{e}");
}

#[test]
fn list_is_aligned() {
    let out = ok(stark().arg("list").output().unwrap());
    let lines: Vec<&str> = out.lines().collect();
    assert!(lines.len() > 5);
    let column = |l: &str| l.find(" s  ").map(|i| i + 4);
    let header_col = lines[0].find("description").unwrap();
    for l in &lines[1..] {
        assert_eq!(column(l), Some(header_col), "misaligned: {l}");
    }
}

/// `stark bench --original FILE` shows the original's walls measured in the same sitting and the
/// speed-up; a malformed file is named with its line and column.
#[test]
fn bench_compares_with_the_original_walls_it_is_given() {
    let dir = std::env::temp_dir().join(format!("stark-cli-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let walls = dir.join("walls.json");
    std::fs::write(&walls, r#"{ "rb_point": 0.5 }"#).unwrap();
    let out = ok(stark()
        .args(["bench", "--scenes", "rb_point", "--threads", "1", "--original"])
        .arg(&walls)
        .output()
        .unwrap());
    let row = out
        .lines()
        .find(|l| l.starts_with("rb_point"))
        .expect("a row for rb_point");
    assert!(row.contains("0.5 s ") && row.trim_end().ends_with('x'), "{row}");
    std::fs::write(&walls, "{ \"rb_point\": \"fast\" }").unwrap();
    let out = stark()
        .args(["bench", "--scenes", "rb_point", "--threads", "1", "--original"])
        .arg(&walls)
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("walls.json:1:") && err.contains("wall times in seconds"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[cfg(unix)]
#[test]
fn sigint_prints_the_summary_keeps_the_logs_and_the_checkpoint_resumes() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("rb_pendulum_chain.steps.jsonl");
    let child = stark()
        .args(["run", "--quiet", "--no-plot", "--duration", "1000", "--threads", "1"])
        .arg(scene("rb_pendulum_chain.toml"))
        .arg("--out")
        .arg(dir.path())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Wait until some steps have been logged (the BufWriter flushes every 8 KiB).
    let start = Instant::now();
    while std::fs::metadata(&log).map(|m| m.len()).unwrap_or(0) < 20_000 {
        assert!(start.elapsed() < Duration::from_secs(120), "the run does not log");
        std::thread::sleep(Duration::from_millis(50));
    }
    let kill = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let out = child.wait_with_output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(
        out.status.code(),
        Some(130),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        stdout.contains("simulated time") && stdout.contains("interrupted"),
        "{stdout}"
    );
    // The summary's step count equals the log's lines: nothing lost.
    let steps: usize = stdout
        .lines()
        .find(|l| l.starts_with("simulated time"))
        .and_then(|l| l.split(" in ").nth(1))
        .and_then(|l| l.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap();
    let lines = log_lines(&log);
    assert_eq!(lines.len(), steps);
    assert_eq!(
        log_lines(&dir.path().join("rb_pendulum_chain.joints.jsonl")).len(),
        steps
    );
    let ckpt = dir.path().join("rb_pendulum_chain.ckpt");
    assert!(ckpt.exists());
    let t_stop = lines.last().unwrap()["time_s"].as_f64().unwrap();

    let resumed = ok(stark()
        .args(["resume", "--quiet", "--no-plot", "--duration", "0.1"])
        .arg(&ckpt)
        .output()
        .unwrap());
    assert!(resumed.contains("resuming"), "{resumed}");
    let lines = log_lines(&log);
    assert_eq!(lines.len(), steps + 10, "0.1 s more at dt = 0.01 s");
    let t_end = lines.last().unwrap()["time_s"].as_f64().unwrap();
    assert!((t_end - (t_stop + 0.1)).abs() < 1e-9, "{t_end} vs {t_stop} + 0.1");
    for (i, l) in lines.iter().enumerate() {
        assert_eq!(
            l["step"].as_u64().unwrap(),
            i as u64,
            "the step log continues without a gap"
        );
    }
}

#[test]
fn sweep_runs_cases_in_parallel_skips_finished_ones_and_summarises() {
    let dir = tempfile::tempdir().unwrap();
    let file = write_sweep(
        dir.path(),
        r#"
scene = "rb_point"
out = "runs"
results = "results"
jobs = 2
threads = 1
duration_s = 0.1
checkpoint_every_s = 0.05
[grid]
"settings.time_step_s" = [0.02, 0.01]
"#,
    );
    let first = ok(stark().arg("sweep").arg(&file).output().unwrap());
    assert!(first.contains("2 cases, 0 finished, 2 to run"), "{first}");
    let results = dir.path().join("results");
    let steps: Vec<u64> = ["rb_point__time_step_s=0.02", "rb_point__time_step_s=0.01"]
        .iter()
        .map(|case| {
            let r = case_result(&results, case);
            assert!(
                (r["summary"]["simulated_time_s"].as_f64().unwrap() - 0.1).abs() < 1e-12,
                "{r}"
            );
            r["summary"]["steps"].as_u64().unwrap()
        })
        .collect();
    // Each case ran with its own time step (the finer one may grow back after easy steps).
    assert_eq!(steps[0], 5);
    assert!(steps[1] > steps[0], "{steps:?}");
    let md = std::fs::read_to_string(results.join("summary.md")).unwrap();
    assert_eq!(md.lines().filter(|l| l.starts_with("| rb_point")).count(), 2, "{md}");

    // Finished cases are skipped; a lost result file is collected again from the run's
    // checkpoint at the end, without simulating.
    std::fs::remove_file(results.join("rb_point__time_step_s=0.01.json")).unwrap();
    let second = ok(stark().arg("sweep").arg(&file).output().unwrap());
    assert!(second.contains("2 cases, 1 finished, 1 to run"), "{second}");
    assert!(!second.contains("start"), "{second}");
    assert!(results.join("rb_point__time_step_s=0.01.json").exists());
}

#[test]
fn sweep_resumes_an_interrupted_case_from_its_checkpoint() {
    let dir = tempfile::tempdir().unwrap();
    let file = write_sweep(
        dir.path(),
        "scene = \"rb_point\"\nout = \"runs\"\nresults = \"results\"\nduration_s = 0.2\ncheckpoint_every_s = 0.05\n",
    );
    // A run of the case's first 0.1 s, as an interrupted sweep leaves it.
    let run_dir = dir.path().join("runs/rb_point");
    ok(stark()
        .args([
            "run",
            "--scene",
            "rb_point",
            "--duration",
            "0.1",
            "--threads",
            "1",
            "--quiet",
        ])
        .args(["--checkpoint-every", "0.05", "--no-frames", "--out"])
        .arg(&run_dir)
        .output()
        .unwrap());
    let out = ok(stark().arg("sweep").arg(&file).output().unwrap());
    assert!(out.contains("done                  rb_point"), "{out}");
    let r = case_result(&dir.path().join("results"), "rb_point");
    // The summary covers the whole run: 0.2 s, the first half from before the resume.
    assert!(
        (r["summary"]["simulated_time_s"].as_f64().unwrap() - 0.2).abs() < 1e-9,
        "{r}"
    );
    let log = run_dir.join("rb_point.steps.jsonl");
    let steps = log_lines(&log);
    assert_eq!(steps.len() as u64, r["summary"]["steps"].as_u64().unwrap());
}

/// A checkpoint the build cannot continue (another format version, a damaged file) does not stop
/// the sweep: the case says so and runs from the start.
#[test]
fn sweep_restarts_a_case_whose_checkpoint_it_cannot_read() {
    let dir = tempfile::tempdir().unwrap();
    let file = write_sweep(
        dir.path(),
        "scene = \"rb_point\"\nout = \"runs\"\nresults = \"results\"\nduration_s = 0.1\n",
    );
    let run_dir = dir.path().join("runs/rb_point");
    std::fs::create_dir_all(&run_dir).unwrap();
    std::fs::write(run_dir.join("rb_point.ckpt"), b"STARKCKP\x7f").unwrap();
    let out = stark().arg("sweep").arg(&file).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    let stdout = ok(out);
    assert!(
        stderr.contains("rb_point") && stderr.contains("starts afresh"),
        "{stderr}"
    );
    assert!(stdout.contains("done                  rb_point"), "{stdout}");
    let r = case_result(&dir.path().join("results"), "rb_point");
    assert!(
        (r["summary"]["simulated_time_s"].as_f64().unwrap() - 0.1).abs() < 1e-9,
        "{r}"
    );
}

/// CI's short robot–towel case (issue 13): the first 0.3 s of the paper's experiment on carpet
/// with the flat towel, checked for intersections after every step. The robot lands, its motors
/// push at their cap and it starts to drive; every step converges to the paper's 1e-6 N.
#[test]
fn robot_towel_case_runs_clean_for_its_first_tenths_of_a_second() {
    let dir = tempfile::tempdir().unwrap();
    let name = "kobuki_towel_carpet_1";
    let out = ok(stark()
        .args([
            "run",
            "--scene",
            name,
            "--duration",
            "0.3",
            "--check",
            "--quiet",
            "--no-frames",
        ])
        .args(["--threads", "2", "--summary-json"])
        .arg(dir.path().join("summary.json"))
        .arg("--out")
        .arg(dir.path())
        .output()
        .unwrap());
    assert!(out.contains("outcome               "), "{out}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("summary.json")).unwrap()).unwrap();
    let s = summary.get(0).unwrap_or(&summary);
    // Every accepted step converged (a failed attempt is retried with half the step).
    assert!(s["max_residual_n"].as_f64().unwrap() <= 1e-6, "{s}");
    let steps = s["steps"].as_u64().unwrap();
    assert!(steps >= 60, "{s}");
    let checked = format!("check                 no intersection in any of {} states", steps + 1);
    assert!(out.contains(&checked), "{out}");
    // The robot drives forward (cap-limited: ~1 m/s² from rest, so ~3 cm in 0.3 s).
    let log = log_lines(&dir.path().join(format!("{name}.robot_towel.jsonl")));
    let y = |l: &serde_json::Value| l["robot_towel"]["sample"]["robot_y_m"].as_f64().unwrap();
    let advance = y(log.last().unwrap()) - y(&log[0]);
    assert!(advance > 0.02 && advance < 0.06, "{advance}");
    for png in ["motors", "final"] {
        assert!(dir.path().join(format!("{name}.{png}.png")).exists());
    }
}

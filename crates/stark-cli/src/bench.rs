//! `stark bench`: the benchmark scenes timed, beside the original's walls when given.

use super::*;

/// The original Stark's wall times, s, per scene, from `--original FILE`: a JSON object
/// `{ "scene": seconds }` measured on this machine in the same sitting
/// (../shared/tools/stark-original/). Stored figures from another day or machine are no reference
/// (machines differ by 2×), so none are built in.
pub(super) fn read_original_walls(path: &std::path::Path) -> stark::Result<std::collections::BTreeMap<String, f64>> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| stark::StarkError::InvalidInput(format!("cannot read {}: {e}", path.display())))?;
    serde_json::from_str(&text).map_err(|e| {
        stark::StarkError::InvalidInput(format!(
            "{}:{}:{}: expected a JSON object of scene names and wall times in seconds: {e}",
            path.display(),
            e.line(),
            e.column()
        ))
    })
}

pub(super) fn bench(
    scenes: Vec<String>,
    threads: Vec<usize>,
    json: Option<PathBuf>,
    original: Option<PathBuf>,
) -> stark::Result<()> {
    let original_walls = match &original {
        Some(path) => read_original_walls(path)?,
        None => Default::default(),
    };
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
            "towel_box".into(),
        ]
    } else {
        scenes
    };
    println!(
        "{:<22} {:>3} {:>6} {:>9} {:>9} {:>9} {:>7} {:>6} {:>6} {:>5} {:>5} {:>6} {:>5} {:>6} {:>9}",
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
        "step%",
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
            // The original's wall at 1 thread against ours at this thread count.
            let original_s = original_walls.get(name.as_str()).copied();
            let original = original_s
                .map(|w| format!("{w:.1} s {:.2}x", w / s.wall_time_s))
                .unwrap_or_else(|| "-".into());
            println!(
                "{:<22} {:>3} {:>6} {:>9.2} {:>9.3} {:>9.2} {:>7.1} {:>6.0} {:>7.0} {:>5.0} {:>5.0} {:>6.0} {:>5.0} {:>6.0} {:>9}",
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
                100.0 * (tt.step_start_s + tt.step_end_s) / total,
                original
            );
            results
                .push(serde_json::json!({ "scene": name, "threads": t, "summary": s, "original_wall_s": original_s }));
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

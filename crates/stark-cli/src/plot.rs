//! `stark plot` and the summary plot of every run: series of the JSON-lines logs against time,
//! drawn with plotters into a PNG. The font (DejaVu Sans) is compiled in, so plotting needs no
//! system font and no Python.

use plotters::prelude::*;
use plotters::style::FontStyle;
use serde_json::Value;
use stark::{Result, StarkError};
use std::path::{Path, PathBuf};
use std::sync::Once;

/// Width of a plot and height of one panel, pixels.
const WIDTH_PX: u32 = 1000;
const PANEL_HEIGHT_PX: u32 = 220;
/// Most panels in one picture (the rest are named in the error).
const MAX_PANELS: usize = 16;

/// One series: its name (the key path) and its (time, value) points.
#[derive(Debug)]
struct Series {
    name: String,
    points: Vec<(f64, f64)>,
}

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The bundled font replaces any system font lookup.
        plotters::style::register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular())
            .unwrap_or_else(|_| panic!("the bundled DejaVu Sans font is valid"));
    });
}

fn plot_err(path: &Path, e: impl std::fmt::Display) -> StarkError {
    StarkError::Output {
        path: path.display().to_string(),
        source: std::io::Error::other(e.to_string()),
    }
}

/// The lines of a JSON-lines log, each with its `time_s`.
fn read_log(path: &Path) -> Result<Vec<(f64, Value)>> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| StarkError::InvalidInput(format!("cannot read log '{}': {e}", path.display())))?;
    let mut lines = Vec::new();
    for (i, line) in text.lines().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        let v: Value = serde_json::from_str(line).map_err(|e| {
            StarkError::InvalidInput(format!(
                "{}:{}: not a JSON line of a stark log: {e}",
                path.display(),
                i + 1
            ))
        })?;
        let t = v
            .get("time_s")
            .and_then(Value::as_f64)
            .ok_or_else(|| StarkError::InvalidInput(format!("{}:{}: the line has no time_s", path.display(), i + 1)))?;
        lines.push((t, v));
    }
    if lines.is_empty() {
        return Err(StarkError::InvalidInput(format!(
            "log '{}' has no lines",
            path.display()
        )));
    }
    Ok(lines)
}

/// Every numeric leaf below `v`, with its key path appended to `prefix`.
fn leaves(prefix: &str, v: &Value, out: &mut Vec<(String, f64)>) {
    let join = |k: &str| {
        if prefix.is_empty() {
            k.to_string()
        } else {
            format!("{prefix}.{k}")
        }
    };
    match v {
        Value::Number(n) => out.push((prefix.to_string(), n.as_f64().unwrap_or(f64::NAN))),
        Value::Object(m) => m.iter().for_each(|(k, x)| leaves(&join(k), x, out)),
        Value::Array(a) => a
            .iter()
            .enumerate()
            .for_each(|(i, x)| leaves(&join(&i.to_string()), x, out)),
        _ => {}
    }
}

/// The value at a dotted key path (object keys or array indices).
fn lookup<'a>(v: &'a Value, key: &str) -> Option<&'a Value> {
    key.split('.').try_fold(v, |v, k| match v {
        Value::Object(m) => m.get(k),
        Value::Array(a) => k.parse::<usize>().ok().and_then(|i| a.get(i)),
        _ => None,
    })
}

/// Series for `keys` in one log (every numeric leaf below each key), in order of appearance.
fn collect_series(log: &Path, lines: &[(f64, Value)], keys: &[String], prefix_with_log: bool) -> Result<Vec<Series>> {
    let mut series: Vec<Series> = Vec::new();
    for key in keys {
        let mut found = false;
        for (t, line) in lines {
            let Some(v) = lookup(line, key) else { continue };
            let mut ls = Vec::new();
            leaves(key, v, &mut ls);
            for (name, y) in ls {
                found = true;
                let name = if prefix_with_log {
                    format!(
                        "{}: {name}",
                        log.file_name().map(|f| f.to_string_lossy()).unwrap_or_default()
                    )
                } else {
                    name
                };
                match series.iter_mut().find(|s| s.name == name) {
                    Some(s) => s.points.push((*t, y)),
                    None => series.push(Series {
                        name,
                        points: vec![(*t, y)],
                    }),
                }
            }
        }
        if !found {
            let mut available = Vec::new();
            leaves("", &lines[0].1, &mut available);
            let names: Vec<String> = available.into_iter().map(|(k, _)| k).take(40).collect();
            return Err(StarkError::InvalidInput(format!(
                "no series `{key}` in '{}' (its numeric keys include: {})",
                log.display(),
                names.join(", ")
            )));
        }
    }
    Ok(series)
}

/// The series plotted when none are named, by kind of log.
fn default_keys(lines: &[(f64, Value)]) -> Vec<String> {
    let first = &lines[0].1;
    let keys: Vec<&str> = if first.get("newton_iterations").is_some() {
        let mut k = vec!["newton_iterations", "residual_n", "dt_s"];
        if lines
            .iter()
            .any(|(_, l)| l.get("contact").is_some_and(|c| !c.is_null()))
        {
            k.push("contact.active_pairs");
        }
        k
    } else if let Some(Value::Object(bodies)) = first.get("bodies") {
        return bodies
            .keys()
            .take(4)
            .map(|b| format!("bodies.{b}.position_m"))
            .collect();
    } else if let Some(Value::Object(joints)) = first.get("joints") {
        return joints
            .keys()
            .take(4)
            .flat_map(|j| [format!("joints.{j}.coordinate"), format!("joints.{j}.driver_effort")])
            .collect();
    } else {
        vec![]
    };
    keys.into_iter().map(str::to_string).collect()
}

/// Draw `series`, one panel each (residuals on a log scale), into `png`.
fn draw(series: &[Series], title: &str, png: &Path) -> Result<()> {
    register_font();
    if series.is_empty() {
        return Err(StarkError::InvalidInput("nothing to plot".into()));
    }
    if series.len() > MAX_PANELS {
        let names: Vec<&str> = series.iter().map(|s| s.name.as_str()).collect();
        return Err(StarkError::InvalidInput(format!(
            "{} series ({}) is more than {MAX_PANELS} panels: name fewer with --series",
            series.len(),
            names.join(", ")
        )));
    }
    if let Some(dir) = png.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| plot_err(png, e))?;
    }
    let height = 40 + PANEL_HEIGHT_PX * series.len() as u32;
    let root = BitMapBackend::new(png, (WIDTH_PX, height)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| plot_err(png, e))?;
    let root = root.titled(title, ("sans-serif", 22)).map_err(|e| plot_err(png, e))?;
    let panels = root.split_evenly((series.len(), 1));
    let t_min = series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.0))
        .fold(f64::INFINITY, f64::min);
    let t_max = series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.0))
        .fold(f64::NEG_INFINITY, f64::max);
    let t_max = if t_max > t_min { t_max } else { t_min + 1.0 };
    for (i, (s, panel)) in series.iter().zip(panels.iter()).enumerate() {
        let finite: Vec<(f64, f64)> = s.points.iter().copied().filter(|p| p.1.is_finite()).collect();
        let log_scale = s.name.contains("residual") && finite.iter().all(|p| p.1 > 0.0) && !finite.is_empty();
        // Dark, distinct colours that stay readable on white.
        const COLOURS: [(u8, u8, u8); 6] = [
            (31, 92, 180),
            (200, 60, 40),
            (40, 140, 60),
            (130, 70, 170),
            (200, 120, 0),
            (20, 140, 150),
        ];
        let (r, g, b) = COLOURS[i % COLOURS.len()];
        let colour = RGBColor(r, g, b).to_rgba();
        let (lo, hi) = finite.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p.1), hi.max(p.1))
        });
        let (lo, hi) = if lo.is_finite() { (lo, hi) } else { (0.0, 1.0) };
        let mut builder = ChartBuilder::on(panel);
        builder.margin(8).x_label_area_size(30).y_label_area_size(80);
        let result = if log_scale {
            let mut chart = builder
                .build_cartesian_2d(t_min..t_max, (lo * 0.8..hi * 1.25).log_scale())
                .map_err(|e| plot_err(png, e))?;
            chart
                .configure_mesh()
                .x_desc("time [s]")
                .y_desc(&s.name)
                .y_label_formatter(&|v| format!("{v:.0e}"))
                .draw()
                .map_err(|e| plot_err(png, e))?;
            chart
                .draw_series(LineSeries::new(finite.iter().copied(), colour.stroke_width(2)))
                .map(|_| ())
        } else {
            let pad = if hi > lo {
                0.05 * (hi - lo)
            } else {
                0.5f64.max(lo.abs() * 0.05)
            };
            let mut chart = builder
                .build_cartesian_2d(t_min..t_max, lo - pad..hi + pad)
                .map_err(|e| plot_err(png, e))?;
            chart
                .configure_mesh()
                .x_desc("time [s]")
                .y_desc(&s.name)
                .draw()
                .map_err(|e| plot_err(png, e))?;
            chart
                .draw_series(LineSeries::new(finite.iter().copied(), colour.stroke_width(2)))
                .map(|_| ())
        };
        result.map_err(|e| plot_err(png, e))?;
    }
    root.present().map_err(|e| plot_err(png, e))?;
    Ok(())
}

/// `stark plot`: the named series (or a default set) of each log against time into one PNG;
/// returns the file written.
pub fn plot_logs(logs: &[PathBuf], keys: &[String], output: Option<&Path>) -> Result<PathBuf> {
    let mut all = Vec::new();
    for log in logs {
        let lines = read_log(log)?;
        let keys = if keys.is_empty() {
            default_keys(&lines)
        } else {
            keys.to_vec()
        };
        if keys.is_empty() {
            return Err(StarkError::InvalidInput(format!(
                "'{}' is not a step, body or joint log: name the series with --series",
                log.display()
            )));
        }
        all.extend(collect_series(log, &lines, &keys, logs.len() > 1)?);
    }
    let png = match output {
        Some(p) => p.to_path_buf(),
        None => logs[0].with_extension("png"),
    };
    let title = logs
        .iter()
        .map(|l| {
            l.file_name()
                .map(|f| f.to_string_lossy().into_owned())
                .unwrap_or_default()
        })
        .collect::<Vec<_>>()
        .join(", ");
    draw(&all, &title, &png)?;
    Ok(png)
}

/// The summary plot of a run: Newton iterations, residual, dt and (with contact) active contact
/// pairs per step, from its step log.
pub fn summary_plot(step_log: &Path, png: &Path) -> Result<()> {
    let lines = read_log(step_log)?;
    let keys = default_keys(&lines);
    let series = collect_series(step_log, &lines, &keys, false)?;
    let name = step_log
        .file_name()
        .map(|f| f.to_string_lossy().trim_end_matches(".steps.jsonl").to_string())
        .unwrap_or_default();
    draw(&series, &format!("{name}: solver per step"), png)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn series_from_nested_keys_and_a_png_is_written() {
        let dir = std::env::temp_dir().join(format!("stark-plot-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let log = dir.join("t.joints.jsonl");
        let mut text = String::new();
        for i in 0..20 {
            let t = i as f64 * 0.1;
            text += &format!(
                "{{\"step\":{i},\"time_s\":{t},\"joints\":{{\"motor\":{{\"coordinate\":{},\"driver_effort\":{},\"force_on_b_n\":[1,2,3]}}}}}}\n",
                t * t,
                2.0 * t
            );
        }
        std::fs::write(&log, text).unwrap();
        let lines = read_log(&log).unwrap();
        let s = collect_series(&log, &lines, &["joints.motor.force_on_b_n".into()], false).unwrap();
        assert_eq!(s.len(), 3);
        assert_eq!(s[2].name, "joints.motor.force_on_b_n.2");
        assert_eq!(s[2].points[5], (0.5, 3.0));
        let d = collect_series(&log, &lines, &default_keys(&lines), false).unwrap();
        assert_eq!(d.len(), 2);
        assert!((d[0].points[10].1 - 1.0).abs() < 1e-12);
        let e = collect_series(&log, &lines, &["joints.wheel".into()], false)
            .unwrap_err()
            .to_string();
        assert!(e.contains("no series `joints.wheel`"), "{e}");
        let png = plot_logs(&[log], &[], None).unwrap();
        let bytes = std::fs::read(&png).unwrap();
        assert_eq!(&bytes[1..4], b"PNG");
        std::fs::remove_dir_all(&dir).ok();
    }
}

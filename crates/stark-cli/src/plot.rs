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

pub(crate) fn register_font() {
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

/// A moment marked on a plot: a vertical line at `time_s` on every panel with a linear scale, its
/// label on the first panel (when that one is linear).
pub struct Mark {
    /// Time, s.
    pub time_s: f64,
    /// Label.
    pub label: String,
}

/// Draw `series`, one panel each (residuals on a log scale), into `png`.
fn draw(series: &[Series], title: &str, png: &Path) -> Result<()> {
    draw_marked(series, title, &[], png)
}

/// [`draw`] with moments marked.
fn draw_marked(series: &[Series], title: &str, marks: &[Mark], png: &Path) -> Result<()> {
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
            for m in marks {
                let red = RGBColor(220, 0, 0);
                chart
                    .draw_series(LineSeries::new(
                        [(m.time_s, lo - pad), (m.time_s, hi + pad)],
                        red.stroke_width(1),
                    ))
                    .map_err(|e| plot_err(png, e))?;
                if i == 0 {
                    chart
                        .draw_series(std::iter::once(Text::new(
                            m.label.clone(),
                            (m.time_s, hi + 0.5 * pad),
                            ("sans-serif", 14).into_font().color(&red),
                        )))
                        .map_err(|e| plot_err(png, e))?;
                }
            }
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
    plot_logs_marked(logs, keys, &[], output)
}

/// [`plot_logs`] with moments marked on every panel (lines on linear panels).
pub fn plot_logs_marked(logs: &[PathBuf], keys: &[String], marks: &[Mark], output: Option<&Path>) -> Result<PathBuf> {
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
    draw_marked(&all, &title, marks, &png)?;
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

/// One mesh of a picture: its label and its edges as world segments.
pub struct PictureMesh {
    /// Label (legend).
    pub label: String,
    /// Edges, m.
    pub edges: Vec<[[f64; 3]; 2]>,
}

/// The edges of every output mesh of a simulation (triangles and segments; tets by their edges
/// too, points as short ticks), in world coordinates.
pub fn picture_meshes(sim: &stark::Simulation) -> Vec<PictureMesh> {
    use stark::io::output::OutputCells;
    sim.output
        .meshes
        .iter()
        .map(|m| {
            let x = sim.positions(m.set);
            let p = |i: usize| -> [f64; 3] { x[i].into() };
            let mut edges: Vec<[[f64; 3]; 2]> = Vec::new();
            match &m.cells {
                OutputCells::Points => edges.extend((0..x.len()).map(|i| [p(i), p(i)])),
                OutputCells::Segments(s) => edges.extend(s.iter().map(|e| [p(e[0]), p(e[1])])),
                OutputCells::Triangles(t) => {
                    // Each edge once (an interior edge belongs to two triangles).
                    let mut idx: Vec<(usize, usize)> = t
                        .iter()
                        .flat_map(|f| {
                            (0..3).map(move |k| {
                                let (a, b) = (f[k], f[(k + 1) % 3]);
                                (a.min(b), a.max(b))
                            })
                        })
                        .collect();
                    idx.sort_unstable();
                    idx.dedup();
                    edges.extend(idx.into_iter().map(|(a, b)| [p(a), p(b)]));
                }
                OutputCells::Tets(t) => {
                    for c in t {
                        for (a, b) in [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)] {
                            edges.push([p(c[a]), p(c[b])]);
                        }
                    }
                }
            }
            PictureMesh {
                label: m.label.clone(),
                edges,
            }
        })
        .collect()
}

/// A picture of a state: a top view (x–y) above a side view (y–z, looking along −x) of the
/// meshes' edges, to scale, one colour per mesh, limited to `region` (`[min, max]` corners, m)
/// when given.
pub fn picture(meshes: &[PictureMesh], title: &str, region: Option<[[f64; 3]; 2]>, png: &Path) -> Result<()> {
    register_font();
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for e in meshes.iter().flat_map(|m| &m.edges) {
        for q in e {
            for k in 0..3 {
                lo[k] = lo[k].min(q[k]);
                hi[k] = hi[k].max(q[k]);
            }
        }
    }
    if let Some([a, b]) = region {
        lo = a;
        hi = b;
    }
    if !lo.iter().chain(&hi).all(|v| v.is_finite()) {
        return Err(StarkError::InvalidInput("nothing to draw".into()));
    }
    let span = |k: usize| (hi[k] - lo[k]).max(1e-3);
    // Side view stretched in z so thin layers show; the factor is in its caption.
    let z_stretch = (0.25 * span(1) / span(2)).clamp(1.0, 10.0);
    let width = WIDTH_PX;
    let scale = (width as f64 - 100.0) / span(1);
    let top_h = (span(0) * scale) as u32 + 60;
    let side_h = (span(2) * z_stretch * scale) as u32 + 60;
    let root = BitMapBackend::new(png, (width, top_h + side_h + 40)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| plot_err(png, e))?;
    let root = root.titled(title, ("sans-serif", 20)).map_err(|e| plot_err(png, e))?;
    let (top, side) = root.split_vertically(top_h);
    let views: [(&DrawingArea<_, _>, usize, String); 2] = [
        (&top, 0, "top view: y → right, x ↑".to_string()),
        (
            &side,
            2,
            format!("side view: y → right, z ↑ (z stretched {z_stretch:.1}×)"),
        ),
    ];
    for (area, k, caption) in views {
        let mut chart = ChartBuilder::on(area)
            .caption(caption, ("sans-serif", 14))
            .margin(10)
            .x_label_area_size(25)
            .y_label_area_size(55)
            .build_cartesian_2d(lo[1]..hi[1], lo[k]..hi[k])
            .map_err(|e| plot_err(png, e))?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc("y [m]")
            .y_desc(if k == 0 { "x [m]" } else { "z [m]" })
            .draw()
            .map_err(|e| plot_err(png, e))?;
        for (i, m) in meshes.iter().enumerate() {
            let color = Palette99::pick(i).to_rgba();
            let inside = |q: &[f64; 3]| (0..3).all(|c| q[c] >= lo[c] - 1e-9 && q[c] <= hi[c] + 1e-9);
            let segments =
                m.edges.iter().filter(|e| inside(&e[0]) && inside(&e[1])).map(move |e| {
                    PathElement::new(vec![(e[0][1], e[0][k]), (e[1][1], e[1][k])], color.stroke_width(1))
                });
            let s = chart.draw_series(segments).map_err(|e| plot_err(png, e))?;
            if k == 0 {
                s.label(m.label.clone())
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 15, y)], color.stroke_width(2)));
            }
        }
        if k == 0 {
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK)
                .label_font(("sans-serif", 12))
                .draw()
                .map_err(|e| plot_err(png, e))?;
        }
    }
    root.present().map_err(|e| plot_err(png, e))?;
    Ok(())
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

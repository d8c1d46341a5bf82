//! Helper for `tests/meshio_check.py`.
//!
//! `vtk_samples write DIR` writes one legacy VTK file per cell kind and encoding plus
//! `manifest.json` describing what each file holds; `vtk_samples read FILE` reads a VTK file
//! with our reader and prints a one-line JSON summary.

use std::fmt::Write as _;

use nalgebra::Vector3;
use stark::io::vtk::{read_vtk, VtkCells, VtkEncoding, VtkPrecision, VtkWriter};
use stark::presets::meshes::{segment_line, tet_grid, triangle_grid};

struct Sample {
    file: String,
    cell_type: &'static str,
    n_cells: usize,
    points: Vec<Vector3<f64>>,
    connectivity_sum: usize,
    point_data: Vec<(String, usize, f64)>,
    cell_data: Vec<(String, f64)>,
    float32: bool,
}

fn json_f64(v: f64) -> String {
    format!("{v:e}")
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    match args.get(1).map(String::as_str) {
        Some("write") => write_samples(std::path::Path::new(&args[2])),
        Some("read") => read_one(&args[2]),
        _ => {
            eprintln!("usage: vtk_samples write DIR | read FILE");
            std::process::exit(2);
        }
    }
}

fn read_one(path: &str) {
    match read_vtk(path) {
        Ok(m) => {
            let mut s = format!(
                "{{\"points\": {}, \"vertices\": {}, \"segments\": {}, \"triangles\": {}, \"tets\": {}, \"point_sum\": {}, \"connectivity_sum\": {}, \"point_data\": {{",
                m.points.len(),
                m.vertices.len(),
                m.segments.len(),
                m.triangles.len(),
                m.tets.len(),
                json_f64(m.points.iter().map(|p| p.sum()).sum()),
                m.vertices.iter().sum::<usize>()
                    + m.segments.iter().flatten().sum::<usize>()
                    + m.triangles.iter().flatten().sum::<usize>()
                    + m.tets.iter().flatten().sum::<usize>(),
            );
            let parts: Vec<String> = m
                .point_data
                .iter()
                .map(|a| {
                    format!(
                        "\"{}\": [{}, {}]",
                        a.name,
                        a.n_components,
                        json_f64(a.values.iter().sum())
                    )
                })
                .collect();
            s += &parts.join(", ");
            s += "}, \"cell_data\": {";
            let parts: Vec<String> = m
                .cell_data
                .iter()
                .map(|a| {
                    format!(
                        "\"{}\": [{}, {}]",
                        a.name,
                        a.n_components,
                        json_f64(a.values.iter().sum())
                    )
                })
                .collect();
            s += &parts.join(", ");
            s += "}}";
            println!("{s}");
        }
        Err(e) => {
            println!("{{\"error\": \"{}\"}}", e.to_string().replace('"', "'"));
        }
    }
}

fn write_samples(dir: &std::path::Path) {
    std::fs::create_dir_all(dir).unwrap();
    let tets = tet_grid(Vector3::new(0.1, -0.2, 0.3), Vector3::new(0.5, 0.4, 0.3), [3, 2, 2]);
    let tris = triangle_grid([0.0, 0.0], [1.0, 0.5], [4, 3], 0.25);
    let line = segment_line(Vector3::zeros(), Vector3::new(1.0, 2.0, 3.0), 7);
    let cloud: Vec<Vector3<f64>> = (0..10)
        .map(|i| Vector3::new(i as f64 * 0.1, (i * i) as f64 * 0.01, -(i as f64)))
        .collect();

    let mut samples = Vec::new();
    for (suffix, encoding) in [("binary", VtkEncoding::Binary), ("ascii", VtkEncoding::Ascii)] {
        for (precision_suffix, precision) in [("", VtkPrecision::Float64), ("_f32", VtkPrecision::Float32)] {
            // Tets with vectors, scalars and cell scalars.
            let velocity: Vec<_> = tets.vertices.iter().map(|p| Vector3::new(p.y, -p.x, 1.0)).collect();
            let temperature: Vec<f64> = (0..tets.vertices.len()).map(|i| 300.0 + i as f64).collect();
            let volume_id: Vec<f64> = (0..tets.elements.len()).map(|i| i as f64 * 0.5).collect();
            let file = format!("tets_{suffix}{precision_suffix}.vtk");
            VtkWriter::new(&tets.vertices, VtkCells::Tets(&tets.elements))
                .encoding(encoding)
                .precision(precision)
                .point_vectors("velocity", &velocity)
                .point_scalars("temperature", &temperature)
                .cell_scalars("tet_id", &volume_id)
                .write(dir.join(&file))
                .unwrap();
            samples.push(Sample {
                file,
                cell_type: "tetra",
                n_cells: tets.elements.len(),
                points: tets.vertices.clone(),
                connectivity_sum: tets.elements.iter().flatten().sum(),
                point_data: vec![
                    ("velocity".into(), 3, velocity.iter().map(|v| v.sum()).sum()),
                    ("temperature".into(), 1, temperature.iter().sum()),
                ],
                cell_data: vec![("tet_id".into(), volume_id.iter().sum())],
                float32: precision == VtkPrecision::Float32,
            });
            if !precision_suffix.is_empty() {
                continue;
            }

            let area: Vec<f64> = (0..tris.elements.len()).map(|i| 1.0 + i as f64).collect();
            let normal = vec![Vector3::new(0.0, 0.0, 1.0); tris.vertices.len()];
            let file = format!("triangles_{suffix}.vtk");
            VtkWriter::new(&tris.vertices, VtkCells::Triangles(&tris.elements))
                .encoding(encoding)
                .point_vectors("normal", &normal)
                .cell_scalars("area", &area)
                .write(dir.join(&file))
                .unwrap();
            samples.push(Sample {
                file,
                cell_type: "triangle",
                n_cells: tris.elements.len(),
                points: tris.vertices.clone(),
                connectivity_sum: tris.elements.iter().flatten().sum(),
                point_data: vec![("normal".into(), 3, tris.vertices.len() as f64)],
                cell_data: vec![("area".into(), area.iter().sum())],
                float32: false,
            });

            let s: Vec<f64> = (0..line.vertices.len()).map(|i| i as f64 * 1e-3).collect();
            let file = format!("segments_{suffix}.vtk");
            VtkWriter::new(&line.vertices, VtkCells::Segments(&line.elements))
                .encoding(encoding)
                .point_scalars("arc_length", &s)
                .write(dir.join(&file))
                .unwrap();
            samples.push(Sample {
                file,
                cell_type: "line",
                n_cells: line.elements.len(),
                points: line.vertices.clone(),
                connectivity_sum: line.elements.iter().flatten().sum(),
                point_data: vec![("arc_length".into(), 1, s.iter().sum())],
                cell_data: vec![],
                float32: false,
            });

            let file = format!("empty_{suffix}.vtk");
            VtkWriter::new(&[], VtkCells::Triangles(&[]))
                .encoding(encoding)
                .write(dir.join(&file))
                .unwrap();
            samples.push(Sample {
                file,
                cell_type: "triangle",
                n_cells: 0,
                points: vec![],
                connectivity_sum: 0,
                point_data: vec![],
                cell_data: vec![],
                float32: false,
            });

            let v: Vec<_> = cloud.iter().map(|p| p * 2.0).collect();
            let file = format!("points_{suffix}.vtk");
            VtkWriter::new(&cloud, VtkCells::Points)
                .encoding(encoding)
                .point_vectors("velocity", &v)
                .write(dir.join(&file))
                .unwrap();
            samples.push(Sample {
                file,
                cell_type: "vertex",
                n_cells: cloud.len(),
                points: cloud.clone(),
                connectivity_sum: (0..cloud.len()).sum(),
                point_data: vec![("velocity".into(), 3, v.iter().map(|x| x.sum()).sum())],
                cell_data: vec![],
                float32: false,
            });
        }
    }

    let mut json = String::from("[\n");
    for (i, s) in samples.iter().enumerate() {
        let point_data: Vec<String> = s
            .point_data
            .iter()
            .map(|(n, c, sum)| format!("\"{n}\": [{c}, {}]", json_f64(*sum)))
            .collect();
        let cell_data: Vec<String> = s
            .cell_data
            .iter()
            .map(|(n, sum)| format!("\"{n}\": {}", json_f64(*sum)))
            .collect();
        let _ = writeln!(
            json,
            "  {{\"file\": \"{}\", \"cell_type\": \"{}\", \"n_cells\": {}, \"n_points\": {}, \"first_point\": [{}], \"point_sum\": {}, \"connectivity_sum\": {}, \"float32\": {}, \"point_data\": {{{}}}, \"cell_data\": {{{}}}}}{}",
            s.file,
            s.cell_type,
            s.n_cells,
            s.points.len(),
            s.points
                .first()
                .map(|p| p.iter().map(|c| json_f64(*c)).collect::<Vec<_>>().join(", "))
                .unwrap_or_default(),
            json_f64(s.points.iter().map(|p| p.sum()).sum()),
            s.connectivity_sum,
            s.float32,
            point_data.join(", "),
            cell_data.join(", "),
            if i + 1 < samples.len() { "," } else { "" }
        );
    }
    json += "]\n";
    std::fs::write(dir.join("manifest.json"), json).unwrap();
    println!("wrote {} files to {}", samples.len(), dir.display());
}

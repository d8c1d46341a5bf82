//! `stark view OUTPUT_DIR`: one self-contained HTML file that plays a run. It reads the run's
//! `.pvd` and VTU frames, packs their binary arrays (still base64, as in the files) into the
//! page, and embeds three.js (vendored, see `assets/README.md`), so the page needs no network:
//! time slider, play/pause, orbit camera, colour by a field.

use stark::{Result, StarkError};
use std::path::{Path, PathBuf};

const THREE: &str = include_str!("../assets/three-bundle.min.js");
const PAGE: &str = include_str!("../assets/viewer.html");

fn bad(m: String) -> StarkError {
    StarkError::InvalidInput(m)
}

/// The value of `attr="..."` in `tag`.
fn attr<'a>(tag: &'a str, attr: &str) -> Option<&'a str> {
    let key = format!("{attr}=\"");
    let start = tag.find(&key)? + key.len();
    let end = tag[start..].find('"')? + start;
    Some(&tag[start..end])
}

/// The entries `(time, part, file)` of a `.pvd`.
fn read_pvd(path: &Path) -> Result<Vec<(f64, usize, String)>> {
    let text = std::fs::read_to_string(path).map_err(|e| bad(format!("cannot read '{}': {e}", path.display())))?;
    let mut out = Vec::new();
    for tag in text.split("<DataSet").skip(1) {
        let tag = &tag[..tag.find("/>").unwrap_or(tag.len())];
        let (Some(t), Some(part), Some(file)) = (attr(tag, "timestep"), attr(tag, "part"), attr(tag, "file")) else {
            return Err(bad(format!(
                "'{}': a DataSet without timestep, part or file",
                path.display()
            )));
        };
        let t: f64 = t
            .parse()
            .map_err(|_| bad(format!("'{}': timestep '{t}' is not a number", path.display())))?;
        let part: usize = part
            .parse()
            .map_err(|_| bad(format!("'{}': part '{part}' is not a number", path.display())))?;
        out.push((t, part, file.to_string()));
    }
    if out.is_empty() {
        return Err(bad(format!("'{}' lists no frames", path.display())));
    }
    Ok(out)
}

/// The base64 payload of the binary `DataArray` named `name` in a VTU text.
fn array<'a>(vtu: &'a str, name: &str) -> Option<&'a str> {
    let key = format!("Name=\"{name}\"");
    let at = vtu.find(&key)?;
    let start = vtu[at..].find('>')? + at + 1;
    let end = vtu[start..].find("</DataArray>")? + start;
    Some(vtu[start..end].trim())
}

/// Point and cell fields the viewer can colour by.
const POINT_FIELDS: [&str; 2] = ["velocity", "contact_force_n"];
const CELL_FIELDS: [&str; 1] = ["von_mises_pa"];

fn json_str(s: &str) -> String {
    serde_json::to_string(s).expect("a string serialises")
}

/// Write the viewer of the run in `dir`; returns the file written.
pub fn write_viewer(dir: &Path, output: Option<&Path>) -> Result<PathBuf> {
    let pvds: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| bad(format!("cannot read the output directory '{}': {e}", dir.display())))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "pvd"))
        .collect();
    let pvd = match pvds.as_slice() {
        [one] => one.clone(),
        [] => {
            return Err(bad(format!(
                "no .pvd in '{}': run the scene with VTU frames (the default, not --legacy-vtk)",
                dir.display()
            )))
        }
        many => {
            let mut names: Vec<String> = many.iter().map(|p| p.display().to_string()).collect();
            names.sort();
            return Err(bad(format!(
                "several runs in '{}' ({}): give each its own --out",
                dir.display(),
                names.join(", ")
            )));
        }
    };
    let name = pvd
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let entries = read_pvd(&pvd)?;
    let n_parts = entries.iter().map(|e| e.1).max().unwrap_or(0) + 1;
    let mut times: Vec<f64> = Vec::new();
    // JSON by hand: the payloads are already base64 text.
    let mut parts = vec![String::new(); n_parts];
    let mut frames: Vec<Vec<String>> = Vec::new();
    for (t, part, file) in &entries {
        if times.last() != Some(t) {
            times.push(*t);
            frames.push(vec!["null".into(); n_parts]);
        }
        let path = dir.join(file);
        let vtu =
            std::fs::read_to_string(&path).map_err(|e| bad(format!("cannot read frame '{}': {e}", path.display())))?;
        let need = |n: &str| array(&vtu, n).ok_or_else(|| bad(format!("'{}' has no {n} array", path.display())));
        if parts[*part].is_empty() {
            let label = file
                .strip_prefix(&format!("{name}_"))
                .and_then(|f| f.rsplit_once('_'))
                .map(|(l, _)| l)
                .unwrap_or(file);
            parts[*part] = format!(
                "{{\"label\":{},\"connectivity\":\"{}\",\"offsets\":\"{}\",\"types\":\"{}\"}}",
                json_str(label),
                need("connectivity")?,
                need("offsets")?,
                need("types")?
            );
        }
        let mut fields = vec![format!("\"points\":\"{}\"", need("Points")?)];
        for f in POINT_FIELDS.iter().chain(&CELL_FIELDS) {
            if let Some(a) = array(&vtu, f) {
                fields.push(format!("\"{f}\":\"{a}\""));
            }
        }
        frames.last_mut().expect("pushed above")[*part] = format!("{{{}}}", fields.join(","));
    }
    let data = format!(
        "{{\"name\":{},\"times\":{},\"parts\":[{}],\"frames\":[{}],\"pointFields\":{},\"cellFields\":{}}}",
        json_str(&name),
        serde_json::to_string(&times).expect("numbers serialise"),
        parts.join(","),
        frames
            .iter()
            .map(|f| format!("[{}]", f.join(",")))
            .collect::<Vec<_>>()
            .join(","),
        serde_json::to_string(&POINT_FIELDS).expect("serialises"),
        serde_json::to_string(&CELL_FIELDS).expect("serialises"),
    );
    let three_url = format!("data:text/javascript;base64,{}", base64(THREE.as_bytes()));
    let html = PAGE
        .replace("__TITLE__", &name)
        .replace("__THREE_URL__", &three_url)
        // `</` cannot appear inside a script element.
        .replace("__DATA__", &data.replace("</", "<\\/"));
    let out = output
        .map(Path::to_path_buf)
        .unwrap_or_else(|| dir.join(format!("{name}.html")));
    std::fs::write(&out, html).map_err(|e| StarkError::Output {
        path: out.display().to_string(),
        source: e,
    })?;
    Ok(out)
}

/// Base64 (RFC 4648) for the embedded script's data URL.
fn base64(bytes: &[u8]) -> String {
    use base64::Engine;
    base64::engine::general_purpose::STANDARD.encode(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pvd_entries_and_arrays_are_found() {
        let dir = std::env::temp_dir().join(format!("stark-view-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(
            dir.join("r.pvd"),
            "<Collection>\n<DataSet timestep=\"0e0\" group=\"\" part=\"0\" file=\"r_a_00000.vtu\"/>\n\
             <DataSet timestep=\"5e-1\" group=\"\" part=\"0\" file=\"r_a_00001.vtu\"/>\n</Collection>",
        )
        .unwrap();
        let e = read_pvd(&dir.join("r.pvd")).unwrap();
        assert_eq!(
            e,
            vec![(0.0, 0, "r_a_00000.vtu".into()), (0.5, 0, "r_a_00001.vtu".into())]
        );
        let vtu =
            "<DataArray type=\"Float64\" Name=\"velocity\" NumberOfComponents=\"3\" format=\"binary\">QUJD</DataArray>";
        assert_eq!(array(vtu, "velocity"), Some("QUJD"));
        assert_eq!(array(vtu, "Points"), None);
        let err = write_viewer(&dir, None).unwrap_err().to_string();
        assert!(err.contains("r_a_00000.vtu"), "{err}");
        std::fs::remove_dir_all(&dir).ok();
    }
}

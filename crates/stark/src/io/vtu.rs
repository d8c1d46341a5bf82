//! VTK XML unstructured grids (`.vtu`, data arrays inline in binary: base64 of a UInt64 byte
//! count followed by the little-endian values) and ParaView collections (`.pvd`) that give each
//! frame its simulated time. ParaView, meshio and VTK read both.
//!
//! Written here rather than with a crate: the format needs a few dozen lines, and the VTK
//! writer crates either target the legacy format or are in pre-release for XML.

use crate::io::fields::CellFields;
use nalgebra::Vector3;
use std::fmt::Write as _;
use std::path::Path;

/// Cells of a VTU mesh, in indices into its points.
#[derive(Clone, Copy, Debug)]
pub enum VtuCells<'a> {
    /// One vertex cell per point.
    Points,
    /// Line segments.
    Segments(&'a [[usize; 2]]),
    /// Triangles.
    Triangles(&'a [[usize; 3]]),
    /// Tetrahedra.
    Tets(&'a [[usize; 4]]),
}

enum Values {
    F64(Vec<f64>),
    U8(Vec<u8>),
}

struct Array {
    name: String,
    components: usize,
    values: Values,
}

/// Builder of one `.vtu` file.
pub struct VtuWriter<'a> {
    points: &'a [Vector3<f64>],
    cells: VtuCells<'a>,
    time_s: Option<f64>,
    point_data: Vec<Array>,
    cell_data: Vec<Array>,
}

/// Base64 (RFC 4648, with padding).
fn base64(bytes: &[u8]) -> String {
    use base64::Engine;
    base64::engine::general_purpose::STANDARD.encode(bytes)
}

/// A binary data array's payload: the byte count (UInt64) then the data, base64-encoded.
fn payload(data: &[u8]) -> String {
    let mut bytes = (data.len() as u64).to_le_bytes().to_vec();
    bytes.extend_from_slice(data);
    base64(&bytes)
}

fn f64_bytes(v: &[f64]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

fn write_array(xml: &mut String, a: &Array) {
    let (ty, data) = match &a.values {
        Values::F64(v) => ("Float64", f64_bytes(v)),
        Values::U8(v) => ("UInt8", v.clone()),
    };
    let _ = writeln!(
        xml,
        r#"<DataArray type="{ty}" Name="{}" NumberOfComponents="{}" format="binary">{}</DataArray>"#,
        a.name,
        a.components,
        payload(&data)
    );
}

impl<'a> VtuWriter<'a> {
    /// A mesh of `points` (m) and `cells`.
    pub fn new(points: &'a [Vector3<f64>], cells: VtuCells<'a>) -> Self {
        VtuWriter {
            points,
            cells,
            time_s: None,
            point_data: Vec::new(),
            cell_data: Vec::new(),
        }
    }

    /// Record the simulated time as the `TimeValue` field (ParaView's convention).
    pub fn time(mut self, time_s: f64) -> Self {
        self.time_s = Some(time_s);
        self
    }

    /// A 3-vector per point.
    pub fn point_vectors(mut self, name: &str, v: &[Vector3<f64>]) -> Self {
        self.point_data.push(Array {
            name: name.into(),
            components: 3,
            values: Values::F64(v.iter().flat_map(|p| [p.x, p.y, p.z]).collect()),
        });
        self
    }

    /// A flag (0 or 1) per point.
    pub fn point_flags(mut self, name: &str, v: &[bool]) -> Self {
        self.point_data.push(Array {
            name: name.into(),
            components: 1,
            values: Values::U8(v.iter().map(|&b| u8::from(b)).collect()),
        });
        self
    }

    /// Strain and stress fields per cell: `green_strain` (9 components, row-major),
    /// `cauchy_stress_pa` (9), `von_mises_pa`, `principal_stress_pa` (3, largest first) and
    /// `strain_limit_active` (0/1).
    pub fn cell_fields(mut self, f: &[CellFields]) -> Self {
        let tensor = |m: &nalgebra::Matrix3<f64>| -> [f64; 9] { std::array::from_fn(|k| m[(k / 3, k % 3)]) };
        let mut add = |name: &str, components: usize, values: Values| {
            self.cell_data.push(Array {
                name: name.into(),
                components,
                values,
            })
        };
        add(
            "green_strain",
            9,
            Values::F64(f.iter().flat_map(|c| tensor(&c.green_strain)).collect()),
        );
        add(
            "cauchy_stress_pa",
            9,
            Values::F64(f.iter().flat_map(|c| tensor(&c.cauchy_stress_pa)).collect()),
        );
        add(
            "von_mises_pa",
            1,
            Values::F64(f.iter().map(|c| c.von_mises_pa).collect()),
        );
        add(
            "principal_stress_pa",
            3,
            Values::F64(f.iter().flat_map(|c| c.principal_stresses_pa).collect()),
        );
        add(
            "strain_limit_active",
            1,
            Values::U8(f.iter().map(|c| u8::from(c.strain_limit_active)).collect()),
        );
        self
    }

    /// The file's text.
    pub fn to_xml(&self) -> String {
        let (connectivity, offsets, types): (Vec<i64>, Vec<i64>, Vec<u8>) = {
            let mut conn = Vec::new();
            let mut off = Vec::new();
            let mut ty = Vec::new();
            let mut push = |cell: &[usize], t: u8| {
                conn.extend(cell.iter().map(|&i| i as i64));
                off.push(conn.len() as i64);
                ty.push(t);
            };
            match self.cells {
                VtuCells::Points => (0..self.points.len()).for_each(|i| push(&[i], 1)),
                VtuCells::Segments(s) => s.iter().for_each(|c| push(c, 3)),
                VtuCells::Triangles(t) => t.iter().for_each(|c| push(c, 5)),
                VtuCells::Tets(t) => t.iter().for_each(|c| push(c, 10)),
            }
            (conn, off, ty)
        };
        let ints = |v: &[i64]| payload(&v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>());
        let mut xml = String::new();
        xml.push_str("<?xml version=\"1.0\"?>\n");
        xml.push_str(
            "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n<UnstructuredGrid>\n",
        );
        if let Some(t) = self.time_s {
            let _ = writeln!(
                xml,
                "<FieldData>\n<DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" format=\"ascii\">{t:e}</DataArray>\n</FieldData>"
            );
        }
        let _ = writeln!(
            xml,
            "<Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">",
            self.points.len(),
            types.len()
        );
        xml.push_str("<PointData>\n");
        self.point_data.iter().for_each(|a| write_array(&mut xml, a));
        xml.push_str("</PointData>\n<CellData>\n");
        self.cell_data.iter().for_each(|a| write_array(&mut xml, a));
        xml.push_str("</CellData>\n<Points>\n");
        let coords: Vec<f64> = self.points.iter().flat_map(|p| [p.x, p.y, p.z]).collect();
        let _ = writeln!(
            xml,
            "<DataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\" format=\"binary\">{}</DataArray>",
            payload(&f64_bytes(&coords))
        );
        xml.push_str("</Points>\n<Cells>\n");
        let _ = writeln!(
            xml,
            "<DataArray type=\"Int64\" Name=\"connectivity\" format=\"binary\">{}</DataArray>",
            ints(&connectivity)
        );
        let _ = writeln!(
            xml,
            "<DataArray type=\"Int64\" Name=\"offsets\" format=\"binary\">{}</DataArray>",
            ints(&offsets)
        );
        let _ = writeln!(
            xml,
            "<DataArray type=\"UInt8\" Name=\"types\" format=\"binary\">{}</DataArray>",
            payload(&types)
        );
        xml.push_str("</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n");
        xml
    }

    /// Write the file.
    pub fn write(&self, path: &Path) -> std::io::Result<()> {
        std::fs::write(path, self.to_xml())
    }
}

/// A ParaView collection: each entry is `(time_s, part, file name relative to the .pvd)`.
pub fn write_pvd(path: &Path, entries: &[(f64, usize, String)]) -> std::io::Result<()> {
    let mut xml = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n<Collection>\n",
    );
    for (t, part, file) in entries {
        let _ = writeln!(
            xml,
            "<DataSet timestep=\"{t:e}\" group=\"\" part=\"{part}\" file=\"{file}\"/>"
        );
    }
    xml.push_str("</Collection>\n</VTKFile>\n");
    // Written whole after every frame: a reader never sees a half-written collection.
    let tmp = path.with_extension("pvd-partial");
    std::fs::write(&tmp, xml)?;
    std::fs::rename(&tmp, path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_matches_rfc4648_vectors() {
        for (input, expected) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(input.as_bytes()), expected);
        }
    }

    #[test]
    fn a_tet_file_has_its_arrays_and_counts() {
        let pts = [Vector3::zeros(), Vector3::x(), Vector3::y(), Vector3::z()];
        let xml = VtuWriter::new(&pts, VtuCells::Tets(&[[0, 1, 2, 3]]))
            .time(0.5)
            .point_vectors("velocity", &pts)
            .point_flags("prescribed", &[true, false, false, false])
            .to_xml();
        assert!(xml.contains("NumberOfPoints=\"4\" NumberOfCells=\"1\""));
        assert!(xml.contains("Name=\"velocity\"") && xml.contains("Name=\"prescribed\""));
        assert!(xml.contains("5e-1</DataArray>"));
        // The types array: 8-byte count (1) then the byte 10 (VTK_TETRA).
        assert!(xml.contains(&payload(&[10u8])));
    }
}

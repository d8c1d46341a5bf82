//! The legacy VTK writer: [`VtkWriter`] and its encoder (ASCII or big-endian binary).

use std::fmt::Write as _;
use std::fs;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use nalgebra::Vector3;

use super::{VtkCellType, VtkEncoding, VtkError, VtkPrecision};

/// The cells of a file to write, borrowed from the caller.
#[derive(Debug, Clone, Copy)]
pub enum VtkCells<'a> {
    /// A point cloud: one `VTK_VERTEX` per point, in point order.
    Points,
    /// `VTK_LINE` cells.
    Segments(&'a [[usize; 2]]),
    /// `VTK_TRIANGLE` cells.
    Triangles(&'a [[usize; 3]]),
    /// `VTK_TETRA` cells.
    Tets(&'a [[usize; 4]]),
}

#[derive(Debug, Clone, Copy)]
enum PointAttribute<'a> {
    Scalars(&'a [f64]),
    Vectors(&'a [Vector3<f64>]),
}

/// Builder for one legacy VTK UNSTRUCTURED_GRID file.
///
/// ```
/// use stark::io::vtk::{VtkCells, VtkEncoding, VtkWriter};
/// use nalgebra::Vector3;
/// let points = [Vector3::new(0.0, 0.0, 0.0), Vector3::new(1.0, 0.0, 0.0), Vector3::new(0.0, 1.0, 0.0)];
/// let velocity = [Vector3::new(0.0, 0.0, -1.0); 3];
/// let bytes = VtkWriter::new(&points, VtkCells::Triangles(&[[0, 1, 2]]))
///     .encoding(VtkEncoding::Ascii)
///     .point_vectors("velocity", &velocity)
///     .cell_scalars("area", &[0.5])
///     .to_bytes()
///     .unwrap();
/// assert!(bytes.starts_with(b"# vtk DataFile Version 4.2\n"));
/// ```
#[derive(Debug, Clone)]
#[must_use = "Builder functions return the updated builder"]
pub struct VtkWriter<'a> {
    points: &'a [Vector3<f64>],
    cells: VtkCells<'a>,
    point_data: Vec<(&'a str, PointAttribute<'a>)>,
    cell_data: Vec<(&'a str, &'a [f64])>,
    encoding: VtkEncoding,
    precision: VtkPrecision,
    title: String,
}

impl<'a> VtkWriter<'a> {
    /// A writer for `points` and `cells`, binary, double precision, no attributes.
    pub fn new(points: &'a [Vector3<f64>], cells: VtkCells<'a>) -> Self {
        VtkWriter {
            points,
            cells,
            point_data: Vec::new(),
            cell_data: Vec::new(),
            encoding: VtkEncoding::default(),
            precision: VtkPrecision::default(),
            title: "written by stark-rs".to_owned(),
        }
    }

    /// Sets the encoding (default: [`VtkEncoding::Binary`]).
    pub fn encoding(mut self, encoding: VtkEncoding) -> Self {
        self.encoding = encoding;
        self
    }

    /// Sets the floating-point type of positions and data (default:
    /// [`VtkPrecision::Float64`]).
    pub fn precision(mut self, precision: VtkPrecision) -> Self {
        self.precision = precision;
        self
    }

    /// Sets the title line (default: "written by stark-rs"); line breaks become spaces and
    /// it is cut to 255 bytes, the format's limit.
    pub fn title(mut self, title: &str) -> Self {
        let mut t: String = title
            .chars()
            .map(|c| if c == '\n' || c == '\r' { ' ' } else { c })
            .collect();
        if t.len() > 255 {
            let mut cut = 255;
            while !t.is_char_boundary(cut) {
                cut -= 1;
            }
            t.truncate(cut);
        }
        self.title = t;
        self
    }

    /// Adds a named per-point scalar field (one value per point).
    pub fn point_scalars(mut self, name: &'a str, values: &'a [f64]) -> Self {
        self.point_data.push((name, PointAttribute::Scalars(values)));
        self
    }

    /// Adds a named per-point 3-vector field (e.g. `velocity`), written as `VECTORS`.
    pub fn point_vectors(mut self, name: &'a str, values: &'a [Vector3<f64>]) -> Self {
        self.point_data.push((name, PointAttribute::Vectors(values)));
        self
    }

    /// Adds a named per-cell scalar field (one value per cell).
    pub fn cell_scalars(mut self, name: &'a str, values: &'a [f64]) -> Self {
        self.cell_data.push((name, values));
        self
    }

    fn n_cells(&self) -> usize {
        match self.cells {
            VtkCells::Points => self.points.len(),
            VtkCells::Segments(c) => c.len(),
            VtkCells::Triangles(c) => c.len(),
            VtkCells::Tets(c) => c.len(),
        }
    }

    fn cell_type(&self) -> VtkCellType {
        match self.cells {
            VtkCells::Points => VtkCellType::Vertex,
            VtkCells::Segments(_) => VtkCellType::Line,
            VtkCells::Triangles(_) => VtkCellType::Triangle,
            VtkCells::Tets(_) => VtkCellType::Tetra,
        }
    }

    /// Flat cell connectivity (without counts).
    fn connectivity(&self) -> Vec<usize> {
        match self.cells {
            VtkCells::Points => (0..self.points.len()).collect(),
            VtkCells::Segments(c) => c.iter().flatten().copied().collect(),
            VtkCells::Triangles(c) => c.iter().flatten().copied().collect(),
            VtkCells::Tets(c) => c.iter().flatten().copied().collect(),
        }
    }

    fn validate(&self, connectivity: &[usize]) -> Result<(), VtkError> {
        let n_points = self.points.len();
        let k = self.cell_type().n_vertices();
        if let Some(pos) = connectivity.iter().position(|&i| i >= n_points) {
            return Err(VtkError::InvalidOutput(format!(
                "cell {} references point {} but there are only {n_points} points",
                pos / k,
                connectivity[pos]
            )));
        }
        if n_points > i32::MAX as usize || connectivity.len() + self.n_cells() > i32::MAX as usize {
            return Err(VtkError::InvalidOutput(
                "mesh too large for the 32-bit legacy VTK cell arrays".to_owned(),
            ));
        }
        let mut names: Vec<&str> = Vec::new();
        for (name, attribute) in &self.point_data {
            check_name(name, "point", &names)?;
            names.push(name);
            let len = match attribute {
                PointAttribute::Scalars(v) => v.len(),
                PointAttribute::Vectors(v) => v.len(),
            };
            if len != n_points {
                return Err(VtkError::InvalidOutput(format!(
                    "point data '{name}' has {len} values for {n_points} points"
                )));
            }
        }
        let mut names: Vec<&str> = Vec::new();
        for (name, values) in &self.cell_data {
            check_name(name, "cell", &names)?;
            names.push(name);
            if values.len() != self.n_cells() {
                return Err(VtkError::InvalidOutput(format!(
                    "cell data '{name}' has {} values for {} cells",
                    values.len(),
                    self.n_cells()
                )));
            }
        }
        Ok(())
    }

    /// Validates the data and returns the complete file contents.
    ///
    /// # Errors
    /// [`VtkError::InvalidOutput`] if a cell references a missing point, an attribute has the
    /// wrong length, or an attribute name is empty, contains whitespace or is used twice.
    pub fn to_bytes(&self) -> Result<Vec<u8>, VtkError> {
        let connectivity = self.connectivity();
        self.validate(&connectivity)?;
        let mut out = Encoder {
            buf: Vec::new(),
            encoding: self.encoding,
            precision: self.precision,
        };
        let type_name = match self.precision {
            VtkPrecision::Float64 => "double",
            VtkPrecision::Float32 => "float",
        };
        let n_points = self.points.len();
        let n_cells = self.n_cells();
        let k = self.cell_type().n_vertices();

        out.text(&format!(
            "# vtk DataFile Version 4.2\n{}\n{}\nDATASET UNSTRUCTURED_GRID\n",
            self.title,
            match self.encoding {
                VtkEncoding::Binary => "BINARY",
                VtkEncoding::Ascii => "ASCII",
            }
        ));

        out.text(&format!("POINTS {n_points} {type_name}\n"));
        out.floats(self.points.iter().flat_map(|p| p.iter().copied()), 3);
        out.text(&format!("CELLS {n_cells} {}\n", n_cells * (k + 1)));
        out.ints(
            connectivity
                .chunks(k)
                .flat_map(|c| std::iter::once(k).chain(c.iter().copied())),
            k + 1,
        );
        out.text(&format!("CELL_TYPES {n_cells}\n"));
        out.ints(std::iter::repeat_n(self.cell_type().id() as usize, n_cells), 1);

        if n_points > 0 && !self.point_data.is_empty() {
            out.text(&format!("POINT_DATA {n_points}\n"));
            for (name, attribute) in &self.point_data {
                match attribute {
                    PointAttribute::Scalars(values) => {
                        out.text(&format!("SCALARS {name} {type_name} 1\nLOOKUP_TABLE default\n"));
                        out.floats(values.iter().copied(), 1);
                    }
                    PointAttribute::Vectors(values) => {
                        out.text(&format!("VECTORS {name} {type_name}\n"));
                        out.floats(values.iter().flat_map(|v| v.iter().copied()), 3);
                    }
                }
            }
        }
        if n_cells > 0 && !self.cell_data.is_empty() {
            out.text(&format!("CELL_DATA {n_cells}\n"));
            for (name, values) in &self.cell_data {
                out.text(&format!("SCALARS {name} {type_name} 1\nLOOKUP_TABLE default\n"));
                out.floats(values.iter().copied(), 1);
            }
        }
        Ok(out.buf)
    }

    /// Writes the file atomically: to `<path>.tmp`, then renamed to `path`.
    ///
    /// # Errors
    /// As [`VtkWriter::to_bytes`], plus [`VtkError::Write`] for I/O failures.
    pub fn write(&self, path: impl AsRef<Path>) -> Result<(), VtkError> {
        let path = path.as_ref();
        let bytes = self.to_bytes()?;
        let mut tmp = path.as_os_str().to_owned();
        tmp.push(".tmp");
        let tmp = PathBuf::from(tmp);
        let result = fs::File::create(&tmp)
            .and_then(|mut f| f.write_all(&bytes).and_then(|_| f.flush()))
            .and_then(|_| fs::rename(&tmp, path));
        result.map_err(|source| {
            let _ = fs::remove_file(&tmp);
            VtkError::Write {
                path: path.to_owned(),
                source,
            }
        })
    }
}

fn check_name(name: &str, kind: &str, previous: &[&str]) -> Result<(), VtkError> {
    if name.is_empty() || name.chars().any(|c| c.is_whitespace() || c.is_control()) {
        return Err(VtkError::InvalidOutput(format!(
            "{kind} data name '{name}' must be non-empty and contain no whitespace"
        )));
    }
    if previous.contains(&name) {
        return Err(VtkError::InvalidOutput(format!(
            "{kind} data name '{name}' is used twice"
        )));
    }
    Ok(())
}

/// Appends data blocks in the chosen encoding.
struct Encoder {
    buf: Vec<u8>,
    encoding: VtkEncoding,
    precision: VtkPrecision,
}

impl Encoder {
    fn text(&mut self, s: &str) {
        self.buf.extend_from_slice(s.as_bytes());
    }

    /// Writes floats, `per_line` per text line in ASCII, then a newline.
    fn floats(&mut self, values: impl Iterator<Item = f64>, per_line: usize) {
        match self.encoding {
            VtkEncoding::Binary => {
                for v in values {
                    match self.precision {
                        VtkPrecision::Float64 => self.buf.extend_from_slice(&v.to_be_bytes()),
                        VtkPrecision::Float32 => self.buf.extend_from_slice(&(v as f32).to_be_bytes()),
                    }
                }
                self.buf.push(b'\n');
            }
            VtkEncoding::Ascii => {
                let mut line = String::new();
                for (i, v) in values.enumerate() {
                    if i % per_line != 0 {
                        line.push(' ');
                    }
                    match self.precision {
                        VtkPrecision::Float64 => push_f64(&mut line, v),
                        VtkPrecision::Float32 => push_f32(&mut line, v as f32),
                    }
                    if i % per_line == per_line - 1 {
                        line.push('\n');
                        self.buf.extend_from_slice(line.as_bytes());
                        line.clear();
                    }
                }
                self.buf.extend_from_slice(line.as_bytes());
            }
        }
    }

    /// Writes 32-bit integers, `per_line` per text line in ASCII, then a newline.
    fn ints(&mut self, values: impl Iterator<Item = usize>, per_line: usize) {
        match self.encoding {
            VtkEncoding::Binary => {
                for v in values {
                    self.buf.extend_from_slice(&(v as i32).to_be_bytes());
                }
                self.buf.push(b'\n');
            }
            VtkEncoding::Ascii => {
                let mut line = String::new();
                for (i, v) in values.enumerate() {
                    if i % per_line != 0 {
                        line.push(' ');
                    }
                    let _ = write!(line, "{v}");
                    if i % per_line == per_line - 1 {
                        line.push('\n');
                        self.buf.extend_from_slice(line.as_bytes());
                        line.clear();
                    }
                }
                self.buf.extend_from_slice(line.as_bytes());
            }
        }
    }
}

/// Shortest round-trip text of `v`: plain decimals for moderate magnitudes, exponent form
/// otherwise; `nan`, `inf`, `-inf` for non-finite values.
fn push_f64(s: &mut String, v: f64) {
    if v.is_nan() {
        s.push_str("nan");
    } else if v.is_infinite() {
        s.push_str(if v > 0.0 { "inf" } else { "-inf" });
    } else if v == 0.0 || (1e-5..1e15).contains(&v.abs()) {
        let _ = write!(s, "{v}");
    } else {
        let _ = write!(s, "{v:e}");
    }
}

fn push_f32(s: &mut String, v: f32) {
    if v.is_nan() {
        s.push_str("nan");
    } else if v.is_infinite() {
        s.push_str(if v > 0.0 { "inf" } else { "-inf" });
    } else if v == 0.0 || (1e-5..1e15).contains(&v.abs()) {
        let _ = write!(s, "{v}");
    } else {
        let _ = write!(s, "{v:e}");
    }
}

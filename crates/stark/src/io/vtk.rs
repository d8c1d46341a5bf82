//! Legacy VTK (`.vtk`) UNSTRUCTURED_GRID writer and reader.
//!
//! # Writing
//! [`VtkWriter`] writes the classic layout shared by VTK file versions 3.0 to 4.2
//! (`CELLS n size` with per-cell counts, `CELL_TYPES`), headed `# vtk DataFile Version 4.2`
//! like Stark's `vtkio` writer (`stark/extern/vtkio/src/VTKFile.h`). One file holds one kind
//! of cell: point clouds (`VTK_VERTEX` = 1, one cell per point), segments (`VTK_LINE` = 3),
//! triangles (`VTK_TRIANGLE` = 5) or tets (`VTK_TETRA` = 10). Optional `POINT_DATA`
//! (named scalars and 3-vectors) and `CELL_DATA` (named scalars) follow. `BINARY` mode writes
//! big-endian values as the format requires; positions and data are `double` by default
//! (Stark casts positions to `float`; [`VtkPrecision::Float32`] does the same). Files are
//! written to `<path>.tmp` and renamed, so a viewer never sees a half-written frame (as
//! Stark's writer does). Output is readable by ParaView and by Python `meshio` (checked by
//! `tests/meshio_check.py`).
//!
//! # Reading
//! [`read_vtk`] / [`parse_vtk`] read ASCII and BINARY legacy files of DATASET
//! UNSTRUCTURED_GRID, both the classic cell layout and the version 5.1 layout
//! (`OFFSETS`/`CONNECTIVITY`, as written by current `meshio` and VTK 9), with vertex, line,
//! triangle and tetra cells (mixed is fine). Attributes `SCALARS`, `VECTORS`, `NORMALS`,
//! `TENSORS`, `TEXTURE_COORDINATES` and `FIELD` arrays are read; `METADATA`, `LOOKUP_TABLE`
//! and `COLOR_SCALARS` blocks are skipped. Blank lines and `#` comment lines between sections
//! are tolerated. Errors name the file, the line and what was expected.

use std::fmt::Write as _;
use std::fs;
use std::io::{self, Write as _};
use std::path::{Path, PathBuf};

use nalgebra::Vector3;

/// Errors of the VTK reader and writer.
#[derive(Debug, thiserror::Error)]
pub enum VtkError {
    /// The file to read does not exist.
    #[error("file '{}' not found", path.display())]
    NotFound {
        /// The path as given.
        path: PathBuf,
    },
    /// Reading the file failed.
    #[error("cannot read '{}': {source}", path.display())]
    Read {
        /// The path as given.
        path: PathBuf,
        /// The underlying error.
        source: io::Error,
    },
    /// Writing the file failed.
    #[error("cannot write '{}': {source}", path.display())]
    Write {
        /// The path as given.
        path: PathBuf,
        /// The underlying error.
        source: io::Error,
    },
    /// The file does not follow the format at a given line.
    #[error("'{file}' line {line}: expected {expected}, found {found}")]
    Expected {
        /// File name (or the name given to [`parse_vtk`]).
        file: String,
        /// 1-based line number.
        line: usize,
        /// What the format requires there.
        expected: String,
        /// What the file has instead.
        found: String,
    },
    /// The file is well formed up to a point but its content is not usable.
    #[error("'{file}' line {line}: {message}")]
    Invalid {
        /// File name.
        file: String,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// The file ends in the middle of a section.
    #[error("'{file}' line {line}: unexpected end of file while reading {what}")]
    UnexpectedEof {
        /// File name.
        file: String,
        /// 1-based line number where the file ends.
        line: usize,
        /// The section being read.
        what: String,
    },
    /// The data handed to [`VtkWriter`] cannot be written.
    #[error("cannot write VTK: {0}")]
    InvalidOutput(String),
}

/// Text or binary encoding of a legacy VTK file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum VtkEncoding {
    /// Big-endian binary data blocks (default; what Stark writes).
    #[default]
    Binary,
    /// Human-readable text.
    Ascii,
}

/// Floating-point type used for positions and data in written files.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum VtkPrecision {
    /// `double` (default): lossless.
    #[default]
    Float64,
    /// `float`: half the size; Stark's frame output uses this for positions.
    Float32,
}

/// VTK cell types this module reads and writes (ids from `vtkCellType.h`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VtkCellType {
    /// `VTK_VERTEX` = 1.
    Vertex,
    /// `VTK_LINE` = 3.
    Line,
    /// `VTK_TRIANGLE` = 5.
    Triangle,
    /// `VTK_TETRA` = 10.
    Tetra,
}

impl VtkCellType {
    /// The numeric VTK id.
    pub fn id(self) -> u8 {
        match self {
            VtkCellType::Vertex => 1,
            VtkCellType::Line => 3,
            VtkCellType::Triangle => 5,
            VtkCellType::Tetra => 10,
        }
    }

    /// Number of vertices of the cell.
    pub fn n_vertices(self) -> usize {
        match self {
            VtkCellType::Vertex => 1,
            VtkCellType::Line => 2,
            VtkCellType::Triangle => 3,
            VtkCellType::Tetra => 4,
        }
    }

    /// The cell type with VTK id `id`, if supported.
    pub fn from_id(id: i64) -> Option<Self> {
        match id {
            1 => Some(VtkCellType::Vertex),
            3 => Some(VtkCellType::Line),
            5 => Some(VtkCellType::Triangle),
            10 => Some(VtkCellType::Tetra),
            _ => None,
        }
    }
}

/// Name of a VTK cell id for error messages.
fn vtk_cell_name(id: i64) -> &'static str {
    match id {
        1 => "vertex",
        2 => "poly-vertex",
        3 => "line",
        4 => "poly-line",
        5 => "triangle",
        6 => "triangle strip",
        7 => "polygon",
        8 => "pixel",
        9 => "quad",
        10 => "tetra",
        11 => "voxel",
        12 => "hexahedron",
        13 => "wedge",
        14 => "pyramid",
        21 => "quadratic edge",
        22 => "quadratic triangle",
        23 => "quadratic quad",
        24 => "quadratic tetra",
        25 => "quadratic hexahedron",
        _ => "unknown",
    }
}

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

// ------------------------------------------------------------------------------------------
// Reader
// ------------------------------------------------------------------------------------------

/// A named attribute array read from a file: `values.len() = n · n_components`, tuples
/// stored contiguously.
#[derive(Debug, Clone, PartialEq)]
pub struct VtkAttribute {
    /// Array name.
    pub name: String,
    /// Components per tuple (1 for scalars, 3 for vectors, 9 for tensors).
    pub n_components: usize,
    /// The values, converted to `f64`.
    pub values: Vec<f64>,
}

impl VtkAttribute {
    /// The values if this is a one-component array.
    pub fn as_scalars(&self) -> Option<&[f64]> {
        (self.n_components == 1).then_some(self.values.as_slice())
    }

    /// The tuples as 3-vectors if this is a three-component array.
    pub fn as_vectors(&self) -> Option<Vec<Vector3<f64>>> {
        (self.n_components == 3).then(|| {
            self.values
                .chunks_exact(3)
                .map(|c| Vector3::new(c[0], c[1], c[2]))
                .collect()
        })
    }
}

/// Contents of a legacy VTK UNSTRUCTURED_GRID file.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct VtkMesh {
    /// The title line.
    pub title: String,
    /// Point positions.
    pub points: Vec<Vector3<f64>>,
    /// `VTK_VERTEX` cells (point indices), in file order.
    pub vertices: Vec<usize>,
    /// `VTK_LINE` cells, in file order.
    pub segments: Vec<[usize; 2]>,
    /// `VTK_TRIANGLE` cells, in file order.
    pub triangles: Vec<[usize; 3]>,
    /// `VTK_TETRA` cells, in file order.
    pub tets: Vec<[usize; 4]>,
    /// Type of every cell in file order; `CELL_DATA` follows this order.
    pub cell_types: Vec<VtkCellType>,
    /// `POINT_DATA` arrays.
    pub point_data: Vec<VtkAttribute>,
    /// `CELL_DATA` arrays, one tuple per cell in file order.
    pub cell_data: Vec<VtkAttribute>,
}

impl VtkMesh {
    /// The point-data array called `name`.
    pub fn point_attribute(&self, name: &str) -> Option<&VtkAttribute> {
        self.point_data.iter().find(|a| a.name == name)
    }

    /// The cell-data array called `name`.
    pub fn cell_attribute(&self, name: &str) -> Option<&VtkAttribute> {
        self.cell_data.iter().find(|a| a.name == name)
    }
}

/// Reads a legacy VTK UNSTRUCTURED_GRID file (ASCII or binary).
///
/// # Errors
/// [`VtkError::NotFound`] / [`VtkError::Read`] for I/O problems, otherwise as [`parse_vtk`].
pub fn read_vtk(path: impl AsRef<Path>) -> Result<VtkMesh, VtkError> {
    let path = path.as_ref();
    let bytes = fs::read(path).map_err(|source| {
        if source.kind() == io::ErrorKind::NotFound {
            VtkError::NotFound { path: path.to_owned() }
        } else {
            VtkError::Read {
                path: path.to_owned(),
                source,
            }
        }
    })?;
    parse_vtk(&bytes, &path.display().to_string())
}

/// Parses the bytes of a legacy VTK UNSTRUCTURED_GRID file; `file_name` is used in errors.
///
/// # Errors
/// [`VtkError::Expected`], [`VtkError::Invalid`] or [`VtkError::UnexpectedEof`] naming the
/// line, e.g. "'box.vtk' line 12: expected CELL_TYPES, found POINT_DATA 8".
pub fn parse_vtk(bytes: &[u8], file_name: &str) -> Result<VtkMesh, VtkError> {
    Parser {
        data: bytes,
        pos: 0,
        line: 1,
        file: file_name,
        binary: false,
    }
    .parse()
}

/// Element types of data arrays.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum DType {
    U8,
    I8,
    U16,
    I16,
    U32,
    I32,
    U64,
    I64,
    F32,
    F64,
}

impl DType {
    fn parse(name: &str) -> Option<Self> {
        Some(match name.to_ascii_lowercase().as_str() {
            "unsigned_char" | "vtktypeuint8" => DType::U8,
            "char" | "signed_char" | "vtktypeint8" => DType::I8,
            "unsigned_short" | "vtktypeuint16" => DType::U16,
            "short" | "vtktypeint16" => DType::I16,
            "unsigned_int" | "vtktypeuint32" => DType::U32,
            "int" | "vtktypeint32" | "vtkidtype" => DType::I32,
            "unsigned_long" | "vtktypeuint64" | "unsigned_long_long" => DType::U64,
            "long" | "vtktypeint64" | "long_long" => DType::I64,
            "float" | "vtktypefloat32" => DType::F32,
            "double" | "vtktypefloat64" => DType::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            DType::U8 | DType::I8 => 1,
            DType::U16 | DType::I16 => 2,
            DType::U32 | DType::I32 | DType::F32 => 4,
            DType::U64 | DType::I64 | DType::F64 => 8,
        }
    }

    fn is_float(self) -> bool {
        matches!(self, DType::F32 | DType::F64)
    }

    fn decode_be(self, b: &[u8]) -> f64 {
        match self {
            DType::U8 => b[0] as f64,
            DType::I8 => b[0] as i8 as f64,
            DType::U16 => u16::from_be_bytes([b[0], b[1]]) as f64,
            DType::I16 => i16::from_be_bytes([b[0], b[1]]) as f64,
            DType::U32 => u32::from_be_bytes(b.try_into().unwrap()) as f64,
            DType::I32 => i32::from_be_bytes(b.try_into().unwrap()) as f64,
            DType::U64 => u64::from_be_bytes(b.try_into().unwrap()) as f64,
            DType::I64 => i64::from_be_bytes(b.try_into().unwrap()) as f64,
            DType::F32 => f32::from_be_bytes(b.try_into().unwrap()) as f64,
            DType::F64 => f64::from_be_bytes(b.try_into().unwrap()),
        }
    }
}

/// Which attribute section we are in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Section {
    None,
    Point(usize),
    Cell(usize),
}

struct Parser<'a> {
    data: &'a [u8],
    pos: usize,
    line: usize,
    file: &'a str,
    binary: bool,
}

/// A header line: its number and text.
type Line = (usize, String);

impl<'a> Parser<'a> {
    fn expected(&self, line: usize, expected: impl Into<String>, found: &str) -> VtkError {
        let mut found = found.trim().to_owned();
        if found.len() > 60 {
            let mut cut = 60;
            while !found.is_char_boundary(cut) {
                cut -= 1;
            }
            found.truncate(cut);
            found.push_str("...");
        }
        VtkError::Expected {
            file: self.file.to_owned(),
            line,
            expected: expected.into(),
            found: if found.is_empty() {
                "an empty line".to_owned()
            } else {
                format!("'{found}'")
            },
        }
    }

    fn invalid(&self, line: usize, message: impl Into<String>) -> VtkError {
        VtkError::Invalid {
            file: self.file.to_owned(),
            line,
            message: message.into(),
        }
    }

    /// Line number to report at the end of the data: the last line, not the empty one after
    /// a final line break.
    fn eof_line(&self) -> usize {
        if self.pos >= self.data.len() && self.data.last() == Some(&b'\n') {
            self.line - 1
        } else {
            self.line
        }
    }

    fn eof(&self, what: impl Into<String>) -> VtkError {
        VtkError::UnexpectedEof {
            file: self.file.to_owned(),
            line: self.eof_line(),
            what: what.into(),
        }
    }

    /// Skips whitespace and `#` comment lines.
    fn skip_blank(&mut self) {
        while self.pos < self.data.len() {
            match self.data[self.pos] {
                b'\n' => {
                    self.line += 1;
                    self.pos += 1;
                }
                b' ' | b'\t' | b'\r' => self.pos += 1,
                b'#' => {
                    while self.pos < self.data.len() && self.data[self.pos] != b'\n' {
                        self.pos += 1;
                    }
                }
                _ => break,
            }
        }
    }

    /// The rest of the current line (without the line break), advancing past it.
    fn raw_line(&mut self) -> Option<Line> {
        if self.pos >= self.data.len() {
            return None;
        }
        let start = self.pos;
        let end = self.data[start..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(self.data.len(), |i| start + i);
        let number = self.line;
        self.pos = (end + 1).min(self.data.len());
        if end < self.data.len() {
            self.line += 1;
        }
        let text = String::from_utf8_lossy(&self.data[start..end]);
        Some((number, text.trim_end_matches('\r').to_owned()))
    }

    /// The next non-blank, non-comment line.
    fn keyword_line(&mut self) -> Option<Line> {
        self.skip_blank();
        self.raw_line()
    }

    /// Whether the next keyword line starts with `keyword` (case-insensitive), without
    /// consuming anything. In binary files the keyword must follow immediately.
    fn peek_keyword(&mut self, keyword: &str) -> bool {
        let mut p = self.pos;
        if !self.binary {
            while p < self.data.len() && self.data[p].is_ascii_whitespace() {
                p += 1;
            }
        }
        self.data
            .get(p..p + keyword.len())
            .is_some_and(|s| s.eq_ignore_ascii_case(keyword.as_bytes()))
    }

    fn parse_count(&self, line: &Line, token: Option<&str>, what: &str) -> Result<usize, VtkError> {
        token
            .and_then(|t| t.parse::<usize>().ok())
            .ok_or_else(|| self.expected(line.0, what, &line.1))
    }

    fn parse_dtype(&self, line: &Line, token: Option<&str>) -> Result<DType, VtkError> {
        let token = token.ok_or_else(|| self.expected(line.0, "a data type", &line.1))?;
        DType::parse(token).ok_or_else(|| {
            self.invalid(
                line.0,
                format!("unsupported data type '{token}' (expected float, double, int, ...)"),
            )
        })
    }

    /// Reads `count` values of type `dtype` as `f64`.
    fn values(&mut self, count: usize, dtype: DType, what: &str) -> Result<Vec<f64>, VtkError> {
        if self.binary {
            let n_bytes = count
                .checked_mul(dtype.size())
                .ok_or_else(|| self.invalid(self.line, format!("{what}: {count} values is too many")))?;
            let available = self.data.len() - self.pos;
            if available < n_bytes {
                return Err(VtkError::UnexpectedEof {
                    file: self.file.to_owned(),
                    line: self.line,
                    what: format!("{what} ({count} binary values need {n_bytes} bytes, {available} left)"),
                });
            }
            let block = &self.data[self.pos..self.pos + n_bytes];
            self.line += block.iter().filter(|&&b| b == b'\n').count();
            self.pos += n_bytes;
            Ok(block.chunks_exact(dtype.size()).map(|b| dtype.decode_be(b)).collect())
        } else {
            let mut out = Vec::with_capacity(count.min(1 << 24));
            while out.len() < count {
                self.skip_blank();
                if self.pos >= self.data.len() {
                    return Err(self.eof(format!("{what} (expected {count} values, found {})", out.len())));
                }
                let start = self.pos;
                while self.pos < self.data.len() && !self.data[self.pos].is_ascii_whitespace() {
                    self.pos += 1;
                }
                let token = String::from_utf8_lossy(&self.data[start..self.pos]);
                let value = token
                    .parse::<f64>()
                    .ok()
                    .filter(|v| dtype.is_float() || (v.fract() == 0.0 && !token.contains(['.', 'e', 'E'])));
                match value {
                    Some(v) => out.push(v),
                    None => {
                        return Err(self.expected(
                            self.line,
                            format!(
                                "{} value {} of {what}",
                                if dtype.is_float() {
                                    "a number as"
                                } else {
                                    "an integer as"
                                },
                                out.len() + 1
                            ),
                            &token,
                        ))
                    }
                }
            }
            Ok(out)
        }
    }

    /// Converts read values to indices.
    fn indices(&self, values: &[f64], line: usize, what: &str) -> Result<Vec<usize>, VtkError> {
        values
            .iter()
            .enumerate()
            .map(|(i, &v)| {
                if v >= 0.0 && v.fract() == 0.0 && v < 9.0e15 {
                    Ok(v as usize)
                } else {
                    Err(self.invalid(line, format!("{what}: entry {i} is {v}, not an index")))
                }
            })
            .collect()
    }

    fn parse(mut self) -> Result<VtkMesh, VtkError> {
        // Header: version line, title, encoding, dataset.
        let first = self.raw_line().ok_or_else(|| self.eof("the header"))?;
        let lower = first.1.trim().to_ascii_lowercase();
        if !lower.starts_with("# vtk datafile version") {
            return Err(self.expected(first.0, "'# vtk DataFile Version x.x'", &first.1));
        }
        let title = self.raw_line().ok_or_else(|| self.eof("the title line"))?.1.to_owned();
        let encoding = self.keyword_line().ok_or_else(|| self.eof("the ASCII/BINARY line"))?;
        match encoding.1.trim().to_ascii_uppercase().as_str() {
            "ASCII" => self.binary = false,
            "BINARY" => self.binary = true,
            _ => return Err(self.expected(encoding.0, "ASCII or BINARY", &encoding.1)),
        }
        let dataset = self.keyword_line().ok_or_else(|| self.eof("the DATASET line"))?;
        let mut tokens = dataset.1.split_whitespace();
        if !tokens.next().is_some_and(|t| t.eq_ignore_ascii_case("DATASET")) {
            return Err(self.expected(dataset.0, "DATASET UNSTRUCTURED_GRID", &dataset.1));
        }
        match tokens.next() {
            Some(t) if t.eq_ignore_ascii_case("UNSTRUCTURED_GRID") => {}
            Some(t) => {
                return Err(self.invalid(
                    dataset.0,
                    format!("unsupported dataset type {t} (only UNSTRUCTURED_GRID is supported)"),
                ))
            }
            None => return Err(self.expected(dataset.0, "DATASET UNSTRUCTURED_GRID", &dataset.1)),
        }

        let mut mesh = VtkMesh {
            title,
            ..VtkMesh::default()
        };
        let mut points_line = None;
        // (line of CELLS, offsets into connectivity, connectivity)
        let mut cells: Option<(usize, Vec<usize>, Vec<usize>)> = None;
        let mut cell_types: Option<(usize, Vec<f64>)> = None;
        let mut section = Section::None;

        while let Some(line) = self.keyword_line() {
            let mut tokens = line.1.split_whitespace();
            let keyword = tokens.next().unwrap_or("").to_ascii_uppercase();
            match keyword.as_str() {
                "POINTS" => {
                    let n = self.parse_count(&line, tokens.next(), "POINTS <count> <type>")?;
                    let dtype = self.parse_dtype(&line, tokens.next())?;
                    let values = self.values(3 * n, dtype, "POINTS")?;
                    mesh.points = values
                        .chunks_exact(3)
                        .map(|c| Vector3::new(c[0], c[1], c[2]))
                        .collect();
                    points_line = Some(line.0);
                }
                "CELLS" => {
                    let a = self.parse_count(&line, tokens.next(), "CELLS <count> <size>")?;
                    let b = self.parse_count(&line, tokens.next(), "CELLS <count> <size>")?;
                    if self.peek_keyword("OFFSETS") {
                        cells = Some(self.cells_v5(&line, a, b)?);
                    } else {
                        cells = Some(self.cells_classic(&line, a, b)?);
                    }
                }
                "CELL_TYPES" => {
                    let n = self.parse_count(&line, tokens.next(), "CELL_TYPES <count>")?;
                    cell_types = Some((line.0, self.values(n, DType::I32, "CELL_TYPES")?));
                }
                "POINT_DATA" => {
                    let n = self.parse_count(&line, tokens.next(), "POINT_DATA <count>")?;
                    if points_line.is_some() && n != mesh.points.len() {
                        return Err(self.invalid(
                            line.0,
                            format!("POINT_DATA {n} does not match the {} points", mesh.points.len()),
                        ));
                    }
                    section = Section::Point(n);
                }
                "CELL_DATA" => {
                    let n = self.parse_count(&line, tokens.next(), "CELL_DATA <count>")?;
                    if let Some((_, offsets, _)) = &cells {
                        if n != offsets.len() - 1 {
                            return Err(self.invalid(
                                line.0,
                                format!("CELL_DATA {n} does not match the {} cells", offsets.len() - 1),
                            ));
                        }
                    }
                    section = Section::Cell(n);
                }
                "SCALARS" | "VECTORS" | "NORMALS" | "TENSORS" | "TEXTURE_COORDINATES" => {
                    let n = match section {
                        Section::Point(n) | Section::Cell(n) => n,
                        Section::None => {
                            return Err(self.expected(
                                line.0,
                                format!("POINT_DATA or CELL_DATA before {keyword}"),
                                &line.1,
                            ))
                        }
                    };
                    let name = tokens
                        .next()
                        .ok_or_else(|| self.expected(line.0, format!("{keyword} <name> <type>"), &line.1))?;
                    let name = name.replace("%20", " ");
                    let (n_components, dtype) = match keyword.as_str() {
                        "SCALARS" => {
                            let dtype = self.parse_dtype(&line, tokens.next())?;
                            let n_comp = match tokens.next() {
                                Some(t) => self.parse_count(&line, Some(t), "SCALARS <name> <type> [components]")?,
                                None => 1,
                            };
                            if self.peek_keyword("LOOKUP_TABLE") {
                                self.keyword_line();
                            }
                            (n_comp, dtype)
                        }
                        "TEXTURE_COORDINATES" => {
                            let dim = self.parse_count(&line, tokens.next(), "TEXTURE_COORDINATES <name> <dim> <type>")?;
                            (dim, self.parse_dtype(&line, tokens.next())?)
                        }
                        "TENSORS" => (9, self.parse_dtype(&line, tokens.next())?),
                        _ => (3, self.parse_dtype(&line, tokens.next())?),
                    };
                    let values = self.values(n * n_components, dtype, &format!("{keyword} {name}"))?;
                    let attribute = VtkAttribute {
                        name,
                        n_components,
                        values,
                    };
                    match section {
                        Section::Point(_) => mesh.point_data.push(attribute),
                        _ => mesh.cell_data.push(attribute),
                    }
                }
                "FIELD" => {
                    let n_arrays = self.parse_count(&line, tokens.nth(1), "FIELD <name> <number of arrays>")?;
                    for _ in 0..n_arrays {
                        let header = self
                            .keyword_line()
                            .ok_or_else(|| self.eof("FIELD arrays"))?;
                        let mut t = header.1.split_whitespace();
                        let name = t.next().unwrap_or("").to_owned();
                        let what = "<array name> <components> <tuples> <type>";
                        let n_comp = self.parse_count(&header, t.next(), what)?;
                        let n_tuples = self.parse_count(&header, t.next(), what)?;
                        let dtype = self.parse_dtype(&header, t.next())?;
                        let values = self.values(n_comp * n_tuples, dtype, &format!("FIELD array {name}"))?;
                        if self.peek_keyword("METADATA") {
                            self.keyword_line();
                            self.skip_metadata();
                        }
                        let attribute = VtkAttribute {
                            name,
                            n_components: n_comp,
                            values,
                        };
                        match section {
                            Section::Point(n) if n == n_tuples => mesh.point_data.push(attribute),
                            Section::Cell(n) if n == n_tuples => mesh.cell_data.push(attribute),
                            // Dataset-level field data or mismatched arrays are not attributes.
                            _ => {}
                        }
                    }
                }
                "METADATA" => self.skip_metadata(),
                "LOOKUP_TABLE" => {
                    let _name = tokens.next();
                    let size = self.parse_count(&line, tokens.next(), "LOOKUP_TABLE <name> <size>")?;
                    let dtype = if self.binary { DType::U8 } else { DType::F64 };
                    self.values(4 * size, dtype, "LOOKUP_TABLE")?;
                }
                "COLOR_SCALARS" => {
                    let n = match section {
                        Section::Point(n) | Section::Cell(n) => n,
                        Section::None => 0,
                    };
                    let _name = tokens.next();
                    let n_values = self.parse_count(&line, tokens.next(), "COLOR_SCALARS <name> <n>")?;
                    let dtype = if self.binary { DType::U8 } else { DType::F64 };
                    self.values(n * n_values, dtype, "COLOR_SCALARS")?;
                }
                _ => {
                    return Err(self.expected(
                        line.0,
                        "a section keyword (POINTS, CELLS, CELL_TYPES, POINT_DATA, CELL_DATA, SCALARS, VECTORS, FIELD, ...)",
                        &line.1,
                    ))
                }
            }
        }

        // Assemble and validate.
        if points_line.is_none() {
            return Err(self.eof("the POINTS section"));
        }
        let n_points = mesh.points.len();
        match (cells, cell_types) {
            (None, None) => {}
            (Some((line, _, _)), None) => {
                return Err(VtkError::Expected {
                    file: self.file.to_owned(),
                    line: self.eof_line(),
                    expected: format!("CELL_TYPES (CELLS given at line {line})"),
                    found: "end of file".to_owned(),
                })
            }
            (None, Some((line, _))) => return Err(self.invalid(line, "CELL_TYPES without CELLS")),
            (Some((cells_line, offsets, connectivity)), Some((types_line, types))) => {
                let n_cells = offsets.len() - 1;
                if types.len() != n_cells {
                    return Err(self.invalid(
                        types_line,
                        format!(
                            "CELL_TYPES has {} entries but CELLS (line {cells_line}) has {n_cells} cells",
                            types.len()
                        ),
                    ));
                }
                for (i, &t) in types.iter().enumerate() {
                    let id = t as i64;
                    let cell_type = VtkCellType::from_id(id).ok_or_else(|| {
                        self.invalid(
                            types_line,
                            format!(
                                "cell {i} has VTK cell type {id} ({}); only vertex (1), line (3), triangle (5) and tetra (10) are supported",
                                vtk_cell_name(id)
                            ),
                        )
                    })?;
                    let nodes = &connectivity[offsets[i]..offsets[i + 1]];
                    if nodes.len() != cell_type.n_vertices() {
                        return Err(self.invalid(
                            cells_line,
                            format!(
                                "cell {i} of type {} has {} vertices, expected {}",
                                vtk_cell_name(id),
                                nodes.len(),
                                cell_type.n_vertices()
                            ),
                        ));
                    }
                    if let Some(&bad) = nodes.iter().find(|&&v| v >= n_points) {
                        return Err(self.invalid(
                            cells_line,
                            format!("cell {i} references point {bad} but there are only {n_points} points"),
                        ));
                    }
                    match cell_type {
                        VtkCellType::Vertex => mesh.vertices.push(nodes[0]),
                        VtkCellType::Line => mesh.segments.push([nodes[0], nodes[1]]),
                        VtkCellType::Triangle => mesh.triangles.push([nodes[0], nodes[1], nodes[2]]),
                        VtkCellType::Tetra => mesh.tets.push([nodes[0], nodes[1], nodes[2], nodes[3]]),
                    }
                    mesh.cell_types.push(cell_type);
                }
            }
        }
        let check = |data: &[VtkAttribute], n: usize, kind: &str| {
            data.iter().try_for_each(|a| {
                if a.values.len() == n * a.n_components {
                    Ok(())
                } else {
                    Err(self.invalid(
                        self.line,
                        format!(
                            "{kind} data '{}' has {} tuples, expected {n}",
                            a.name,
                            a.values.len() / a.n_components.max(1)
                        ),
                    ))
                }
            })
        };
        check(&mesh.point_data, n_points, "point")?;
        check(&mesh.cell_data, mesh.cell_types.len(), "cell")?;
        Ok(mesh)
    }

    /// Classic layout: `CELLS n size` then, per cell, a count followed by the indices.
    fn cells_classic(
        &mut self,
        line: &Line,
        n_cells: usize,
        size: usize,
    ) -> Result<(usize, Vec<usize>, Vec<usize>), VtkError> {
        let raw = self.values(size, DType::I32, "CELLS")?;
        let raw = self.indices(&raw, line.0, "CELLS")?;
        let mut offsets = Vec::with_capacity(n_cells + 1);
        let mut connectivity = Vec::with_capacity(size.saturating_sub(n_cells));
        let mut p = 0;
        offsets.push(0);
        for i in 0..n_cells {
            let Some(&k) = raw.get(p) else {
                return Err(self.invalid(line.0, format!("CELLS: size {size} ends before cell {i} of {n_cells}")));
            };
            let Some(nodes) = raw.get(p + 1..p + 1 + k) else {
                return Err(self.invalid(
                    line.0,
                    format!("CELLS: cell {i} with {k} vertices runs past size {size}"),
                ));
            };
            connectivity.extend_from_slice(nodes);
            offsets.push(connectivity.len());
            p += k + 1;
        }
        if p != size {
            return Err(self.invalid(
                line.0,
                format!("CELLS: {n_cells} cells use {p} entries but size is {size}"),
            ));
        }
        Ok((line.0, offsets, connectivity))
    }

    /// Version 5.1 layout: `CELLS n_offsets n_connectivity`, then `OFFSETS type` and
    /// `CONNECTIVITY type` arrays.
    fn cells_v5(
        &mut self,
        line: &Line,
        n_offsets: usize,
        n_connectivity: usize,
    ) -> Result<(usize, Vec<usize>, Vec<usize>), VtkError> {
        let offsets_line = self.keyword_line().ok_or_else(|| self.eof("OFFSETS"))?;
        let dtype = self.parse_dtype(&offsets_line, offsets_line.1.split_whitespace().nth(1))?;
        let offsets = self.values(n_offsets, dtype, "OFFSETS")?;
        let offsets = self.indices(&offsets, offsets_line.0, "OFFSETS")?;
        let conn_line = self.keyword_line().ok_or_else(|| self.eof("CONNECTIVITY"))?;
        if !conn_line
            .1
            .trim_start()
            .to_ascii_uppercase()
            .starts_with("CONNECTIVITY")
        {
            return Err(self.expected(conn_line.0, "CONNECTIVITY <type>", &conn_line.1));
        }
        let dtype = self.parse_dtype(&conn_line, conn_line.1.split_whitespace().nth(1))?;
        let connectivity = self.values(n_connectivity, dtype, "CONNECTIVITY")?;
        let connectivity = self.indices(&connectivity, conn_line.0, "CONNECTIVITY")?;
        let offsets = if offsets.is_empty() { vec![0] } else { offsets };
        if offsets[0] != 0 || offsets.windows(2).any(|w| w[0] > w[1]) || *offsets.last().unwrap() != n_connectivity {
            return Err(self.invalid(
                offsets_line.0,
                format!("OFFSETS must rise from 0 to the connectivity size {n_connectivity}"),
            ));
        }
        Ok((line.0, offsets, connectivity))
    }

    /// Skips a METADATA block: text lines up to the next blank line.
    fn skip_metadata(&mut self) {
        while let Some((_, text)) = self.raw_line() {
            if text.trim().is_empty() {
                break;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::presets::meshes::{segment_line, tet_grid, triangle_grid};

    fn roundtrip(writer: &VtkWriter<'_>) -> VtkMesh {
        let bytes = writer.to_bytes().unwrap();
        parse_vtk(&bytes, "test.vtk").unwrap()
    }

    #[test]
    fn tets_roundtrip_binary_and_ascii_with_data() {
        let m = tet_grid(Vector3::zeros(), Vector3::new(0.3, 0.2, 0.1), [2, 2, 3]);
        let velocity: Vec<_> = m.vertices.iter().map(|p| p * 2.0 + Vector3::x()).collect();
        let temperature: Vec<f64> = (0..m.vertices.len()).map(|i| i as f64 * 0.1).collect();
        let tet_ids: Vec<f64> = (0..m.elements.len()).map(|i| i as f64).collect();
        for encoding in [VtkEncoding::Binary, VtkEncoding::Ascii] {
            let writer = VtkWriter::new(&m.vertices, VtkCells::Tets(&m.elements))
                .encoding(encoding)
                .title("tet grid")
                .point_vectors("velocity", &velocity)
                .point_scalars("temperature", &temperature)
                .cell_scalars("id", &tet_ids);
            let r = roundtrip(&writer);
            assert_eq!(r.title, "tet grid");
            assert_eq!(r.points, m.vertices, "{encoding:?}: positions not bit-exact");
            assert_eq!(r.tets, m.elements);
            assert!(r.triangles.is_empty() && r.segments.is_empty() && r.vertices.is_empty());
            assert_eq!(r.point_attribute("velocity").unwrap().as_vectors().unwrap(), velocity);
            assert_eq!(
                r.point_attribute("temperature").unwrap().as_scalars().unwrap(),
                &temperature[..]
            );
            assert_eq!(r.cell_attribute("id").unwrap().as_scalars().unwrap(), &tet_ids[..]);
        }
    }

    #[test]
    fn all_cell_kinds_roundtrip() {
        let g = triangle_grid([0.0, 0.0], [1.0, 1.0], [3, 2], 0.25);
        let l = segment_line(Vector3::zeros(), Vector3::new(1.0, 1.0, 1.0), 5);
        for encoding in [VtkEncoding::Binary, VtkEncoding::Ascii] {
            let r = roundtrip(&VtkWriter::new(&g.vertices, VtkCells::Triangles(&g.elements)).encoding(encoding));
            assert_eq!(
                (r.points.clone(), r.triangles.clone()),
                (g.vertices.clone(), g.elements.clone())
            );
            assert!(r.cell_types.iter().all(|&t| t == VtkCellType::Triangle));
            let r = roundtrip(&VtkWriter::new(&l.vertices, VtkCells::Segments(&l.elements)).encoding(encoding));
            assert_eq!(r.segments, l.elements);
            assert_eq!(r.points, l.vertices);
            let r = roundtrip(&VtkWriter::new(&l.vertices, VtkCells::Points).encoding(encoding));
            assert_eq!(r.vertices, (0..6).collect::<Vec<_>>());
            assert_eq!(r.cell_types, vec![VtkCellType::Vertex; 6]);
        }
    }

    #[test]
    fn float32_and_awkward_values() {
        let points = vec![
            Vector3::new(1e-300, -2.5e20, 0.1),
            Vector3::new(-0.0, 123456.789, 1e-7),
            Vector3::new(f64::MAX, f64::MIN_POSITIVE, -1.0 / 3.0),
        ];
        let s = [f64::NAN, f64::INFINITY, -5e-324];
        for encoding in [VtkEncoding::Binary, VtkEncoding::Ascii] {
            let r = roundtrip(
                &VtkWriter::new(&points, VtkCells::Points)
                    .encoding(encoding)
                    .point_scalars("s", &s),
            );
            assert_eq!(r.points, points);
            let back = r.point_attribute("s").unwrap().as_scalars().unwrap().to_vec();
            assert!(back[0].is_nan() && back[1] == f64::INFINITY && back[2] == -5e-324);
            let small = [Vector3::new(0.1, 0.2, 0.3)];
            let r = roundtrip(
                &VtkWriter::new(&small, VtkCells::Points)
                    .encoding(encoding)
                    .precision(VtkPrecision::Float32),
            );
            assert_eq!(r.points[0].map(|c| c as f32), small[0].map(|c| c as f32));
        }
        let text = VtkWriter::new(&points[..1], VtkCells::Points)
            .encoding(VtkEncoding::Ascii)
            .precision(VtkPrecision::Float32)
            .to_bytes()
            .unwrap();
        assert!(String::from_utf8(text).unwrap().contains("POINTS 1 float\n"));
    }

    #[test]
    fn ascii_layout_is_classic_legacy() {
        let points = [
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
        ];
        let text = VtkWriter::new(&points, VtkCells::Triangles(&[[0, 1, 2]]))
            .encoding(VtkEncoding::Ascii)
            .title("t")
            .cell_scalars("a", &[0.5])
            .to_bytes()
            .unwrap();
        let expected = "# vtk DataFile Version 4.2\nt\nASCII\nDATASET UNSTRUCTURED_GRID\n\
            POINTS 3 double\n0 0 0\n1 0 0\n0 1 0\nCELLS 1 4\n3 0 1 2\nCELL_TYPES 1\n5\n\
            CELL_DATA 1\nSCALARS a double 1\nLOOKUP_TABLE default\n0.5\n";
        assert_eq!(String::from_utf8(text).unwrap(), expected);
    }

    #[test]
    fn empty_mesh_roundtrips() {
        for encoding in [VtkEncoding::Binary, VtkEncoding::Ascii] {
            let r = roundtrip(&VtkWriter::new(&[], VtkCells::Triangles(&[])).encoding(encoding));
            assert!(r.points.is_empty() && r.triangles.is_empty());
        }
    }

    #[test]
    fn writer_rejects_bad_input() {
        let p = [Vector3::zeros(), Vector3::x()];
        let err = VtkWriter::new(&p, VtkCells::Segments(&[[0, 1], [1, 2]]))
            .to_bytes()
            .unwrap_err();
        assert_eq!(
            err.to_string(),
            "cannot write VTK: cell 1 references point 2 but there are only 2 points"
        );
        let err = VtkWriter::new(&p, VtkCells::Points)
            .point_scalars("s", &[1.0])
            .to_bytes()
            .unwrap_err();
        assert_eq!(
            err.to_string(),
            "cannot write VTK: point data 's' has 1 values for 2 points"
        );
        let err = VtkWriter::new(&p, VtkCells::Points)
            .point_scalars("my field", &[1.0, 2.0])
            .to_bytes()
            .unwrap_err();
        assert!(err.to_string().contains("no whitespace"));
        let err = VtkWriter::new(&p, VtkCells::Points)
            .point_scalars("a", &[1.0, 2.0])
            .point_vectors("a", &p)
            .to_bytes()
            .unwrap_err();
        assert!(err.to_string().contains("used twice"));
        let err = VtkWriter::new(&p, VtkCells::Points)
            .cell_scalars("c", &[1.0])
            .to_bytes()
            .unwrap_err();
        assert!(err.to_string().contains("1 values for 2 cells"));
    }

    #[test]
    fn write_and_read_files() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("frame_0.vtk");
        let m = tet_grid(Vector3::zeros(), Vector3::repeat(1.0), [1, 1, 1]);
        VtkWriter::new(&m.vertices, VtkCells::Tets(&m.elements))
            .write(&path)
            .unwrap();
        assert!(!dir.path().join("frame_0.vtk.tmp").exists());
        let r = read_vtk(&path).unwrap();
        assert_eq!(r.tets, m.elements);
        let missing = dir.path().join("nope.vtk");
        let err = read_vtk(&missing).unwrap_err();
        assert!(matches!(err, VtkError::NotFound { .. }));
        assert_eq!(err.to_string(), format!("file '{}' not found", missing.display()));
        let err = VtkWriter::new(&m.vertices, VtkCells::Points)
            .write(dir.path().join("no_dir/x.vtk"))
            .unwrap_err();
        assert!(matches!(err, VtkError::Write { .. }));
    }

    #[test]
    fn reads_tolerant_ascii_with_comments_and_mixed_cells() {
        let text = "# vtk DataFile Version 3.0\nhand written\n\nascii\n  DATASET UNSTRUCTURED_GRID\n\
            # a comment line\n\
            POINTS 5 float\n0 0 0  1 0 0\n0 1 0\n0 0 1   1 1 1\n\n\
            CELLS 3 12\n4 0 1 2 3\n3 1 2 4\n2 0 4\n\
            CELL_TYPES 3\n10\n5\n3\n\
            CELL_DATA 3\nSCALARS mat int\n1 2 3\n\
            POINT_DATA 5\nNORMALS n float\n0 0 1 0 0 1 0 0 1 0 0 1 0 0 1\n";
        let r = parse_vtk(text.as_bytes(), "hand.vtk").unwrap();
        assert_eq!(r.points.len(), 5);
        assert_eq!(r.tets, vec![[0, 1, 2, 3]]);
        assert_eq!(r.triangles, vec![[1, 2, 4]]);
        assert_eq!(r.segments, vec![[0, 4]]);
        assert_eq!(
            r.cell_types,
            vec![VtkCellType::Tetra, VtkCellType::Triangle, VtkCellType::Line]
        );
        assert_eq!(r.cell_attribute("mat").unwrap().values, vec![1.0, 2.0, 3.0]);
        assert_eq!(r.point_attribute("n").unwrap().n_components, 3);
    }

    #[test]
    fn reads_version_5_layout_like_meshio() {
        // As written by meshio 5.3.5 (`meshio.write(..., binary=False)`).
        let text = "# vtk DataFile Version 5.1\nwritten by meshio v5.3.5\nASCII\nDATASET UNSTRUCTURED_GRID\n\
            POINTS 4 double\n0.0 0.0 0.0 1.0 0.0 0.0 0.0 1.0 0.0 0.0 0.0 1.0\n\
            CELLS 3 7\nOFFSETS vtktypeint64\n0\n4\n7\nCONNECTIVITY vtktypeint64\n0\n1\n2\n3\n0\n1\n2\n\
            CELL_TYPES 2\n10\n5\n\
            POINT_DATA 4\nFIELD FieldData 2\nv 3 4 double\n0.0 0.0 0.0 2.0 0.0 0.0 0.0 2.0 0.0 0.0 0.0 2.0\n\
            s 1 4 double\n0.0 1.0 2.0 3.0\n\
            CELL_DATA 2\nFIELD FieldData 1\nc 1 2 double\n1.5 2.5\n";
        let r = parse_vtk(text.as_bytes(), "meshio.vtk").unwrap();
        assert_eq!(r.tets, vec![[0, 1, 2, 3]]);
        assert_eq!(r.triangles, vec![[0, 1, 2]]);
        assert_eq!(
            r.point_attribute("v").unwrap().as_vectors().unwrap()[1],
            Vector3::new(2.0, 0.0, 0.0)
        );
        assert_eq!(r.point_attribute("s").unwrap().values, vec![0.0, 1.0, 2.0, 3.0]);
        assert_eq!(r.cell_attribute("c").unwrap().values, vec![1.5, 2.5]);
    }

    #[test]
    fn reads_version_5_binary() {
        let mut b: Vec<u8> =
            b"# vtk DataFile Version 5.1\nx\nBINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 double\n".to_vec();
        for v in [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0f64] {
            b.extend_from_slice(&v.to_be_bytes());
        }
        b.extend_from_slice(b"\nCELLS 2 4\nOFFSETS vtktypeint64\n");
        for v in [0i64, 4] {
            b.extend_from_slice(&v.to_be_bytes());
        }
        b.extend_from_slice(b"\nCONNECTIVITY vtktypeint64\n");
        for v in [0i64, 1, 2, 3] {
            b.extend_from_slice(&v.to_be_bytes());
        }
        b.extend_from_slice(b"\nCELL_TYPES 1\n");
        b.extend_from_slice(&10i32.to_be_bytes());
        b.extend_from_slice(b"\n");
        let r = parse_vtk(&b, "bin5.vtk").unwrap();
        assert_eq!(r.tets, vec![[0, 1, 2, 3]]);
        assert_eq!(r.points[3], Vector3::new(0.0, 0.0, 1.0));
    }

    #[test]
    fn parse_errors_name_file_and_line() {
        let good = "# vtk DataFile Version 4.2\nt\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 double\n\
            0 0 0\n1 0 0\n0 1 0\n0 0 1\nCELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10\n";
        assert!(parse_vtk(good.as_bytes(), "box.vtk").is_ok());

        let err = |text: &str| parse_vtk(text.as_bytes(), "box.vtk").unwrap_err().to_string();

        assert_eq!(
            err(&good.replace("CELL_TYPES 1\n10\n", "POINT_DATA 4\n")),
            "'box.vtk' line 12: expected CELL_TYPES (CELLS given at line 10), found end of file"
        );
        assert_eq!(
            err(&good.replace("CELL_TYPES", "CELL_TYPO")),
            "'box.vtk' line 12: expected a section keyword (POINTS, CELLS, CELL_TYPES, POINT_DATA, CELL_DATA, SCALARS, VECTORS, FIELD, ...), found 'CELL_TYPO 1'"
        );
        assert_eq!(
            err(&good.replace("\n10\n", "\n12\n")),
            "'box.vtk' line 12: cell 0 has VTK cell type 12 (hexahedron); only vertex (1), line (3), triangle (5) and tetra (10) are supported"
        );
        assert_eq!(
            err(&good.replace("\n10\n", "\n5\n")),
            "'box.vtk' line 10: cell 0 of type triangle has 4 vertices, expected 3"
        );
        assert_eq!(
            err(&good.replace("4 0 1 2 3", "4 0 1 2 7")),
            "'box.vtk' line 10: cell 0 references point 7 but there are only 4 points"
        );
        assert_eq!(
            err(&good.replace("0 0 1\nCELLS", "0 zero 1\nCELLS")),
            "'box.vtk' line 9: expected a number as value 11 of POINTS, found 'zero'"
        );
        let cut = &good[..good.find("0 1 0\n").unwrap()];
        assert_eq!(
            err(cut),
            "'box.vtk' line 7: unexpected end of file while reading POINTS (expected 12 values, found 6)"
        );
        assert_eq!(
            err("hello\n"),
            "'box.vtk' line 1: expected '# vtk DataFile Version x.x', found 'hello'"
        );
        assert_eq!(
            err(&good.replace("UNSTRUCTURED_GRID", "POLYDATA")),
            "'box.vtk' line 4: unsupported dataset type POLYDATA (only UNSTRUCTURED_GRID is supported)"
        );
        assert_eq!(
            err(&good.replace("ASCII", "TEXT")),
            "'box.vtk' line 3: expected ASCII or BINARY, found 'TEXT'"
        );
        assert_eq!(
            err(&good.replace("POINTS 4 double", "POINTS 4 quad")),
            "'box.vtk' line 5: unsupported data type 'quad' (expected float, double, int, ...)"
        );
        assert!(err("").contains("unexpected end of file while reading the header"));
        assert_eq!(
            err(&format!("{good}POINT_DATA 5\n")),
            "'box.vtk' line 14: POINT_DATA 5 does not match the 4 points"
        );
        assert_eq!(
            err(&format!("{good}CELL_DATA 2\n")),
            "'box.vtk' line 14: CELL_DATA 2 does not match the 1 cells"
        );
    }

    #[test]
    fn truncated_binary_is_reported() {
        let m = tet_grid(Vector3::zeros(), Vector3::repeat(1.0), [1, 1, 1]);
        let bytes = VtkWriter::new(&m.vertices, VtkCells::Tets(&m.elements))
            .to_bytes()
            .unwrap();
        for cut in [30, 100, 200, bytes.len() - 60] {
            let e = parse_vtk(&bytes[..cut], "cut.vtk").unwrap_err();
            assert!(
                matches!(
                    e,
                    VtkError::UnexpectedEof { .. } | VtkError::Expected { .. } | VtkError::Invalid { .. }
                ),
                "cut {cut}: {e}"
            );
        }
        let e = parse_vtk(&bytes[..200], "cut.vtk").unwrap_err().to_string();
        assert!(
            e.starts_with(
                "'cut.vtk' line 6: unexpected end of file while reading POINTS (27 binary values need 216 bytes"
            ),
            "{e}"
        );
    }
}

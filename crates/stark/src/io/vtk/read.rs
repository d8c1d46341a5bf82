//! The legacy VTK reader: [`read_vtk`] / [`parse_vtk`] into a [`VtkMesh`] (ASCII and binary,
//! classic and version 5.1 cell layouts).

use std::fs;
use std::io;
use std::path::Path;

use nalgebra::Vector3;

use super::{VtkCellType, VtkError};

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

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
//!
//! The writer is in `vtk/write.rs`, the reader in `vtk/read.rs`; this file holds the types both use.

mod read;
mod write;

use std::io;
use std::path::PathBuf;

pub use read::{parse_vtk, read_vtk, VtkAttribute, VtkMesh};
pub use write::{VtkCells, VtkWriter};

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

#[cfg(test)]
mod tests;

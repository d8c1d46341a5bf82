//! Errors of the geometry module.

use thiserror::Error;

/// Errors reported by the mesh-level functions of [`crate::geometry`].
///
/// Per-primitive functions take points, not indices, and never fail; the functions that take
/// index lists (edges, triangles) or several parallel arrays check them and report the first
/// problem found.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum GeometryError {
    /// A primitive refers to a vertex that does not exist.
    #[error("{primitive} {index} refers to vertex {vertex}, but there are only {num_vertices} vertices")]
    VertexIndexOutOfRange {
        /// Kind of primitive (`"edge"`, `"triangle"`).
        primitive: &'static str,
        /// Index of the primitive in its list.
        index: usize,
        /// The offending vertex index.
        vertex: usize,
        /// Number of vertices available.
        num_vertices: usize,
    },
    /// Two arrays that must have the same length do not.
    #[error("{what}: expected {expected} entries, found {found}")]
    LengthMismatch {
        /// What was being compared, e.g. `"refit boxes"`.
        what: &'static str,
        /// The required length.
        expected: usize,
        /// The length that was passed.
        found: usize,
    },
}

//! Mesh topology, measures and transforms.
//!
//! Counterparts of Stark's `stark/src/utils/mesh_utils.{h,cpp}`: surface extraction
//! (`find_surface`), edges (`find_edges_from_simplices`), hinges (`find_internal_angles`),
//! perimeter and sharp edges, `reduce_connectivity`, `clean_triangle_mesh` (here
//! [`merge_by_distance`]), element measures with Stark's exact floating-point expressions,
//! lumped masses as in `EnergyLumpedInertia::add`, and point transforms.
//!
//! Differences from Stark, all deliberate: outputs are deterministic (Stark iterates hash maps
//! in `find_surface`, `find_perimeter_edges` and `clean_triangle_mesh`), invalid input is
//! reported as a [`MeshError`] instead of `exit(-1)`, hinges come from actual triangle
//! adjacency instead of common vertex neighbours, and merging is by true distance instead of
//! grid quantisation.
//!
//! Functions that take vertex positions index them directly and panic on an out-of-range
//! index; call [`check_indices`] first on untrusted connectivity.

use std::collections::HashMap;

use nalgebra::geometry::AbstractRotation;
use nalgebra::{Unit, UnitQuaternion, Vector3};

/// Invalid mesh input, naming the offending element.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeshError {
    /// An element references a vertex that does not exist.
    #[error("{kind} {element}: vertex index {vertex} is out of range (the mesh has {n_vertices} vertices)")]
    IndexOutOfRange {
        /// Element kind ("segment", "triangle", "tet", ...).
        kind: &'static str,
        /// Index of the element.
        element: usize,
        /// The offending vertex index.
        vertex: usize,
        /// Number of vertices in the mesh.
        n_vertices: usize,
    },
    /// An element uses the same vertex twice.
    #[error("{kind} {element}: vertex {vertex} appears more than once")]
    RepeatedVertex {
        /// Element kind.
        kind: &'static str,
        /// Index of the element.
        element: usize,
        /// The repeated vertex index.
        vertex: usize,
    },
    /// A tet has zero, negative or non-finite signed volume.
    #[error("tet {tet}: rest volume {volume:e} m³ is not positive")]
    NonPositiveVolume {
        /// Index of the tet.
        tet: usize,
        /// Its signed volume `((x1−x0)×(x2−x0))·(x3−x0)/6`.
        volume: f64,
    },
    /// More than two triangles share an edge.
    #[error("edge ({e0}, {e1}) is shared by {count} triangles")]
    NonManifoldEdge {
        /// Smaller vertex index of the edge.
        e0: usize,
        /// Larger vertex index of the edge.
        e1: usize,
        /// Number of triangles using the edge.
        count: usize,
    },
    /// More than two tets share a triangular face.
    #[error("face ({}, {}, {}) is shared by {count} tets", face[0], face[1], face[2])]
    NonManifoldFace {
        /// Sorted vertex indices of the face.
        face: [usize; 3],
        /// Number of tets using the face.
        count: usize,
    },
    /// A merge tolerance that is negative or not finite.
    #[error("merge tolerance {tolerance} m must be finite and non-negative")]
    InvalidTolerance {
        /// The rejected tolerance.
        tolerance: f64,
    },
    /// A merge tolerance so small relative to the coordinates that grid cells overflow.
    #[error("merge tolerance {tolerance:e} m is too small for coordinates of magnitude {magnitude:e} m")]
    ToleranceTooSmall {
        /// The rejected tolerance.
        tolerance: f64,
        /// Largest absolute coordinate in the mesh.
        magnitude: f64,
    },
    /// A vertex position is NaN or infinite.
    #[error("vertex {vertex}: position ({}, {}, {}) is not finite", position[0], position[1], position[2])]
    NonFiniteVertex {
        /// Index of the vertex.
        vertex: usize,
        /// Its position.
        position: [f64; 3],
    },
}

/// Human-readable name of a `K`-vertex simplex, used in error messages.
pub(crate) fn element_name(k: usize) -> &'static str {
    match k {
        1 => "vertex",
        2 => "segment",
        3 => "triangle",
        4 => "tet",
        _ => "element",
    }
}

/// Checks that every index in `elements` is below `n_vertices` and that no element repeats a
/// vertex. The error names the first offending element.
pub fn check_indices<const K: usize>(n_vertices: usize, elements: &[[usize; K]]) -> Result<(), MeshError> {
    let kind = element_name(K);
    for (element, e) in elements.iter().enumerate() {
        for (a, &vertex) in e.iter().enumerate() {
            if vertex >= n_vertices {
                return Err(MeshError::IndexOutOfRange {
                    kind,
                    element,
                    vertex,
                    n_vertices,
                });
            }
            if e[..a].contains(&vertex) {
                return Err(MeshError::RepeatedVertex { kind, element, vertex });
            }
        }
    }
    Ok(())
}

fn check_repeated<const K: usize>(elements: &[[usize; K]]) -> Result<(), MeshError> {
    check_indices(usize::MAX, elements)
}

// ------------------------------------------------------------------------------------------
// Topology
// ------------------------------------------------------------------------------------------

/// Compacts the vertex indexing of `elements` to the vertices they use.
///
/// Returns the re-indexed elements and the map `new_to_old` (new vertex `i` is old vertex
/// `new_to_old[i]`). New indices are assigned in order of first appearance while scanning the
/// elements, exactly as Stark's `reduce_connectivity`.
pub fn reduce_connectivity<const K: usize>(elements: &[[usize; K]]) -> (Vec<[usize; K]>, Vec<usize>) {
    let mut old_to_new: HashMap<usize, usize> = HashMap::new();
    let mut new_to_old = Vec::new();
    let reduced = elements
        .iter()
        .map(|e| {
            e.map(|old| {
                *old_to_new.entry(old).or_insert_with(|| {
                    new_to_old.push(old);
                    new_to_old.len() - 1
                })
            })
        })
        .collect();
    (reduced, new_to_old)
}

/// Outward faces of a positively oriented tet `[a, b, c, d]`, in the order
/// (abc, abd, acd, bcd) of Stark's `find_surface`, each wound counter-clockwise seen from
/// outside.
fn outward_tet_faces(t: &[usize; 4]) -> [[usize; 3]; 4] {
    let [a, b, c, d] = *t;
    [[a, c, b], [a, b, d], [a, d, c], [b, c, d]]
}

/// Boundary triangles of a tet mesh, in the tet mesh's vertex indexing.
///
/// A face is on the boundary when exactly one tet uses it. The triangles are wound so that
/// their normal `(x1−x0)×(x2−x0)` points out of the solid, which assumes positively oriented
/// tets (`((x1−x0)×(x2−x0))·(x3−x0) > 0`, see [`check_tet_volumes`] and
/// [`fix_tet_orientation`]); Stark decides the winding per face from the tet's centroid, which
/// gives the same result for positive tets. Triangles are listed by tet index, then by the
/// local face order (abc, abd, acd, bcd), so the output is deterministic (Stark's order
/// follows a hash map).
///
/// # Errors
/// [`MeshError::RepeatedVertex`] for a degenerate tet and [`MeshError::NonManifoldFace`] for a
/// face used by more than two tets.
pub fn find_surface_triangles(tets: &[[usize; 4]]) -> Result<Vec<[usize; 3]>, MeshError> {
    check_repeated(tets)?;
    // (sorted face, tet, local face)
    let mut faces: Vec<([usize; 3], usize, usize)> = Vec::with_capacity(4 * tets.len());
    for (ti, t) in tets.iter().enumerate() {
        for (fi, f) in outward_tet_faces(t).iter().enumerate() {
            let mut key = *f;
            key.sort_unstable();
            faces.push((key, ti, fi));
        }
    }
    faces.sort_unstable();
    let mut boundary: Vec<(usize, usize)> = Vec::new();
    for group in faces.chunk_by(|a, b| a.0 == b.0) {
        match group.len() {
            1 => boundary.push((group[0].1, group[0].2)),
            2 => {}
            count => {
                return Err(MeshError::NonManifoldFace {
                    face: group[0].0,
                    count,
                })
            }
        }
    }
    boundary.sort_unstable();
    Ok(boundary
        .into_iter()
        .map(|(ti, fi)| outward_tet_faces(&tets[ti])[fi])
        .collect())
}

/// Boundary surface of a tet mesh with its own compact vertex indexing.
///
/// Returns `(triangles, surface_to_volume)`: the outward boundary triangles of
/// [`find_surface_triangles`] re-indexed by [`reduce_connectivity`], and the map from surface
/// vertex `i` to tet-mesh vertex `surface_to_volume[i]`. Same contract as Stark's
/// `find_surface(vertices, tets)` (which returns `out_triangle_to_tet_node_map`), except that
/// the order is deterministic and the winding comes from the tet orientation.
///
/// # Errors
/// As [`find_surface_triangles`].
pub fn find_surface(tets: &[[usize; 4]]) -> Result<(Vec<[usize; 3]>, Vec<usize>), MeshError> {
    Ok(reduce_connectivity(&find_surface_triangles(tets)?))
}

/// Unique edges `[a, b]` with `a < b` of any simplices, sorted lexicographically.
///
/// Same result and order as Stark's `find_edges_from_simplices`.
pub fn edges_from_simplices<const K: usize>(elements: &[[usize; K]]) -> Vec<[usize; 2]> {
    let mut edges = Vec::with_capacity(elements.len() * K * K.saturating_sub(1) / 2);
    for e in elements {
        for i in 0..K {
            for j in i + 1..K {
                edges.push([e[i].min(e[j]), e[i].max(e[j])]);
            }
        }
    }
    edges.sort_unstable();
    edges.dedup();
    edges
}

/// Unique sorted edges of a triangle mesh (see [`edges_from_simplices`]).
pub fn edges_from_triangles(triangles: &[[usize; 3]]) -> Vec<[usize; 2]> {
    edges_from_simplices(triangles)
}

/// Unique sorted edges of a tet mesh (see [`edges_from_simplices`]).
pub fn edges_from_tets(tets: &[[usize; 4]]) -> Vec<[usize; 2]> {
    edges_from_simplices(tets)
}

/// One use of an edge by a triangle: (sorted edge, triangle, opposite vertex, whether the
/// triangle traverses the edge from the smaller to the larger index).
type EdgeUse = ([usize; 2], usize, usize, bool);

fn edge_uses(triangles: &[[usize; 3]]) -> Result<Vec<EdgeUse>, MeshError> {
    check_repeated(triangles)?;
    let mut uses = Vec::with_capacity(3 * triangles.len());
    for (ti, t) in triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b, opposite) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            uses.push(([a.min(b), a.max(b)], ti, opposite, a < b));
        }
    }
    uses.sort_unstable();
    Ok(uses)
}

/// Hinges (pairs of triangles sharing an edge) for dihedral-angle bending.
///
/// For every edge used by exactly two triangles, returns `[e0, e1, x2, x3]` with `e0 < e1`
/// the edge, `x2` the opposite vertex of the triangle that traverses `e0 → e1` (triangle A)
/// and `x3` the opposite vertex of the other one (triangle B, which traverses `e1 → e0` when
/// the mesh is consistently oriented). Then `n_A = (x1−x0)×(x2−x0)` and
/// `n_B = −(x1−x0)×(x3−x0)` are the triangles' own normals, so they coincide on a flat,
/// consistently oriented mesh (dihedral angle 0), and the sign of `(n_A×n_B)·(x1−x0)` tells
/// convex from concave. If both triangles traverse the edge the same way (inconsistent
/// orientation), the lower-indexed triangle is A.
///
/// Hinges are sorted by edge, the order of Stark's `find_internal_angles`, which however
/// lists `x2 < x3` by index. Stark's bending energy uses the unsigned angle
/// `acos(n̂_A·n̂_B)`, which is the same (bit for bit) for either order of `x2`, `x3`.
/// Boundary edges (one triangle) are skipped.
///
/// # Errors
/// [`MeshError::NonManifoldEdge`] for an edge shared by more than two triangles and
/// [`MeshError::RepeatedVertex`] for a degenerate triangle.
pub fn find_hinges(triangles: &[[usize; 3]]) -> Result<Vec<[usize; 4]>, MeshError> {
    let uses = edge_uses(triangles)?;
    let mut hinges = Vec::new();
    for group in uses.chunk_by(|a, b| a.0 == b.0) {
        let [e0, e1] = group[0].0;
        match group {
            [_] => {}
            [a, b] => {
                let (x2, x3) = if !a.3 && b.3 { (b.2, a.2) } else { (a.2, b.2) };
                hinges.push([e0, e1, x2, x3]);
            }
            _ => {
                return Err(MeshError::NonManifoldEdge {
                    e0,
                    e1,
                    count: group.len(),
                })
            }
        }
    }
    Ok(hinges)
}

/// Edges used by exactly one triangle (the open boundary of a surface).
///
/// Each edge keeps the direction in which its triangle traverses it, so for a consistently
/// oriented surface the boundary loops run counter-clockwise around the surface normal.
/// Sorted by `(min, max)` index. Stark's `find_perimeter_edges` returns the same set (in hash
/// order, compacted); compact with [`reduce_connectivity`] if needed. Degenerate triangles
/// are ignored.
pub fn perimeter_edges(triangles: &[[usize; 3]]) -> Vec<[usize; 2]> {
    let mut uses: Vec<([usize; 2], [usize; 2])> = Vec::with_capacity(3 * triangles.len());
    for t in triangles {
        if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
            continue;
        }
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            uses.push(([a.min(b), a.max(b)], [a, b]));
        }
    }
    uses.sort_unstable();
    uses.chunk_by(|a, b| a.0 == b.0)
        .filter(|g| g.len() == 1)
        .map(|g| g[0].1)
        .collect()
}

/// Interior edges whose two triangles' normals differ by more than `angle_deg` degrees.
///
/// Reproduces Stark's `find_sharp_edges` test `n̂_A·n̂_B < cos(angle)` with
/// `n_A = normal(x0, x1, x2)`, `n_B = normal(x1, x0, x3)` over the hinges of
/// [`find_hinges`]. Returns sorted `[e0, e1]` with `e0 < e1` in the input indexing (Stark
/// returns them compacted; use [`reduce_connectivity`]).
///
/// # Errors
/// As [`find_hinges`].
pub fn sharp_edges(
    vertices: &[Vector3<f64>],
    triangles: &[[usize; 3]],
    angle_deg: f64,
) -> Result<Vec<[usize; 2]>, MeshError> {
    let cos_threshold = deg_to_rad(angle_deg).cos();
    Ok(find_hinges(triangles)?
        .into_iter()
        .filter(|h| {
            let [x0, x1, x2, x3] = h.map(|i| vertices[i]);
            triangle_normal(&x0, &x1, &x2).dot(&triangle_normal(&x1, &x0, &x3)) < cos_threshold
        })
        .map(|h| [h[0], h[1]])
        .collect())
}

// ------------------------------------------------------------------------------------------
// Measures
// ------------------------------------------------------------------------------------------

/// Stark's `deg2rad`: `2π·(deg/360)`.
fn deg_to_rad(deg: f64) -> f64 {
    2.0 * std::f64::consts::PI * (deg / 360.0)
}

/// Unit normal `(p0−p2)×(p1−p2)/‖·‖` (Stark's `triangle_normal`); NaN for a degenerate
/// triangle.
pub fn triangle_normal(p0: &Vector3<f64>, p1: &Vector3<f64>, p2: &Vector3<f64>) -> Vector3<f64> {
    let n = (p0 - p2).cross(&(p1 - p2));
    n / n.norm()
}

/// Triangle area `½‖(p0−p2)×(p1−p2)‖` in m² (Stark's `triangle_area`, same expression).
pub fn triangle_area(p0: &Vector3<f64>, p1: &Vector3<f64>, p2: &Vector3<f64>) -> f64 {
    0.5 * (p0 - p2).cross(&(p1 - p2)).norm()
}

/// Signed tet volume `((p1−p0)×(p2−p0))·(p3−p0)/6` in m³ (Stark's `signed_tetra_volume`,
/// same expression); positive when `p3` lies on the side `(p1−p0)×(p2−p0)` points to.
pub fn tet_signed_volume(p0: &Vector3<f64>, p1: &Vector3<f64>, p2: &Vector3<f64>, p3: &Vector3<f64>) -> f64 {
    (1.0 / 6.0) * (p1 - p0).cross(&(p2 - p0)).dot(&(p3 - p0))
}

/// Segment length `‖p0−p1‖` in m.
pub fn segment_length(p0: &Vector3<f64>, p1: &Vector3<f64>) -> f64 {
    (p0 - p1).norm()
}

/// Length of every segment, in m.
pub fn segment_lengths(vertices: &[Vector3<f64>], segments: &[[usize; 2]]) -> Vec<f64> {
    segments
        .iter()
        .map(|s| segment_length(&vertices[s[0]], &vertices[s[1]]))
        .collect()
}

/// Area of every triangle, in m² ([`triangle_area`]).
pub fn triangle_areas(vertices: &[Vector3<f64>], triangles: &[[usize; 3]]) -> Vec<f64> {
    triangles
        .iter()
        .map(|t| triangle_area(&vertices[t[0]], &vertices[t[1]], &vertices[t[2]]))
        .collect()
}

/// Signed volume of every tet, in m³ ([`tet_signed_volume`]).
pub fn tet_signed_volumes(vertices: &[Vector3<f64>], tets: &[[usize; 4]]) -> Vec<f64> {
    tets.iter()
        .map(|t| tet_signed_volume(&vertices[t[0]], &vertices[t[1]], &vertices[t[2]], &vertices[t[3]]))
        .collect()
}

/// Sum of the unsigned tet volumes in m³ (Stark's `total_volume`).
pub fn total_tet_volume(vertices: &[Vector3<f64>], tets: &[[usize; 4]]) -> f64 {
    tet_signed_volumes(vertices, tets).into_iter().map(f64::abs).sum()
}

/// Checks indices and that every tet has a finite, strictly positive signed volume.
///
/// # Errors
/// [`MeshError::IndexOutOfRange`], [`MeshError::RepeatedVertex`] or
/// [`MeshError::NonPositiveVolume`] naming the first offending tet, e.g.
/// "tet 812: rest volume -1.2e-9 m³ is not positive".
pub fn check_tet_volumes(vertices: &[Vector3<f64>], tets: &[[usize; 4]]) -> Result<(), MeshError> {
    check_indices(vertices.len(), tets)?;
    for (tet, t) in tets.iter().enumerate() {
        let volume = tet_signed_volume(&vertices[t[0]], &vertices[t[1]], &vertices[t[2]], &vertices[t[3]]);
        if volume.is_nan() || volume <= 0.0 {
            return Err(MeshError::NonPositiveVolume { tet, volume });
        }
    }
    Ok(())
}

/// Swaps the last two vertices of every tet with negative signed volume, so that all tets
/// become positively oriented. Returns how many tets were flipped. Zero-volume tets are left
/// alone ([`check_tet_volumes`] still rejects them).
pub fn fix_tet_orientation(vertices: &[Vector3<f64>], tets: &mut [[usize; 4]]) -> usize {
    let mut flipped = 0;
    for t in tets.iter_mut() {
        if tet_signed_volume(&vertices[t[0]], &vertices[t[1]], &vertices[t[2]], &vertices[t[3]]) < 0.0 {
            t.swap(2, 3);
            flipped += 1;
        }
    }
    flipped
}

/// Per-vertex lumped measure: each element gives `measure/K` to each of its vertices, in
/// element order (as Stark's `EnergyLumpedInertia::add` accumulates `lumped_volume`), then
/// everything is multiplied by `density`.
fn lumped<const K: usize>(
    n_vertices: usize,
    elements: &[[usize; K]],
    measure: impl Fn(&[usize; K]) -> f64,
    density: f64,
) -> Vec<f64> {
    let mut out = vec![0.0; n_vertices];
    for e in elements {
        let share = measure(e) / K as f64;
        for &i in e {
            out[i] += share;
        }
    }
    out.iter_mut().for_each(|m| *m *= density);
    out
}

/// Lumped vertex masses in kg of a rod: each segment gives `L/2 · density_kg_per_m` to both
/// ends. With `density_kg_per_m = 1` this is Stark's per-vertex `lumped_volume` (m).
pub fn lumped_masses_from_segments(
    vertices: &[Vector3<f64>],
    segments: &[[usize; 2]],
    density_kg_per_m: f64,
) -> Vec<f64> {
    lumped(
        vertices.len(),
        segments,
        |s| segment_length(&vertices[s[0]], &vertices[s[1]]),
        density_kg_per_m,
    )
}

/// Lumped vertex masses in kg of a surface: each triangle gives `A/3 · density_kg_per_m2` to
/// each corner (Stark's `EnergyLumpedInertia::add` for triangles).
pub fn lumped_masses_from_triangles(
    vertices: &[Vector3<f64>],
    triangles: &[[usize; 3]],
    density_kg_per_m2: f64,
) -> Vec<f64> {
    lumped(
        vertices.len(),
        triangles,
        |t| triangle_area(&vertices[t[0]], &vertices[t[1]], &vertices[t[2]]),
        density_kg_per_m2,
    )
}

/// Lumped vertex masses in kg of a solid: each tet gives `|V|/4 · density_kg_per_m3` to each
/// corner (Stark's `EnergyLumpedInertia::add` for tets, which uses the unsigned volume).
pub fn lumped_masses_from_tets(vertices: &[Vector3<f64>], tets: &[[usize; 4]], density_kg_per_m3: f64) -> Vec<f64> {
    lumped(
        vertices.len(),
        tets,
        |t| tet_signed_volume(&vertices[t[0]], &vertices[t[1]], &vertices[t[2]], &vertices[t[3]]).abs(),
        density_kg_per_m3,
    )
}

/// Area-weighted unit vertex normals (Stark's `compute_node_normals`). Vertices that touch no
/// triangle of positive area get a zero vector.
pub fn vertex_normals(vertices: &[Vector3<f64>], triangles: &[[usize; 3]]) -> Vec<Vector3<f64>> {
    let mut normals = vec![Vector3::zeros(); vertices.len()];
    for t in triangles {
        let [p0, p1, p2] = t.map(|i| vertices[i]);
        // (p0−p2)×(p1−p2) has length 2A and the direction of the normal.
        let weighted = 0.5 * (p0 - p2).cross(&(p1 - p2));
        for &i in t {
            normals[i] += weighted;
        }
    }
    for n in &mut normals {
        let len = n.norm();
        if len > 0.0 {
            *n /= len;
        }
    }
    normals
}

// ------------------------------------------------------------------------------------------
// Merging
// ------------------------------------------------------------------------------------------

/// Result of [`merge_by_distance`].
#[derive(Debug, Clone, PartialEq)]
pub struct MergedMesh<const K: usize> {
    /// The kept vertices, in order of first occurrence.
    pub vertices: Vec<Vector3<f64>>,
    /// The re-indexed elements, without degenerate and duplicate ones.
    pub elements: Vec<[usize; K]>,
    /// For every input vertex, its index in [`MergedMesh::vertices`].
    pub old_to_new: Vec<usize>,
    /// For every output element, the index of the input element it came from.
    pub kept_elements: Vec<usize>,
}

/// Merges vertices closer than `tolerance_m` and drops the elements this makes degenerate or
/// duplicate (Stark's `clean_triangle_mesh`, for any simplex size).
///
/// Vertices are visited in order; each one is merged into the earliest kept vertex within
/// `tolerance_m` (Euclidean distance, inclusive), or kept. `tolerance_m = 0` merges only exactly
/// equal positions. Elements that repeat a vertex after merging are dropped, and of elements
/// with the same vertex set only the first is kept (with its winding). Stark instead snaps
/// vertices to a grid of cell size `merge_by_distance`, which can miss close pairs across a
/// cell face and merge along chains, and its output order follows a hash map.
///
/// # Errors
/// [`MeshError::InvalidTolerance`] if `tolerance_m` is negative or not finite,
/// [`MeshError::NonFiniteVertex`] for a NaN/infinite position, and
/// [`MeshError::ToleranceTooSmall`] if the coordinates span more than ~10¹⁵ tolerances.
pub fn merge_by_distance<const K: usize>(
    vertices: &[Vector3<f64>],
    elements: &[[usize; K]],
    tolerance_m: f64,
) -> Result<MergedMesh<K>, MeshError> {
    if !(tolerance_m >= 0.0 && tolerance_m.is_finite()) {
        return Err(MeshError::InvalidTolerance { tolerance: tolerance_m });
    }
    check_indices(vertices.len(), elements).or_else(|e| match e {
        // Repeated vertices are fine on input: those elements are dropped below.
        MeshError::RepeatedVertex { .. } => Ok(()),
        other => Err(other),
    })?;
    let mut magnitude = 0.0f64;
    for (vertex, p) in vertices.iter().enumerate() {
        if !p.iter().all(|c| c.is_finite()) {
            return Err(MeshError::NonFiniteVertex {
                vertex,
                position: [p.x, p.y, p.z],
            });
        }
        magnitude = magnitude.max(p.amax());
    }

    let mut kept: Vec<Vector3<f64>> = Vec::new();
    let mut old_to_new = Vec::with_capacity(vertices.len());
    if tolerance_m == 0.0 {
        // `+ 0.0` turns -0.0 into 0.0 so both hash alike.
        let mut exact: HashMap<[u64; 3], usize> = HashMap::new();
        for p in vertices {
            let key = [(p.x + 0.0).to_bits(), (p.y + 0.0).to_bits(), (p.z + 0.0).to_bits()];
            let idx = *exact.entry(key).or_insert_with(|| {
                kept.push(*p);
                kept.len() - 1
            });
            old_to_new.push(idx);
        }
    } else {
        if magnitude / tolerance_m > 1e15 {
            return Err(MeshError::ToleranceTooSmall {
                tolerance: tolerance_m,
                magnitude,
            });
        }
        let cell_of = |p: &Vector3<f64>| p.map(|c| (c / tolerance_m).floor() as i64);
        let mut grid: HashMap<Vector3<i64>, Vec<usize>> = HashMap::new();
        let tol_sq = tolerance_m * tolerance_m;
        for p in vertices {
            let cell = cell_of(p);
            let mut best: Option<usize> = None;
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        let Some(candidates) = grid.get(&(cell + Vector3::new(dx, dy, dz))) else {
                            continue;
                        };
                        for &c in candidates {
                            if (kept[c] - p).norm_squared() <= tol_sq && best.is_none_or(|b| c < b) {
                                best = Some(c);
                            }
                        }
                    }
                }
            }
            let idx = best.unwrap_or_else(|| {
                kept.push(*p);
                grid.entry(cell).or_default().push(kept.len() - 1);
                kept.len() - 1
            });
            old_to_new.push(idx);
        }
    }

    let mut seen: HashMap<[usize; K], ()> = HashMap::new();
    let mut new_elements = Vec::with_capacity(elements.len());
    let mut kept_elements = Vec::with_capacity(elements.len());
    for (ei, e) in elements.iter().enumerate() {
        let mapped = e.map(|i| old_to_new[i]);
        let mut key = mapped;
        key.sort_unstable();
        if key.windows(2).any(|w| w[0] == w[1]) {
            continue;
        }
        if seen.insert(key, ()).is_none() {
            new_elements.push(mapped);
            kept_elements.push(ei);
        }
    }
    Ok(MergedMesh {
        vertices: kept,
        elements: new_elements,
        old_to_new,
        kept_elements,
    })
}

// ------------------------------------------------------------------------------------------
// Transforms
// ------------------------------------------------------------------------------------------

/// Adds `translation` to every point (Stark's `move`).
pub fn translate(points: &mut [Vector3<f64>], translation: &Vector3<f64>) {
    points.iter_mut().for_each(|p| *p += translation);
}

/// Rotates every point about the origin by any nalgebra 3D rotation (`Rotation3`,
/// `UnitQuaternion`).
pub fn rotate<R: AbstractRotation<f64, 3>>(points: &mut [Vector3<f64>], rotation: &R) {
    points.iter_mut().for_each(|p| *p = rotation.transform_vector(p));
}

/// Rotates every point about `pivot` (Stark's `rotate_deg(points, angle, axis, pivot)` with
/// the rotation given explicitly).
pub fn rotate_about<R: AbstractRotation<f64, 3>>(points: &mut [Vector3<f64>], rotation: &R, pivot: &Vector3<f64>) {
    points
        .iter_mut()
        .for_each(|p| *p = rotation.transform_vector(&(*p - pivot)) + pivot);
}

/// Rotates every point by `angle_deg` degrees about `axis` (normalised here) through the
/// origin, right-handed (Stark's `rotate_deg(points, angle, axis)`). A zero axis leaves the
/// points unchanged.
pub fn rotate_deg(points: &mut [Vector3<f64>], angle_deg: f64, axis: &Vector3<f64>) {
    if let Some(axis) = Unit::try_new(*axis, 0.0) {
        let q = UnitQuaternion::from_axis_angle(&axis, deg_to_rad(angle_deg));
        rotate(points, &q.to_rotation_matrix());
    }
}

/// Multiplies every point by `factor` about the origin (Stark's `scale(points, double)`).
pub fn scale(points: &mut [Vector3<f64>], factor: f64) {
    points.iter_mut().for_each(|p| *p *= factor);
}

/// Multiplies every point component-wise by `factors` (Stark's `scale(points, Vector3d)`).
pub fn scale_xyz(points: &mut [Vector3<f64>], factors: &Vector3<f64>) {
    points.iter_mut().for_each(|p| *p = p.component_mul(factors));
}

/// Mirrors every point across the plane `x[axis] = pivot` (Stark's `mirror`). This flips the
/// orientation of triangles and tets; swap two indices per element afterwards if needed.
///
/// # Panics
/// If `axis > 2`.
pub fn mirror(points: &mut [Vector3<f64>], axis: usize, pivot: f64) {
    assert!(axis < 3, "mirror: axis must be 0, 1 or 2, got {axis}");
    points.iter_mut().for_each(|p| p[axis] = pivot - (p[axis] - pivot));
}

/// Moves the points so that their centroid is at the origin (Stark's `center`) and returns
/// the former centroid (zero for no points).
pub fn center(points: &mut [Vector3<f64>]) -> Vector3<f64> {
    if points.is_empty() {
        return Vector3::zeros();
    }
    let centroid = points.iter().sum::<Vector3<f64>>() / points.len() as f64;
    points.iter_mut().for_each(|p| *p -= centroid);
    centroid
}

/// Axis-aligned bounding box `(min, max)` of the points, `None` if there are none.
pub fn bounding_box(points: &[Vector3<f64>]) -> Option<(Vector3<f64>, Vector3<f64>)> {
    let first = points.first()?;
    Some(
        points
            .iter()
            .fold((*first, *first), |(lo, hi), p| (lo.inf(p), hi.sup(p))),
    )
}

#[cfg(test)]
mod tests;

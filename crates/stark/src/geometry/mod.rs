//! Contact geometry for IPC-style contact.
//!
//! - [`distance`]: squared distances between point, edge and triangle primitives, with the
//!   IPC region classification (Li et al. 2020, "Incremental Potential Contact"), closest-point
//!   parameters for lagged friction, and the edge–edge mollifier.
//! - [`ccd`]: conservative continuous collision detection for linear trajectories, an
//!   inclusion-based interval root finder in the spirit of Tight Inclusion (Wang et al. 2021),
//!   and the line-search step-size helpers built on it.
//! - [`intersection`]: exact edge–triangle intersection tests with adaptive-precision predicates
//!   (Shewchuk 1997) and a parallel mesh-level check.
//! - [`aabb`] and [`bvh`]: the broad phase, axis-aligned boxes and a Morton-sorted bounding volume
//!   hierarchy with parallel build, refit and deterministic pair queries.
//! - [`mesh`]: topology and measures of meshes (surfaces of tet meshes, edges, hinges, lumped
//!   masses, merging, transforms).
//!
//! Conventions: points are `nalgebra::Vector3<f64>`; every distance whose name ends in `_sq` is a
//! squared distance; `_t0`/`_t1` are the start and end of a linear motion; an edge's ends are
//! `e0`, `e1`, a triangle's corners `t0`, `t1`, `t2`.
//!
//! Non-finite input never panics. Distances propagate NaN; CCD reports an impact at time 0 (the
//! conservative answer); bounding boxes of non-finite primitives cover all of space, so a NaN vertex
//! is a candidate for everything and reaches the (conservative) narrow phase.

pub mod aabb;
pub mod bvh;
pub mod ccd;
pub mod distance;
mod error;
pub mod intersection;
pub mod mesh;

pub use mesh::{
    bounding_box, center, check_indices, check_tet_volumes, edges_from_simplices, edges_from_tets,
    edges_from_triangles, find_hinges, find_surface, find_surface_triangles, fix_tet_orientation,
    lumped_masses_from_segments, lumped_masses_from_tets, lumped_masses_from_triangles, merge_by_distance, mirror,
    perimeter_edges, reduce_connectivity, rotate, rotate_about, rotate_deg, scale, scale_xyz, segment_length,
    segment_lengths, sharp_edges, tet_signed_volume, tet_signed_volumes, total_tet_volume, translate, triangle_area,
    triangle_areas, triangle_normal, vertex_normals, MergedMesh, MeshError,
};

pub use error::GeometryError;

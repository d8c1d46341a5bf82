//! Ready-made geometry: mesh generators reproducing Stark's conventions.

// The mesh generators are ground floor (rigid-body shapes build their meshes with them);
// re-exported so `presets::meshes` keeps working.
pub use crate::meshes;

pub use meshes::{
    box_mesh, cylinder_mesh, cylindrical_triangle_grid, segment_line, sphere_mesh, tet_grid, torus_mesh, triangle_grid,
    Mesh, SegmentMesh, TetMesh, TriangleMesh,
};

pub mod materials;
pub mod objects;
pub mod rigid;

pub use materials::{Bending, LineMaterial, SurfaceMaterial, VolumeMaterial};
pub use objects::{FixedSurfaceHandle, LineHandle, ObstacleHandle, SurfaceHandle, VolumeHandle};
pub use rigid::RigidHandle;

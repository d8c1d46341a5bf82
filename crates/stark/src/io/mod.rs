//! File input and output: legacy VTK frames, mesh loaders (OBJ, STL, VTK, Gmsh `.msh`) and
//! declarative scene files (TOML or JSON).

pub mod checkpoint;
pub mod fields;
pub mod mesh_files;
pub mod output;
pub mod scene;
pub mod vtk;
pub mod vtu;

pub use checkpoint::{read_header as read_checkpoint_header, CheckpointHeader, SceneOrigin, CHECKPOINT_FORMAT_VERSION};
pub use mesh_files::{
    load_mesh, load_msh, load_obj, load_obj_shapes, load_stl, load_tet_mesh, load_triangle_mesh, load_vtk_mesh,
    parse_msh, LoadedMesh, MeshFileError,
};
pub use scene::{
    load_scene, load_scene_with, load_scene_with_overrides, parse_scene, parse_scene_with, LoadedScene, SceneError,
};
pub use vtk::{
    parse_vtk, read_vtk, VtkAttribute, VtkCellType, VtkCells, VtkEncoding, VtkError, VtkMesh, VtkPrecision, VtkWriter,
};

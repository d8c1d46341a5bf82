//! File input and output: legacy VTK frames and mesh loaders (OBJ, STL, VTK, Gmsh `.msh`).

pub mod mesh_files;
pub mod output;
pub mod vtk;

pub use mesh_files::{
    load_mesh, load_msh, load_obj, load_obj_shapes, load_stl, load_tet_mesh, load_triangle_mesh,
    load_vtk_mesh, parse_msh, LoadedMesh, MeshFileError,
};
pub use vtk::{
    parse_vtk, read_vtk, VtkAttribute, VtkCellType, VtkCells, VtkEncoding, VtkError, VtkMesh,
    VtkPrecision, VtkWriter,
};

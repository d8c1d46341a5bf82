//! The `meshes` submodule: mesh generators and mesh files. Every function returns
//! `(vertices (n, 3) float64, elements (m, k) int64)`.

use crate::convert::{elements_out, guarded, points_out, stark_err, V3};
use nalgebra::Vector3;
use numpy::PyArray2;
use pyo3::prelude::*;

type MeshOut<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<i64>>);

fn out<'py, const K: usize>(py: Python<'py>, m: &stark::presets::Mesh<K>) -> MeshOut<'py> {
    (points_out(py, &m.vertices), elements_out(py, &m.elements))
}

fn generate<const K: usize>(f: impl FnOnce() -> stark::presets::Mesh<K>) -> PyResult<stark::presets::Mesh<K>> {
    guarded(|| Ok(f()))
}

fn positive(what: &str, values: &[f64]) -> PyResult<()> {
    if values.iter().all(|v| *v > 0.0 && v.is_finite()) {
        Ok(())
    } else {
        Err(stark_err(format!("{what} must be positive and finite, got {values:?}")))
    }
}

/// A rectangular triangle grid of `size` centred at `center` in the plane z = `z`, `quads` per side.
#[pyfunction]
#[pyo3(signature = (size, quads, center=[0.0, 0.0], z=0.0))]
fn triangle_grid(py: Python<'_>, size: [f64; 2], quads: [usize; 2], center: [f64; 2], z: f64) -> PyResult<MeshOut<'_>> {
    positive("size", &size)?;
    let m = generate(|| stark::presets::triangle_grid(center, size, quads, z))?;
    Ok(out(py, &m))
}

/// A tet grid of `size` centred at `center`, `hexes` cells per side, 12 tets per cell.
#[pyfunction]
#[pyo3(signature = (size, hexes, center=None))]
fn tet_grid(py: Python<'_>, size: V3, hexes: [usize; 3], center: Option<V3>) -> PyResult<MeshOut<'_>> {
    positive("size", size.0.as_slice())?;
    let c = center.map(|c| c.0).unwrap_or_else(Vector3::zeros);
    let m = generate(|| stark::presets::tet_grid(c, size.0, hexes))?;
    Ok(out(py, &m))
}

/// A straight line of `n_segments` segments from `begin` to `end`.
#[pyfunction]
fn segment_line(py: Python<'_>, begin: V3, end: V3, n_segments: usize) -> PyResult<MeshOut<'_>> {
    let m = generate(|| stark::presets::segment_line(begin.0, end.0, n_segments))?;
    Ok(out(py, &m))
}

/// The closed surface of a box of `size` centred at the origin (12 triangles).
#[pyfunction]
fn box_mesh(py: Python<'_>, size: V3) -> PyResult<MeshOut<'_>> {
    positive("size", size.0.as_slice())?;
    let m = generate(|| stark::presets::box_mesh(size.0))?;
    Ok(out(py, &m))
}

/// An icosphere of `radius` with `subdivisions` refinements.
#[pyfunction]
#[pyo3(signature = (radius, subdivisions=2))]
fn sphere_mesh(py: Python<'_>, radius: f64, subdivisions: usize) -> PyResult<MeshOut<'_>> {
    positive("radius", &[radius])?;
    if subdivisions > 7 {
        return Err(stark_err("at most 7 subdivisions"));
    }
    let m = generate(|| stark::presets::sphere_mesh(radius, subdivisions))?;
    Ok(out(py, &m))
}

/// A closed cylinder of `radius` and `height` along z, centred.
#[pyfunction]
#[pyo3(signature = (radius, height, slices=16, stacks=1))]
fn cylinder_mesh(py: Python<'_>, radius: f64, height: f64, slices: usize, stacks: usize) -> PyResult<MeshOut<'_>> {
    positive("radius and height", &[radius, height])?;
    let m = generate(|| stark::presets::cylinder_mesh(radius, height, slices, stacks))?;
    Ok(out(py, &m))
}

/// A torus in the xy plane: major radius (tube centre), minor (tube) radius.
#[pyfunction]
#[pyo3(signature = (major_radius, minor_radius, major_segments=32, minor_segments=16))]
fn torus_mesh(
    py: Python<'_>,
    major_radius: f64,
    minor_radius: f64,
    major_segments: usize,
    minor_segments: usize,
) -> PyResult<MeshOut<'_>> {
    positive("radii", &[major_radius, minor_radius])?;
    let m = generate(|| stark::presets::torus_mesh(major_radius, minor_radius, major_segments, minor_segments))?;
    Ok(out(py, &m))
}

/// An open cylindrical triangle grid of `radius` and `height` along z, `quads` = (around, along).
#[pyfunction]
fn cylindrical_triangle_grid(py: Python<'_>, radius: f64, height: f64, quads: [usize; 2]) -> PyResult<MeshOut<'_>> {
    positive("radius and height", &[radius, height])?;
    let m = generate(|| stark::presets::cylindrical_triangle_grid(radius, height, quads))?;
    Ok(out(py, &m))
}

/// Load a triangle mesh (OBJ, STL, VTK, Gmsh .msh): `(vertices, triangles)`.
#[pyfunction]
fn load_triangle_mesh(py: Python<'_>, path: std::path::PathBuf) -> PyResult<MeshOut<'_>> {
    let m = guarded(|| stark::io::load_triangle_mesh(&path).map_err(stark::StarkError::from))?;
    Ok(out(py, &m))
}

/// Load a tet mesh (VTK, Gmsh .msh): `(vertices, tets)`.
#[pyfunction]
fn load_tet_mesh(py: Python<'_>, path: std::path::PathBuf) -> PyResult<MeshOut<'_>> {
    let m = guarded(|| stark::io::load_tet_mesh(&path).map_err(stark::StarkError::from))?;
    Ok(out(py, &m))
}

/// Build the submodule.
pub fn module(py: Python<'_>) -> PyResult<Bound<'_, PyModule>> {
    let m = PyModule::new(py, "meshes")?;
    m.add(
        "__doc__",
        "Mesh generators and mesh files: each returns (vertices (n, 3), elements (m, k)).",
    )?;
    m.add_function(wrap_pyfunction!(triangle_grid, &m)?)?;
    m.add_function(wrap_pyfunction!(tet_grid, &m)?)?;
    m.add_function(wrap_pyfunction!(segment_line, &m)?)?;
    m.add_function(wrap_pyfunction!(box_mesh, &m)?)?;
    m.add_function(wrap_pyfunction!(sphere_mesh, &m)?)?;
    m.add_function(wrap_pyfunction!(cylinder_mesh, &m)?)?;
    m.add_function(wrap_pyfunction!(torus_mesh, &m)?)?;
    m.add_function(wrap_pyfunction!(cylindrical_triangle_grid, &m)?)?;
    m.add_function(wrap_pyfunction!(load_triangle_mesh, &m)?)?;
    m.add_function(wrap_pyfunction!(load_tet_mesh, &m)?)?;
    Ok(m)
}

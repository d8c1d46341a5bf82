//! Mass properties of rigid bodies.

use crate::convert::{guarded, m3_out, v3_out, Elements, Points, M3, V3};
use nalgebra::{Matrix3, Vector3};
use pyo3::prelude::*;

/// Mass, centre of mass and inertia tensor of a solid with uniform density.
///
/// Build one with `cuboid`, `sphere`, `cylinder`, `torus` or `from_mesh`, or directly with
/// `MassProperties(mass_kg, center_of_mass_m, inertia_kg_m2)`; pass it to
/// `Simulation.add_rigid_body_with`.
#[pyclass(module = "starkrs", frozen)]
#[derive(Clone, Copy, Debug)]
pub struct MassProperties {
    mass_kg: f64,
    center_of_mass_m: Vector3<f64>,
    inertia_kg_m2: Matrix3<f64>,
}

impl MassProperties {
    /// The library value.
    pub fn rust(&self) -> stark::rigidbodies::MassProperties {
        stark::rigidbodies::MassProperties {
            mass_kg: self.mass_kg,
            center_of_mass_m: self.center_of_mass_m,
            inertia_kg_m2: self.inertia_kg_m2,
        }
    }

    fn wrap(m: stark::rigidbodies::MassProperties) -> Self {
        MassProperties {
            mass_kg: m.mass_kg,
            center_of_mass_m: m.center_of_mass_m,
            inertia_kg_m2: m.inertia_kg_m2,
        }
    }
}

#[pymethods]
impl MassProperties {
    #[new]
    #[pyo3(signature = (mass_kg, center_of_mass_m, inertia_kg_m2))]
    fn py_new(mass_kg: f64, center_of_mass_m: V3, inertia_kg_m2: M3) -> Self {
        MassProperties {
            mass_kg,
            center_of_mass_m: center_of_mass_m.0,
            inertia_kg_m2: inertia_kg_m2.0,
        }
    }

    /// Solid box of `mass_kg` with side lengths `size_m`, centred at the origin.
    #[staticmethod]
    fn cuboid(mass_kg: f64, size_m: V3) -> Self {
        Self::wrap(stark::rigidbodies::MassProperties::cuboid(mass_kg, size_m.0))
    }

    /// Solid sphere of `mass_kg` and radius `radius_m`.
    #[staticmethod]
    fn sphere(mass_kg: f64, radius_m: f64) -> Self {
        Self::wrap(stark::rigidbodies::MassProperties::sphere(mass_kg, radius_m))
    }

    /// Solid cylinder of `mass_kg`, `radius_m` and `height_m` along z, centred.
    #[staticmethod]
    fn cylinder(mass_kg: f64, radius_m: f64, height_m: f64) -> Self {
        Self::wrap(stark::rigidbodies::MassProperties::cylinder(
            mass_kg, radius_m, height_m,
        ))
    }

    /// Solid torus in the xy plane: `major_radius_m` (to the centre of the tube) and
    /// `minor_radius_m` (of the tube).
    #[staticmethod]
    fn torus(mass_kg: f64, major_radius_m: f64, minor_radius_m: f64) -> Self {
        Self::wrap(stark::rigidbodies::MassProperties::torus(
            mass_kg,
            major_radius_m,
            minor_radius_m,
        ))
    }

    /// A closed, outward-oriented triangle mesh (vertices (n, 3), triangles (m, 3)) of uniform density (kg/m³).
    #[staticmethod]
    fn from_mesh(vertices_m: Points, triangles: Elements<3>, density_kg_m3: f64) -> PyResult<Self> {
        guarded(|| stark::rigidbodies::MassProperties::from_mesh(&vertices_m.0, &triangles.0, density_kg_m3))
            .map(Self::wrap)
    }

    /// Mass, kg.
    #[getter]
    fn mass_kg(&self) -> f64 {
        self.mass_kg
    }

    /// Centre of mass in the input frame, m (zero for the centred primitives).
    #[getter]
    fn center_of_mass_m<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArray1<f64>> {
        v3_out(py, &self.center_of_mass_m)
    }

    /// Inertia tensor about the centre of mass, kg·m², (3, 3).
    #[getter]
    fn inertia_kg_m2<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArray2<f64>> {
        m3_out(py, &self.inertia_kg_m2)
    }

    fn __repr__(&self) -> String {
        format!(
            "MassProperties(mass_kg={}, center_of_mass_m={:?}, inertia diagonal={:?})",
            self.mass_kg,
            self.center_of_mass_m.as_slice(),
            self.inertia_kg_m2.diagonal().as_slice()
        )
    }
}

/// Register the class.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<MassProperties>()
}

//! Mass, centre of mass and inertia tensor of solids with uniform density.
//!
//! Primitives use the textbook formulas; a closed triangle mesh is integrated exactly as a sum of
//! signed tetrahedra from the origin (the divergence theorem; each tet's second moment is
//! `V/20·(Σᵢxᵢxᵢᵀ + (Σᵢxᵢ)(Σᵢxᵢ)ᵀ)` over its four vertices, one at the origin).

use crate::error::{Result, StarkError};
use nalgebra::{Matrix3, Vector3};

/// Mass properties of a solid in its own frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MassProperties {
    /// Mass, kg.
    pub mass_kg: f64,
    /// Centre of mass in the input frame, m (zero for the centred primitives).
    pub center_of_mass_m: Vector3<f64>,
    /// Inertia tensor about the centre of mass, kg·m².
    pub inertia_kg_m2: Matrix3<f64>,
}

impl MassProperties {
    fn centred(mass_kg: f64, diagonal: Vector3<f64>) -> Self {
        MassProperties {
            mass_kg,
            center_of_mass_m: Vector3::zeros(),
            inertia_kg_m2: Matrix3::from_diagonal(&diagonal),
        }
    }

    /// Solid box with side lengths `size` (m) centred at the origin.
    pub fn cuboid(mass_kg: f64, size: Vector3<f64>) -> Self {
        let s = size.component_mul(&size);
        Self::centred(
            mass_kg,
            Vector3::new(s.y + s.z, s.x + s.z, s.x + s.y) * (mass_kg / 12.0),
        )
    }

    /// Solid sphere of radius `r` (m).
    pub fn sphere(mass_kg: f64, r: f64) -> Self {
        Self::centred(mass_kg, Vector3::repeat(0.4 * mass_kg * r * r))
    }

    /// Solid cylinder of radius `r` and height `h` (m) along z, centred.
    pub fn cylinder(mass_kg: f64, r: f64, h: f64) -> Self {
        let side = mass_kg * (3.0 * r * r + h * h) / 12.0;
        Self::centred(mass_kg, Vector3::new(side, side, 0.5 * mass_kg * r * r))
    }

    /// Solid torus in the xy plane: major radius `major` (centre of the tube), tube radius
    /// `minor` (m).
    pub fn torus(mass_kg: f64, major: f64, minor: f64) -> Self {
        let (rr, aa) = (major * major, minor * minor);
        let axial = mass_kg * (rr + 0.75 * aa);
        let side = mass_kg * (0.5 * rr + 0.625 * aa);
        Self::centred(mass_kg, Vector3::new(side, side, axial))
    }

    /// A closed, outward-oriented triangle mesh of uniform `density_kg_m3`.
    pub fn from_mesh(vertices: &[Vector3<f64>], triangles: &[[usize; 3]], density_kg_m3: f64) -> Result<Self> {
        if !(density_kg_m3 > 0.0 && density_kg_m3.is_finite()) {
            return Err(StarkError::InvalidInput(format!(
                "density {density_kg_m3} kg/m³ must be positive"
            )));
        }
        if let Some((i, t)) = triangles
            .iter()
            .enumerate()
            .find(|(_, t)| t.iter().any(|&v| v >= vertices.len()))
        {
            return Err(StarkError::InvalidInput(format!(
                "triangle {i} {t:?} refers to a vertex beyond the {} given",
                vertices.len()
            )));
        }
        // Integrate about a point near the mesh, for accuracy far from the origin.
        let origin = vertices.iter().sum::<Vector3<f64>>() / vertices.len().max(1) as f64;
        let mut volume = 0.0;
        let mut first = Vector3::zeros();
        let mut second = Matrix3::zeros();
        for t in triangles {
            let [a, b, c] = t.map(|i| vertices[i] - origin);
            let v = a.dot(&b.cross(&c)) / 6.0;
            let s = a + b + c;
            volume += v;
            first += v * s / 4.0;
            second += (a * a.transpose() + b * b.transpose() + c * c.transpose() + s * s.transpose()) * (v / 20.0);
        }
        if !(volume > 0.0) {
            return Err(StarkError::InvalidInput(format!(
                "the mesh encloses a volume of {volume:.3e} m³: it must be closed and oriented outward"
            )));
        }
        let mass = density_kg_m3 * volume;
        let com = first / volume;
        // Second moment about the centre of mass, then I = tr(C)·1 − C.
        let c = (second - volume * com * com.transpose()) * density_kg_m3;
        let inertia = Matrix3::identity() * c.trace() - c;
        Ok(MassProperties {
            mass_kg: mass,
            center_of_mass_m: com + origin,
            inertia_kg_m2: inertia,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::presets::meshes;

    #[test]
    fn box_mesh_matches_the_formula() {
        let size = Vector3::new(0.3, 0.5, 0.7);
        let m = meshes::box_mesh(size);
        let (v, t) = (m.vertices, m.elements);
        let offset = Vector3::new(1.0, -2.0, 3.0);
        let v: Vec<_> = v.iter().map(|p| p + offset).collect();
        let mesh = MassProperties::from_mesh(&v, &t, 1000.0).unwrap();
        let exact = MassProperties::cuboid(1000.0 * size.x * size.y * size.z, size);
        assert!((mesh.mass_kg - exact.mass_kg).abs() < 1e-12 * exact.mass_kg);
        assert!((mesh.center_of_mass_m - offset).norm() < 1e-12);
        assert!((mesh.inertia_kg_m2 - exact.inertia_kg_m2).norm() < 1e-12 * exact.inertia_kg_m2.norm());
    }

    #[test]
    fn sphere_mesh_converges_to_the_formula() {
        let m = meshes::sphere_mesh(0.5, 4);
        let (v, t) = (m.vertices, m.elements);
        let mesh = MassProperties::from_mesh(&v, &t, 1.0).unwrap();
        let exact = MassProperties::sphere(mesh.mass_kg, 0.5);
        let rel = (mesh.inertia_kg_m2 - exact.inertia_kg_m2).norm() / exact.inertia_kg_m2.norm();
        assert!(rel < 0.02, "relative error {rel}");
        assert!((mesh.mass_kg - 4.0 / 3.0 * std::f64::consts::PI * 0.125).abs() < 0.02);
    }

    #[test]
    fn open_or_inverted_meshes_are_rejected() {
        let m = meshes::box_mesh(Vector3::repeat(1.0));
        let (v, mut t) = (m.vertices, m.elements);
        for tri in t.iter_mut() {
            tri.swap(1, 2);
        }
        assert!(MassProperties::from_mesh(&v, &t, 1.0).is_err());
        assert!(MassProperties::from_mesh(&v, &t[..0], 1.0).is_err());
    }
}

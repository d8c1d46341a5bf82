//! [`Shape`]: the one typed description of a solid's geometry, shared by the rigid-body presets,
//! the scene loader and the URDF importer.
//!
//! A shape validates itself ([`Shape::validate`], errors naming the field), gives its closed
//! surface mesh at the resolution it carries ([`Shape::surface_mesh`]) and its mass properties
//! from a mass or a density ([`Shape::solid`]): textbook formulas for the primitives, the exact
//! integral of the closed mesh otherwise ([`MassProperties::from_mesh`]). Every shape is given in
//! its own frame: primitives are centred at the origin (cylinder and capsule along z, torus in
//! the xy plane); a mesh keeps its file's coordinates (multiplied by `scale`).

use super::MassProperties;
// Upward on purpose: `Shape::MeshFile` loads its file when meshed; the loader (with the VTK
// reader) is file I/O and stays in io.
use crate::io::mesh_files::load_triangle_mesh;
use crate::meshes::{self, Mesh};
use nalgebra::{Matrix3, Vector3};
use std::collections::HashMap;
use std::f64::consts::PI;
use std::path::PathBuf;

/// Most subdivisions of a sphere (7: 163 842 vertices).
pub const MAX_SPHERE_SUBDIVISIONS: usize = 7;

/// A solid's geometry, in its own frame.
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// Box of full side lengths `size_m`, centred.
    Box {
        /// Side lengths along x, y, z, m.
        size_m: Vector3<f64>,
    },
    /// Sphere, meshed as an icosphere with `subdivisions` (2: 162 vertices; at most
    /// [`MAX_SPHERE_SUBDIVISIONS`]).
    Sphere {
        /// Radius, m.
        radius_m: f64,
        /// Icosphere subdivisions.
        subdivisions: usize,
    },
    /// Cylinder along z, centred, with `slices` around (≥ 3) and `stacks` along (≥ 1).
    Cylinder {
        /// Radius, m.
        radius_m: f64,
        /// Height, m.
        height_m: f64,
        /// Segments around the axis.
        slices: usize,
        /// Segments along the axis.
        stacks: usize,
    },
    /// Capsule along z, centred: a cylinder of `height_m` between the centres of two
    /// hemispherical caps of `radius_m` (total length `height_m + 2·radius_m`, as URDF's
    /// `<capsule length>`). `slices` around (≥ 3), `cap_rings` from pole to equator (≥ 1).
    Capsule {
        /// Radius, m.
        radius_m: f64,
        /// Length of the cylindrical part, m.
        height_m: f64,
        /// Segments around the axis.
        slices: usize,
        /// Rings per cap.
        cap_rings: usize,
    },
    /// Torus in the xy plane around z: `major_radius_m` to the centre of the tube, tube radius
    /// `minor_radius_m` (smaller); `major_segments` and `minor_segments` (≥ 3 each).
    Torus {
        /// Axis to tube centre, m.
        major_radius_m: f64,
        /// Tube radius, m.
        minor_radius_m: f64,
        /// Segments around the axis.
        major_segments: usize,
        /// Segments around the tube.
        minor_segments: usize,
    },
    /// A triangle mesh file (OBJ, STL, COLLADA `.dae`, VTK, Gmsh), coincident vertices welded,
    /// coordinates multiplied by `scale` per axis (a mirroring scale flips the triangles back
    /// outward).
    MeshFile {
        /// The file.
        path: PathBuf,
        /// Per-axis scale factors (non-zero).
        scale: Vector3<f64>,
    },
    /// An inline triangle mesh, coordinates multiplied by `scale` per axis.
    Mesh {
        /// Vertices, m (before scaling).
        vertices_m: Vec<Vector3<f64>>,
        /// Triangles (indices into the vertices).
        triangles: Vec<[usize; 3]>,
        /// Per-axis scale factors (non-zero).
        scale: Vector3<f64>,
    },
}

/// How heavy a solid is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Mass {
    /// Its mass, kg.
    Kg(f64),
    /// Its uniform density, kg/m³.
    DensityKgM3(f64),
}

/// A shape's surface and mass properties (the centre of mass in the shape's frame).
#[derive(Clone, Debug, PartialEq)]
pub struct Solid {
    /// The closed surface, in the shape's frame.
    pub mesh: Mesh<3>,
    /// Mass, centre of mass (shape frame) and inertia about it.
    pub mass: MassProperties,
}

/// A bad shape: the field at fault (`radius_m`, `size_m.y`, `path`, `triangles`, ...) and what is
/// wrong with it (the message names the field).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{message}")]
pub struct ShapeError {
    /// The field, relative to the shape (`size_m.x`, `radius_m`, `path`, `triangles`,
    /// `mass_kg`, ...; `surface` when a mesh is not a closed, outward-oriented surface).
    pub field: &'static str,
    /// The element of a list field at fault (the triangle), if one is.
    pub index: Option<usize>,
    /// What is wrong.
    pub message: String,
}

fn err(field: &'static str, message: impl Into<String>) -> ShapeError {
    ShapeError {
        field,
        index: None,
        message: message.into(),
    }
}

fn positive(field: &'static str, v: f64, unit: &str) -> Result<(), ShapeError> {
    if v > 0.0 && v.is_finite() {
        Ok(())
    } else {
        Err(err(
            field,
            format!("{field} = {v} must be positive and finite ({unit})"),
        ))
    }
}

fn at_least(field: &'static str, n: usize, min: usize) -> Result<(), ShapeError> {
    if n >= min {
        Ok(())
    } else {
        Err(err(field, format!("{field} = {n} must be at least {min}")))
    }
}

fn check_scale(scale: &Vector3<f64>) -> Result<(), ShapeError> {
    if scale.iter().all(|s| s.is_finite() && *s != 0.0) {
        Ok(())
    } else {
        Err(err(
            "scale",
            format!("scale = {:?} must be finite and non-zero", scale.as_slice()),
        ))
    }
}

impl Shape {
    /// A box of side lengths `size_m`.
    pub fn cuboid(size_m: Vector3<f64>) -> Shape {
        Shape::Box { size_m }
    }

    /// A mesh file at unit scale.
    pub fn mesh_file(path: impl Into<PathBuf>) -> Shape {
        Shape::MeshFile {
            path: path.into(),
            scale: Vector3::repeat(1.0),
        }
    }

    /// The shape's name as in scene files (`box`, `sphere`, ..., `mesh`).
    pub fn kind(&self) -> &'static str {
        match self {
            Shape::Box { .. } => "box",
            Shape::Sphere { .. } => "sphere",
            Shape::Cylinder { .. } => "cylinder",
            Shape::Capsule { .. } => "capsule",
            Shape::Torus { .. } => "torus",
            Shape::MeshFile { .. } => "mesh",
            Shape::Mesh { .. } => "vertices_m",
        }
    }

    /// Check every field (sizes positive and finite, resolutions large enough, scales non-zero,
    /// inline triangles in range and vertices finite). Mesh files are checked when loaded.
    pub fn validate(&self) -> Result<(), ShapeError> {
        match self {
            Shape::Box { size_m } => {
                for (field, s) in [("size_m.x", size_m.x), ("size_m.y", size_m.y), ("size_m.z", size_m.z)] {
                    positive(field, s, "m")?;
                }
            }
            Shape::Sphere { radius_m, subdivisions } => {
                positive("radius_m", *radius_m, "m")?;
                if *subdivisions > MAX_SPHERE_SUBDIVISIONS {
                    return Err(err(
                        "subdivisions",
                        format!(
                            "subdivisions = {subdivisions} is too many (at most {MAX_SPHERE_SUBDIVISIONS}; each one \
                             quadruples the triangles)"
                        ),
                    ));
                }
            }
            Shape::Cylinder {
                radius_m,
                height_m,
                slices,
                stacks,
            } => {
                positive("radius_m", *radius_m, "m")?;
                positive("height_m", *height_m, "m")?;
                at_least("slices", *slices, 3)?;
                at_least("stacks", *stacks, 1)?;
            }
            Shape::Capsule {
                radius_m,
                height_m,
                slices,
                cap_rings,
            } => {
                positive("radius_m", *radius_m, "m")?;
                positive("height_m", *height_m, "m")?;
                at_least("slices", *slices, 3)?;
                at_least("cap_rings", *cap_rings, 1)?;
            }
            Shape::Torus {
                major_radius_m,
                minor_radius_m,
                major_segments,
                minor_segments,
            } => {
                positive("major_radius_m", *major_radius_m, "m")?;
                positive("minor_radius_m", *minor_radius_m, "m")?;
                if minor_radius_m >= major_radius_m {
                    return Err(err(
                        "minor_radius_m",
                        format!(
                            "minor_radius_m = {minor_radius_m} must be smaller than major_radius_m = {major_radius_m} \
                             (the tube would cross the axis)"
                        ),
                    ));
                }
                at_least("major_segments", *major_segments, 3)?;
                at_least("minor_segments", *minor_segments, 3)?;
            }
            Shape::MeshFile { scale, .. } => check_scale(scale)?,
            Shape::Mesh {
                vertices_m,
                triangles,
                scale,
            } => {
                check_scale(scale)?;
                if triangles.is_empty() {
                    return Err(err("triangles", "the triangle list is empty"));
                }
                let n = vertices_m.len();
                for (i, t) in triangles.iter().enumerate() {
                    if let Some(v) = t.iter().find(|&&v| v >= n) {
                        return Err(ShapeError {
                            index: Some(i),
                            ..err(
                                "triangles",
                                format!("triangle {i} refers to vertex {v}, but there are {n} vertices"),
                            )
                        });
                    }
                }
                if let Some(i) = vertices_m.iter().position(|v| !v.iter().all(|c| c.is_finite())) {
                    return Err(err(
                        "vertices_m",
                        format!("vertex {i} = {:?} is not finite", vertices_m[i].as_slice()),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Volume of a primitive, m³ (`None` for meshes, whose volume comes from [`Shape::solid`]).
    pub fn primitive_volume_m3(&self) -> Option<f64> {
        Some(match *self {
            Shape::Box { size_m } => size_m.x * size_m.y * size_m.z,
            Shape::Sphere { radius_m: r, .. } => 4.0 / 3.0 * PI * r * r * r,
            Shape::Cylinder {
                radius_m: r,
                height_m: h,
                ..
            } => PI * r * r * h,
            Shape::Capsule {
                radius_m: r,
                height_m: h,
                ..
            } => PI * r * r * h + 4.0 / 3.0 * PI * r * r * r,
            Shape::Torus {
                major_radius_m: big,
                minor_radius_m: small,
                ..
            } => 2.0 * PI * PI * big * small * small,
            Shape::MeshFile { .. } | Shape::Mesh { .. } => return None,
        })
    }

    /// The surface mesh at the shape's resolution, in its frame (validated first). Mesh files
    /// are loaded with coincident vertices welded; scaled meshes whose scale mirrors them get
    /// their triangles flipped so that they stay outward oriented.
    pub fn surface_mesh(&self) -> Result<Mesh<3>, ShapeError> {
        self.validate()?;
        Ok(match self {
            Shape::Box { size_m } => meshes::box_mesh(*size_m),
            Shape::Sphere { radius_m, subdivisions } => meshes::sphere_mesh(*radius_m, *subdivisions),
            Shape::Cylinder {
                radius_m,
                height_m,
                slices,
                stacks,
            } => meshes::cylinder_mesh(*radius_m, *height_m, *slices, *stacks),
            Shape::Capsule {
                radius_m,
                height_m,
                slices,
                cap_rings,
            } => meshes::capsule_mesh(*radius_m, *height_m, *slices, *cap_rings),
            Shape::Torus {
                major_radius_m,
                minor_radius_m,
                major_segments,
                minor_segments,
            } => meshes::torus_mesh(*major_radius_m, *minor_radius_m, *major_segments, *minor_segments),
            Shape::MeshFile { path, scale } => {
                let m = load_triangle_mesh(path).map_err(|e| err("path", e.to_string()))?;
                scaled(m, scale)
            }
            Shape::Mesh {
                vertices_m,
                triangles,
                scale,
            } => scaled(
                Mesh {
                    vertices: vertices_m.clone(),
                    elements: triangles.clone(),
                },
                scale,
            ),
        })
    }

    /// The surface mesh and the mass properties of the solid of mass (or density) `mass`.
    /// Primitives use the textbook formulas (centre of mass at the origin); meshes must be
    /// closed and outward oriented, and are integrated exactly (centre of mass in the mesh
    /// frame).
    pub fn solid(&self, mass: Mass) -> Result<Solid, ShapeError> {
        match mass {
            Mass::Kg(m) => positive("mass_kg", m, "kg")?,
            Mass::DensityKgM3(rho) => positive("density_kg_m3", rho, "kg/m³")?,
        }
        let mesh = self.surface_mesh()?;
        let primitive_mass = |volume: f64| match mass {
            Mass::Kg(m) => m,
            Mass::DensityKgM3(rho) => rho * volume,
        };
        let volume = self.primitive_volume_m3();
        let props = match *self {
            Shape::Box { size_m } => MassProperties::cuboid(primitive_mass(volume.unwrap_or(0.0)), size_m),
            Shape::Sphere { radius_m, .. } => MassProperties::sphere(primitive_mass(volume.unwrap_or(0.0)), radius_m),
            Shape::Cylinder { radius_m, height_m, .. } => {
                MassProperties::cylinder(primitive_mass(volume.unwrap_or(0.0)), radius_m, height_m)
            }
            Shape::Capsule { radius_m, height_m, .. } => {
                MassProperties::capsule(primitive_mass(volume.unwrap_or(0.0)), radius_m, height_m)
            }
            Shape::Torus {
                major_radius_m,
                minor_radius_m,
                ..
            } => MassProperties::torus(primitive_mass(volume.unwrap_or(0.0)), major_radius_m, minor_radius_m),
            Shape::MeshFile { .. } | Shape::Mesh { .. } => {
                let field = "surface";
                check_closed_surface(mesh.vertices.len(), &mesh.elements).map_err(|m| err(field, m))?;
                let mut p = MassProperties::from_mesh(&mesh.vertices, &mesh.elements, 1.0)
                    .map_err(|e| err(field, e.to_string().trim_start_matches("invalid input: ").to_string()))?;
                let factor = match mass {
                    Mass::Kg(m) => m / p.mass_kg,
                    Mass::DensityKgM3(rho) => rho,
                };
                p.mass_kg *= factor;
                p.inertia_kg_m2 *= factor;
                p
            }
        };
        Ok(Solid { mesh, mass: props })
    }
}

/// `m` with every vertex multiplied by `scale` per axis; a mirroring scale (odd number of
/// negative factors) reverses the triangles so that the surface stays outward oriented.
fn scaled(mut m: Mesh<3>, scale: &Vector3<f64>) -> Mesh<3> {
    if *scale != Vector3::repeat(1.0) {
        m.vertices.iter_mut().for_each(|v| *v = v.component_mul(scale));
        if scale.x * scale.y * scale.z < 0.0 {
            m.elements.iter_mut().for_each(|t| t.swap(1, 2));
        }
    }
    m
}

/// Check that `triangles` form a closed, consistently oriented 2-manifold: every directed edge
/// is used by exactly one triangle and its reverse by exactly one other. The message says
/// which triangles break it.
pub fn check_closed_surface(n_vertices: usize, triangles: &[[usize; 3]]) -> Result<(), String> {
    if triangles.is_empty() {
        return Err("the mesh has no triangles".into());
    }
    let mut directed: HashMap<(usize, usize), usize> = HashMap::with_capacity(3 * triangles.len());
    for (i, t) in triangles.iter().enumerate() {
        if let Some(&v) = t.iter().find(|&&v| v >= n_vertices) {
            return Err(format!(
                "triangle {i} refers to node {v}, but the mesh has {n_vertices} nodes"
            ));
        }
        if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
            return Err(format!("triangle {i} repeats a vertex: {t:?}"));
        }
        for k in 0..3 {
            let e = (t[k], t[(k + 1) % 3]);
            if let Some(j) = directed.insert(e, i) {
                return Err(format!(
                    "the mesh is not a consistently oriented closed surface: triangles {j} and {i} both use the \
                     edge {} → {} in the same direction",
                    e.0, e.1
                ));
            }
        }
    }
    if let Some((&(a, b), &i)) = directed.iter().find(|(&(a, b), _)| !directed.contains_key(&(b, a))) {
        return Err(format!(
            "the mesh is not closed: the edge {a}–{b} of triangle {i} has no neighbouring triangle (mass \
             properties need a closed, outward-oriented surface)"
        ));
    }
    Ok(())
}

impl MassProperties {
    /// Solid capsule along z: a cylinder of radius `r` and height `h` between two hemispheres
    /// (m). Each hemisphere (mass `m_s/2`) has `2/5·(m_s/2)·r²` about any axis through the
    /// centre of its flat face and its centre of mass `3r/8` beyond it, so about the capsule's
    /// centre the caps add `m_s(2r²/5 + h²/4 + 3hr/8)` transversally.
    pub fn capsule(mass_kg: f64, r: f64, h: f64) -> MassProperties {
        let (vc, vs) = (PI * r * r * h, 4.0 / 3.0 * PI * r * r * r);
        let (mc, ms) = (mass_kg * vc / (vc + vs), mass_kg * vs / (vc + vs));
        let axial = 0.5 * mc * r * r + 0.4 * ms * r * r;
        let side = mc * (h * h / 12.0 + r * r / 4.0) + ms * (0.4 * r * r + h * h / 4.0 + 3.0 * h * r / 8.0);
        MassProperties {
            mass_kg,
            center_of_mass_m: Vector3::zeros(),
            inertia_kg_m2: Matrix3::from_diagonal(&Vector3::new(side, side, axial)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: &Matrix3<f64>, b: &Matrix3<f64>, rel: f64) -> bool {
        (a - b).norm() <= rel * b.norm()
    }

    #[test]
    fn capsule_mesh_is_closed_and_converges_to_the_formula() {
        let shape = Shape::Capsule {
            radius_m: 0.1,
            height_m: 0.3,
            slices: 64,
            cap_rings: 16,
        };
        let mesh = shape.surface_mesh().unwrap();
        check_closed_surface(mesh.vertices.len(), &mesh.elements).unwrap();
        let integrated = MassProperties::from_mesh(&mesh.vertices, &mesh.elements, 1000.0).unwrap();
        let v = shape.primitive_volume_m3().unwrap();
        assert!((integrated.mass_kg - 1000.0 * v).abs() < 0.01 * 1000.0 * v);
        let exact = MassProperties::capsule(integrated.mass_kg, 0.1, 0.3);
        assert!(close(&integrated.inertia_kg_m2, &exact.inertia_kg_m2, 0.01));
        assert!(integrated.center_of_mass_m.norm() < 1e-12);
        // The limit h → 0 of the formula is the sphere's.
        let s = MassProperties::capsule(2.0, 0.3, 1e-12).inertia_kg_m2;
        assert!(close(&s, &MassProperties::sphere(2.0, 0.3).inertia_kg_m2, 1e-9));
    }

    #[test]
    fn primitives_give_their_formulas_from_mass_or_density() {
        let b = Shape::cuboid(Vector3::new(0.1, 0.2, 0.3));
        let s = b.solid(Mass::DensityKgM3(1000.0)).unwrap();
        assert!((s.mass.mass_kg - 6.0).abs() < 1e-12);
        assert_eq!(
            s.mass,
            MassProperties::cuboid(s.mass.mass_kg, Vector3::new(0.1, 0.2, 0.3))
        );
        let c = Shape::Cylinder {
            radius_m: 0.1,
            height_m: 0.2,
            slices: 16,
            stacks: 1,
        };
        assert_eq!(
            c.solid(Mass::Kg(2.0)).unwrap().mass,
            MassProperties::cylinder(2.0, 0.1, 0.2)
        );
        assert_eq!(c.solid(Mass::Kg(2.0)).unwrap().mesh.vertices.len(), 34);
    }

    #[test]
    fn a_mirrored_inline_mesh_stays_outward_and_keeps_its_mass_properties() {
        let m = meshes::box_mesh(Vector3::new(1.0, 2.0, 3.0));
        let shape = Shape::Mesh {
            vertices_m: m.vertices.iter().map(|v| v + Vector3::new(1.0, 0.0, 0.0)).collect(),
            triangles: m.elements,
            scale: Vector3::new(-0.5, 1.0, 1.0),
        };
        let s = shape.solid(Mass::Kg(3.0)).unwrap();
        assert!((s.mass.center_of_mass_m - Vector3::new(-0.5, 0.0, 0.0)).norm() < 1e-12);
        let exact = MassProperties::cuboid(3.0, Vector3::new(0.5, 2.0, 3.0));
        assert!(close(&s.mass.inertia_kg_m2, &exact.inertia_kg_m2, 1e-12));
    }

    #[test]
    fn bad_shapes_name_their_field() {
        let f = |s: Shape| s.validate().unwrap_err().field;
        assert_eq!(f(Shape::cuboid(Vector3::new(1.0, -1.0, 1.0))), "size_m.y");
        assert_eq!(
            f(Shape::Sphere {
                radius_m: 1.0,
                subdivisions: 9
            }),
            "subdivisions"
        );
        assert_eq!(
            f(Shape::Capsule {
                radius_m: f64::NAN,
                height_m: 1.0,
                slices: 8,
                cap_rings: 2
            }),
            "radius_m"
        );
        assert_eq!(
            f(Shape::MeshFile {
                path: "x.stl".into(),
                scale: Vector3::new(1.0, 0.0, 1.0)
            }),
            "scale"
        );
        let e = Shape::mesh_file("/no/such/mesh.stl").surface_mesh().unwrap_err();
        assert!(e.field == "path" && e.message.contains("/no/such/mesh.stl"), "{e}");
        let m = meshes::box_mesh(Vector3::repeat(1.0));
        let open = Shape::Mesh {
            vertices_m: m.vertices,
            triangles: m.elements[1..].to_vec(),
            scale: Vector3::repeat(1.0),
        };
        let e = open.solid(Mass::Kg(1.0)).unwrap_err();
        assert!(e.field == "surface" && e.message.contains("not closed"), "{e}");
        let e = Shape::cuboid(Vector3::repeat(1.0)).solid(Mass::Kg(0.0)).unwrap_err();
        assert_eq!(e.field, "mass_kg");
    }
}

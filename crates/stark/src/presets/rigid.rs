//! Ready-made rigid bodies: a body with its mass properties and a collision mesh in one call
//! (the original's `RigidBodyPresets`).
//!
//! Primitives take their mass and use the textbook inertia of the solid shape
//! ([`MassProperties`]); the collision mesh is the shape's triangulation (`presets::meshes`),
//! whose vertices lie on the solid's surface, so the contact surface sits one contact thickness
//! outside the mesh, as in the original. [`Simulation::add_rigid_mesh`] instead integrates the
//! mass properties of a closed triangle mesh of given density.

use crate::error::{check_param, Result, StarkError};
use crate::rigidbodies::{Mass, MassProperties, RigidBodyHandle, RigidMeshHandle, Shape, ShapeError};
use crate::simulation::Simulation;
use nalgebra::{UnitQuaternion, Vector3};

/// Handles of a rigid body made by a preset.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RigidHandle {
    /// The body.
    pub body: RigidBodyHandle,
    /// Its collision mesh.
    pub mesh: RigidMeshHandle,
}

pub use crate::rigidbodies::shape::MAX_SPHERE_SUBDIVISIONS;

fn check_orientation(label: &str, q: &UnitQuaternion<f64>) -> Result<()> {
    if q.coords.iter().all(|c| c.is_finite()) {
        Ok(())
    } else {
        Err(StarkError::InvalidInput(format!(
            "orientation of rigid body '{label}' is not finite: {q:?}"
        )))
    }
}

/// A [`ShapeError`] as an error of rigid body `label`.
fn shape_error(label: &str, e: ShapeError) -> StarkError {
    StarkError::InvalidInput(format!("rigid body '{label}': {}", e.message))
}

impl Simulation {
    /// A rigid body with mass properties `props` (centre of mass at the origin of the body
    /// frame), its centre of mass at `position_m`, rotated by `orientation`, and the collision
    /// mesh `local_vertices`/`triangles` (body frame) with contact thickness `thickness_m` (or
    /// the default).
    fn add_rigid_preset(
        &mut self,
        label: &str,
        props: &MassProperties,
        local_vertices: &[Vector3<f64>],
        triangles: &[[usize; 3]],
        position_m: Vector3<f64>,
        orientation: UnitQuaternion<f64>,
        thickness_m: Option<f64>,
    ) -> Result<RigidHandle> {
        check_orientation(label, &orientation)?;
        if let Some(t) = thickness_m {
            check_param(
                label,
                "contact thickness_m",
                t,
                t > 0.0 && t.is_finite(),
                "must be positive and finite",
            )?;
        } else if self.settings.contact.default_thickness_m.is_none() {
            return Err(StarkError::InvalidInput(format!(
                "rigid body '{label}' needs a contact thickness (or settings.contact.default_thickness_m)"
            )));
        }
        let body = self.add_rigid_body_with(label, props, position_m, orientation)?;
        let mesh = self.add_rigid_collision_mesh(body, local_vertices, triangles, thickness_m)?;
        Ok(RigidHandle { body, mesh })
    }

    /// A rigid body of the solid `shape` (in the body frame) with mass (or density) `mass`: its
    /// mass properties and collision mesh come from the shape ([`Shape::solid`]). The body frame
    /// is the shape's frame moved to its centre of mass, which goes to `position_m`; the body is
    /// rotated by `orientation`. Contact thickness `thickness_m`, or the default.
    pub fn add_shape_body(
        &mut self,
        label: &str,
        shape: &Shape,
        mass: Mass,
        position_m: Vector3<f64>,
        orientation: UnitQuaternion<f64>,
        thickness_m: Option<f64>,
    ) -> Result<RigidHandle> {
        let solid = shape.solid(mass).map_err(|e| shape_error(label, e))?;
        let com = solid.mass.center_of_mass_m;
        let local: Vec<Vector3<f64>> = solid.mesh.vertices.iter().map(|p| p - com).collect();
        let centred = MassProperties {
            center_of_mass_m: Vector3::zeros(),
            ..solid.mass
        };
        self.add_rigid_preset(
            label,
            &centred,
            &local,
            &solid.mesh.elements,
            position_m,
            orientation,
            thickness_m,
        )
    }

    /// A solid box of `mass_kg` and full side lengths `size_m` (along the body's x, y, z), centre
    /// at `position_m`, rotated by `orientation`. Collision mesh: the 8-vertex, 12-triangle box
    /// (the original's par_shapes cube). Contact thickness `thickness_m`, or the default.
    pub fn add_box(
        &mut self,
        label: &str,
        mass_kg: f64,
        size_m: Vector3<f64>,
        position_m: Vector3<f64>,
        orientation: UnitQuaternion<f64>,
        thickness_m: Option<f64>,
    ) -> Result<RigidHandle> {
        let shape = Shape::Box { size_m };
        self.add_shape_body(label, &shape, Mass::Kg(mass_kg), position_m, orientation, thickness_m)
    }

    /// A solid sphere of `mass_kg` and `radius_m`; collision mesh: an icosphere with
    /// `subdivisions` (the original's default is 2: 162 vertices, 320 triangles; at most
    /// [`MAX_SPHERE_SUBDIVISIONS`]).
    pub fn add_sphere(
        &mut self,
        label: &str,
        mass_kg: f64,
        radius_m: f64,
        subdivisions: usize,
        position_m: Vector3<f64>,
        orientation: UnitQuaternion<f64>,
        thickness_m: Option<f64>,
    ) -> Result<RigidHandle> {
        let shape = Shape::Sphere { radius_m, subdivisions };
        self.add_shape_body(label, &shape, Mass::Kg(mass_kg), position_m, orientation, thickness_m)
    }

    /// A solid cylinder of `mass_kg`, `radius_m` and `height_m` along the body's z axis, centred;
    /// collision mesh with `slices` around (≥ 3) and `stacks` along (≥ 1) the axis and flat caps
    /// (the original's defaults: 16 and 1).
    pub fn add_cylinder(
        &mut self,
        label: &str,
        mass_kg: f64,
        radius_m: f64,
        height_m: f64,
        slices: usize,
        stacks: usize,
        position_m: Vector3<f64>,
        orientation: UnitQuaternion<f64>,
        thickness_m: Option<f64>,
    ) -> Result<RigidHandle> {
        let shape = Shape::Cylinder {
            radius_m,
            height_m,
            slices,
            stacks,
        };
        self.add_shape_body(label, &shape, Mass::Kg(mass_kg), position_m, orientation, thickness_m)
    }

    /// A solid torus of `mass_kg` in the body's xy plane: `major_radius_m` from the axis to the
    /// centre of the tube, tube radius `minor_radius_m` (smaller than the major radius);
    /// collision mesh with `major_segments` around the axis and `minor_segments` around the tube
    /// (≥ 3 each; the original's defaults: 32 and 16).
    pub fn add_torus(
        &mut self,
        label: &str,
        mass_kg: f64,
        major_radius_m: f64,
        minor_radius_m: f64,
        major_segments: usize,
        minor_segments: usize,
        position_m: Vector3<f64>,
        orientation: UnitQuaternion<f64>,
        thickness_m: Option<f64>,
    ) -> Result<RigidHandle> {
        let shape = Shape::Torus {
            major_radius_m,
            minor_radius_m,
            major_segments,
            minor_segments,
        };
        self.add_shape_body(label, &shape, Mass::Kg(mass_kg), position_m, orientation, thickness_m)
    }

    /// A rigid body from a closed, outward-oriented triangle mesh given in world coordinates, of
    /// uniform `density_kg_m3`: its mass, centre of mass and inertia tensor are integrated from
    /// the mesh ([`MassProperties::from_mesh`]), the mesh becomes its collision mesh, re-centred
    /// on the centre of mass, and the body is placed where the mesh is (body axes along the world
    /// axes, so its inertia tensor need not be diagonal). Contact thickness `thickness_m`, or the
    /// default. The mesh must not intersect itself (self-collision within a body is off, so this
    /// is not checked).
    pub fn add_rigid_mesh(
        &mut self,
        label: &str,
        vertices_m: &[Vector3<f64>],
        triangles: &[[usize; 3]],
        density_kg_m3: f64,
        thickness_m: Option<f64>,
    ) -> Result<RigidHandle> {
        let shape = Shape::Mesh {
            vertices_m: vertices_m.to_vec(),
            triangles: triangles.to_vec(),
            scale: Vector3::repeat(1.0),
        };
        let com = shape
            .solid(Mass::DensityKgM3(density_kg_m3))
            .map_err(|e| shape_error(label, e))?
            .mass
            .center_of_mass_m;
        // Body axes along the world axes: the mesh keeps its place, the centre of mass is the
        // body's position.
        self.add_shape_body(
            label,
            &shape,
            Mass::DensityKgM3(density_kg_m3),
            com,
            UnitQuaternion::identity(),
            thickness_m,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::presets::meshes;
    use crate::Settings;

    fn sim() -> Simulation {
        let mut s = Settings::default();
        s.output.frames = false;
        s.output.step_log = false;
        s.contact.default_thickness_m = Some(1e-3);
        Simulation::new(s).unwrap()
    }

    #[test]
    fn primitives_have_their_mass_properties_and_meshes() {
        let mut sim = sim();
        let q = UnitQuaternion::from_euler_angles(0.1, 0.2, 0.3);
        let p = Vector3::new(1.0, 2.0, 3.0);
        let b = sim
            .add_box("box", 2.0, Vector3::new(0.1, 0.2, 0.3), p, q, None)
            .unwrap();
        assert_eq!(b.mesh.nodes.len, 8);
        assert_eq!(sim.bodies.mass[b.body.i()], 2.0);
        let expected = MassProperties::cuboid(2.0, Vector3::new(0.1, 0.2, 0.3)).inertia_kg_m2;
        assert_eq!(sim.bodies.inertia_local[b.body.i()], expected);
        // The mesh follows the pose: a corner at p + q·(±size/2).
        let corner = sim.positions(b.mesh.nodes)[6];
        assert!((corner - (p + q * Vector3::new(0.05, 0.1, 0.15))).norm() < 1e-15);

        let s = sim
            .add_sphere(
                "ball",
                1.0,
                0.2,
                2,
                Vector3::zeros(),
                UnitQuaternion::identity(),
                Some(2e-3),
            )
            .unwrap();
        assert_eq!(s.mesh.nodes.len, 162);
        let c = sim
            .add_cylinder(
                "can",
                1.0,
                0.1,
                0.3,
                16,
                1,
                Vector3::x(),
                UnitQuaternion::identity(),
                None,
            )
            .unwrap();
        assert_eq!(c.mesh.nodes.len, 34);
        let t = sim
            .add_torus(
                "ring",
                1.0,
                0.3,
                0.05,
                32,
                16,
                Vector3::y(),
                UnitQuaternion::identity(),
                None,
            )
            .unwrap();
        assert_eq!(t.mesh.nodes.len, 512);
        assert_eq!(sim.num_rigid_bodies(), 4);
    }

    #[test]
    fn a_closed_mesh_becomes_a_body_where_the_mesh_was() {
        let mut sim = sim();
        // An off-centre box, rotated: mass and inertia must match the formula in the rotated
        // frame, the centre of mass lands on the box centre and the vertices stay in place.
        let size = Vector3::new(0.2, 0.4, 0.6);
        let rot = UnitQuaternion::from_euler_angles(0.4, -0.3, 0.9);
        let centre = Vector3::new(0.5, -1.0, 2.0);
        let m = meshes::box_mesh(size);
        let world: Vec<Vector3<f64>> = m.vertices.iter().map(|p| centre + rot * p).collect();
        let h = sim.add_rigid_mesh("part", &world, &m.elements, 500.0, None).unwrap();
        let b = h.body.i();
        let mass = 500.0 * size.x * size.y * size.z;
        assert!((sim.bodies.mass[b] - mass).abs() < 1e-12 * mass);
        assert!((sim.bodies.position[b] - centre).norm() < 1e-12);
        let r = rot.to_rotation_matrix().into_inner();
        let expected = r * MassProperties::cuboid(mass, size).inertia_kg_m2 * r.transpose();
        assert!((sim.bodies.inertia_local[b] - expected).norm() < 1e-12 * expected.norm());
        for (p, q) in sim.positions(h.mesh.nodes).iter().zip(&world) {
            assert!((p - q).norm() < 1e-12);
        }
    }

    #[test]
    fn bad_arguments_give_clear_errors() {
        let mut sim = sim();
        let (p, q) = (Vector3::zeros(), UnitQuaternion::identity());
        let err = |r: Result<RigidHandle>| r.unwrap_err().to_string();
        let e = err(sim.add_box("a", 0.0, Vector3::repeat(1.0), p, q, None));
        assert!(e.contains("mass_kg") && e.contains("positive"), "{e}");
        let e = err(sim.add_box("a", f64::NAN, Vector3::repeat(1.0), p, q, None));
        assert!(e.contains("mass_kg"), "{e}");
        let e = err(sim.add_box("a", 1.0, Vector3::new(1.0, -1.0, 1.0), p, q, None));
        assert!(e.contains("size_m.y"), "{e}");
        let e = err(sim.add_box(
            "a",
            1.0,
            Vector3::repeat(1.0),
            Vector3::new(f64::NAN, 0.0, 0.0),
            q,
            None,
        ));
        assert!(e.contains("position") && e.contains("not finite"), "{e}");
        let e = err(sim.add_box("a", 1.0, Vector3::repeat(1.0), p, q, Some(0.0)));
        assert!(e.contains("thickness"), "{e}");
        let e = err(sim.add_sphere("a", 1.0, 0.1, 9, p, q, None));
        assert!(e.contains("subdivisions"), "{e}");
        let e = err(sim.add_sphere("a", 1.0, -0.1, 2, p, q, None));
        assert!(e.contains("radius_m"), "{e}");
        let e = err(sim.add_cylinder("a", 1.0, 0.1, 0.2, 2, 1, p, q, None));
        assert!(e.contains("slices"), "{e}");
        let e = err(sim.add_torus("a", 1.0, 0.1, 0.2, 16, 8, p, q, None));
        assert!(e.contains("minor_radius_m") && e.contains("major"), "{e}");
        // Open mesh, inverted mesh, bad index.
        let m = meshes::box_mesh(Vector3::repeat(1.0));
        let e = err(sim.add_rigid_mesh("a", &m.vertices, &m.elements[1..], 1.0, None));
        assert!(e.contains("not closed"), "{e}");
        let flipped: Vec<[usize; 3]> = m.elements.iter().map(|t| [t[0], t[2], t[1]]).collect();
        let e = err(sim.add_rigid_mesh("a", &m.vertices, &flipped, 1.0, None));
        assert!(e.contains("outward"), "{e}");
        let mut bad = m.elements.clone();
        bad[0][0] = 8;
        let e = err(sim.add_rigid_mesh("a", &m.vertices, &bad, 1.0, None));
        assert!(e.contains("refers to vertex 8"), "{e}");
        let e = err(sim.add_rigid_mesh("a", &m.vertices, &m.elements, 0.0, None));
        assert!(e.contains("density"), "{e}");
        // Nothing was added by the failed calls, and the label is still free.
        assert_eq!(sim.num_rigid_bodies(), 0);
        sim.add_box("a", 1.0, Vector3::repeat(1.0), p, q, None).unwrap();
        let e = err(sim.add_box("a", 1.0, Vector3::repeat(1.0), p, q, None));
        assert!(e.contains("already used"), "{e}");
        let mut no_default = Simulation::new(Settings::default()).unwrap();
        let e = err(no_default.add_box("b", 1.0, Vector3::repeat(1.0), p, q, None));
        assert!(e.contains("thickness"), "{e}");
        assert_eq!(no_default.num_rigid_bodies(), 0);
    }
}

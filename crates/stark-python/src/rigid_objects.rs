//! Rigid-body presets and deformable–rigid attachments: `Simulation` methods mirroring the
//! library's `presets::rigid` and `rigidbodies::attachments`.

use crate::convert::{pose, Elements, Indices, Points, Rot, V3};
use crate::handles::*;
use crate::params::{self, attachment_params_arg};
use crate::simulation::Simulation;
use pyo3::prelude::*;

/// A rigid body made by a preset: the body and its collision mesh.
#[pyclass(module = "starkrs", frozen, get_all, from_py_object)]
#[derive(Clone, Debug)]
pub struct RigidObject {
    /// The body.
    pub body: RigidBody,
    /// Its collision mesh.
    pub mesh: RigidMesh,
}

#[pymethods]
impl RigidObject {
    fn __repr__(&self) -> String {
        format!("RigidObject('{}')", self.body.label)
    }
}

impl Simulation {
    fn rigid_object(&self, label: &str, h: stark::presets::RigidHandle) -> RigidObject {
        let body = RigidBody::new(self.id(), h.body, label);
        RigidObject {
            mesh: RigidMesh {
                body: body.clone(),
                nodes: NodeSet::new(self.id(), h.mesh.nodes),
                contact: ContactHandle::new(self.id(), h.mesh.contact),
            },
            body,
        }
    }
}

#[pymethods]
impl Simulation {
    // ---- Rigid-body presets ----

    /// A solid box of `mass_kg` and side lengths `size_m` with its collision mesh.
    #[pyo3(signature = (label, mass_kg, size_m, position_m=None, orientation=None, thickness_m=None))]
    #[allow(clippy::too_many_arguments)]
    fn add_box(
        &self,
        label: &str,
        mass_kg: f64,
        size_m: V3,
        position_m: Option<V3>,
        orientation: Option<Rot>,
        thickness_m: Option<f64>,
    ) -> PyResult<RigidObject> {
        let (p, q) = pose(position_m, orientation);
        let h = self.with(|s| s.add_box(label, mass_kg, size_m.0, p, q, thickness_m))?;
        Ok(self.rigid_object(label, h))
    }

    /// A solid sphere (icosphere mesh with `subdivisions`).
    #[pyo3(signature = (label, mass_kg, radius_m, subdivisions=2, position_m=None, orientation=None, thickness_m=None))]
    #[allow(clippy::too_many_arguments)]
    fn add_sphere(
        &self,
        label: &str,
        mass_kg: f64,
        radius_m: f64,
        subdivisions: usize,
        position_m: Option<V3>,
        orientation: Option<Rot>,
        thickness_m: Option<f64>,
    ) -> PyResult<RigidObject> {
        let (p, q) = pose(position_m, orientation);
        let h = self.with(|s| s.add_sphere(label, mass_kg, radius_m, subdivisions, p, q, thickness_m))?;
        Ok(self.rigid_object(label, h))
    }

    /// A solid cylinder along z (mesh with `slices` around and `stacks` along).
    #[pyo3(signature = (label, mass_kg, radius_m, height_m, slices=16, stacks=1, position_m=None, orientation=None, thickness_m=None))]
    #[allow(clippy::too_many_arguments)]
    fn add_cylinder(
        &self,
        label: &str,
        mass_kg: f64,
        radius_m: f64,
        height_m: f64,
        slices: usize,
        stacks: usize,
        position_m: Option<V3>,
        orientation: Option<Rot>,
        thickness_m: Option<f64>,
    ) -> PyResult<RigidObject> {
        let (p, q) = pose(position_m, orientation);
        let h = self.with(|s| s.add_cylinder(label, mass_kg, radius_m, height_m, slices, stacks, p, q, thickness_m))?;
        Ok(self.rigid_object(label, h))
    }

    /// A solid torus in the body's xy plane.
    #[pyo3(signature = (label, mass_kg, major_radius_m, minor_radius_m, major_segments=32, minor_segments=16, position_m=None, orientation=None, thickness_m=None))]
    #[allow(clippy::too_many_arguments)]
    fn add_torus(
        &self,
        label: &str,
        mass_kg: f64,
        major_radius_m: f64,
        minor_radius_m: f64,
        major_segments: usize,
        minor_segments: usize,
        position_m: Option<V3>,
        orientation: Option<Rot>,
        thickness_m: Option<f64>,
    ) -> PyResult<RigidObject> {
        let (p, q) = pose(position_m, orientation);
        let h = self.with(|s| {
            s.add_torus(
                label,
                mass_kg,
                major_radius_m,
                minor_radius_m,
                major_segments,
                minor_segments,
                p,
                q,
                thickness_m,
            )
        })?;
        Ok(self.rigid_object(label, h))
    }

    /// A body from a closed triangle mesh in world coordinates (n, 3) of uniform
    /// `density_kg_m3`: its mass properties are integrated and it is placed where the mesh is.
    #[pyo3(signature = (label, vertices_m, triangles, density_kg_m3, thickness_m=None))]
    fn add_rigid_mesh(
        &self,
        label: &str,
        vertices_m: Points,
        triangles: Elements<3>,
        density_kg_m3: f64,
        thickness_m: Option<f64>,
    ) -> PyResult<RigidObject> {
        let h = self.with(|s| s.add_rigid_mesh(label, &vertices_m.0, &triangles.0, density_kg_m3, thickness_m))?;
        Ok(self.rigid_object(label, h))
    }

    /// Give a body a mesh that is only drawn (body frame, relative to its centre of mass): it is
    /// written to the frames but takes no part in contact. Returns its node set.
    fn add_rigid_output_mesh(
        &self,
        body: BodyArg,
        local_vertices_m: Points,
        triangles: Elements<3>,
    ) -> PyResult<NodeSet> {
        let b = self.body(&body)?;
        let h = self.with(|s| s.add_rigid_output_mesh(b, &local_vertices_m.0, &triangles.0))?;
        Ok(NodeSet::new(self.id(), h))
    }

    /// Switch contact between all collision meshes of bodies a and b off or on (jointed links
    /// whose meshes overlap).
    fn set_bodies_collision(&self, a: BodyArg, b: BodyArg, enabled: bool) -> PyResult<()> {
        let (a, b) = (self.body(&a)?, self.body(&b)?);
        self.with(|s| s.set_bodies_collision(a, b, enabled))
    }

    // ---- Deformable–rigid attachments ----

    /// Glue nodes `points` (local indices) of the deformable object `nodes` to `body` where
    /// they are now.
    #[pyo3(signature = (label, body, nodes, points, params=None))]
    fn attach_to_body(
        &self,
        py: Python<'_>,
        label: &str,
        body: BodyArg,
        nodes: NodesArg,
        points: Indices,
        params: Option<&Bound<'_, params::AttachmentParams>>,
    ) -> PyResult<RigidAttachmentHandle> {
        self.own(&nodes.0)?;
        let b = self.body(&body)?;
        let p = attachment_params_arg(py, params)?;
        let h = self.with(|s| s.attach_to_body(label, b, nodes.0.rust(), &points.0, p))?;
        Ok(RigidAttachmentHandle::new(self.id(), h))
    }

    /// Glue every node of `nodes` within `distance_m` of the body's collision mesh `mesh`
    /// (whose triangles are `mesh_triangles`) to the body. Returns the handle and the number of
    /// nodes glued.
    #[pyo3(signature = (label, mesh, mesh_triangles, nodes, distance_m, params=None))]
    #[allow(clippy::too_many_arguments)]
    fn attach_to_body_by_distance(
        &self,
        py: Python<'_>,
        label: &str,
        mesh: RigidMesh,
        mesh_triangles: Elements<3>,
        nodes: NodesArg,
        distance_m: f64,
        params: Option<&Bound<'_, params::AttachmentParams>>,
    ) -> PyResult<(RigidAttachmentHandle, usize)> {
        self.own(&mesh.body)?;
        self.own(&nodes.0)?;
        let p = attachment_params_arg(py, params)?;
        let m = stark::rigidbodies::RigidMeshHandle {
            body: mesh.body.rust(),
            nodes: mesh.nodes.rust(),
            contact: mesh.contact.rust(),
        };
        let (h, n) =
            self.with(|s| s.attach_to_body_by_distance(label, &m, &mesh_triangles.0, nodes.0.rust(), distance_m, p))?;
        Ok((RigidAttachmentHandle::new(self.id(), h), n))
    }

    /// Largest gap of a deformable–rigid attachment group at the current positions, m.
    fn rigid_attachment_gap(&self, attachment: RigidAttachmentHandle) -> PyResult<f64> {
        self.own(&attachment)?;
        self.with(|s| s.rigid_bodies.attachments.potential.max_gap_now_m(attachment.rust(), s))
    }
}

/// Register the classes.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<RigidObject>()?;
    Ok(())
}

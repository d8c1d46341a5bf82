//! Rigid bodies: state, inertia, mass properties and joints (one file each).
//!
//! A body has 6 velocity DOFs (linear `v`, angular `ω`), integrated as in DESIGN §2. Everything
//! else sees a body through the kinematic map ([`crate::energy::kinematics`]): its collision mesh
//! vertices are nodes of the simulation that move with it, and joints are potentials on
//! body-fixed points ([`Node::Rigid`](crate::energy::Node::Rigid)), so contact, friction and
//! attachments work on bodies unchanged.

pub mod attachments;
pub mod inertia;
pub mod joints;
pub mod mass_properties;
pub mod shape;

use crate::contact::ContactHandle;
use crate::deformables::NodeSetHandle;
use crate::energy::kinematics::integrate_orientation;
use crate::energy::EnergyTerm;
use crate::error::{Result, StarkError};
use crate::geometry::mesh;
// Upward on purpose: each model adds its builder methods to `Simulation` in its own
// `impl Simulation` block (the public builder API), so it names the simulation floor.
use crate::simulation::Simulation;
use crate::state::OutputCells;
use crate::state::{rigid_body_of, BodyArrays, NodeArrays};
use nalgebra::{Matrix3, UnitQuaternion, Vector3};

pub use inertia::{RigidBodyParams, RigidInertia};
pub use mass_properties::MassProperties;
pub use shape::{Mass, Shape, ShapeError, Solid};

/// A rigid body of a simulation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub struct RigidBodyHandle {
    /// Index of the body.
    pub index: u32,
}

impl RigidBodyHandle {
    /// Index as `usize`.
    #[inline]
    pub fn i(&self) -> usize {
        self.index as usize
    }
}

/// The collision mesh of a rigid body: its vertices are nodes that move with the body.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RigidMeshHandle {
    /// The body.
    pub body: RigidBodyHandle,
    /// Its vertices in the node arrays.
    pub nodes: NodeSetHandle,
    /// Its contact object.
    pub contact: ContactHandle,
}

/// Every rigid-body model of a simulation.
pub struct RigidBodies {
    /// Label of each body.
    pub labels: Vec<String>,
    /// Inertia, gravity, external forces and damping.
    pub inertia: RigidInertia,
    /// Joints, motors and controllers.
    pub joints: joints::Joints,
    /// Deformable nodes glued to bodies.
    pub attachments: crate::energy::PotentialTerm<attachments::RigidAttachmentSet, 2>,
    /// Every joint made by the `Simulation::add_*` joint constructors, in creation order (the
    /// joint log writes their states).
    pub named_joints: Vec<joints::JointHandle>,
    /// The contact objects of each body's collision meshes.
    pub collision_meshes: Vec<Vec<ContactHandle>>,
}

impl Default for RigidBodies {
    fn default() -> Self {
        RigidBodies {
            labels: Vec::new(),
            inertia: RigidInertia::default(),
            joints: joints::Joints::new(joints::JointSet::default()),
            attachments: crate::energy::PotentialTerm::new(attachments::RigidAttachmentSet::default()),
            named_joints: Vec::new(),
            collision_meshes: Vec::new(),
        }
    }
}

impl RigidBodies {
    /// All terms, for the solver.
    pub fn terms_mut(&mut self) -> Vec<&mut dyn EnergyTerm> {
        vec![&mut self.inertia, &mut self.joints, &mut self.attachments]
    }

    /// The body with this label.
    pub fn by_label(&self, label: &str) -> Option<RigidBodyHandle> {
        self.labels
            .iter()
            .position(|l| l == label)
            .map(|i| RigidBodyHandle { index: i as u32 })
    }

    /// Set `masses` (per node) of each rigid node to its body's effective mass at that point,
    /// averaged over directions: `1/m = 1/M + (|r|² tr I⁻¹ − rᵀ I⁻¹ r)/3` with `r` the lever arm
    /// from the centre of mass and `I` the world inertia tensor; the mass a contact at the point
    /// moves (for choosing the contact stiffness, `contact::stiffness`).
    pub fn set_node_contact_masses(nodes: &NodeArrays, bodies: &BodyArrays, masses: &mut [f64]) {
        if bodies.is_empty() {
            return;
        }
        let inverse_inertia: Vec<Matrix3<f64>> = (0..bodies.len())
            .map(|b| bodies.inertia_world(b).try_inverse().unwrap_or_else(Matrix3::zeros))
            .collect();
        for (i, (m, &b)) in masses.iter_mut().zip(&nodes.body).enumerate() {
            if let Some(b) = rigid_body_of(b) {
                let r = nodes.x[i] - bodies.position[b];
                let inv = &inverse_inertia[b];
                let rotational = (r.norm_squared() * inv.trace() - r.dot(&(inv * r))) / 3.0;
                *m = 1.0 / (1.0 / bodies.mass[b] + rotational.max(0.0));
            }
        }
    }
}

fn check_vector(label: &str, what: &str, v: &Vector3<f64>) -> Result<()> {
    if v.iter().all(|c| c.is_finite()) {
        Ok(())
    } else {
        Err(StarkError::InvalidInput(format!(
            "{what} of rigid body '{label}' is not finite: {v:?}"
        )))
    }
}

impl Simulation {
    /// Add a rigid body of `mass_kg` and inertia tensor `inertia_kg_m2` (about its centre of
    /// mass, in its body frame) with its centre of mass at `position_m` and body frame rotated by
    /// `orientation`. It starts at rest.
    pub fn add_rigid_body(
        &mut self,
        label: &str,
        mass_kg: f64,
        inertia_kg_m2: Matrix3<f64>,
        position_m: Vector3<f64>,
        orientation: UnitQuaternion<f64>,
    ) -> Result<RigidBodyHandle> {
        if label.is_empty() || self.rigid_bodies.by_label(label).is_some() {
            return Err(StarkError::InvalidInput(format!(
                "rigid body label '{label}' is empty or already used"
            )));
        }
        if !(mass_kg > 0.0 && mass_kg.is_finite()) {
            return Err(StarkError::InvalidInput(format!(
                "mass of rigid body '{label}' must be positive, got {mass_kg} kg"
            )));
        }
        let symmetric = (inertia_kg_m2 - inertia_kg_m2.transpose()).norm() <= 1e-9 * inertia_kg_m2.norm();
        let eig = inertia_kg_m2.symmetric_eigenvalues();
        if !symmetric || !inertia_kg_m2.iter().all(|c| c.is_finite()) || eig.min() <= 0.0 {
            return Err(StarkError::InvalidInput(format!(
                "inertia tensor of rigid body '{label}' must be symmetric positive definite, got {inertia_kg_m2:?}"
            )));
        }
        check_vector(label, "position", &position_m)?;
        let b = &mut self.bodies;
        b.position.push(position_m);
        b.orientation.push(orientation);
        b.velocity.push(Vector3::zeros());
        b.angular_velocity.push(Vector3::zeros());
        b.mass.push(mass_kg);
        b.inertia_local.push(inertia_kg_m2);
        b.force.push(Vector3::zeros());
        b.torque.push(Vector3::zeros());
        b.acceleration.push(Vector3::zeros());
        b.angular_acceleration.push(Vector3::zeros());
        self.rigid_bodies.labels.push(label.to_string());
        self.rigid_bodies.collision_meshes.push(Vec::new());
        self.rigid_bodies.inertia.params.push(RigidBodyParams::default());
        Ok(RigidBodyHandle {
            index: (b.len() - 1) as u32,
        })
    }

    /// Add a rigid body from its mass properties; its centre of mass goes to `position_m`.
    pub fn add_rigid_body_with(
        &mut self,
        label: &str,
        props: &MassProperties,
        position_m: Vector3<f64>,
        orientation: UnitQuaternion<f64>,
    ) -> Result<RigidBodyHandle> {
        self.add_rigid_body(label, props.mass_kg, props.inertia_kg_m2, position_m, orientation)
    }

    /// Give body `body` a collision mesh (vertices in the body frame, relative to its centre of
    /// mass) with contact thickness `thickness_m` (or the default). Its vertices become nodes that
    /// move with the body; the mesh is written to the output frames. Self-collision within the
    /// body is off.
    pub fn add_rigid_collision_mesh(
        &mut self,
        body: RigidBodyHandle,
        local_vertices: &[Vector3<f64>],
        triangles: &[[usize; 3]],
        thickness_m: Option<f64>,
    ) -> Result<RigidMeshHandle> {
        let b = self.check_body(body)?;
        let label = self.rigid_bodies.labels[b].clone();
        let thickness = thickness_m
            .or(self.settings.contact.default_thickness_m)
            .ok_or_else(|| {
                StarkError::InvalidInput(format!(
                    "collision mesh of rigid body '{label}' needs a contact thickness (or settings.contact.default_thickness_m)"
                ))
            })?;
        let world: Vec<Vector3<f64>> = local_vertices
            .iter()
            .map(|p| self.bodies.position[b] + self.bodies.orientation[b] * p)
            .collect();
        let mesh_label = format!("{label}.mesh{}", self.deformables.sets.len());
        let nodes = self.add_nodes(&mesh_label, &world)?;
        for (k, i) in nodes.range().enumerate() {
            self.nodes.body[i] = body.index;
            self.nodes.rest[i] = local_vertices[k];
        }
        let edges = mesh::edges_from_triangles(triangles);
        let all: Vec<usize> = (0..local_vertices.len()).collect();
        let rest = self.nodes.rest.clone();
        let contact = self
            .contact
            .add_object(&label, nodes, &rest, triangles, &edges, &all, thickness)?;
        // A body does not collide with itself: not within a mesh, nor between its meshes.
        self.contact.disable_collision(contact, contact)?;
        for &other in &self.rigid_bodies.collision_meshes[b] {
            self.contact.disable_collision(contact, other)?;
        }
        self.rigid_bodies.collision_meshes[b].push(contact);
        self.output
            .add_mesh(&label, nodes, OutputCells::Triangles(triangles.to_vec()));
        Ok(RigidMeshHandle { body, nodes, contact })
    }

    /// Switch contact between every collision mesh of body `a` and every one of body `b` off or
    /// on (typically for two jointed bodies whose meshes overlap at the joint). Applies to the
    /// meshes the bodies have now.
    pub fn set_bodies_collision(&mut self, a: RigidBodyHandle, b: RigidBodyHandle, enabled: bool) -> Result<()> {
        let (ia, ib) = (self.check_body(a)?, self.check_body(b)?);
        if ia == ib {
            return Err(StarkError::InvalidInput(format!(
                "set_bodies_collision: both bodies are '{}' (a body never collides with itself)",
                self.rigid_bodies.labels[ia]
            )));
        }
        for &ca in &self.rigid_bodies.collision_meshes[ia] {
            for &cb in &self.rigid_bodies.collision_meshes[ib] {
                self.contact.set_collision(ca, cb, enabled)?;
            }
        }
        Ok(())
    }

    /// The contact objects of body `body`'s collision meshes.
    pub fn body_collision_meshes(&self, body: RigidBodyHandle) -> Result<&[ContactHandle]> {
        let b = self.check_body(body)?;
        Ok(&self.rigid_bodies.collision_meshes[b])
    }

    /// Give body `body` a mesh that is only drawn (vertices in the body frame, relative to its
    /// centre of mass): its vertices become nodes that move with the body and are written to the
    /// output frames, but it takes no part in contact. Returns its node set.
    pub fn add_rigid_output_mesh(
        &mut self,
        body: RigidBodyHandle,
        local_vertices: &[Vector3<f64>],
        triangles: &[[usize; 3]],
    ) -> Result<NodeSetHandle> {
        let b = self.check_body(body)?;
        let label = self.rigid_bodies.labels[b].clone();
        mesh::check_indices(local_vertices.len(), triangles)
            .map_err(|e| StarkError::InvalidInput(format!("output mesh of rigid body '{label}': {e}")))?;
        let world: Vec<Vector3<f64>> = local_vertices
            .iter()
            .map(|p| self.bodies.position[b] + self.bodies.orientation[b] * p)
            .collect();
        let mesh_label = format!("{label}.mesh{}", self.deformables.sets.len());
        let nodes = self.add_nodes(&mesh_label, &world)?;
        for (k, i) in nodes.range().enumerate() {
            self.nodes.body[i] = body.index;
            self.nodes.rest[i] = local_vertices[k];
        }
        self.output
            .add_mesh(&label, nodes, OutputCells::Triangles(triangles.to_vec()));
        Ok(nodes)
    }

    /// Record a joint in [`RigidBodies::named_joints`], replacing the record of the same joint
    /// (same first element) when a composite joint extends one it built.
    pub(crate) fn register_joint(&mut self, h: joints::JointHandle) -> joints::JointHandle {
        let list = &mut self.rigid_bodies.named_joints;
        match list.iter_mut().find(|j| j.elements.first() == h.elements.first()) {
            Some(j) => *j = h.clone(),
            None => list.push(h.clone()),
        }
        h
    }

    pub(crate) fn check_body(&self, body: RigidBodyHandle) -> Result<usize> {
        let i = body.i();
        if i < self.bodies.len() {
            Ok(i)
        } else {
            Err(StarkError::InvalidHandle {
                kind: "rigid body",
                index: i,
                len: self.bodies.len(),
            })
        }
    }

    /// Number of rigid bodies.
    pub fn num_rigid_bodies(&self) -> usize {
        self.bodies.len()
    }

    /// Centre of mass of a body, m.
    pub fn body_position(&self, body: RigidBodyHandle) -> Vector3<f64> {
        self.bodies.position[body.i()]
    }
    /// Orientation of a body (body → world).
    pub fn body_orientation(&self, body: RigidBodyHandle) -> UnitQuaternion<f64> {
        self.bodies.orientation[body.i()]
    }
    /// Linear velocity of the centre of mass, m/s.
    pub fn body_velocity(&self, body: RigidBodyHandle) -> Vector3<f64> {
        self.bodies.velocity[body.i()]
    }
    /// Angular velocity (world frame), rad/s.
    pub fn body_angular_velocity(&self, body: RigidBodyHandle) -> Vector3<f64> {
        self.bodies.angular_velocity[body.i()]
    }
    /// Angular momentum about the centre of mass (world), kg·m²/s.
    pub fn body_angular_momentum(&self, body: RigidBodyHandle) -> Vector3<f64> {
        self.bodies.inertia_world(body.i()) * self.bodies.angular_velocity[body.i()]
    }
    /// World position of the body-local point `local_m`.
    pub fn body_point_to_world(&self, body: RigidBodyHandle, local_m: &Vector3<f64>) -> Vector3<f64> {
        self.bodies.position[body.i()] + self.bodies.orientation[body.i()] * local_m
    }
    /// Body-local coordinates of the world point `world_m`.
    pub fn body_point_to_local(&self, body: RigidBodyHandle, world_m: &Vector3<f64>) -> Vector3<f64> {
        self.bodies.orientation[body.i()].inverse() * (world_m - self.bodies.position[body.i()])
    }
    /// World direction of the body-local direction `local`.
    pub fn body_direction_to_world(&self, body: RigidBodyHandle, local: &Vector3<f64>) -> Vector3<f64> {
        self.bodies.orientation[body.i()] * local
    }
    /// Body-local direction of the world direction `world`.
    pub fn body_direction_to_local(&self, body: RigidBodyHandle, world: &Vector3<f64>) -> Vector3<f64> {
        self.bodies.orientation[body.i()].inverse() * world
    }
    /// Velocity of the world point `world_m` moving with the body, m/s.
    pub fn body_velocity_at(&self, body: RigidBodyHandle, world_m: &Vector3<f64>) -> Vector3<f64> {
        let b = body.i();
        self.bodies.velocity[b] + self.bodies.angular_velocity[b].cross(&(world_m - self.bodies.position[b]))
    }

    /// Move a body: centre of mass to `position_m`, orientation to `orientation` (its mesh
    /// follows).
    pub fn set_body_pose(
        &mut self,
        body: RigidBodyHandle,
        position_m: Vector3<f64>,
        orientation: UnitQuaternion<f64>,
    ) -> Result<()> {
        let b = self.check_body(body)?;
        check_vector(&self.rigid_bodies.labels[b], "position", &position_m)?;
        self.bodies.position[b] = position_m;
        self.bodies.orientation[b] = orientation;
        self.place_rigid_nodes();
        Ok(())
    }
    /// Set the linear velocity of a body's centre of mass, m/s.
    pub fn set_body_velocity(&mut self, body: RigidBodyHandle, v_m_s: Vector3<f64>) -> Result<()> {
        let b = self.check_body(body)?;
        check_vector(&self.rigid_bodies.labels[b], "velocity", &v_m_s)?;
        self.bodies.velocity[b] = v_m_s;
        Ok(())
    }
    /// Set the angular velocity of a body (world frame), rad/s.
    pub fn set_body_angular_velocity(&mut self, body: RigidBodyHandle, w_rad_s: Vector3<f64>) -> Result<()> {
        let b = self.check_body(body)?;
        check_vector(&self.rigid_bodies.labels[b], "angular velocity", &w_rad_s)?;
        self.bodies.angular_velocity[b] = w_rad_s;
        Ok(())
    }
    /// Set the external force at the centre of mass (persists until changed), N.
    pub fn set_body_force(&mut self, body: RigidBodyHandle, force_n: Vector3<f64>) -> Result<()> {
        let b = self.check_body(body)?;
        check_vector(&self.rigid_bodies.labels[b], "force", &force_n)?;
        self.bodies.force[b] = force_n;
        Ok(())
    }
    /// Set the external torque (persists until changed), N·m.
    pub fn set_body_torque(&mut self, body: RigidBodyHandle, torque_n_m: Vector3<f64>) -> Result<()> {
        let b = self.check_body(body)?;
        check_vector(&self.rigid_bodies.labels[b], "torque", &torque_n_m)?;
        self.bodies.torque[b] = torque_n_m;
        Ok(())
    }
    /// Add a force applied at the world point `at_m`: a force at the centre of mass plus the
    /// torque `(at − c) × f` (persists until changed).
    pub fn add_body_force_at(
        &mut self,
        body: RigidBodyHandle,
        force_n: Vector3<f64>,
        at_m: Vector3<f64>,
    ) -> Result<()> {
        let b = self.check_body(body)?;
        check_vector(&self.rigid_bodies.labels[b], "force", &force_n)?;
        check_vector(&self.rigid_bodies.labels[b], "force point", &at_m)?;
        self.bodies.force[b] += force_n;
        self.bodies.torque[b] += (at_m - self.bodies.position[b]).cross(&force_n);
        Ok(())
    }
    /// Set the external acceleration (added to gravity; persists), m/s².
    pub fn set_body_acceleration(&mut self, body: RigidBodyHandle, a_m_s2: Vector3<f64>) -> Result<()> {
        let b = self.check_body(body)?;
        check_vector(&self.rigid_bodies.labels[b], "acceleration", &a_m_s2)?;
        self.bodies.acceleration[b] = a_m_s2;
        Ok(())
    }
    /// Set the external angular acceleration (persists), rad/s².
    pub fn set_body_angular_acceleration(&mut self, body: RigidBodyHandle, a_rad_s2: Vector3<f64>) -> Result<()> {
        let b = self.check_body(body)?;
        check_vector(&self.rigid_bodies.labels[b], "angular acceleration", &a_rad_s2)?;
        self.bodies.angular_acceleration[b] = a_rad_s2;
        Ok(())
    }
    /// Damping and other inertia parameters of a body.
    pub fn body_params(&self, body: RigidBodyHandle) -> Result<RigidBodyParams> {
        let b = self.check_body(body)?;
        Ok(self.rigid_bodies.inertia.params[b])
    }
    /// Change the inertia parameters of a body.
    pub fn set_body_params(&mut self, body: RigidBodyHandle, params: RigidBodyParams) -> Result<()> {
        let b = self.check_body(body)?;
        params.validate(&self.rigid_bodies.labels[b])?;
        self.rigid_bodies.inertia.params[b] = params;
        Ok(())
    }
    /// Change the mass (kg) and body-frame inertia tensor (kg·m²) of a body.
    pub fn set_body_mass(&mut self, body: RigidBodyHandle, mass_kg: f64, inertia_kg_m2: Matrix3<f64>) -> Result<()> {
        let b = self.check_body(body)?;
        let label = self.rigid_bodies.labels[b].clone();
        if !(mass_kg > 0.0 && mass_kg.is_finite()) || inertia_kg_m2.symmetric_eigenvalues().min() <= 0.0 {
            return Err(StarkError::InvalidInput(format!(
                "rigid body '{label}' needs a positive mass and positive definite inertia"
            )));
        }
        self.bodies.mass[b] = mass_kg;
        self.bodies.inertia_local[b] = inertia_kg_m2;
        Ok(())
    }

    /// Put every rigid node at its body's current pose.
    pub(crate) fn place_rigid_nodes(&mut self) {
        for i in 0..self.nodes.len() {
            if let Some(b) = rigid_body_of(self.nodes.body[i]) {
                self.nodes.x[i] = self.bodies.position[b] + self.bodies.orientation[b] * self.nodes.rest[i];
            }
        }
    }
}

/// Commit the end-of-step body state: velocities from the solve, pose integrated (DESIGN §2).
pub(crate) fn commit_bodies(bodies: &mut BodyArrays, v: &[Vector3<f64>], n_nodes: usize, dt: f64) {
    for b in 0..bodies.len() {
        let vel = v[crate::state::linear_block(n_nodes, b) as usize];
        let w = v[crate::state::angular_block(n_nodes, b) as usize];
        bodies.position[b] += vel * dt;
        bodies.orientation[b] = integrate_orientation(&bodies.orientation[b], &w, dt);
        bodies.velocity[b] = vel;
        bodies.angular_velocity[b] = w;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::presets::meshes::box_mesh;
    use crate::Settings;

    fn settings() -> Settings {
        let mut s = Settings::default();
        s.output.frames = false;
        s.output.step_log = false;
        s.time_step_s = 0.01;
        s.gravity_m_s2 = [0.0; 3];
        s.contact.default_thickness_m = Some(1e-3);
        s
    }

    #[test]
    fn meshes_of_one_body_do_not_collide_with_each_other() {
        let mut sim = Simulation::new(settings()).unwrap();
        let props = MassProperties::cuboid(1.0, Vector3::repeat(0.1));
        let body = sim
            .add_rigid_body_with("body", &props, Vector3::zeros(), UnitQuaternion::identity())
            .unwrap();
        // Two overlapping boxes on the same body: a compound shape, not a collision.
        let a = box_mesh(Vector3::repeat(0.1));
        let mut b = box_mesh(Vector3::new(0.2, 0.05, 0.05));
        b.vertices.iter_mut().for_each(|v| v.x += 0.05);
        let ma = sim
            .add_rigid_collision_mesh(body, &a.vertices, &a.elements, None)
            .unwrap();
        let mb = sim
            .add_rigid_collision_mesh(body, &b.vertices, &b.elements, None)
            .unwrap();
        assert!(!sim.contact.collision_enabled(ma.contact, mb.contact).unwrap());
        assert_eq!(sim.body_collision_meshes(body).unwrap(), &[ma.contact, mb.contact]);
        sim.set_body_velocity(body, Vector3::new(0.1, 0.0, 0.0)).unwrap();
        sim.run(0.05).unwrap();
        assert!((sim.body_position(body).x - 0.005).abs() < 1e-9);
    }

    #[test]
    fn collision_mesh_vertices_are_not_unknowns() {
        // A 4-node cloth and, 5 m above it, a body with a compound mesh of two boxes: the solve
        // has 3 unknowns per cloth node and 6 for the body, none for the mesh vertices, and the
        // mesh follows the body.
        let mut sim = Simulation::new(settings()).unwrap();
        let cotton = crate::presets::SurfaceMaterial::cotton_fabric();
        sim.add_surface_grid("cloth", [0.1, 0.1], [1, 1], &cotton).unwrap();
        let props = MassProperties::cuboid(1.0, Vector3::repeat(0.1));
        let up = Vector3::new(0.0, 0.0, 5.0);
        let body = sim
            .add_rigid_body_with("body", &props, up, UnitQuaternion::identity())
            .unwrap();
        let m = box_mesh(Vector3::repeat(0.1));
        let mesh = sim
            .add_rigid_collision_mesh(body, &m.vertices, &m.elements, None)
            .unwrap();
        let mut far = box_mesh(Vector3::repeat(0.1));
        far.vertices.iter_mut().for_each(|v| v.x += 1.0);
        sim.add_rigid_collision_mesh(body, &far.vertices, &far.elements, None)
            .unwrap();
        sim.set_body_angular_velocity(body, Vector3::new(0.0, 0.0, 1.0))
            .unwrap();
        sim.run(0.05).unwrap();
        let rigid_vertices = 2 * m.vertices.len();
        assert_eq!(sim.summary().nodes, 4 + rigid_vertices);
        assert_eq!(sim.summary().unknowns, 3 * 4 + 6);
        assert_eq!(3 * sim.newton.assembler.matrix.n_blocks, 3 * 4 + 6);
        // The mesh vertices are where the body's pose puts them.
        let x = sim.positions(mesh.nodes);
        let (p, q) = (sim.body_position(body), sim.body_orientation(body));
        for (xi, local) in x.iter().zip(&m.vertices) {
            assert!((xi - (p + q * local)).norm() < 1e-12);
        }
    }

    #[test]
    fn jointed_bodies_can_overlap_with_their_collision_off() {
        let build = |collide: bool| -> Result<Simulation> {
            let mut sim = Simulation::new(settings())?;
            let size = Vector3::new(0.2, 0.05, 0.05);
            let m = box_mesh(size);
            let props = MassProperties::cuboid(1.0, size);
            let mut bodies = Vec::new();
            for (k, x) in [0.0, 0.15].into_iter().enumerate() {
                let b = sim.add_rigid_body_with(
                    &format!("link{k}"),
                    &props,
                    Vector3::new(x, 0.0, 0.0),
                    UnitQuaternion::identity(),
                )?;
                sim.add_rigid_collision_mesh(b, &m.vertices, &m.elements, None)?;
                bodies.push(b);
            }
            // The links overlap by 5 cm around the hinge at x = 0.075.
            sim.add_hinge_joint(
                "hinge",
                Some(bodies[0]),
                bodies[1],
                Vector3::new(0.075, 0.0, 0.0),
                Vector3::z(),
                joints::JointParams::default(),
            )?;
            sim.set_bodies_collision(bodies[0], bodies[1], collide)?;
            sim.set_body_angular_velocity(bodies[1], Vector3::new(0.0, 0.0, 1.0))?;
            sim.run(0.05)?;
            Ok(sim)
        };
        let err = build(true)
            .err()
            .expect("overlapping colliding bodies must be rejected");
        assert!(err.to_string().contains("intersect"), "{err}");
        let sim = build(false).unwrap();
        let w = sim.body_angular_velocity(RigidBodyHandle { index: 1 }).z;
        assert!(w > 0.1, "the hinge turns freely: {w}");
        let bad = Simulation::new(settings()).unwrap().set_bodies_collision(
            RigidBodyHandle { index: 0 },
            RigidBodyHandle { index: 1 },
            false,
        );
        assert!(bad.is_err());
    }
}

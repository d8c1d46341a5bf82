//! Rigid bodies: adding them, their state, forces and mass.

use super::Simulation;
use crate::convert::{m3_out, pose, quat_out, to_python, v3_out, Elements, Points, Rot, M3, V3};
use crate::handles::*;
use crate::rigid::MassProperties;
use pyo3::prelude::*;
use pyo3::types::PyDict;

#[pymethods]
impl Simulation {
    /// Add a rigid body of `mass_kg` and body-frame inertia tensor `inertia_kg_m2` (3, 3) about
    /// its centre of mass, placed at `position_m` with `orientation` (quaternion (w, x, y, z) or
    /// (3, 3) matrix). It starts at rest.
    #[pyo3(signature = (label, mass_kg, inertia_kg_m2, position_m=None, orientation=None))]
    fn add_rigid_body(
        &self,
        label: &str,
        mass_kg: f64,
        inertia_kg_m2: M3,
        position_m: Option<V3>,
        orientation: Option<Rot>,
    ) -> PyResult<RigidBody> {
        let (p, q) = pose(position_m, orientation);
        let h = self.with(|s| s.add_rigid_body(label, mass_kg, inertia_kg_m2.0, p, q))?;
        Ok(RigidBody::new(self.id, h, label))
    }

    /// Add a rigid body from its mass properties; its centre of mass goes to `position_m`.
    #[pyo3(signature = (label, mass_properties, position_m=None, orientation=None))]
    fn add_rigid_body_with(
        &self,
        label: &str,
        mass_properties: &MassProperties,
        position_m: Option<V3>,
        orientation: Option<Rot>,
    ) -> PyResult<RigidBody> {
        let (p, q) = pose(position_m, orientation);
        let props = mass_properties.rust();
        let h = self.with(|s| s.add_rigid_body_with(label, &props, p, q))?;
        Ok(RigidBody::new(self.id, h, label))
    }

    /// Give a body a collision mesh: vertices (n, 3) in the body frame (relative to its centre of
    /// mass) and triangles (m, 3), with contact thickness `thickness_m` (or the default).
    #[pyo3(signature = (body, local_vertices_m, triangles, thickness_m=None))]
    fn add_rigid_collision_mesh(
        &self,
        body: BodyArg,
        local_vertices_m: Points,
        triangles: Elements<3>,
        thickness_m: Option<f64>,
    ) -> PyResult<RigidMesh> {
        self.own(&body.0)?;
        let h =
            self.with(|s| s.add_rigid_collision_mesh(body.0.rust(), &local_vertices_m.0, &triangles.0, thickness_m))?;
        Ok(RigidMesh {
            body: body.0,
            nodes: NodeSet::new(self.id, h.nodes),
            contact: ContactHandle::new(self.id, h.contact),
        })
    }

    /// The rigid body labelled `label`, or None.
    fn rigid_body(&self, label: &str) -> PyResult<Option<RigidBody>> {
        Ok(self
            .get(|s| s.rigid_bodies.by_label(label))?
            .map(|h| RigidBody::new(self.id, h, label)))
    }

    /// All rigid bodies, in creation order.
    fn rigid_bodies(&self) -> PyResult<Vec<RigidBody>> {
        let labels = self.get(|s| s.rigid_bodies.labels.clone())?;
        Ok(labels
            .into_iter()
            .enumerate()
            .map(|(i, label)| RigidBody {
                index: i as u32,
                label,
                sim: self.id,
            })
            .collect())
    }

    /// Centre of mass of a body, m.
    fn body_position<'py>(&self, py: Python<'py>, body: BodyArg) -> PyResult<Bound<'py, numpy::PyArray1<f64>>> {
        let b = self.body(&body)?;
        Ok(v3_out(py, &self.get(|s| s.body_position(b))?))
    }

    /// Orientation of a body (body → world) as a quaternion (w, x, y, z).
    fn body_orientation<'py>(&self, py: Python<'py>, body: BodyArg) -> PyResult<Bound<'py, numpy::PyArray1<f64>>> {
        let b = self.body(&body)?;
        Ok(quat_out(py, &self.get(|s| s.body_orientation(b))?))
    }

    /// Rotation matrix of a body (body → world), (3, 3).
    fn body_rotation<'py>(&self, py: Python<'py>, body: BodyArg) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
        let b = self.body(&body)?;
        let r = self.get(|s| s.body_orientation(b).to_rotation_matrix().into_inner())?;
        Ok(m3_out(py, &r))
    }

    /// Linear velocity of a body's centre of mass, m/s.
    fn body_velocity<'py>(&self, py: Python<'py>, body: BodyArg) -> PyResult<Bound<'py, numpy::PyArray1<f64>>> {
        let b = self.body(&body)?;
        Ok(v3_out(py, &self.get(|s| s.body_velocity(b))?))
    }

    /// Angular velocity of a body (world frame), rad/s.
    fn body_angular_velocity<'py>(&self, py: Python<'py>, body: BodyArg) -> PyResult<Bound<'py, numpy::PyArray1<f64>>> {
        let b = self.body(&body)?;
        Ok(v3_out(py, &self.get(|s| s.body_angular_velocity(b))?))
    }

    /// Angular momentum of a body about its centre of mass (world), kg·m²/s.
    fn body_angular_momentum<'py>(&self, py: Python<'py>, body: BodyArg) -> PyResult<Bound<'py, numpy::PyArray1<f64>>> {
        let b = self.body(&body)?;
        Ok(v3_out(py, &self.get(|s| s.body_angular_momentum(b))?))
    }

    /// Mass of a body, kg.
    fn body_mass(&self, body: BodyArg) -> PyResult<f64> {
        let b = self.body(&body)?;
        self.get(|s| s.bodies.mass[b.i()])
    }

    /// Body-frame inertia tensor of a body about its centre of mass, kg·m², (3, 3).
    fn body_inertia<'py>(&self, py: Python<'py>, body: BodyArg) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
        let b = self.body(&body)?;
        Ok(m3_out(py, &self.get(|s| s.bodies.inertia_local[b.i()])?))
    }

    /// External force on a body's centre of mass, N.
    fn body_force<'py>(&self, py: Python<'py>, body: BodyArg) -> PyResult<Bound<'py, numpy::PyArray1<f64>>> {
        let b = self.body(&body)?;
        Ok(v3_out(py, &self.get(|s| s.bodies.force[b.i()])?))
    }

    /// External torque on a body, N·m.
    fn body_torque<'py>(&self, py: Python<'py>, body: BodyArg) -> PyResult<Bound<'py, numpy::PyArray1<f64>>> {
        let b = self.body(&body)?;
        Ok(v3_out(py, &self.get(|s| s.bodies.torque[b.i()])?))
    }

    /// World positions of body-frame points: (3,) → (3,), (n, 3) → (n, 3).
    fn body_point_to_world<'py>(
        &self,
        py: Python<'py>,
        body: BodyArg,
        points_m: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let b = self.body(&body)?;
        self.map_points(py, points_m, |s, p| s.body_point_to_world(b, p))
    }

    /// Body-frame coordinates of world points: (3,) → (3,), (n, 3) → (n, 3).
    fn body_point_to_local<'py>(
        &self,
        py: Python<'py>,
        body: BodyArg,
        points_m: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let b = self.body(&body)?;
        self.map_points(py, points_m, |s, p| s.body_point_to_local(b, p))
    }

    /// World directions of body-frame directions: (3,) → (3,), (n, 3) → (n, 3).
    fn body_direction_to_world<'py>(
        &self,
        py: Python<'py>,
        body: BodyArg,
        directions: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let b = self.body(&body)?;
        self.map_points(py, directions, |s, p| s.body_direction_to_world(b, p))
    }

    /// Body-frame directions of world directions: (3,) → (3,), (n, 3) → (n, 3).
    fn body_direction_to_local<'py>(
        &self,
        py: Python<'py>,
        body: BodyArg,
        directions: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let b = self.body(&body)?;
        self.map_points(py, directions, |s, p| s.body_direction_to_local(b, p))
    }

    /// Velocities of world points moving with the body, m/s: (3,) → (3,), (n, 3) → (n, 3).
    fn body_velocity_at<'py>(
        &self,
        py: Python<'py>,
        body: BodyArg,
        points_m: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let b = self.body(&body)?;
        self.map_points(py, points_m, |s, p| s.body_velocity_at(b, p))
    }

    /// Move a body: centre of mass to `position_m`, orientation to `orientation` (default:
    /// unchanged); its meshes follow.
    #[pyo3(signature = (body, position_m, orientation=None))]
    fn set_body_pose(&self, body: BodyArg, position_m: V3, orientation: Option<Rot>) -> PyResult<()> {
        let b = self.body(&body)?;
        self.with(|s| {
            let q = orientation.map(|q| q.0).unwrap_or_else(|| s.body_orientation(b));
            s.set_body_pose(b, position_m.0, q)
        })
    }

    /// Set the linear velocity of a body's centre of mass, m/s.
    fn set_body_velocity(&self, body: BodyArg, velocity_m_s: V3) -> PyResult<()> {
        let b = self.body(&body)?;
        self.with(|s| s.set_body_velocity(b, velocity_m_s.0))
    }

    /// Set the angular velocity of a body (world frame), rad/s.
    fn set_body_angular_velocity(&self, body: BodyArg, angular_velocity_rad_s: V3) -> PyResult<()> {
        let b = self.body(&body)?;
        self.with(|s| s.set_body_angular_velocity(b, angular_velocity_rad_s.0))
    }

    /// Set the external force at a body's centre of mass (persists until changed), N.
    fn set_body_force(&self, body: BodyArg, force_n: V3) -> PyResult<()> {
        let b = self.body(&body)?;
        self.with(|s| s.set_body_force(b, force_n.0))
    }

    /// Set the external torque on a body (persists until changed), N·m.
    fn set_body_torque(&self, body: BodyArg, torque_n_m: V3) -> PyResult<()> {
        let b = self.body(&body)?;
        self.with(|s| s.set_body_torque(b, torque_n_m.0))
    }

    /// Add a force `force_n` applied at the world point `at_m`: a force at the centre of mass
    /// plus the torque (at − c) × f (persists until changed).
    fn add_body_force_at(&self, body: BodyArg, force_n: V3, at_m: V3) -> PyResult<()> {
        let b = self.body(&body)?;
        self.with(|s| s.add_body_force_at(b, force_n.0, at_m.0))
    }

    /// Set the external acceleration of a body (added to gravity; persists), m/s².
    fn set_body_acceleration(&self, body: BodyArg, acceleration_m_s2: V3) -> PyResult<()> {
        let b = self.body(&body)?;
        self.with(|s| s.set_body_acceleration(b, acceleration_m_s2.0))
    }

    /// Set the external angular acceleration of a body (persists), rad/s².
    fn set_body_angular_acceleration(&self, body: BodyArg, angular_acceleration_rad_s2: V3) -> PyResult<()> {
        let b = self.body(&body)?;
        self.with(|s| s.set_body_angular_acceleration(b, angular_acceleration_rad_s2.0))
    }

    /// Every body's pose and velocity by label: dicts with `position_m`, `orientation_wxyz`,
    /// `velocity_m_s` and `angular_velocity_rad_s` (world frame), as in the body log.
    fn body_states<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let states = self.get(|s| s.body_states())?;
        let d = PyDict::new(py);
        for (label, state) in states {
            d.set_item(label, to_python(py, &state)?)?;
        }
        Ok(d)
    }

    /// The contact objects of a body's collision meshes, in the order they were added.
    fn body_collision_meshes(&self, body: BodyArg) -> PyResult<Vec<ContactHandle>> {
        let b = self.body(&body)?;
        let hs = self.with(|s| s.body_collision_meshes(b).map(|c| c.to_vec()))?;
        Ok(hs.into_iter().map(|c| ContactHandle::new(self.id, c)).collect())
    }

    /// Change the mass (kg) and body-frame inertia tensor (kg·m², (3, 3)) of a body.
    fn set_body_mass(&self, body: BodyArg, mass_kg: f64, inertia_kg_m2: M3) -> PyResult<()> {
        let b = self.body(&body)?;
        self.with(|s| s.set_body_mass(b, mass_kg, inertia_kg_m2.0))
    }
}

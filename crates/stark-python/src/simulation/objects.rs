//! Nodes and deformable objects: node arrays, adding surfaces, volumes and lines, prescribed
//! nodes.

use super::{check_finite, points_or_vector, prescribed_params, Simulation};
use crate::convert::{floats_out, points_out, stark_err, Elements, Indices, Points, Rot, V3};
use crate::handles::*;
use crate::params::{self, Mirror};
use nalgebra::UnitQuaternion;
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;

#[pymethods]
impl Simulation {
    /// Add bare nodes (no energy) at `positions` (n, 3) as a labelled object.
    fn add_nodes(&self, label: &str, positions: Points) -> PyResult<NodeSet> {
        let h = self.with(|s| s.add_nodes(label, &positions.0))?;
        Ok(NodeSet::new(self.id, h))
    }

    /// The node set labelled `label`, or None.
    fn node_set(&self, label: &str) -> PyResult<Option<NodeSet>> {
        Ok(self
            .get(|s| s.deformables.set_by_label(label))?
            .map(|h| NodeSet::new(self.id, h)))
    }

    /// Labels of all node sets (objects and collision meshes), in creation order.
    fn node_set_labels(&self) -> PyResult<Vec<String>> {
        self.get(|s| s.deformables.sets.iter().map(|(l, _)| l.clone()).collect())
    }

    /// Positions of an object's nodes, m: a new (n, 3) array.
    fn positions<'py>(&self, py: Python<'py>, nodes: NodesArg) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
        self.own(&nodes.0)?;
        let x = self.get(|s| s.positions(nodes.0.rust()).to_vec())?;
        Ok(points_out(py, &x))
    }

    /// Velocities of an object's nodes, m/s: a new (n, 3) array.
    fn velocities<'py>(&self, py: Python<'py>, nodes: NodesArg) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
        self.own(&nodes.0)?;
        let v = self.get(|s| s.velocities(nodes.0.rust()).to_vec())?;
        Ok(points_out(py, &v))
    }

    /// Rest positions of an object's nodes, m (body-frame positions for a rigid collision mesh).
    fn rest_positions<'py>(&self, py: Python<'py>, nodes: NodesArg) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
        self.own(&nodes.0)?;
        let r = nodes.0.rust().range();
        let x = self.get(|s| s.nodes.rest[r].to_vec())?;
        Ok(points_out(py, &x))
    }

    /// External forces on an object's nodes, N.
    fn forces<'py>(&self, py: Python<'py>, nodes: NodesArg) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
        self.own(&nodes.0)?;
        let r = nodes.0.rust().range();
        let f = self.get(|s| s.nodes.force[r].to_vec())?;
        Ok(points_out(py, &f))
    }

    /// Lumped masses of an object's nodes, kg: a new (n,) array.
    fn masses<'py>(&self, py: Python<'py>, nodes: NodesArg) -> PyResult<Bound<'py, numpy::PyArray1<f64>>> {
        self.own(&nodes.0)?;
        let r = nodes.0.rust().range();
        let m = self.get(|s| s.deformables.inertia.node_masses(s.nodes.len())[r].to_vec())?;
        Ok(floats_out(py, m))
    }

    /// Move an object's nodes to `positions` (n, 3), m (deformable objects only).
    fn set_positions(&self, nodes: NodesArg, positions: Points) -> PyResult<()> {
        self.set_node_field(nodes, Some(positions), None, |s| &mut s.nodes.x, "positions")
    }

    /// Set the velocities of an object's nodes, m/s: an (n, 3) array or one (3,) vector for all.
    fn set_velocities(&self, nodes: NodesArg, velocities: &Bound<'_, PyAny>) -> PyResult<()> {
        let (many, one) = points_or_vector(velocities)?;
        self.set_node_field(nodes, many, one, |s| &mut s.nodes.v, "velocities")
    }

    /// Set the velocity of every node of an object, m/s (the Rust `set_velocity`).
    fn set_velocity(&self, nodes: NodesArg, velocity: V3) -> PyResult<()> {
        self.set_node_field(nodes, None, Some(velocity.0), |s| &mut s.nodes.v, "velocities")
    }

    /// Set the external forces on an object's nodes, N (persist until changed): (n, 3) or (3,).
    fn set_forces(&self, nodes: NodesArg, forces: &Bound<'_, PyAny>) -> PyResult<()> {
        let (many, one) = points_or_vector(forces)?;
        self.set_node_field(nodes, many, one, |s| &mut s.nodes.force, "forces")
    }

    /// Set the external accelerations of an object's nodes (added to gravity), m/s²: (n, 3) or (3,).
    fn set_accelerations(&self, nodes: NodesArg, accelerations: &Bound<'_, PyAny>) -> PyResult<()> {
        let (many, one) = points_or_vector(accelerations)?;
        self.set_node_field(nodes, many, one, |s| &mut s.nodes.acceleration, "accelerations")
    }

    // -----------------------------------------------------------------------------------------
    // Deformable objects
    // -----------------------------------------------------------------------------------------

    /// A shell or cloth from vertices (n, 3) and triangles (m, 3).
    fn add_surface(
        &self,
        py: Python<'_>,
        label: &str,
        vertices: Points,
        triangles: Elements<3>,
        material: &Bound<'_, params::SurfaceMaterial>,
    ) -> PyResult<Surface> {
        let m = material.borrow().to_rust(py)?;
        let h = self.with(|s| s.add_surface(label, &vertices.0, &triangles.0, &m))?;
        Surface::new(py, self.id, label, &h)
    }

    /// A rectangular cloth of `size` (m) in the XY plane centred at the origin, `quads` per side.
    fn add_surface_grid(
        &self,
        py: Python<'_>,
        label: &str,
        size: [f64; 2],
        quads: [usize; 2],
        material: &Bound<'_, params::SurfaceMaterial>,
    ) -> PyResult<Surface> {
        let m = material.borrow().to_rust(py)?;
        let h = self.with(|s| s.add_surface_grid(label, size, quads, &m))?;
        Surface::new(py, self.id, label, &h)
    }

    /// A solid from vertices (n, 3) and tets (m, 4).
    fn add_volume(
        &self,
        py: Python<'_>,
        label: &str,
        vertices: Points,
        tets: Elements<4>,
        material: &Bound<'_, params::VolumeMaterial>,
    ) -> PyResult<Volume> {
        let m = material.borrow().to_rust(py)?;
        let h = self.with(|s| s.add_volume(label, &vertices.0, &tets.0, &m))?;
        Ok(Volume::new(self.id, label, &h))
    }

    /// A box of `size` (m) centred at the origin, `hexes` cells per side, 12 tets per cell.
    fn add_volume_grid(
        &self,
        py: Python<'_>,
        label: &str,
        size: [f64; 3],
        hexes: [usize; 3],
        material: &Bound<'_, params::VolumeMaterial>,
    ) -> PyResult<Volume> {
        let m = material.borrow().to_rust(py)?;
        let h = self.with(|s| s.add_volume_grid(label, size, hexes, &m))?;
        Ok(Volume::new(self.id, label, &h))
    }

    /// A rod or cable from vertices (n, 3) and segments (m, 2).
    fn add_line(
        &self,
        py: Python<'_>,
        label: &str,
        vertices: Points,
        segments: Elements<2>,
        material: &Bound<'_, params::LineMaterial>,
    ) -> PyResult<Line> {
        let m = material.borrow().to_rust(py)?;
        let h = self.with(|s| s.add_line(label, &vertices.0, &segments.0, &m))?;
        Ok(Line::new(self.id, label, &h))
    }

    /// A straight line of `n_segments` from `begin` to `end`.
    fn add_line_segments(
        &self,
        py: Python<'_>,
        label: &str,
        begin: V3,
        end: V3,
        n_segments: usize,
        material: &Bound<'_, params::LineMaterial>,
    ) -> PyResult<Line> {
        let m = material.borrow().to_rust(py)?;
        let h = self.with(|s| s.add_line_segments(label, begin.0, end.0, n_segments, &m))?;
        Ok(Line::new(self.id, label, &h))
    }

    /// A kinematic obstacle: a triangle surface whose nodes all follow prescribed targets
    /// (springs of `stiffness` N/m). Move it with `set_transform(obstacle, ...)`.
    #[pyo3(signature = (label, vertices, triangles, thickness_m, stiffness=1e6))]
    fn add_prescribed_surface(
        &self,
        label: &str,
        vertices: Points,
        triangles: Elements<3>,
        thickness_m: f64,
        stiffness: f64,
    ) -> PyResult<Obstacle> {
        let h = self.with(|s| s.add_prescribed_surface(label, &vertices.0, &triangles.0, thickness_m, stiffness))?;
        Ok(Obstacle::new(self.id, label, &h))
    }

    /// A contact surface fixed in the world (a floor, a wall): its nodes never move and are not
    /// unknowns of the solve (unlike `add_prescribed_surface`, it cannot be moved).
    fn add_fixed_surface(
        &self,
        label: &str,
        vertices: Points,
        triangles: Elements<3>,
        thickness_m: f64,
    ) -> PyResult<FixedSurface> {
        let h = self.with(|s| s.add_fixed_surface(label, &vertices.0, &triangles.0, thickness_m))?;
        Ok(FixedSurface::new(self.id, label, &h))
    }

    /// Prescribe the nodes of an object inside the axis-aligned box of `center` and full `size`
    /// (m); selecting no node is an error.
    #[pyo3(signature = (nodes, center, size, params=None))]
    fn prescribe_in_box(
        &self,
        py: Python<'_>,
        nodes: NodesArg,
        center: V3,
        size: V3,
        params: Option<&Bound<'_, params::PrescribedParams>>,
    ) -> PyResult<PrescribedHandle> {
        self.own(&nodes.0)?;
        let p = prescribed_params(py, params)?;
        let h = self.with(|s| s.prescribe_in_box(nodes.0.rust(), center.0, size.0, p))?;
        Ok(PrescribedHandle::new(self.id, h))
    }

    /// Prescribe the nodes of an object outside the axis-aligned box of `center` and `size` (m).
    #[pyo3(signature = (nodes, center, size, params=None))]
    fn prescribe_outside_box(
        &self,
        py: Python<'_>,
        nodes: NodesArg,
        center: V3,
        size: V3,
        params: Option<&Bound<'_, params::PrescribedParams>>,
    ) -> PyResult<PrescribedHandle> {
        self.own(&nodes.0)?;
        let p = prescribed_params(py, params)?;
        let set = nodes.0.rust();
        let h = self.with(|s| {
            let label = s.deformables.sets[set.index as usize].0.clone();
            let (h, n) = s
                .deformables
                .prescribed
                .add_in_box(&s.nodes, set, &label, center.0, size.0, false, p)?;
            if n == 0 {
                return Err(stark::StarkError::InvalidInput(format!(
                    "every node of '{label}' lies inside the box: nothing to prescribe"
                )));
            }
            Ok(h)
        })?;
        Ok(PrescribedHandle::new(self.id, h))
    }

    /// Prescribe the nodes `indices` (local to the object); targets start at their positions.
    #[pyo3(signature = (nodes, indices, params=None))]
    fn prescribe_nodes(
        &self,
        py: Python<'_>,
        nodes: NodesArg,
        indices: Indices,
        params: Option<&Bound<'_, params::PrescribedParams>>,
    ) -> PyResult<PrescribedHandle> {
        self.own(&nodes.0)?;
        let p = prescribed_params(py, params)?;
        let set = nodes.0.rust();
        let h = self.with(|s| {
            let label = s.deformables.sets[set.index as usize].0.clone();
            s.deformables.prescribed.add(&s.nodes, set, &label, &indices.0, p)
        })?;
        Ok(PrescribedHandle::new(self.id, h))
    }

    /// Targets become `R·p + translation` for the reference positions `p` (positions when the
    /// group was added); `rotation` is a quaternion (w, x, y, z) or a (3, 3) matrix.
    #[pyo3(signature = (prescribed, translation, rotation=None))]
    fn set_transform(&self, prescribed: PrescribedArg, translation: V3, rotation: Option<Rot>) -> PyResult<()> {
        self.own(&prescribed.0)?;
        let r = rotation.map(|r| r.0).unwrap_or_else(UnitQuaternion::identity);
        check_finite(&translation.0, "translation")?;
        self.with(|s| {
            s.deformables
                .prescribed
                .set_transform(prescribed.0.rust(), translation.0, r.to_rotation_matrix())
        })
    }

    /// `set_transform` with a rotation by `angle_deg` about `axis` through the origin.
    fn set_transform_deg(&self, prescribed: PrescribedArg, translation: V3, angle_deg: f64, axis: V3) -> PyResult<()> {
        self.own(&prescribed.0)?;
        check_finite(&translation.0, "translation")?;
        if !angle_deg.is_finite() || axis.0.norm() == 0.0 || !axis.0.iter().all(|c| c.is_finite()) {
            return Err(stark_err(format!(
                "angle {angle_deg} and axis {:?} must be finite and the axis non-zero",
                axis.0
            )));
        }
        self.with(|s| {
            s.deformables
                .prescribed
                .set_transform_deg(prescribed.0.rust(), translation.0, angle_deg, axis.0)
        })
    }

    /// Set the target of the `i`-th node of a prescribed group, m.
    fn set_target(&self, prescribed: PrescribedArg, i: usize, target: V3) -> PyResult<()> {
        self.own(&prescribed.0)?;
        check_finite(&target.0, "target")?;
        self.with(|s| s.deformables.prescribed.set_target(prescribed.0.rust(), i, target.0))
    }

    /// Targets of a prescribed group, m: a new (n, 3) array.
    fn targets<'py>(&self, py: Python<'py>, prescribed: PrescribedArg) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
        self.own(&prescribed.0)?;
        let t = self.with(|s| {
            s.deformables
                .prescribed
                .targets(prescribed.0.rust())
                .map(|t| t.to_vec())
        })?;
        Ok(points_out(py, &t))
    }

    /// Global node indices of a prescribed group.
    fn prescribed_nodes(&self, prescribed: PrescribedArg) -> PyResult<Vec<u32>> {
        self.own(&prescribed.0)?;
        self.with(|s| {
            s.deformables
                .prescribed
                .nodes_of(prescribed.0.rust())
                .map(|n| n.to_vec())
        })
    }

    /// Largest distance of a prescribed group's nodes to their targets, m.
    fn max_violation(&self, prescribed: PrescribedArg) -> PyResult<f64> {
        self.own(&prescribed.0)?;
        self.with(|s| {
            s.deformables
                .prescribed
                .max_violation_m(prescribed.0.rust(), &s.nodes.x)
        })
    }

    /// Total mass of an object's inertia group, kg.
    fn mass(&self, inertia: &Bound<'_, PyAny>) -> PyResult<f64> {
        let h = if let Ok(h) = inertia.cast::<InertiaHandle>() {
            *h.get()
        } else {
            inertia
                .getattr("inertia")
                .ok()
                .and_then(|a| a.cast::<InertiaHandle>().ok().map(|h| *h.get()))
                .ok_or_else(|| PyTypeError::new_err("expected an InertiaHandle or an object with inertia"))?
        };
        self.own(&h)?;
        self.with(|s| s.deformables.inertia.mass(h.rust()))
    }

    /// Number of inverted tets at the current positions.
    fn count_inverted_tets(&self) -> PyResult<usize> {
        self.get(|s| s.deformables.tets.count_inverted(&s.nodes.x))
    }
}

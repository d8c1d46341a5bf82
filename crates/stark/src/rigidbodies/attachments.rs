//! Deformable–rigid attachments: deformable nodes glued to points fixed in a rigid body,
//! `½k‖x_node − (t + R·p)‖²`, hardened (stiffness ×2, step retried) while a gap exceeds the
//! tolerance, like the deformable attachments (stark-features §2.4).

use crate::deformables::attachments::harden_out_of_tolerance;
use crate::deformables::{AttachmentParams, Groups, NodeSetHandle};
use crate::energy::potential::{Potential, Stencil};
use crate::energy::term::StepCheck;
use crate::energy::{Node, Scalar, Vec3};
use crate::error::{Result, StarkError};
use crate::geometry::distance::point_triangle_distance_sq;
use crate::rigidbodies::{RigidBodyHandle, RigidMeshHandle};
// Upward on purpose: each model adds its builder methods to `Simulation` in its own
// `impl Simulation` block (the public builder API), so it names the simulation floor.
use crate::simulation::Simulation;
use crate::state::{EvalState, FIXED_NODE, NO_BODY};
use nalgebra::Vector3;

/// A group of nodes glued to a body.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub struct RigidAttachmentHandle(pub u32);

/// All deformable–rigid attachments: element = (body point, node).
#[derive(Default)]
pub struct RigidAttachmentSet {
    groups: Groups<AttachmentParams>,
    ranges: Vec<std::ops::Range<usize>>,
    elements: Vec<[Node; 2]>,
    group: Vec<u32>,
    version: u64,
}

impl RigidAttachmentSet {
    fn gap(&self, e: usize, state: &EvalState) -> f64 {
        let [a, b] = self.elements[e];
        (a.position(state) - b.position(state)).norm()
    }

    /// Largest gap of a group at `state`, m.
    pub fn max_gap_m(&self, h: RigidAttachmentHandle, state: &EvalState) -> Result<f64> {
        let g = self.groups.check("rigid attachment", h.0)?;
        Ok(self.ranges[g].clone().map(|e| self.gap(e, state)).fold(0.0, f64::max))
    }

    /// Largest gap of a group at the bodies' poses and node positions of `sim` (after the last
    /// step), m.
    pub fn max_gap_now_m(&self, h: RigidAttachmentHandle, sim: &Simulation) -> Result<f64> {
        let g = self.groups.check("rigid attachment", h.0)?;
        let world = |n: Node| match n {
            Node::Rigid { body, local } => {
                sim.bodies.position[body as usize] + sim.bodies.orientation[body as usize] * Vector3::from(local)
            }
            Node::Point(i) => sim.nodes.x[i as usize],
            _ => unreachable!("rigid attachments join a body point and a node"),
        };
        Ok(self.ranges[g]
            .clone()
            .map(|e| {
                let [a, b] = self.elements[e];
                (world(a) - world(b)).norm()
            })
            .fold(0.0, f64::max))
    }

    /// Parameters of a group.
    pub fn params(&self, h: RigidAttachmentHandle) -> Result<&AttachmentParams> {
        self.groups.get("rigid attachment", h.0)
    }

    /// Change the parameters of a group (stiffness, tolerance).
    pub fn set_params(&mut self, h: RigidAttachmentHandle, params: AttachmentParams) -> Result<()> {
        self.groups
            .set("rigid attachment", h.0, params, |p, label| p.validate(label))
    }
}

impl RigidAttachmentSet {
    /// Every deformable node attached to a body (global indices, with repeats).
    pub fn attached_nodes(&self) -> impl Iterator<Item = u32> + '_ {
        self.elements.iter().flatten().filter_map(|n| match n {
            Node::Point(i) => Some(*i),
            _ => None,
        })
    }
}

impl Potential<2> for RigidAttachmentSet {
    fn name(&self) -> &str {
        "rigid attachments"
    }
    fn save_state(&self) -> Vec<u8> {
        // Hardened stiffnesses live in the parameters.
        crate::energy::encode_state(&self.groups.params)
    }
    fn restore_state(&mut self, bytes: &[u8]) -> Result<(), String> {
        crate::energy::restore_vec(&mut self.groups.params, crate::energy::decode_state(bytes)?, "groups")
    }
    fn num_elements(&self) -> usize {
        self.elements.len()
    }
    fn nodes(&self, e: usize) -> [Node; 2] {
        self.elements[e]
    }
    fn energy<S: Scalar>(&self, e: usize, x: &[Vec3<S>; 2], _stencil: &Stencil<2>) -> S {
        let k = self.groups.params[self.group[e] as usize].stiffness;
        (x[0] - x[1]).norm_sq() * (0.5 * k)
    }
    fn topology_version(&self) -> u64 {
        self.version
    }
    fn check_converged_step(&mut self, state: &EvalState) -> StepCheck {
        let Self {
            groups,
            ranges,
            elements,
            ..
        } = self;
        let gap = |e: usize| {
            let [a, b] = elements[e];
            (a.position(state) - b.position(state)).norm()
        };
        harden_out_of_tolerance(groups, ranges, gap, "rigid attachments")
    }
}

impl Simulation {
    /// Glue nodes `points` (local indices) of the deformable object `set` to `body` where they
    /// are now.
    pub fn attach_to_body(
        &mut self,
        label: &str,
        body: RigidBodyHandle,
        set: NodeSetHandle,
        points: &[usize],
        params: AttachmentParams,
    ) -> Result<RigidAttachmentHandle> {
        params.validate(label)?;
        let b = self.check_body(body)?;
        if points.is_empty() {
            return Err(StarkError::InvalidInput(format!(
                "rigid attachment '{label}' has no nodes"
            )));
        }
        let mut elements = Vec::with_capacity(points.len());
        for &p in points {
            if p >= set.len as usize {
                return Err(StarkError::InvalidInput(format!(
                    "rigid attachment '{label}': node {p} does not exist ({} nodes)",
                    set.len
                )));
            }
            let i = set.global(p);
            if self.nodes.body[i] != NO_BODY {
                let what = if self.nodes.body[i] == FIXED_NODE {
                    "is fixed in the world"
                } else {
                    "belongs to a rigid body"
                };
                return Err(StarkError::InvalidInput(format!(
                    "rigid attachment '{label}': node {p} {what}"
                )));
            }
            let local = self.body_point_to_local(body, &self.nodes.x[i]);
            elements.push([Node::rigid(b, &local), Node::Point(i as u32)]);
        }
        let s = &mut self.rigid_bodies.attachments.potential;
        let g = s.groups.push(label, params);
        let start = s.elements.len();
        s.group.extend(std::iter::repeat_n(g, elements.len()));
        s.elements.extend(elements);
        s.ranges.push(start..s.elements.len());
        s.version += 1;
        Ok(RigidAttachmentHandle(g))
    }

    /// Glue every node of `set` within `distance_m` of the body's collision mesh `mesh` to the
    /// body where it is now (Stark's `add_by_distance`). Returns the handle and the node count;
    /// selecting no node is an error.
    pub fn attach_to_body_by_distance(
        &mut self,
        label: &str,
        mesh: &RigidMeshHandle,
        mesh_triangles: &[[usize; 3]],
        set: NodeSetHandle,
        distance_m: f64,
        params: AttachmentParams,
    ) -> Result<(RigidAttachmentHandle, usize)> {
        if !(distance_m >= 0.0 && distance_m.is_finite()) {
            return Err(StarkError::InvalidInput(format!(
                "rigid attachment '{label}': distance {distance_m} m must be non-negative"
            )));
        }
        let vertex = |i: usize| -> Vector3<f64> { self.nodes.x[mesh.nodes.global(i)] };
        let d2 = distance_m * distance_m;
        let points: Vec<usize> = (0..set.len as usize)
            .filter(|&p| {
                let x = self.nodes.x[set.global(p)];
                mesh_triangles
                    .iter()
                    .any(|t| point_triangle_distance_sq(&x, &vertex(t[0]), &vertex(t[1]), &vertex(t[2])) <= d2)
            })
            .collect();
        if points.is_empty() {
            return Err(StarkError::InvalidInput(format!(
                "rigid attachment '{label}': no node lies within {distance_m} m of the body's mesh"
            )));
        }
        let n = points.len();
        Ok((self.attach_to_body(label, mesh.body, set, &points, params)?, n))
    }
}

//! Simulation state: the flat node arrays of all deformables and the view of one Newton iterate
//! that energies evaluate.

use nalgebra::{Matrix3, UnitQuaternion, Vector3};

/// `NodeArrays::body` of a deformable node: it is not attached to a rigid body.
pub const NO_BODY: u32 = u32::MAX;

/// `NodeArrays::body` of a node fixed in the world (a static obstacle's vertex): it never moves,
/// its velocity is not an unknown, and the derivatives of energies with respect to it are
/// dropped (a fixed floor couples nothing through the Hessian, unlike one held by a penalty).
pub const FIXED_NODE: u32 = u32::MAX - 1;

/// The rigid body of a `NodeArrays::body` entry: `None` for deformable and fixed nodes.
#[inline]
pub fn rigid_body_of(body: u32) -> Option<usize> {
    (body < FIXED_NODE).then_some(body as usize)
}

/// A DOF block that is not there: padding of an element's stencil, or a rigid node's block in
/// [`DofMap::dof_of_block`].
pub const NO_DOF: u32 = u32::MAX;

/// A contiguous range of deformable nodes: one object.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub struct NodeSetHandle {
    /// Index of the set.
    pub index: u32,
    /// First node in the simulation's node arrays.
    pub first: u32,
    /// Number of nodes.
    pub len: u32,
}

impl NodeSetHandle {
    /// Global index of local node `i`.
    #[inline]
    pub fn global(&self, i: usize) -> usize {
        self.first as usize + i
    }
    /// Global node range.
    pub fn range(&self) -> std::ops::Range<usize> {
        self.first as usize..(self.first + self.len) as usize
    }
}

/// Cells of an output mesh, in indices local to its node set.
#[derive(Clone, Debug)]
pub enum OutputCells {
    /// Just the nodes.
    Points,
    /// Segments.
    Segments(Vec<[usize; 2]>),
    /// Triangles.
    Triangles(Vec<[usize; 3]>),
    /// Tetrahedra.
    Tets(Vec<[usize; 4]>),
}

/// All deformable nodes of a simulation in one flat set of arrays (segmented per object by
/// [`NodeSetHandle`]).
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct NodeArrays {
    /// Rest (material) positions `X`, m.
    pub rest: Vec<Vector3<f64>>,
    /// Positions at the start of the current step (the committed state), m.
    pub x: Vec<Vector3<f64>>,
    /// Velocities at the start of the current step, m/s.
    pub v: Vec<Vector3<f64>>,
    /// External force per node, N. Persists until changed.
    pub force: Vec<Vector3<f64>>,
    /// External acceleration per node (added to gravity), m/s². Persists until changed.
    pub acceleration: Vec<Vector3<f64>>,
    /// The rigid body a node belongs to ([`NO_BODY`] for deformable nodes, [`FIXED_NODE`] for
    /// nodes fixed in the world). A rigid node is a vertex of a body's collision mesh: its `rest`
    /// is its body-local position and its position follows the body (its own DOF block stays
    /// zero and is not an unknown: [`DofMap`]); a fixed node stays where it is.
    #[serde(default)]
    pub body: Vec<u32>,
}

impl NodeArrays {
    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.x.len()
    }
    /// No nodes.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }
    /// Append nodes at rest at `positions`; returns the index of the first.
    pub fn push(&mut self, positions: &[Vector3<f64>]) -> usize {
        let first = self.x.len();
        self.body.resize(first + positions.len(), NO_BODY);
        self.rest.extend_from_slice(positions);
        self.x.extend_from_slice(positions);
        self.v.extend(std::iter::repeat_n(Vector3::zeros(), positions.len()));
        self.force
            .extend(std::iter::repeat_n(Vector3::zeros(), positions.len()));
        self.acceleration
            .extend(std::iter::repeat_n(Vector3::zeros(), positions.len()));
        first
    }
}

/// Start-of-step state of all rigid bodies, one entry per body in each array.
///
/// A body's frame has its origin at the centre of mass; its collision-mesh vertices and joint
/// anchors are stored in that frame.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct BodyArrays {
    /// Centre of mass, m.
    pub position: Vec<Vector3<f64>>,
    /// Orientation (body → world).
    pub orientation: Vec<UnitQuaternion<f64>>,
    /// Linear velocity of the centre of mass, m/s.
    pub velocity: Vec<Vector3<f64>>,
    /// Angular velocity (world frame), rad/s.
    pub angular_velocity: Vec<Vector3<f64>>,
    /// Mass, kg.
    pub mass: Vec<f64>,
    /// Inertia tensor about the centre of mass in the body frame, kg·m².
    pub inertia_local: Vec<Matrix3<f64>>,
    /// External force at the centre of mass (world), N. Persists until changed.
    pub force: Vec<Vector3<f64>>,
    /// External torque (world), N·m. Persists until changed.
    pub torque: Vec<Vector3<f64>>,
    /// External acceleration (added to gravity), m/s². Persists until changed.
    pub acceleration: Vec<Vector3<f64>>,
    /// External angular acceleration, rad/s². Persists until changed.
    pub angular_acceleration: Vec<Vector3<f64>>,
}

impl BodyArrays {
    /// Number of bodies.
    pub fn len(&self) -> usize {
        self.position.len()
    }
    /// No bodies.
    pub fn is_empty(&self) -> bool {
        self.position.is_empty()
    }
    /// Rotation matrix of body `b` at the start of the step.
    pub fn rotation(&self, b: usize) -> Matrix3<f64> {
        self.orientation[b].to_rotation_matrix().into_inner()
    }
    /// World inertia tensor `R J Rᵀ` of body `b` at the start of the step, kg·m².
    pub fn inertia_world(&self, b: usize) -> Matrix3<f64> {
        let r = self.rotation(b);
        r * self.inertia_local[b] * r.transpose()
    }
}

/// DOF block of the linear velocity of body `b` when there are `n_nodes` nodes. DOF blocks are
/// the node blocks followed by two blocks (linear, angular) per body.
#[inline]
pub fn linear_block(n_nodes: usize, b: usize) -> u32 {
    (n_nodes + 2 * b) as u32
}

/// DOF block of the angular velocity of body `b` (see [`linear_block`]).
#[inline]
pub fn angular_block(n_nodes: usize, b: usize) -> u32 {
    (n_nodes + 2 * b + 1) as u32
}

/// What DOF block `block` is when there are `n_nodes` nodes (the inverse of [`linear_block`] and
/// [`angular_block`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BlockKind {
    /// Node `i`'s velocity.
    Node(usize),
    /// Body `b`'s linear velocity.
    Linear(usize),
    /// Body `b`'s angular velocity.
    Angular(usize),
}

/// See [`BlockKind`].
#[inline]
pub fn block_kind(n_nodes: usize, block: usize) -> BlockKind {
    match block.checked_sub(n_nodes) {
        None => BlockKind::Node(block),
        Some(k) if k.is_multiple_of(2) => BlockKind::Linear(k / 2),
        Some(k) => BlockKind::Angular(k / 2),
    }
}

/// Trial pose of a rigid body and the derivatives of its rotation with respect to `ω`. Made by
/// the kinematic map (`BodyPose::new` and `BodyPose::at_rest` in `energy::kinematics`).
#[derive(Clone, Copy, Debug)]
pub struct BodyPose {
    /// Centre of mass, m.
    pub t: Vector3<f64>,
    /// Rotation matrix.
    pub r: Matrix3<f64>,
    /// `∂R/∂ω_k`, s.
    pub dr: [Matrix3<f64>; 3],
    /// `∂²R/∂ω_k∂ω_l`, s².
    pub d2r: [[Matrix3<f64>; 3]; 3],
}

impl BodyPose {
    /// World position of the body-local point `p`.
    #[inline]
    pub fn point(&self, p: &Vector3<f64>) -> Vector3<f64> {
        self.t + self.r * p
    }

    /// `∂x/∂ω` of the body-local point `p` (columns `∂R/∂ω_k · p`).
    #[inline]
    pub fn point_jacobian_w(&self, p: &Vector3<f64>) -> Matrix3<f64> {
        Matrix3::from_columns(&[self.dr[0] * p, self.dr[1] * p, self.dr[2] * p])
    }
}

/// The state at one Newton iterate: start-of-step state plus the trial end-of-step velocities.
///
/// Positions are functions of the unknown velocities (backward Euler, DESIGN §2): a deformable node
/// is at `x = x0 + dt·v`.
pub struct EvalState<'a> {
    /// Time step, s.
    pub dt: f64,
    /// Time at the end of the step, s.
    pub time: f64,
    /// Gravity, m/s².
    pub gravity: Vector3<f64>,
    /// Start-of-step node state.
    pub nodes: &'a NodeArrays,
    /// Trial end-of-step DOF velocities: one block per node (m/s; zero for rigid nodes), then
    /// linear (m/s) and angular (rad/s) velocity per body.
    pub v: &'a [Vector3<f64>],
    /// Trial end-of-step node positions (`x0 + dt·v`, or on their body), m.
    pub x: &'a [Vector3<f64>],
    /// Start-of-step rigid bodies.
    pub bodies: &'a BodyArrays,
    /// Trial end-of-step pose of each body.
    pub poses: &'a [BodyPose],
}

impl EvalState<'_> {
    /// Start-of-step position of node `i`.
    #[inline]
    pub fn x0(&self, i: usize) -> Vector3<f64> {
        self.nodes.x[i]
    }
}

impl EvalState<'_> {
    /// Number of nodes (the first DOF blocks).
    #[inline]
    pub fn n_nodes(&self) -> usize {
        self.nodes.len()
    }
    /// Trial linear velocity of body `b`, m/s.
    #[inline]
    pub fn body_velocity(&self, b: usize) -> Vector3<f64> {
        self.v[linear_block(self.n_nodes(), b) as usize]
    }
    /// Trial angular velocity of body `b`, rad/s.
    #[inline]
    pub fn body_angular_velocity(&self, b: usize) -> Vector3<f64> {
        self.v[angular_block(self.n_nodes(), b) as usize]
    }
}

/// Positions `x0 + dt·v` for all deformable nodes (only; rigid nodes are placed by
/// `energy::kinematics::apply_kinematic_map`: plain text, state links no higher module).
pub fn positions_from_velocities(nodes: &NodeArrays, v: &[Vector3<f64>], dt: f64, out: &mut Vec<Vector3<f64>>) {
    use rayon::prelude::*;
    out.resize(nodes.len(), Vector3::zeros());
    out.par_iter_mut()
        .zip(nodes.x.par_iter().zip(v[..nodes.len()].par_iter()))
        .for_each(|(x, (x0, v))| *x = x0 + v * dt);
}

/// The start-of-step DOF velocities: node velocities (zero for rigid nodes), then per body its
/// linear and angular velocity.
pub fn start_velocities(nodes: &NodeArrays, bodies: &BodyArrays, out: &mut Vec<Vector3<f64>>) {
    out.clear();
    out.extend(
        nodes
            .v
            .iter()
            .zip(&nodes.body)
            .map(|(v, &b)| if b == NO_BODY { *v } else { Vector3::zeros() }),
    );
    for b in 0..bodies.len() {
        out.push(bodies.velocity[b]);
        out.push(bodies.angular_velocity[b]);
    }
}

/// Number of DOF blocks of a state: one per node, two per body.
pub fn dof_blocks(nodes: &NodeArrays, bodies: &BodyArrays) -> usize {
    nodes.len() + 2 * bodies.len()
}

/// Which DOF blocks are unknowns of the linear system.
///
/// Velocities are stored per block (one per node, two per body: [`dof_blocks`]) so that energies
/// index them by node. A rigid node (a vertex of a body's collision mesh) follows its body
/// through the kinematic map: its own block is always zero and is not an unknown. The solver's
/// gradient, matrix and step are over the unknowns only, in block order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DofMap {
    /// The block of each unknown.
    pub block_of_dof: Vec<u32>,
    /// The unknown of each block ([`NO_DOF`] for rigid and fixed nodes).
    pub dof_of_block: Vec<u32>,
}

impl DofMap {
    /// The unknowns of a state: every deformable node's block and both blocks of every body.
    pub fn new(nodes: &NodeArrays, bodies: &BodyArrays) -> Self {
        let n_blocks = dof_blocks(nodes, bodies);
        let mut map = DofMap {
            block_of_dof: Vec::with_capacity(n_blocks),
            dof_of_block: vec![NO_DOF; n_blocks],
        };
        // Rigid and fixed nodes.
        let not_deformable = |i: usize| nodes.body.get(i).is_some_and(|&b| b != NO_BODY);
        for block in 0..n_blocks {
            if block < nodes.len() && not_deformable(block) {
                continue;
            }
            map.dof_of_block[block] = map.block_of_dof.len() as u32;
            map.block_of_dof.push(block as u32);
        }
        map
    }

    /// Number of unknown blocks (three scalar unknowns each).
    pub fn len(&self) -> usize {
        self.block_of_dof.len()
    }

    /// No unknowns.
    pub fn is_empty(&self) -> bool {
        self.block_of_dof.is_empty()
    }

    /// Number of DOF blocks (unknown or not).
    pub fn n_blocks(&self) -> usize {
        self.dof_of_block.len()
    }
}

//! Energies written in world positions, and the wrapper that turns them into solver terms.
//!
//! A [`Potential`] is the one thing a model writes: for each element, the world positions of its
//! `N` nodes go in and a scalar energy comes out, generic over the [`Scalar`] type. It does not
//! know whether a node is a cloth vertex or (later) a point on a rigid body: [`PotentialTerm`]
//! applies the kinematic map (DESIGN §2, paper eq. 1: `f = −Gᵀ ∂Ψ/∂x`), takes derivatives (generated
//! kernels where the potential supplies them, hyper-duals otherwise), projects element Hessians
//! and writes them in DOF space.

use super::dual::HyperDual;
use super::kinematics::{count_blocks, element_blocks, map_element, DeformableRow, MapProjection, NodeMap};
use super::psd::project_psd;
use super::scalar::Scalar;
use super::tensor::Vec3;
use super::term::{width_of_stride, EnergyTerm, EvalMode, StepCheck, NO_DOF};
use crate::state::{angular_block, linear_block, EvalState, FIXED_NODE, NO_BODY};
use nalgebra::Vector3;
use rayon::prelude::*;
use std::sync::Mutex;

/// A node of an element stencil: something with a world position that the kinematic map
/// connects to DOFs.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Node {
    /// A node of the simulation's node arrays: a deformable node (its DOF block is its velocity,
    /// `∂x/∂v = dt·I`) or a rigid body's mesh vertex (it moves with its body).
    Point(u32),
    /// A point fixed in a rigid body: body index and body-local position (m, relative to the
    /// centre of mass). Joints are written on these.
    Rigid {
        /// Body index.
        body: u32,
        /// Body-local position, m.
        local: [f64; 3],
    },
    /// The angular velocity of a body (rad/s) in place of a position: its "position" is `ω` and
    /// its start value `ω0` (velocity controllers are written on it).
    AngularVelocity(u32),
    /// A fixed point of the world, m (no DOFs): the other side of a joint to the world.
    World([f64; 3]),
}

impl Node {
    /// The node-array index of a [`Node::Point`].
    ///
    /// # Panics
    /// For other nodes.
    #[inline]
    pub fn index(&self) -> usize {
        match *self {
            Node::Point(i) => i as usize,
            _ => panic!("not a node-array point: {self:?}"),
        }
    }

    /// A rigid-body point.
    pub fn rigid(body: usize, local: &Vector3<f64>) -> Self {
        Node::Rigid {
            body: body as u32,
            local: [local.x, local.y, local.z],
        }
    }

    /// How the node depends on the DOFs in `state`.
    #[inline]
    pub fn map<'s>(&self, state: &'s EvalState) -> NodeMap<'s> {
        let n = state.n_nodes();
        match *self {
            Node::Point(i) => {
                let b = state.nodes.body[i as usize];
                if b == NO_BODY {
                    NodeMap::Free { block: i }
                } else if b == FIXED_NODE {
                    NodeMap::Fixed
                } else {
                    NodeMap::Rigid {
                        lin: linear_block(n, b as usize),
                        ang: angular_block(n, b as usize),
                        local: state.nodes.rest[i as usize],
                        pose: &state.poses[b as usize],
                    }
                }
            }
            Node::Rigid { body, local } => NodeMap::Rigid {
                lin: linear_block(n, body as usize),
                ang: angular_block(n, body as usize),
                local: Vector3::from(local),
                pose: &state.poses[body as usize],
            },
            Node::AngularVelocity(body) => NodeMap::AngularVelocity {
                ang: angular_block(n, body as usize),
            },
            Node::World(_) => NodeMap::Fixed,
        }
    }

    /// Trial end-of-step position in `state`.
    #[inline]
    pub fn position(&self, state: &EvalState) -> Vector3<f64> {
        match *self {
            Node::Point(i) => state.x[i as usize],
            Node::Rigid { body, local } => state.poses[body as usize].point(&Vector3::from(local)),
            Node::AngularVelocity(body) => state.body_angular_velocity(body as usize),
            Node::World(p) => Vector3::from(p),
        }
    }

    /// Start-of-step position in `state`.
    #[inline]
    pub fn start_position(&self, state: &EvalState) -> Vector3<f64> {
        match *self {
            Node::Point(i) => state.nodes.x[i as usize],
            Node::Rigid { body, local } => {
                let b = body as usize;
                state.bodies.position[b] + state.bodies.orientation[b] * Vector3::from(local)
            }
            Node::AngularVelocity(body) => state.bodies.angular_velocity[body as usize],
            Node::World(p) => Vector3::from(p),
        }
    }

    /// Whether the node is a deformable node (`∂x/∂v = dt·I` on its own block).
    #[inline]
    pub fn is_free(&self, state: &EvalState) -> bool {
        matches!(*self, Node::Point(i) if state.nodes.body[i as usize] == NO_BODY)
    }
}

/// The data an element energy may read besides the differentiated positions.
pub struct Stencil<'a, const N: usize> {
    /// The nodes.
    pub nodes: [Node; N],
    /// Trial end-of-step positions, m (the values of the differentiated variables).
    pub x: [Vector3<f64>; N],
    /// Start-of-step positions, m.
    pub x0: [Vector3<f64>; N],
    /// Time step, s.
    pub dt: f64,
    /// The whole state (velocities, gravity, time).
    pub state: &'a EvalState<'a>,
}

impl<'a, const N: usize> Stencil<'a, N> {
    /// Gather the stencil of `nodes` from `state`.
    #[inline]
    pub fn new(nodes: [Node; N], state: &'a EvalState<'a>) -> Self {
        Stencil {
            nodes,
            x: nodes.map(|n| n.position(state)),
            x0: nodes.map(|n| n.start_position(state)),
            dt: state.dt,
            state,
        }
    }

    /// Positions as constants of scalar type `S`.
    #[inline]
    pub fn x_as<S: Scalar>(&self) -> [Vec3<S>; N] {
        self.x.map(|p| Vec3::constant(&p))
    }
}

/// What a fast derivative path produced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FastDerivatives {
    /// No fast path: use hyper-duals.
    Unavailable,
    /// The exact Hessian.
    Exact,
    /// A Hessian already projected to positive semi-definite.
    Projected,
}

/// An energy defined per element on `N` nodes, written in world positions.
///
/// Implement [`Potential::energy`] once, generically; register the potential with
/// `Simulation::add_potential` (it is wrapped in a [`PotentialTerm`]). Optionally supply
/// [`Potential::derivatives`] from generated code for speed; tests compare it with the hyper-dual
/// derivatives of `energy`.
pub trait Potential<const N: usize>: Send + Sync {
    /// Name used in logs and errors.
    fn name(&self) -> &str;
    /// Number of elements.
    fn num_elements(&self) -> usize;
    /// Nodes of element `e`.
    fn nodes(&self, e: usize) -> [Node; N];
    /// Energy of element `e` at positions `x` (J).
    fn energy<S: Scalar>(&self, e: usize, x: &[Vec3<S>; N], stencil: &Stencil<N>) -> S;
    /// Value, gradient and full Hessian with respect to `x` from a fast path (generated code),
    /// written into `out` (hyper-dual layout, both triangles). With `project`, the energy may
    /// project the Hessian itself (e.g. in deformation-gradient space, which is cheaper) and say
    /// so. The default uses hyper-duals.
    fn derivatives(
        &self,
        _e: usize,
        _stencil: &Stencil<N>,
        _project: bool,
        _out: &mut HyperDual<N>,
    ) -> FastDerivatives {
        FastDerivatives::Unavailable
    }
    /// Value, gradient and Hessian of element `e`, whose nodes are all deformable, written
    /// straight into its DOF-space row by a closed form that needs no projection (`project` is
    /// whether the caller wants the Hessian projected); `false`, with nothing written, where
    /// there is none (then [`derivatives`](Self::derivatives) serves). This skips the hyper-dual
    /// in between: for a tet, zeroing and copying it cost a third of its derivatives.
    fn write_deformable(&self, _e: usize, _stencil: &Stencil<N>, _project: bool, _row: &mut DeformableRow) -> bool {
        false
    }
    /// See [`EnergyTerm::topology_version`].
    fn topology_version(&self) -> u64 {
        0
    }
    /// The element Hessians are positive semi-definite everywhere (a convex energy, e.g. a
    /// quadratic spring): projection is skipped.
    fn is_convex(&self) -> bool {
        false
    }
    /// Element `e`'s Hessian in world positions is positive semi-definite everywhere. On rigid
    /// bodies its Hessian in their velocities is then projected only in each body's 3×3
    /// second-order rotation term ([`MapProjection::SecondOrderOnly`]) instead of whole.
    fn is_element_convex(&self, _e: usize) -> bool {
        self.is_convex()
    }
    /// See [`EnergyTerm::before_step`].
    fn before_step(&mut self, _state: &EvalState) {}
    /// See [`EnergyTerm::check_converged_step`].
    fn check_converged_step(&mut self, _state: &EvalState) -> StepCheck {
        StepCheck::Accept
    }
    /// See [`EnergyTerm::after_step`].
    fn after_step(&mut self, _state: &EvalState) {}
    /// See [`EnergyTerm::save_state`].
    fn save_state(&self) -> Vec<u8> {
        Vec::new()
    }
    /// See [`EnergyTerm::restore_state`].
    fn restore_state(&mut self, _bytes: &[u8]) -> Result<(), String> {
        Ok(())
    }
}

/// Value, gradient and Hessian of element `e` with respect to its node positions, by hyper-duals
/// (the oracle) — both Hessian triangles filled.
pub fn dual_derivatives<P: Potential<N>, const N: usize>(p: &P, e: usize, stencil: &Stencil<N>) -> HyperDual<N> {
    let xs = HyperDual::<N>::variables(&stencil.x);
    let mut d = p.energy(e, &xs, stencil);
    symmetrize(&mut d);
    d
}

/// A generated kernel: `(x, p, grad, hess) -> value` on flat slices.
pub type Kernel = fn(&[f64], &[f64], &mut [f64], &mut [f64]) -> f64;

/// Run a generated kernel on the stencil positions, writing value, gradient and Hessian to `out`.
pub fn run_kernel<const N: usize>(
    kernel: Kernel,
    x: &[Vector3<f64>; N],
    params: &[f64],
    out: &mut HyperDual<N>,
) -> FastDerivatives {
    let mut flat = [0.0; 12];
    super::tensor::flat_from_points(x, &mut flat);
    out.value = kernel(
        &flat[..3 * N],
        params,
        out.grad.as_flattened_mut(),
        out.hess.as_flattened_mut().as_flattened_mut().as_flattened_mut(),
    );
    FastDerivatives::Exact
}

/// Element derivatives by the fastest available path, written into `out`; returns whether the
/// Hessian is already projected.
pub fn element_derivatives<P: Potential<N>, const N: usize>(
    p: &P,
    e: usize,
    stencil: &Stencil<N>,
    project: bool,
    out: &mut HyperDual<N>,
) -> bool {
    match p.derivatives(e, stencil, project, out) {
        FastDerivatives::Exact => false,
        FastDerivatives::Projected => true,
        FastDerivatives::Unavailable => {
            *out = dual_derivatives(p, e, stencil);
            false
        }
    }
}

/// Copy the upper triangle of a hyper-dual Hessian to the lower.
pub fn symmetrize<const N: usize>(d: &mut HyperDual<N>) {
    let n = 3 * N;
    let h = d.hess.as_flattened_mut().as_flattened_mut().as_flattened_mut();
    for i in 0..n {
        for j in 0..i {
            h[i * n + j] = h[j * n + i];
        }
    }
}

/// Sum `f(0) + … + f(n−1)` in parallel, in a fixed order (independent of the thread count).
pub fn deterministic_sum(n: usize, f: impl Fn(usize) -> f64 + Sync) -> f64 {
    const CHUNK: usize = 512;
    if n <= CHUNK {
        return (0..n).map(f).sum();
    }
    let parts: Vec<f64> = (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| (c * CHUNK..n.min((c + 1) * CHUNK)).map(&f).sum())
        .collect();
    parts.iter().sum()
}

/// Identity of the element set a stencil width was computed for:
/// (topology version, elements, nodes, bodies).
type WidthKey = (u64, usize, usize, usize);

/// A [`Potential`] as a solver [`EnergyTerm`].
pub struct PotentialTerm<P, const N: usize> {
    /// The wrapped potential.
    pub potential: P,
    /// Most DOF blocks of an element (`N` unless elements touch rigid bodies), cached.
    width: Mutex<Option<(WidthKey, usize)>>,
}

impl<P, const N: usize> PotentialTerm<P, N> {
    /// Wrap a potential.
    pub fn new(potential: P) -> Self {
        PotentialTerm {
            potential,
            width: Mutex::new(None),
        }
    }
}

impl<P: Potential<N>, const N: usize> PotentialTerm<P, N> {
    /// Whether an element's `nodes` are all deformable (`∂x/∂v = dt·I` on their own blocks).
    fn all_free(nodes: &[Node; N], state: &EvalState) -> bool {
        state.bodies.is_empty() || nodes.iter().all(|n| n.is_free(state))
    }
}

impl<P, const N: usize> std::ops::Deref for PotentialTerm<P, N> {
    type Target = P;
    fn deref(&self) -> &P {
        &self.potential
    }
}
impl<P, const N: usize> std::ops::DerefMut for PotentialTerm<P, N> {
    fn deref_mut(&mut self) -> &mut P {
        &mut self.potential
    }
}

impl<P: Potential<N>, const N: usize> EnergyTerm for PotentialTerm<P, N> {
    fn name(&self) -> &str {
        self.potential.name()
    }
    fn num_elements(&self) -> usize {
        self.potential.num_elements()
    }
    fn stencil_width(&self, state: &EvalState) -> usize {
        let n = self.potential.num_elements();
        let key = (
            self.potential.topology_version(),
            n,
            state.n_nodes(),
            state.bodies.len(),
        );
        let mut cache = self.width.lock().expect("no poisoned lock");
        if let Some((k, w)) = *cache {
            if k == key {
                return w;
            }
        }
        let w = if state.bodies.is_empty() {
            N
        } else {
            (0..n)
                .into_par_iter()
                .map(|e| {
                    let nodes = self.potential.nodes(e);
                    if Self::all_free(&nodes, state) {
                        N
                    } else {
                        count_blocks(&nodes.map(|node| node.map(state)))
                    }
                })
                .max()
                .unwrap_or(N)
                .max(N)
        };
        *cache = Some((key, w));
        w
    }
    fn write_stencils(&self, state: &EvalState, out: &mut [u32]) {
        let w = self.stencil_width(state);
        out.par_chunks_mut(w).enumerate().for_each(|(e, o)| {
            let nodes = self.potential.nodes(e);
            if Self::all_free(&nodes, state) {
                o.iter_mut().for_each(|s| *s = NO_DOF);
                for (slot, node) in o.iter_mut().zip(nodes) {
                    *slot = node.index() as u32;
                }
            } else {
                element_blocks(&nodes.map(|node| node.map(state)), o);
            }
        });
    }
    fn topology_version(&self) -> u64 {
        self.potential.topology_version()
    }
    fn energy(&self, state: &EvalState) -> f64 {
        deterministic_sum(self.potential.num_elements(), |e| {
            let stencil = Stencil::new(self.potential.nodes(e), state);
            let x = stencil.x_as::<f64>();
            self.potential.energy(e, &x, &stencil)
        })
    }
    fn evaluate_element(&self, e: usize, state: &EvalState, mode: EvalMode, o: &mut [f64]) {
        let dt = state.dt;
        let n = 3 * N;
        let project = mode == EvalMode::ProjectedHessian && !self.potential.is_convex();
        let stencil = Stencil::new(self.potential.nodes(e), state);
        let all_free = Self::all_free(&stencil.nodes, state);
        if all_free
            && self
                .potential
                .write_deformable(e, &stencil, project, &mut DeformableRow::new(N, dt, o))
        {
            return;
        }
        let mut d = HyperDual::<N>::constant(0.0);
        if !all_free {
            // Rigid nodes: chain rule through the kinematic map, projected in DOF space (the
            // second-order rotation term belongs in the Hessian before projection, DESIGN §2).
            // The exact element Hessian is needed before the map (generated or JIT kernels
            // where the potential has them, hyper-duals otherwise).
            element_derivatives(&self.potential, e, &stencil, false, &mut d);
            let maps: [NodeMap; N] = stencil.nodes.map(|node| node.map(state));
            // A convex element's `JᵀHJ` is positive semi-definite already: only the rotation's
            // second-order terms need projecting.
            let projection = match (mode == EvalMode::ProjectedHessian, self.potential.is_element_convex(e)) {
                (false, _) => MapProjection::None,
                (true, true) => MapProjection::SecondOrderOnly,
                (true, false) => MapProjection::Full,
            };
            map_element(&maps, &d, dt, width_of_stride(o.len()), projection, o);
            return;
        }
        let projected = element_derivatives(&self.potential, e, &stencil, project, &mut d);
        // Deformable map: ∂x/∂v = dt·I, so ∇ᵥ = dt ∇ₓ and Hᵥ = dt² Hₓ (projection commutes with
        // the positive scaling). This is `kinematics::write_deformable_element`, kept inline here:
        // the call measured 4–8% slower on hanging_deformable_box (BENCHMARKS.md).
        let h = d.hess.as_flattened_mut().as_flattened_mut().as_flattened_mut();
        if project && !projected {
            project_psd(h, n);
        }
        o[0] = d.value;
        for (k, g) in d.grad.as_flattened().iter().enumerate() {
            o[1 + k] = dt * g;
        }
        let dt2 = dt * dt;
        // The term's width exceeds N when other elements touch rigid bodies.
        let w = width_of_stride(o.len());
        if w > N {
            o[1 + n..].iter_mut().for_each(|v| *v = 0.0);
        }
        let base = 1 + 3 * w;
        for a in 0..N {
            for b in 0..N {
                let blk = &mut o[base + 9 * (a * w + b)..base + 9 * (a * w + b) + 9];
                for i in 0..3 {
                    for j in 0..3 {
                        blk[3 * i + j] = dt2 * h[(3 * a + i) * n + 3 * b + j];
                    }
                }
            }
        }
    }
    fn before_step(&mut self, state: &EvalState) {
        self.potential.before_step(state)
    }
    fn check_converged_step(&mut self, state: &EvalState) -> StepCheck {
        self.potential.check_converged_step(state)
    }
    fn after_step(&mut self, state: &EvalState) {
        self.potential.after_step(state)
    }
    fn save_state(&self) -> Vec<u8> {
        self.potential.save_state()
    }
    fn restore_state(&mut self, bytes: &[u8]) -> Result<(), String> {
        self.potential.restore_state(bytes)
    }
}

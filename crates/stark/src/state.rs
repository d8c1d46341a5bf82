//! Simulation state: the flat node arrays of all deformables and the view of one Newton iterate
//! that energies evaluate.

use nalgebra::Vector3;

/// All deformable nodes of a simulation in one flat set of arrays (segmented per object by
/// [`NodeSetHandle`](crate::deformables::NodeSetHandle)).
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
    /// Trial end-of-step node velocities `v`, m/s.
    pub v: &'a [Vector3<f64>],
    /// Trial end-of-step node positions `x0 + dt·v`, m.
    pub x: &'a [Vector3<f64>],
}

impl EvalState<'_> {
    /// Start-of-step position of node `i`.
    #[inline]
    pub fn x0(&self, i: usize) -> Vector3<f64> {
        self.nodes.x[i]
    }
}

/// Positions `x0 + dt·v` for all nodes.
pub fn positions_from_velocities(nodes: &NodeArrays, v: &[Vector3<f64>], dt: f64, out: &mut Vec<Vector3<f64>>) {
    use rayon::prelude::*;
    out.resize(v.len(), Vector3::zeros());
    out.par_iter_mut()
        .zip(nodes.x.par_iter().zip(v.par_iter()))
        .for_each(|(x, (x0, v))| *x = x0 + v * dt);
}

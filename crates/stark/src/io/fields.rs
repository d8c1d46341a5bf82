//! Fields written with the frames: per cell, strain and stress measures; per node, contact
//! force and whether the node is prescribed or attached.

use nalgebra::Vector3;

// CellFields is computed by the strain energies (models floor), so it lives in energy;
// re-exported here for the writers and the public path.
pub use crate::energy::cell_fields::CellFields;

/// Per-node data of a frame, over all nodes of the simulation.
#[derive(Clone, Debug, Default)]
pub struct NodeFields {
    /// Contact (barrier) force on each node, N.
    pub contact_force_n: Vec<Vector3<f64>>,
    /// The node has a prescribed target.
    pub prescribed: Vec<bool>,
    /// The node is attached (to another node, an edge, a triangle or a rigid body).
    pub attached: Vec<bool>,
}

//! Deformable bodies: node sets and the energies defined on them (one file each).
//!
//! All deformable nodes live in one flat set of arrays ([`NodeArrays`](crate::state::NodeArrays));
//! a [`NodeSetHandle`] names the contiguous range of one object. Energies are added per object
//! ("group") with their own parameters and return a typed handle for reading and changing them.

pub mod attachments;
pub mod dihedral_bending;
pub mod flat_bending;
pub mod inertia;
pub mod prescribed_positions;
pub mod segment_strain;
pub mod tet_strain;
pub mod triangle_strain;

use crate::energy::PotentialTerm;
use crate::error::{Result, StarkError};

pub use attachments::{AttachmentHandle, AttachmentParams, Attachments};
pub use dihedral_bending::{DihedralBending, DihedralBendingHandle, DihedralBendingParams};
pub use flat_bending::{FlatBending, FlatBendingHandle, FlatBendingParams};
pub use inertia::{InertiaHandle, InertiaParams, LumpedInertia};
pub use prescribed_positions::{PrescribedHandle, PrescribedParams, PrescribedPositions};
pub use segment_strain::{SegmentStrain, SegmentStrainHandle, SegmentStrainParams};
pub use tet_strain::{TetStrain, TetStrainHandle, TetStrainParams};
pub use triangle_strain::{TriangleStrain, TriangleStrainHandle, TriangleStrainParams};

// Defined in state (contact uses it too and sits beside deformables); re-exported here.
pub use crate::state::NodeSetHandle;

/// Map local element indices of `set` to global node indices, checking bounds.
pub(crate) fn globalize<const K: usize>(
    set: &NodeSetHandle,
    label: &str,
    kind: &'static str,
    elements: &[[usize; K]],
) -> Result<Vec<[u32; K]>> {
    elements
        .iter()
        .enumerate()
        .map(|(index, el)| {
            let mut out = [0u32; K];
            for (o, &node) in out.iter_mut().zip(el) {
                if node >= set.len as usize {
                    return Err(StarkError::NodeOutOfRange {
                        object: label.to_string(),
                        kind,
                        index,
                        node,
                        n_nodes: set.len as usize,
                    });
                }
                *o = set.global(node) as u32;
            }
            Ok(out)
        })
        .collect()
}

/// Per-group labels and parameters of a model (one group per `add` call).
#[derive(Clone, Debug, Default)]
pub struct Groups<P> {
    /// Label of each group (the object's name).
    pub labels: Vec<String>,
    /// Parameters of each group.
    pub params: Vec<P>,
}

impl<P> Groups<P> {
    /// Append a group.
    pub fn push(&mut self, label: &str, params: P) -> u32 {
        self.labels.push(label.to_string());
        self.params.push(params);
        (self.params.len() - 1) as u32
    }
    /// Parameters of a group.
    pub fn get(&self, kind: &'static str, index: u32) -> Result<&P> {
        Ok(&self.params[self.check(kind, index)?])
    }
    /// Replace the parameters of a group after `validate(params, label)`.
    pub fn set(
        &mut self,
        kind: &'static str,
        index: u32,
        params: P,
        validate: impl FnOnce(&P, &str) -> Result<()>,
    ) -> Result<()> {
        let i = self.check(kind, index)?;
        validate(&params, &self.labels[i])?;
        self.params[i] = params;
        Ok(())
    }
    /// Check a group index from a handle.
    pub fn check(&self, kind: &'static str, index: u32) -> Result<usize> {
        let i = index as usize;
        if i < self.params.len() {
            Ok(i)
        } else {
            Err(StarkError::InvalidHandle {
                kind,
                index: i,
                len: self.params.len(),
            })
        }
    }
}

/// Every deformable energy model of a simulation.
pub struct Deformables {
    /// Node sets (objects).
    pub sets: Vec<(String, NodeSetHandle)>,
    /// Lumped inertia, gravity and external forces.
    pub inertia: PotentialTerm<LumpedInertia, 1>,
    /// Prescribed positions (kinematic targets).
    pub prescribed: PotentialTerm<PrescribedPositions, 1>,
    /// Rods: segment strain.
    pub segments: PotentialTerm<SegmentStrain, 2>,
    /// Shells: membrane strain.
    pub triangles: PotentialTerm<TriangleStrain, 3>,
    /// Shells: discrete-shell dihedral bending.
    pub dihedral_bending: PotentialTerm<DihedralBending, 4>,
    /// Shells: flat quadratic bending (Bergou et al. 2006).
    pub flat_bending: PotentialTerm<FlatBending, 4>,
    /// Solids: tetrahedral strain.
    pub tets: PotentialTerm<TetStrain, 4>,
    /// Deformable–deformable attachments.
    pub attachments: Attachments,
}

impl Default for Deformables {
    fn default() -> Self {
        Deformables {
            sets: Vec::new(),
            inertia: PotentialTerm::new(LumpedInertia::default()),
            prescribed: PotentialTerm::new(PrescribedPositions::default()),
            segments: PotentialTerm::new(SegmentStrain::default()),
            triangles: PotentialTerm::new(TriangleStrain::default()),
            dihedral_bending: PotentialTerm::new(DihedralBending::default()),
            flat_bending: PotentialTerm::new(FlatBending::default()),
            tets: PotentialTerm::new(TetStrain::default()),
            attachments: Attachments::default(),
        }
    }
}

impl Deformables {
    /// All terms, for the solver.
    pub fn terms_mut(&mut self) -> Vec<&mut dyn crate::energy::EnergyTerm> {
        let mut v: Vec<&mut dyn crate::energy::EnergyTerm> = vec![
            &mut self.inertia,
            &mut self.prescribed,
            &mut self.segments,
            &mut self.triangles,
            &mut self.dihedral_bending,
            &mut self.flat_bending,
            &mut self.tets,
        ];
        v.extend(self.attachments.terms_mut());
        v
    }

    /// The node set with this label.
    pub fn set_by_label(&self, label: &str) -> Option<NodeSetHandle> {
        self.sets.iter().find(|(l, _)| l == label).map(|(_, h)| *h)
    }
}

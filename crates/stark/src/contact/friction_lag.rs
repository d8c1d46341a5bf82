//! Friction lagging: friction elements built from the pairs of a converged (or start-of-step)
//! state; the re-lag happens in `check_converged_step`.

use super::barrier::barrier;
use super::friction::FrictionElement;
use super::pairs::{ContactPair, PairKind};
use super::Contact;
use crate::geometry::distance::{
    edge_edge_closest_parameters_typed, point_edge_closest_parameter_typed, point_triangle_closest_barycentric_typed,
    EdgeEdgeDistanceType as Ee, PointEdgeDistanceType, PointTriangleDistanceType as Pt,
};
use nalgebra::Vector3;
use rayon::prelude::*;

impl Contact {
    /// Lagged friction elements from the pairs active at `x0`. The slip is measured from the
    /// start-of-step positions `x_start` (equal to `x0` at the first lag; a re-lag takes normal
    /// forces, tangents and weights from the converged state but must keep the slip origin).
    pub(super) fn lag_friction(
        &mut self,
        pairs: &[ContactPair],
        x0: &[Vector3<f64>],
        x_start: &[Vector3<f64>],
        dt: f64,
    ) {
        let eps = self.settings.friction_stick_slide_threshold_m_s * dt;
        let kind = self.settings.barrier;
        // In parallel, in the pairs' order.
        self.friction_elements = pairs
            .par_iter()
            .with_min_len(256)
            .filter(|p| p.mu > 0.0)
            .filter_map(|p| {
                let x = Self::stencil_x(&p.nodes, x0);
                let weights = match p.kind {
                    PairKind::PointPoint => [1.0, -1.0, 0.0, 0.0],
                    PairKind::PointEdge => {
                        let a =
                            point_edge_closest_parameter_typed(&x[0], &x[1], &x[2], PointEdgeDistanceType::PointEdge);
                        [1.0, -(1.0 - a), -a, 0.0]
                    }
                    PairKind::PointTriangle => {
                        let (b1, b2) =
                            point_triangle_closest_barycentric_typed(&x[0], &x[1], &x[2], &x[3], Pt::PointTriangle);
                        [1.0, -(1.0 - b1 - b2), -b1, -b2]
                    }
                    PairKind::EdgeEdge | PairKind::EdgeEdgeMollified(_) => {
                        let ty = match p.kind {
                            PairKind::EdgeEdgeMollified(r) => r,
                            _ => Ee::EaEb,
                        };
                        let (a, b) = edge_edge_closest_parameters_typed(&x[0], &x[1], &x[2], &x[3], ty);
                        [1.0 - a, a, -(1.0 - b), -b]
                    }
                };
                let rel: Vector3<f64> = (0..p.kind.len()).map(|i| x[i] * weights[i]).sum();
                let d = rel.norm();
                let (_, db, _) = barrier(kind, d, p.dhat);
                let lambda = p.kappa * p.multiplicity * db.abs();
                (lambda > 0.0 && lambda.is_finite()).then(|| {
                    let start = Self::stencil_x(&p.nodes, x_start);
                    FrictionElement::new(p.nodes, p.kind.len(), weights, rel, &start, p.mu * lambda, eps)
                })
            })
            .collect();
        self.stats.friction_pairs = self.friction_elements.len();
        self.friction_nodes.clear();
        self.friction_nodes
            .extend(self.friction_elements.iter().map(|f| f.nodes));
        self.friction_by_nodes.clear();
        for (i, f) in self.friction_elements.iter().enumerate() {
            self.friction_by_nodes.entry(f.nodes).or_insert(i as u32);
        }
        self.match_friction();
    }

    /// Pair each barrier pair with the friction element on the same nodes, if any and not taken
    /// by an earlier pair ([`Contact::pair_friction`], [`Contact::lone_friction`]); a new
    /// layout (`version`) if that changed the elements. The pairs and the friction elements
    /// both follow the candidates' order, so the next element after the last match is tried
    /// first.
    pub(super) fn match_friction(&mut self) {
        let n = self.friction_elements.len();
        let mut taken = vec![false; n];
        let mut next = 0usize;
        let pair_friction: Vec<u32> = self
            .pairs
            .iter()
            .map(|p| {
                let found = if next < n && self.friction_nodes[next] == p.nodes && !taken[next] {
                    Some(next)
                } else {
                    self.friction_by_nodes
                        .get(&p.nodes)
                        .map(|&i| i as usize)
                        .filter(|&i| !taken[i])
                };
                match found {
                    Some(i) => {
                        taken[i] = true;
                        next = i + 1;
                        i as u32
                    }
                    None => NO_FRICTION,
                }
            })
            .collect();
        let lone: Vec<u32> = (0..n as u32).filter(|&i| !taken[i as usize]).collect();
        if pair_friction != self.pair_friction || lone != self.lone_friction {
            self.version += 1;
        }
        self.pair_friction = pair_friction;
        self.lone_friction = lone;
    }
}

/// [`Contact::pair_friction`] of a pair without a friction element.
pub(super) const NO_FRICTION: u32 = u32::MAX;

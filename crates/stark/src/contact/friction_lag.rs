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
        self.friction_elements = pairs
            .iter()
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
    }
}

//! Narrow phase: the active barrier pairs among the candidates, classified by closest-point
//! region.

use super::broad_phase::Candidates;
use super::objects::sorted2;
use super::pairs::{ContactPair, PairKind};
use super::{pairs, Contact};
use crate::energy::term::NO_DOF;
use crate::energy::Vec3;
use crate::geometry::distance::{
    edge_edge_cross_norm_sq, edge_edge_distance_sq_typed, edge_edge_distance_type, point_triangle_distance_sq_typed,
    point_triangle_distance_type, EdgeEdgeDistanceType as Ee, PointTriangleDistanceType as Pt,
};
use nalgebra::Vector3;
use rayon::prelude::*;

impl Contact {
    /// Active pairs at `x` among candidates: classification by closest-point region; candidates
    /// that reduce to the same pair are merged (their multiplicities summed).
    pub(super) fn narrow_phase(&self, c: &Candidates, x: &[Vector3<f64>]) -> Vec<ContactPair> {
        let mut found: Vec<ContactPair> = c
            .point_triangle
            .par_iter()
            .filter_map(|&(pi, ti)| self.point_triangle_pair(pi as usize, ti as usize, x))
            .collect();
        found.par_extend(
            c.edge_edge
                .par_iter()
                .filter_map(|&(a, b)| self.edge_edge_pair(a as usize, b as usize, x)),
        );
        // Point–triangle and edge–edge pairs are one per candidate; a pair reduced to a point–point
        // or point–edge distance can come from several candidates (a vertex near a fan of
        // triangles, an edge's end near several edges): those are merged into one pair whose
        // multiplicity counts them. Only they need the sort, in parallel, by a key that leaves
        // only equal pairs in an undetermined order (a pair found from either side keeps the
        // smaller object pair); the others follow in the candidates' order.
        let reduced = |p: &ContactPair| matches!(p.kind, PairKind::PointPoint | PairKind::PointEdge);
        let mut merged: Vec<ContactPair> = found.par_iter().filter(|p| reduced(p)).cloned().collect();
        merged.par_sort_unstable_by_key(|p| (p.kind, p.nodes, p.objects));
        merged.dedup_by(|later, kept| {
            let same = later.kind == kept.kind && later.nodes == kept.nodes;
            if same {
                kept.multiplicity += later.multiplicity;
            }
            same
        });
        merged.reserve(found.len() - merged.len());
        merged.extend(found.into_iter().filter(|p| !reduced(p)));
        merged
    }

    /// Active pairs at positions `x`, from the cached candidates when they cover `x` (else a new
    /// broad phase, then cached).
    pub(super) fn detect(&mut self, x: &[Vector3<f64>]) -> Vec<ContactPair> {
        let cached = self.candidate_cache.take();
        let candidates = self.candidates_for(cached, x, x);
        let pairs = self.narrow_phase(&candidates, x);
        self.candidate_cache = Some(candidates);
        pairs
    }

    /// The pair of a point–triangle candidate at `x`, if within `d̂` (candidates are already
    /// enabled and not adjacent).
    fn point_triangle_pair(&self, pi: usize, ti: usize, x: &[Vector3<f64>]) -> Option<ContactPair> {
        let (po, to) = (self.point_obj[pi], self.tri_obj[ti]);
        let p = self.points[pi];
        let t = self.triangles[ti];
        let (xp, x0, x1, x2) = (&x[p as usize], &x[t[0] as usize], &x[t[1] as usize], &x[t[2] as usize]);
        let dhat = self.dhat(po, to);
        // Cheap rejection: the point is farther than d̂ from the triangle's box on some axis.
        if (0..3).any(|k| xp[k] + dhat < x0[k].min(x1[k]).min(x2[k]) || xp[k] - dhat > x0[k].max(x1[k]).max(x2[k])) {
            return None;
        }
        let ty = point_triangle_distance_type(xp, x0, x1, x2);
        let d_sq = point_triangle_distance_sq_typed(xp, x0, x1, x2, ty);
        if !(d_sq < dhat * dhat) {
            return None;
        }
        let (kind, full) = match ty {
            Pt::PointT0 | Pt::PointT1 | Pt::PointT2 => {
                let v = t[match ty {
                    Pt::PointT0 => 0,
                    Pt::PointT1 => 1,
                    _ => 2,
                }];
                let s = sorted2(p, v);
                (PairKind::PointPoint, [s[0], s[1], NO_DOF, NO_DOF])
            }
            Pt::PointEdge0 | Pt::PointEdge1 | Pt::PointEdge2 => {
                let i = match ty {
                    Pt::PointEdge0 => 0,
                    Pt::PointEdge1 => 1,
                    _ => 2,
                };
                let e = sorted2(t[i], t[(i + 1) % 3]);
                (PairKind::PointEdge, [p, e[0], e[1], NO_DOF])
            }
            Pt::PointTriangle => (PairKind::PointTriangle, [p, t[0], t[1], t[2]]),
        };
        Some(ContactPair {
            kind,
            nodes: full,
            dhat,
            eps_x: 0.0,
            mu: self.mu(po, to),
            kappa: self.kappa.get(po as usize, to as usize),
            objects: [po, to],
            multiplicity: 1.0,
        })
    }

    /// The pair of an edge–edge candidate at `x`, if within `d̂` (candidates are already enabled
    /// and share no vertex).
    fn edge_edge_pair(&self, a: usize, b: usize, x: &[Vector3<f64>]) -> Option<ContactPair> {
        let (oa, ob) = (self.edge_obj[a], self.edge_obj[b]);
        let (ea, eb) = (self.edges[a], self.edges[b]);
        let p = |i: u32| &x[i as usize];
        let (a0, a1, b0, b1) = (p(ea[0]), p(ea[1]), p(eb[0]), p(eb[1]));
        let dhat = self.dhat(oa, ob);
        if (0..3).any(|k| a0[k].max(a1[k]) + dhat < b0[k].min(b1[k]) || a0[k].min(a1[k]) - dhat > b0[k].max(b1[k])) {
            return None;
        }
        let ty = edge_edge_distance_type(a0, a1, b0, b1);
        let d_sq = edge_edge_distance_sq_typed(a0, a1, b0, b1, ty);
        if !(d_sq < dhat * dhat) {
            return None;
        }
        let mu = self.mu(oa, ob);
        let kappa = self.kappa.get(oa as usize, ob as usize);
        let eps_x = 1e-3 * self.edge_rest_len_sq[a] * self.edge_rest_len_sq[b];
        if edge_edge_cross_norm_sq(a0, a1, b0, b1) < eps_x {
            return Some(ContactPair {
                kind: PairKind::EdgeEdgeMollified(ty),
                nodes: [ea[0], ea[1], eb[0], eb[1]],
                dhat,
                eps_x,
                mu,
                kappa,
                objects: [oa, ob],
                multiplicity: 1.0,
            });
        }
        let mut nodes = [NO_DOF; 4];
        let kind = match ty {
            Ee::Ea0Eb0 | Ee::Ea0Eb1 | Ee::Ea1Eb0 | Ee::Ea1Eb1 => {
                let u = if matches!(ty, Ee::Ea0Eb0 | Ee::Ea0Eb1) {
                    ea[0]
                } else {
                    ea[1]
                };
                let v = if matches!(ty, Ee::Ea0Eb0 | Ee::Ea1Eb0) {
                    eb[0]
                } else {
                    eb[1]
                };
                nodes[..2].copy_from_slice(&sorted2(u, v));
                PairKind::PointPoint
            }
            Ee::EaEb0 | Ee::EaEb1 => {
                nodes[0] = if ty == Ee::EaEb0 { eb[0] } else { eb[1] };
                nodes[1..3].copy_from_slice(&sorted2(ea[0], ea[1]));
                PairKind::PointEdge
            }
            Ee::Ea0Eb | Ee::Ea1Eb => {
                nodes[0] = if ty == Ee::Ea0Eb { ea[0] } else { ea[1] };
                nodes[1..3].copy_from_slice(&sorted2(eb[0], eb[1]));
                PairKind::PointEdge
            }
            Ee::EaEb => {
                let (sa, sb) = (sorted2(ea[0], ea[1]), sorted2(eb[0], eb[1]));
                let (first, second) = if sa < sb { (sa, sb) } else { (sb, sa) };
                nodes = [first[0], first[1], second[0], second[1]];
                PairKind::EdgeEdge
            }
        };
        Some(ContactPair {
            kind,
            nodes,
            dhat,
            eps_x,
            mu,
            kappa,
            objects: [oa, ob],
            multiplicity: 1.0,
        })
    }

    /// Distance of an active pair at `x`, m.
    pub(super) fn pair_distance(p: &ContactPair, x: &[Vector3<f64>]) -> f64 {
        let (dist, idx) = p.kind.distance();
        let x = Self::stencil_x(&p.nodes, x);
        let n = dist.len();
        let sub: [Vec3<f64>; 4] = std::array::from_fn(|k| Vec3::constant(&x[if k < n { idx[k] } else { 0 }]));
        pairs::distance_sq(dist, &sub[..n]).sqrt()
    }

    pub(super) fn stencil_x(nodes: &[u32; 4], x: &[Vector3<f64>]) -> [Vector3<f64>; 4] {
        nodes.map(|i| if i == NO_DOF { Vector3::zeros() } else { x[i as usize] })
    }
}

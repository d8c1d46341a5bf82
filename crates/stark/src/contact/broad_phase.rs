//! Broad phase: candidate pairs from grown swept boxes, and the cache that lets several line
//! searches share them.

use super::ccd::box_gap;
use super::Contact;
use crate::geometry::aabb::{edge_swept_aabb, point_swept_aabb, triangle_swept_aabb, Aabb};
use crate::geometry::bvh::Bvh;
use crate::geometry::distance::{
    edge_edge_distance_sq_typed, edge_edge_distance_type, point_triangle_distance_sq_typed,
    point_triangle_distance_type,
};
use nalgebra::Vector3;
use rayon::prelude::*;

impl Contact {
    /// Candidate pairs for every state in which each contact point stays within `margin_m`
    /// (per axis) of the box it sweeps from `from` to `to`: primitives' swept boxes, grown by
    /// their object's thickness plus the margin, that overlap. A pair that comes within its
    /// `d̂ = thickness_a + thickness_b` in such a state has overlapping grown boxes, so the list
    /// serves the line searches (and CCD) of several Newton iterations without a new broad phase.
    fn candidates(&self, from: &[Vector3<f64>], to: &[Vector3<f64>], margin_m: f64) -> Candidates {
        let grow = |o: u16| self.objects[o as usize].thickness_m + margin_m;
        let mut c = Candidates {
            swept: self
                .points
                .par_iter()
                .map(|&p| point_swept_aabb(&from[p as usize], &to[p as usize], 0.0))
                .collect(),
            margin_m,
            ..Default::default()
        };
        if self.objects.is_empty() {
            return c;
        }
        let x = |i: u32| (&from[i as usize], &to[i as usize]);
        // How far each node can be from its position in `from` in a state the candidates cover
        // (within the margin, per axis, of the box it sweeps), for the pruning when they serve
        // again.
        c.origin = from.to_vec();
        c.reach_m = from
            .par_iter()
            .zip(to)
            .map(|(a, b)| (b - a).norm() + 3f64.sqrt() * margin_m)
            .collect();
        if !self.triangles.is_empty() && !self.points.is_empty() {
            let point_boxes: Vec<Aabb> = c
                .swept
                .par_iter()
                .zip(&self.point_obj)
                .map(|(b, &o)| b.inflated(grow(o)))
                .collect();
            let tri_boxes: Vec<Aabb> = self
                .triangles
                .par_iter()
                .zip(&self.tri_obj)
                .map(|(t, &o)| {
                    let (a, b, c) = (x(t[0]), x(t[1]), x(t[2]));
                    triangle_swept_aabb(a.0, b.0, c.0, a.1, b.1, c.1, grow(o))
                })
                .collect();
            c.point_triangle = Bvh::build(&point_boxes).pairs_with_where(&Bvh::build(&tri_boxes), 0.0, |pi, ti| {
                self.pair_ok(self.point_obj[pi], self.tri_obj[ti]) && !self.triangles[ti].contains(&self.points[pi])
            });
        }
        if self.edges.len() > 1 {
            let edge_boxes: Vec<Aabb> = self
                .edges
                .par_iter()
                .zip(&self.edge_obj)
                .map(|(e, &o)| {
                    let (a, b) = (x(e[0]), x(e[1]));
                    edge_swept_aabb(a.0, b.0, a.1, b.1, grow(o))
                })
                .collect();
            c.edge_edge = Bvh::build(&edge_boxes).self_pairs_where(0.0, |i, j| {
                let (ea, eb) = (self.edges[i], self.edges[j]);
                self.pair_ok(self.edge_obj[i], self.edge_obj[j]) && !ea.iter().any(|v| eb.contains(v))
            });
        }
        c
    }

    /// Drop the candidates that can neither become active nor bound a step in any state the
    /// candidates cover: a pair's distance shrinks from its value at the candidates' origin by
    /// at most the largest reach of its one side plus that of the other (the points of an edge
    /// or a triangle are convex combinations of its corners). The boxes the broad phase compares
    /// are much larger than the primitives for long edges and large triangles (a rigid box's
    /// faces against a fine mesh): there most candidates go. The pairs that remain, and their
    /// order, are those any covering candidates give, so the results do not change. Returns the
    /// fraction removed.
    fn prune(&self, c: &mut Candidates) -> f64 {
        let (x, reach) = (&c.origin, &c.reach_m);
        let quiet = super::ccd::ccd_silent_above_m();
        let before = (c.point_triangle.len(), c.edge_edge.len());
        c.point_triangle = c
            .point_triangle
            .par_iter()
            .copied()
            .filter(|&(pi, ti)| {
                let (p, t) = (self.points[pi as usize], self.triangles[ti as usize]);
                let gap = self.dhat(self.point_obj[pi as usize], self.tri_obj[ti as usize]);
                within_reach(x, reach, &[p], &t, gap.max(quiet), || {
                    let [a, b0, b1, b2] = [p, t[0], t[1], t[2]].map(|i| &x[i as usize]);
                    point_triangle_distance_sq_typed(a, b0, b1, b2, point_triangle_distance_type(a, b0, b1, b2))
                })
            })
            .collect();
        c.edge_edge = c
            .edge_edge
            .par_iter()
            .copied()
            .filter(|&(i, j)| {
                let (ea, eb) = (self.edges[i as usize], self.edges[j as usize]);
                let gap = self.dhat(self.edge_obj[i as usize], self.edge_obj[j as usize]);
                within_reach(x, reach, &ea, &eb, gap.max(quiet), || {
                    let [a0, a1, b0, b1] = [ea[0], ea[1], eb[0], eb[1]].map(|i| &x[i as usize]);
                    edge_edge_distance_sq_typed(a0, a1, b0, b1, edge_edge_distance_type(a0, a1, b0, b1))
                })
            })
            .collect();
        c.origin = Vec::new();
        c.reach_m = Vec::new();
        let (kept, found) = (c.point_triangle.len() + c.edge_edge.len(), before.0 + before.1);
        1.0 - kept as f64 / found.max(1) as f64
    }

    /// A fingerprint of what the candidates depend on besides positions: the primitives, the
    /// objects' thicknesses and which pairs of objects collide.
    pub(super) fn candidate_config(&self) -> u64 {
        use std::hash::{Hash, Hasher};
        let mut h = std::collections::hash_map::DefaultHasher::new();
        (self.points.len(), self.edges.len(), self.triangles.len()).hash(&mut h);
        for o in &self.objects {
            o.thickness_m.to_bits().hash(&mut h);
        }
        self.enabled.hash(&mut h);
        h.finish()
    }

    /// Candidates covering the segment `from → to`: the cached ones if every contact point stays
    /// within their margin on it, else a new broad phase over the segment with a margin of the
    /// largest thickness (so the next, shorter Newton steps usually reuse it).
    pub(super) fn candidates_for(
        &self,
        cache: Option<Candidates>,
        from: &[Vector3<f64>],
        to: &[Vector3<f64>],
    ) -> Candidates {
        if let Some(mut c) = cache {
            if c.cover(&self.points, from) && c.cover(&self.points, to) {
                c.reuses += 1;
                if c.reuses == PRUNE_AT_REUSE && !c.reach_m.is_empty() {
                    // After a pruning that removed little (a cloth wrapped round a box: a tenth),
                    // the next ones are skipped, then tried again.
                    use std::sync::atomic::Ordering::Relaxed;
                    let skips = self.prune_skips.load(Relaxed);
                    if skips > 0 {
                        self.prune_skips.store(skips - 1, Relaxed);
                    } else if self.prune(&mut c) < PRUNE_MIN_YIELD {
                        self.prune_skips.store(PRUNE_SKIPS_AFTER_LOW_YIELD, Relaxed);
                    }
                }
                return c;
            }
        }
        let thickest = self.objects.iter().map(|o| o.thickness_m).fold(0.0, f64::max);
        self.candidates(from, to, thickest)
    }
}

/// Whether two primitives (their corner nodes `a` and `b`) can come within `gap` of each other
/// while each node stays within its `reach` of `x`: a primitive's points move no farther than its
/// farthest corner. `distance_sq` is their squared distance at `x`, computed only when the boxes'
/// gap (a tenth of its cost) does not already decide.
fn within_reach(
    x: &[Vector3<f64>],
    reach: &[f64],
    a: &[u32],
    b: &[u32],
    gap: f64,
    distance_sq: impl FnOnce() -> f64,
) -> bool {
    let farthest = |s: &[u32]| s.iter().map(|&i| reach[i as usize]).fold(0.0, f64::max);
    let bound = gap + farthest(a) + farthest(b);
    let corners = |s: &[u32]| {
        let mut c = [Vector3::zeros(); 3];
        for (k, &i) in s.iter().enumerate() {
            c[k] = x[i as usize];
        }
        (c, s.len())
    };
    let ((ca, na), (cb, nb)) = (corners(a), corners(b));
    box_gap(&ca[..na], &cb[..nb]) <= bound && distance_sq() <= bound * bound * (1.0 + 1e-9)
}

/// Candidates are pruned when they serve for this many times after their broad phase: a pruning
/// costs about one narrow phase over them, and candidates that serve a single line search (a
/// cloth on a spinning box: a new broad phase at nearly every Newton iteration) never repay it.
const PRUNE_AT_REUSE: u32 = 2;
/// A pruning that removed less than this fraction of the candidates does not pay for itself.
const PRUNE_MIN_YIELD: f64 = 0.25;
/// Pruning opportunities skipped after one that did not pay.
const PRUNE_SKIPS_AFTER_LOW_YIELD: u32 = 15;

/// Candidate pairs (indices into the contact points, edges and triangles), valid while every
/// contact point stays within `margin_m` of the box it `swept` when they were found. Both lists
/// are sorted (the BVH's pairs are; edge pairs as `(lower, higher)`), so the pairs found from
/// any candidates that cover a state come in one order: a run resumed from a checkpoint, whose
/// first broad phase is new, evaluates its pairs in the order of the run that kept its cache.
#[derive(Default)]
pub(super) struct Candidates {
    pub(super) point_triangle: Vec<(u32, u32)>,
    pub(super) edge_edge: Vec<(u32, u32)>,
    swept: Vec<Aabb>,
    margin_m: f64,
    /// All nodes' positions where the candidates were found, m, and how far each can be from
    /// there in a covered state, m (until the candidates are pruned; empty after).
    origin: Vec<Vector3<f64>>,
    reach_m: Vec<f64>,
    /// Times the candidates served again after the broad phase that found them.
    reuses: u32,
}

impl Candidates {
    /// Whether every contact point of `x` is within the margin of its swept box.
    fn cover(&self, points: &[u32], x: &[Vector3<f64>]) -> bool {
        let m = self.margin_m;
        self.swept.len() == points.len()
            && points.par_iter().zip(&self.swept).all(|(&p, b)| {
                let q = &x[p as usize];
                (0..3).all(|k| q[k] >= b.min[k] - m && q[k] <= b.max[k] + m)
            })
    }
}

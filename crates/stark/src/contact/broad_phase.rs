//! Broad phase: candidate pairs from grown swept boxes, and the cache that lets several line
//! searches share them.

use super::Contact;
use crate::geometry::aabb::{edge_swept_aabb, point_swept_aabb, triangle_swept_aabb, Aabb};
use crate::geometry::bvh::Bvh;
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
            let found = Bvh::build(&point_boxes).pairs_with(&Bvh::build(&tri_boxes), 0.0);
            c.point_triangle = found
                .into_par_iter()
                .filter(|&(pi, ti)| {
                    self.pair_ok(self.point_obj[pi], self.tri_obj[ti]) && !self.triangles[ti].contains(&self.points[pi])
                })
                .map(|(pi, ti)| (pi as u32, ti as u32))
                .collect();
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
            let found = Bvh::build(&edge_boxes).self_pairs(0.0);
            c.edge_edge = found
                .into_par_iter()
                .filter(|&(i, j)| {
                    let (ea, eb) = (self.edges[i], self.edges[j]);
                    self.pair_ok(self.edge_obj[i], self.edge_obj[j]) && !ea.iter().any(|v| eb.contains(v))
                })
                .map(|(i, j)| (i as u32, j as u32))
                .collect();
        }
        c
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
        if let Some(c) = cache {
            if c.cover(&self.points, from) && c.cover(&self.points, to) {
                return c;
            }
        }
        let thickest = self.objects.iter().map(|o| o.thickness_m).fold(0.0, f64::max);
        self.candidates(from, to, thickest)
    }
}

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

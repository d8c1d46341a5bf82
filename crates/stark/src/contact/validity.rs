//! The exact validity test of trial states: no edge of a rigid body's mesh may cross a triangle
//! (deformable crossings are left to CCD).

use super::Contact;
use crate::geometry::aabb::{edge_aabb, triangle_aabb, Aabb};
use crate::geometry::bvh::Bvh;
use crate::geometry::intersection::{edge_triangle_intersect, find_edge_triangle_intersections};
use crate::state::{rigid_body_of, EvalState};
use nalgebra::Vector3;
use rayon::prelude::*;

/// The contact primitives split by whether they belong to a rigid body's collision mesh.
#[derive(Default)]
pub(super) struct RigidSplit {
    /// Triangles of rigid objects.
    rigid_triangles: Vec<u32>,
    /// Edges of rigid objects.
    rigid_edges: Vec<u32>,
    /// Triangles of the other objects.
    other_triangles: Vec<u32>,
}

impl RigidSplit {
    pub(super) fn is_empty(&self) -> bool {
        self.rigid_triangles.is_empty() && self.rigid_edges.is_empty()
    }
}

impl Contact {
    /// Pairs of edges and triangles that intersect at positions `x` (ignoring pairs of objects
    /// whose collisions are off), as `(edge, triangle)` indices into the contact surfaces, with a
    /// readable description of each. The exact test of `geometry::intersection` (robust
    /// predicates); used on the initial state and by tests after every step.
    pub fn find_intersections(&self, x: &[Vector3<f64>]) -> Vec<String> {
        let edges: Vec<[usize; 2]> = self.edges.iter().map(|e| [e[0] as usize, e[1] as usize]).collect();
        let tris: Vec<[usize; 3]> = self
            .triangles
            .iter()
            .map(|t| [t[0] as usize, t[1] as usize, t[2] as usize])
            .collect();
        let found =
            find_edge_triangle_intersections(x, &edges, &tris, |e, t| self.pair_ok(self.edge_obj[e], self.tri_obj[t]))
                .expect("contact primitives refer to existing nodes");
        found
            .into_iter()
            .map(|(e, t)| {
                format!(
                    "edge {:?} of '{}' crosses triangle {:?} of '{}'",
                    self.edges[e],
                    self.objects[self.edge_obj[e] as usize].label,
                    self.triangles[t],
                    self.objects[self.tri_obj[t] as usize].label
                )
            })
            .collect()
    }
}

impl Contact {
    /// Whether any contact object is a rigid body's mesh.
    pub(super) fn has_rigid_objects(&self, state: &EvalState) -> bool {
        !state.bodies.is_empty()
            && self
                .objects
                .iter()
                .any(|o| rigid_body_of(state.nodes.body[o.nodes.first as usize]).is_some())
    }

    /// Split the primitives into those of rigid bodies' meshes and the others (empty without
    /// rigid contact objects, which makes the validity test free).
    pub(super) fn split_rigid(&self, state: &EvalState) -> RigidSplit {
        if !self.has_rigid_objects(state) {
            return RigidSplit::default();
        }
        let rigid: Vec<bool> = self
            .objects
            .iter()
            .map(|o| rigid_body_of(state.nodes.body[o.nodes.first as usize]).is_some())
            .collect();
        let (rigid_triangles, other_triangles) =
            (0..self.triangles.len() as u32).partition(|&t| rigid[self.tri_obj[t as usize] as usize]);
        RigidSplit {
            rigid_triangles,
            rigid_edges: (0..self.edges.len() as u32)
                .filter(|&e| rigid[self.edge_obj[e as usize] as usize])
                .collect(),
            other_triangles,
        }
    }

    /// Whether, at positions `x`, an edge crosses a triangle (exact test,
    /// [`edge_triangle_intersect`]) in a pair of enabled objects of which at least one is a rigid
    /// body's mesh; pairs of deformable primitives are not tested. This is the line-search
    /// validity test: deformable nodes move on straight lines in a line search, so CCD on the
    /// chord guards them exactly, but a rigid point moves on an arc (its position is non-linear in
    /// `ω`) and the trial state can leave the chord that CCD checked. Uses the split of the last
    /// `before_step`.
    ///
    /// Cost: a BVH over the rigid triangles and one over the rigid edges, queried with the box of
    /// every edge and of every other triangle that overlaps the rigid primitives' overall box.
    pub fn rigid_pairs_intersect(&self, x: &[Vector3<f64>]) -> bool {
        let split = &self.rigid_split;
        if split.is_empty() {
            return false;
        }
        let p = |i: u32| &x[i as usize];
        let tri_box = |t: u32| {
            let t = self.triangles[t as usize];
            triangle_aabb(p(t[0]), p(t[1]), p(t[2]), 0.0)
        };
        let edge_box = |e: u32| {
            let e = self.edges[e as usize];
            edge_aabb(p(e[0]), p(e[1]), 0.0)
        };
        let crosses = |e: u32, t: u32| {
            let (ea, tb) = (self.edges[e as usize], self.triangles[t as usize]);
            self.pair_ok(self.edge_obj[e as usize], self.tri_obj[t as usize])
                && !tb.contains(&ea[0])
                && !tb.contains(&ea[1])
                && edge_triangle_intersect(p(ea[0]), p(ea[1]), p(tb[0]), p(tb[1]), p(tb[2]))
        };
        // Every edge against the rigid triangles, then the other triangles against the rigid
        // edges. Small sets run sequentially (rayon's start-up costs more than the test).
        let boxes: Vec<Aabb> = split.rigid_triangles.iter().map(|&t| tri_box(t)).collect();
        let bvh = Bvh::build(&boxes);
        let near = bvh.aabb();
        let edge_hits = |e: u32| {
            let b = edge_box(e);
            let mut hit = false;
            if b.intersects(&near) {
                bvh.query_aabb(&b, |k| hit = hit || crosses(e, split.rigid_triangles[k]));
            }
            hit
        };
        let n_edges = self.edges.len() as u32;
        let hit = if n_edges < PARALLEL_VALIDITY_MIN {
            (0..n_edges).any(edge_hits)
        } else {
            (0..n_edges).into_par_iter().any(edge_hits)
        };
        if hit {
            return true;
        }
        let boxes: Vec<Aabb> = split.rigid_edges.iter().map(|&e| edge_box(e)).collect();
        let bvh = Bvh::build(&boxes);
        let near = bvh.aabb();
        let triangle_hits = |&t: &u32| {
            let b = tri_box(t);
            let mut hit = false;
            if b.intersects(&near) {
                bvh.query_aabb(&b, |k| hit = hit || crosses(split.rigid_edges[k], t));
            }
            hit
        };
        if split.other_triangles.len() < PARALLEL_VALIDITY_MIN as usize {
            split.other_triangles.iter().any(triangle_hits)
        } else {
            split.other_triangles.par_iter().any(triangle_hits)
        }
    }
}

/// Primitive counts below which the validity test runs on one thread.
const PARALLEL_VALIDITY_MIN: u32 = 4096;

//! Continuous collision detection: the largest collision-free fraction of a line-search step.

use super::broad_phase::Candidates;
use super::Contact;
use crate::geometry::ccd::{edge_edge_max_step, point_triangle_max_step, CcdParams};
use crate::geometry::distance::{
    edge_edge_distance_sq_typed, edge_edge_distance_type, point_triangle_distance_sq_typed,
    point_triangle_distance_type,
};
use nalgebra::Vector3;
use rayon::prelude::*;

impl Contact {
    /// Largest fraction of the motion `from → to` free of collisions (additive CCD with a
    /// minimum separation) over the candidates, and the number of exact CCD queries.
    pub(super) fn ccd_fraction(&self, c: &Candidates, from: &[Vector3<f64>], to: &[Vector3<f64>]) -> (f64, usize) {
        // A bounded search: a query that cannot be decided within the budget returns the start of
        // its earliest undecided box, still a safe (if short) step.
        let params = CcdParams {
            max_iterations: 10_000,
            ..CcdParams::default()
        };
        // A cheap conservative filter first: the distance of a pair can shrink by at most the sum
        // of the largest displacements of its two sides, so a pair farther apart than that
        // cannot collide within the step.
        let disp = |i: u32| (to[i as usize] - from[i as usize]).norm();
        let (a_pt, q_pt) = c
            .point_triangle
            .par_iter()
            .map(|&(pi, ti)| {
                let p = self.points[pi as usize];
                let t = self.triangles[ti as usize];
                let x0 = [
                    from[p as usize],
                    from[t[0] as usize],
                    from[t[1] as usize],
                    from[t[2] as usize],
                ];
                let d0 = point_triangle_distance_sq_typed(
                    &x0[0],
                    &x0[1],
                    &x0[2],
                    &x0[3],
                    point_triangle_distance_type(&x0[0], &x0[1], &x0[2], &x0[3]),
                )
                .sqrt();
                if d0 > disp(p) + disp(t[0]).max(disp(t[1])).max(disp(t[2])) {
                    return (1.0, 0);
                }
                let x1 = [to[p as usize], to[t[0] as usize], to[t[1] as usize], to[t[2] as usize]];
                (point_triangle_max_step(&x0, &x1, 0.0, 1.0, &params), 1)
            })
            .reduce(|| (1.0, 0), |a, b| (a.0.min(b.0), a.1 + b.1));
        let (a_ee, q_ee) = c
            .edge_edge
            .par_iter()
            .map(|&(i, j)| {
                let (ea, eb) = (self.edges[i as usize], self.edges[j as usize]);
                let x0 = [
                    from[ea[0] as usize],
                    from[ea[1] as usize],
                    from[eb[0] as usize],
                    from[eb[1] as usize],
                ];
                let ty = edge_edge_distance_type(&x0[0], &x0[1], &x0[2], &x0[3]);
                let d0 = edge_edge_distance_sq_typed(&x0[0], &x0[1], &x0[2], &x0[3], ty).sqrt();
                if d0 > disp(ea[0]).max(disp(ea[1])) + disp(eb[0]).max(disp(eb[1])) {
                    return (1.0, 0);
                }
                let x1 = [
                    to[ea[0] as usize],
                    to[ea[1] as usize],
                    to[eb[0] as usize],
                    to[eb[1] as usize],
                ];
                (edge_edge_max_step(&x0, &x1, 0.0, 1.0, &params), 1)
            })
            .reduce(|| (1.0, 0), |a, b| (a.0.min(b.0), a.1 + b.1));
        (a_pt.min(a_ee), q_pt + q_ee)
    }
}

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

/// The distance between the bounding boxes of two point sets: a lower bound of the distance
/// between their convex hulls (a primitive's points span it).
#[inline]
pub(super) fn box_gap(a: &[Vector3<f64>], b: &[Vector3<f64>]) -> f64 {
    let mut gap_sq = 0.0;
    for k in 0..3 {
        let (a_min, a_max) = a.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p[k]), hi.max(p[k]))
        });
        let (b_min, b_max) = b.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p[k]), hi.max(p[k]))
        });
        let g = (b_min - a_max).max(a_min - b_max).max(0.0);
        gap_sq += g * g;
    }
    gap_sq.sqrt()
}

/// The CCD queries' parameters: a bounded search (a query that cannot be decided within the
/// budget returns the start of its earliest undecided box, still a safe if short step).
fn ccd_params() -> CcdParams {
    CcdParams {
        max_iterations: 10_000,
        ..CcdParams::default()
    }
}

/// A pair whose distance stays above this along a step never bounds it: CCD stops a pair where
/// its distance reaches at most `max_gap` (its target gap; here `min_distance` is 0), give or
/// take its tolerance (twice that, for room), m.
pub(super) fn ccd_silent_above_m() -> f64 {
    let p = ccd_params();
    2.0 * (p.max_gap + p.tolerance)
}

impl Contact {
    /// Largest fraction of the motion `from → to` free of collisions (additive CCD with a
    /// minimum separation) over the candidates, and the number of exact CCD queries.
    pub(super) fn ccd_fraction(&self, c: &Candidates, from: &[Vector3<f64>], to: &[Vector3<f64>]) -> (f64, usize) {
        let params = ccd_params();
        // A cheap conservative filter first: the distance of a pair can shrink by at most the sum
        // of the largest displacements of its two sides, so a pair farther apart than that
        // cannot collide within the step.
        let displacement: Vec<f64> = from.par_iter().zip(to).map(|(a, b)| (b - a).norm()).collect();
        let disp = |i: u32| displacement[i as usize];
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
                let reach = disp(p) + disp(t[0]).max(disp(t[1])).max(disp(t[2]));
                // The boxes' gap bounds the distance from below and costs a tenth of it.
                if box_gap(&x0[..1], &x0[1..]) > reach {
                    return (1.0, 0);
                }
                let d0 = point_triangle_distance_sq_typed(
                    &x0[0],
                    &x0[1],
                    &x0[2],
                    &x0[3],
                    point_triangle_distance_type(&x0[0], &x0[1], &x0[2], &x0[3]),
                )
                .sqrt();
                if d0 > reach {
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
                let reach = disp(ea[0]).max(disp(ea[1])) + disp(eb[0]).max(disp(eb[1]));
                if box_gap(&x0[..2], &x0[2..]) > reach {
                    return (1.0, 0);
                }
                let ty = edge_edge_distance_type(&x0[0], &x0[1], &x0[2], &x0[3]);
                let d0 = edge_edge_distance_sq_typed(&x0[0], &x0[1], &x0[2], &x0[3], ty).sqrt();
                if d0 > reach {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The boxes' gap never exceeds the primitives' distance (so the filter never skips a pair
    /// that could collide), and it is the distance for primitives stacked apart along an axis.
    #[test]
    fn box_gap_bounds_the_distance_from_below() {
        let mut seed = 7u64;
        let mut r = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for _ in 0..2000 {
            let mut p = [Vector3::zeros(); 4];
            for q in p.iter_mut() {
                *q = Vector3::new(r(), r(), r());
            }
            // Push the second primitive away by a random offset, sometimes not at all.
            let shift = Vector3::new(r(), r(), r()) * 2.0 * (r() + 0.5);
            for q in p[1..].iter_mut() {
                *q += shift;
            }
            let pt = point_triangle_distance_sq_typed(
                &p[0],
                &p[1],
                &p[2],
                &p[3],
                point_triangle_distance_type(&p[0], &p[1], &p[2], &p[3]),
            )
            .sqrt();
            assert!(box_gap(&p[..1], &p[1..]) <= pt + 1e-12);
            let mut e = p;
            for q in e[2..].iter_mut() {
                *q += shift;
            }
            let ty = edge_edge_distance_type(&e[0], &e[1], &e[2], &e[3]);
            let ee = edge_edge_distance_sq_typed(&e[0], &e[1], &e[2], &e[3], ty).sqrt();
            assert!(box_gap(&e[..2], &e[2..]) <= ee + 1e-12);
        }
        // Two horizontal triangles' worth of points 3 mm apart vertically.
        let lower = [
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
        ];
        let upper = lower.map(|q| q + Vector3::new(0.2, 0.2, 0.003));
        assert!((box_gap(&lower, &upper[..1]) - 0.003).abs() < 1e-15);
    }
}

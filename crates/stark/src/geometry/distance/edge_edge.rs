//! Edge–edge squared distance and the edge–edge mollifier.
//!
//! With `u = ea1 − ea0`, `v = eb1 − eb0`, `w = ea0 − eb0`, the squared distance between points
//! `ea0 + s u` and `eb0 + t v` is minimised over the unit square. If the lines are not parallel its
//! unconstrained minimiser is `s = (b e − c d)/D`, `t = (a e − b d)/D` with `a = u·u`, `b = u·v`,
//! `c = v·v`, `d = u·w`, `e = v·w` and `D = a c − b² = |u × v|²`; when that lies strictly inside the
//! square the answer is the line–line distance `(w·(u × v))² / |u × v|²`. Otherwise (or for parallel
//! or degenerate edges) the minimum of this convex function lies on the square's boundary, i.e. it
//! is the smallest of the four point–edge distances of an end vertex to the other edge. This is the
//! same answer as the clamped segment–segment classification of the IPC Toolkit
//! (`edge_edge_distance_type`; ipc-notes B.1).
//!
//! The mollifier (Li et al. 2020, §4.3; ipc-notes B.3) smoothly switches off the barrier of nearly
//! parallel edge pairs, whose distance type changes discontinuously.

use nalgebra::Vector3;

use super::point_edge::{
    point_edge_closest_parameter_typed, point_edge_distance_sq_typed, point_edge_distance_type, point_line_distance_sq,
    PointEdgeDistanceType,
};
use super::point_point::point_point_distance_sq;

/// Edges are treated as parallel when `|u × v|² < EDGE_EDGE_PARALLEL_THRESHOLD · |u|² |v|²`
/// (`sin² θ < 2.5e-16`, the IPC Toolkit's constant). The line–line formula divides by `|u × v|²`,
/// whose relative error grows like `ε / sin θ`; below this angle the boundary distances are used,
/// which are exact and differ from the line–line distance only where the two agree anyway.
pub const EDGE_EDGE_PARALLEL_THRESHOLD: f64 = 2.5e-16;

/// Region of the closest points of two edges (IPC `EdgeEdgeDistanceType`). Ordered, so contact
/// pairs keyed by it can be sorted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum EdgeEdgeDistanceType {
    /// Vertex `ea0` and vertex `eb0` (IPC `EA0_EB0`).
    Ea0Eb0,
    /// Vertex `ea0` and vertex `eb1` (IPC `EA0_EB1`).
    Ea0Eb1,
    /// Vertex `ea1` and vertex `eb0` (IPC `EA1_EB0`).
    Ea1Eb0,
    /// Vertex `ea1` and vertex `eb1` (IPC `EA1_EB1`).
    Ea1Eb1,
    /// Interior of edge a and vertex `eb0` (IPC `EA_EB0`).
    EaEb0,
    /// Interior of edge a and vertex `eb1` (IPC `EA_EB1`).
    EaEb1,
    /// Vertex `ea0` and interior of edge b (IPC `EA0_EB`).
    Ea0Eb,
    /// Vertex `ea1` and interior of edge b (IPC `EA1_EB`).
    Ea1Eb,
    /// Both interiors: line–line distance (IPC `EA_EB`).
    EaEb,
}

/// `u × v` and the unconstrained line–line parameters `(s, t)`, or `None` when the edges are
/// (nearly) parallel or degenerate (see [`EDGE_EDGE_PARALLEL_THRESHOLD`]).
fn line_line_parameters(
    ea0: &Vector3<f64>,
    ea1: &Vector3<f64>,
    eb0: &Vector3<f64>,
    eb1: &Vector3<f64>,
) -> Option<(Vector3<f64>, f64, f64)> {
    let u = ea1 - ea0;
    let v = eb1 - eb0;
    let w = ea0 - eb0;
    let a = u.norm_squared();
    let c = v.norm_squared();
    let cross = u.cross(&v);
    let denom = cross.norm_squared();
    // `>` is false for NaN and for zero or underflowed lengths.
    let skew = denom > EDGE_EDGE_PARALLEL_THRESHOLD * a * c && denom.is_finite();
    skew.then(|| {
        let b = u.dot(&v);
        let d = u.dot(&w);
        let e = v.dot(&w);
        (cross, (b * e - c * d) / denom, (a * e - b * d) / denom)
    })
}

/// The nearest of the four end-vertex-to-edge distances, as an edge–edge type. Ties go to the
/// earlier candidate in the order eb0→a, eb1→a, ea0→b, ea1→b.
fn closest_on_boundary(
    ea0: &Vector3<f64>,
    ea1: &Vector3<f64>,
    eb0: &Vector3<f64>,
    eb1: &Vector3<f64>,
) -> (EdgeEdgeDistanceType, f64) {
    use EdgeEdgeDistanceType as Ee;
    use PointEdgeDistanceType as Pe;
    // (point, edge start, edge end, types for [PointE0, PointE1, PointEdge]).
    type Candidate<'a> = (&'a Vector3<f64>, &'a Vector3<f64>, &'a Vector3<f64>, [Ee; 3]);
    let candidates: [Candidate; 4] = [
        (eb0, ea0, ea1, [Ee::Ea0Eb0, Ee::Ea1Eb0, Ee::EaEb0]),
        (eb1, ea0, ea1, [Ee::Ea0Eb1, Ee::Ea1Eb1, Ee::EaEb1]),
        (ea0, eb0, eb1, [Ee::Ea0Eb0, Ee::Ea0Eb1, Ee::Ea0Eb]),
        (ea1, eb0, eb1, [Ee::Ea1Eb0, Ee::Ea1Eb1, Ee::Ea1Eb]),
    ];
    let mut best = (Ee::Ea0Eb0, f64::INFINITY);
    for (i, (p, e0, e1, map)) in candidates.iter().enumerate() {
        let ty = point_edge_distance_type(p, e0, e1);
        let d = point_edge_distance_sq_typed(p, e0, e1, ty);
        let mapped = map[match ty {
            Pe::PointE0 => 0,
            Pe::PointE1 => 1,
            Pe::PointEdge => 2,
        }];
        if i == 0 || d < best.1 {
            best = (mapped, d);
        }
    }
    best
}

/// Classifies which features of the closed edges `[ea0, ea1]` and `[eb0, eb1]` are closest.
///
/// Non-parallel edges whose line–line closest points are strictly inside both edges give
/// [`EaEb`](EdgeEdgeDistanceType::EaEb); otherwise the nearest end-vertex-to-edge pair decides
/// (vertex–vertex types when that point is an end vertex). Parallel edges (see
/// [`EDGE_EDGE_PARALLEL_THRESHOLD`]) and zero-length edges never give `EaEb`. NaN input gives some
/// type.
pub fn edge_edge_distance_type(
    ea0: &Vector3<f64>,
    ea1: &Vector3<f64>,
    eb0: &Vector3<f64>,
    eb1: &Vector3<f64>,
) -> EdgeEdgeDistanceType {
    if let Some((_, s, t)) = line_line_parameters(ea0, ea1, eb0, eb1) {
        if s > 0.0 && s < 1.0 && t > 0.0 && t < 1.0 {
            return EdgeEdgeDistanceType::EaEb;
        }
    }
    closest_on_boundary(ea0, ea1, eb0, eb1).0
}

/// Squared distance between edge a and edge b for a given region type.
///
/// Vertex–vertex types give point–point distances, edge–vertex types point–line distances
/// ([`point_line_distance_sq`]), and `EaEb` the line–line distance
/// `((ea0 − eb0)·(u × v))² / |u × v|²`. For exactly parallel lines (`u × v = 0`), `EaEb` returns the
/// distance between the two parallel lines instead of `0/0`.
pub fn edge_edge_distance_sq_typed(
    ea0: &Vector3<f64>,
    ea1: &Vector3<f64>,
    eb0: &Vector3<f64>,
    eb1: &Vector3<f64>,
    ty: EdgeEdgeDistanceType,
) -> f64 {
    use EdgeEdgeDistanceType as Ee;
    match ty {
        Ee::Ea0Eb0 => point_point_distance_sq(ea0, eb0),
        Ee::Ea0Eb1 => point_point_distance_sq(ea0, eb1),
        Ee::Ea1Eb0 => point_point_distance_sq(ea1, eb0),
        Ee::Ea1Eb1 => point_point_distance_sq(ea1, eb1),
        Ee::EaEb0 => point_line_distance_sq(eb0, ea0, ea1),
        Ee::EaEb1 => point_line_distance_sq(eb1, ea0, ea1),
        Ee::Ea0Eb => point_line_distance_sq(ea0, eb0, eb1),
        Ee::Ea1Eb => point_line_distance_sq(ea1, eb0, eb1),
        Ee::EaEb => {
            let cross = (ea1 - ea0).cross(&(eb1 - eb0));
            let denom = cross.norm_squared();
            if denom > 0.0 && denom.is_finite() {
                let h = (ea0 - eb0).dot(&cross);
                h * h / denom
            } else if (ea1 - ea0).norm_squared() > 0.0 {
                point_line_distance_sq(eb0, ea0, ea1)
            } else {
                point_line_distance_sq(ea0, eb0, eb1)
            }
        }
    }
}

/// Squared distance between the closed edges `[ea0, ea1]` and `[eb0, eb1]` (classifies with
/// [`edge_edge_distance_type`] first).
pub fn edge_edge_distance_sq(ea0: &Vector3<f64>, ea1: &Vector3<f64>, eb0: &Vector3<f64>, eb1: &Vector3<f64>) -> f64 {
    let ty = edge_edge_distance_type(ea0, ea1, eb0, eb1);
    edge_edge_distance_sq_typed(ea0, ea1, eb0, eb1, ty)
}

/// Parameters `(α, β) ∈ [0, 1]²` of the closest points `ea0 + α (ea1 − ea0)` and
/// `eb0 + β (eb1 − eb0)` of the two closed edges.
pub fn edge_edge_closest_parameters(
    ea0: &Vector3<f64>,
    ea1: &Vector3<f64>,
    eb0: &Vector3<f64>,
    eb1: &Vector3<f64>,
) -> (f64, f64) {
    let ty = edge_edge_distance_type(ea0, ea1, eb0, eb1);
    edge_edge_closest_parameters_typed(ea0, ea1, eb0, eb1, ty)
}

/// Parameters `(α, β)` of the closest points for a fixed region type.
///
/// Vertex ends give 0 or 1; edge interiors use the *unclamped* point–line parameter; `EaEb` gives
/// the unclamped line–line parameters `α = (b e − c d)/D`, `β = (a e − b d)/D` (what lagged friction
/// of an edge–edge collision uses). For (nearly) parallel lines, `EaEb` falls back to the closest
/// points of the segments.
pub fn edge_edge_closest_parameters_typed(
    ea0: &Vector3<f64>,
    ea1: &Vector3<f64>,
    eb0: &Vector3<f64>,
    eb1: &Vector3<f64>,
    ty: EdgeEdgeDistanceType,
) -> (f64, f64) {
    use EdgeEdgeDistanceType as Ee;
    use PointEdgeDistanceType::PointEdge;
    match ty {
        Ee::Ea0Eb0 => (0.0, 0.0),
        Ee::Ea0Eb1 => (0.0, 1.0),
        Ee::Ea1Eb0 => (1.0, 0.0),
        Ee::Ea1Eb1 => (1.0, 1.0),
        Ee::EaEb0 => (point_edge_closest_parameter_typed(eb0, ea0, ea1, PointEdge), 0.0),
        Ee::EaEb1 => (point_edge_closest_parameter_typed(eb1, ea0, ea1, PointEdge), 1.0),
        Ee::Ea0Eb => (0.0, point_edge_closest_parameter_typed(ea0, eb0, eb1, PointEdge)),
        Ee::Ea1Eb => (1.0, point_edge_closest_parameter_typed(ea1, eb0, eb1, PointEdge)),
        Ee::EaEb => match line_line_parameters(ea0, ea1, eb0, eb1) {
            Some((_, s, t)) => (s, t),
            None => {
                let ty = closest_on_boundary(ea0, ea1, eb0, eb1).0;
                edge_edge_closest_parameters_typed(ea0, ea1, eb0, eb1, ty)
            }
        },
    }
}

/// `x = |(ea1 − ea0) × (eb1 − eb0)|²`, the argument of the edge–edge mollifier (ipc-notes B.3).
#[inline]
pub fn edge_edge_cross_norm_sq(ea0: &Vector3<f64>, ea1: &Vector3<f64>, eb0: &Vector3<f64>, eb1: &Vector3<f64>) -> f64 {
    (ea1 - ea0).cross(&(eb1 - eb0)).norm_squared()
}

/// Mollifier threshold `ε_x = 1e-3 · |ea0 − ea1|² · |eb0 − eb1|²` from the **rest** positions
/// (Li et al. 2020, §4.3; same constant in Stark).
#[inline]
pub fn edge_edge_mollifier_threshold(
    ea0_rest: &Vector3<f64>,
    ea1_rest: &Vector3<f64>,
    eb0_rest: &Vector3<f64>,
    eb1_rest: &Vector3<f64>,
) -> f64 {
    1e-3 * (ea0_rest - ea1_rest).norm_squared() * (eb0_rest - eb1_rest).norm_squared()
}

/// Edge–edge mollifier `m(x) = (2 − x/ε_x)(x/ε_x)` for `x < ε_x`, else `1` (Li et al. 2020, eq. 24).
///
/// `x` is [`edge_edge_cross_norm_sq`], `eps_x` is [`edge_edge_mollifier_threshold`]. A threshold
/// `ε_x ≤ 0` (degenerate rest edges) gives `m = 1`. NaN `x` gives NaN.
#[inline]
pub fn edge_edge_mollifier(x: f64, eps_x: f64) -> f64 {
    if x < eps_x {
        let r = x / eps_x;
        (2.0 - r) * r
    } else if x.is_nan() {
        f64::NAN
    } else {
        1.0
    }
}

/// Derivative `m'(x) = (2/ε_x)(1 − x/ε_x)` for `x < ε_x`, else `0`.
#[inline]
pub fn edge_edge_mollifier_derivative(x: f64, eps_x: f64) -> f64 {
    if x < eps_x {
        2.0 / eps_x * (1.0 - x / eps_x)
    } else if x.is_nan() {
        f64::NAN
    } else {
        0.0
    }
}

/// Second derivative `m''(x) = −2/ε_x²` for `x < ε_x`, else `0`.
#[inline]
pub fn edge_edge_mollifier_second_derivative(x: f64, eps_x: f64) -> f64 {
    if x < eps_x {
        -2.0 / (eps_x * eps_x)
    } else if x.is_nan() {
        f64::NAN
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::distance::test_util::{random_point, SCALES};
    use rand::rngs::StdRng;
    use rand::{Rng, SeedableRng};
    use EdgeEdgeDistanceType as Ee;

    fn v(x: f64, y: f64, z: f64) -> Vector3<f64> {
        Vector3::new(x, y, z)
    }

    /// Checks type, distance and closest parameters.
    fn check(e: [Vector3<f64>; 4], ty: Ee, d: f64, params: (f64, f64)) {
        let [a0, a1, b0, b1] = e;
        assert_eq!(edge_edge_distance_type(&a0, &a1, &b0, &b1), ty, "{e:?}");
        let got = edge_edge_distance_sq(&a0, &a1, &b0, &b1);
        assert!((got - d).abs() <= 1e-14 * (1.0 + d), "{got} vs {d}");
        let (s, t) = edge_edge_closest_parameters(&a0, &a1, &b0, &b1);
        assert!(
            (s - params.0).abs() < 1e-14 && (t - params.1).abs() < 1e-14,
            "{s} {t} vs {params:?}"
        );
    }

    #[test]
    fn every_region_closed_form() {
        // Edge a along x from 0 to 2; edge b along y at height z = 1, placed to hit each region.
        let a0 = v(0.0, 0.0, 0.0);
        let a1 = v(2.0, 0.0, 0.0);
        let eb = |x: f64, y0: f64, y1: f64| [a0, a1, v(x, y0, 1.0), v(x, y1, 1.0)];
        // Interior–interior.
        check(eb(1.0, -1.0, 1.0), Ee::EaEb, 1.0, (0.5, 0.5));
        // Edge a interior with eb0 / eb1 (b lies entirely on one side in y).
        check(eb(1.0, 1.0, 3.0), Ee::EaEb0, 2.0, (0.5, 0.0));
        check(eb(1.0, 3.0, 1.0), Ee::EaEb1, 2.0, (0.5, 1.0));
        // ea0 / ea1 with the interior of b (b beyond an end of a in x).
        check(eb(-1.0, -1.0, 1.0), Ee::Ea0Eb, 2.0, (0.0, 0.5));
        check(eb(3.0, -1.0, 1.0), Ee::Ea1Eb, 2.0, (1.0, 0.5));
        // Vertex–vertex.
        check(eb(-1.0, 1.0, 2.0), Ee::Ea0Eb0, 3.0, (0.0, 0.0));
        check(eb(-1.0, 2.0, 1.0), Ee::Ea0Eb1, 3.0, (0.0, 1.0));
        check(eb(3.0, 1.0, 2.0), Ee::Ea1Eb0, 3.0, (1.0, 0.0));
        check(eb(3.0, 2.0, 1.0), Ee::Ea1Eb1, 3.0, (1.0, 1.0));
    }

    #[test]
    fn parallel_and_coplanar() {
        let a0 = v(0.0, 0.0, 0.0);
        let a1 = v(2.0, 0.0, 0.0);
        // Parallel, overlapping in x: distance is the line separation, never `EaEb`.
        let (b0, b1) = (v(1.0, 1.0, 0.0), v(3.0, 1.0, 0.0));
        let ty = edge_edge_distance_type(&a0, &a1, &b0, &b1);
        assert_ne!(ty, Ee::EaEb);
        assert_eq!(edge_edge_distance_sq(&a0, &a1, &b0, &b1), 1.0);
        // The mollified (forced `EaEb`) distance of parallel lines is their separation too.
        assert_eq!(edge_edge_distance_sq_typed(&a0, &a1, &b0, &b1, Ee::EaEb), 1.0);
        // Parallel, disjoint in x.
        let (b0, b1) = (v(3.0, 1.0, 0.0), v(4.0, 1.0, 0.0));
        check([a0, a1, b0, b1], Ee::Ea1Eb0, 2.0, (1.0, 0.0));
        // Anti-parallel collinear overlap: distance 0.
        let (b0, b1) = (v(3.0, 0.0, 0.0), v(1.0, 0.0, 0.0));
        assert_eq!(edge_edge_distance_sq(&a0, &a1, &b0, &b1), 0.0);
        // Coplanar crossing: distance exactly 0 at the crossing.
        let (b0, b1) = (v(1.0, -1.0, 0.0), v(1.0, 1.0, 0.0));
        check([a0, a1, b0, b1], Ee::EaEb, 0.0, (0.5, 0.5));
        // Coplanar T: eb0 lies exactly on edge a.
        let (b0, b1) = (v(0.5, 0.0, 0.0), v(0.5, 1.0, 0.0));
        assert_eq!(edge_edge_distance_sq(&a0, &a1, &b0, &b1), 0.0);
        // Nearly parallel (angle 1e-9): classified as parallel, still the true minimum.
        let (b0, b1) = (v(0.0, 1.0, 0.0), v(2.0, 1.0 + 2e-9, 0.0));
        let d = edge_edge_distance_sq(&a0, &a1, &b0, &b1);
        assert!((d - 1.0).abs() < 1e-12);
    }

    #[test]
    fn degenerate_scales() {
        for &s in &SCALES {
            // Edge b of length |s| crossing above the middle of a unit edge at height 1.
            let a0 = v(0.0, 0.0, 0.0);
            let a1 = v(1.0, 0.0, 0.0);
            let (b0, b1) = (v(0.5, -0.5 * s, 1.0), v(0.5, 0.5 * s, 1.0));
            let d = edge_edge_distance_sq(&a0, &a1, &b0, &b1);
            assert!((d - 1.0).abs() <= 1e-12, "s = {s}: {d}");
            // Crossing edges separated by s in z: distance s².
            let (b0, b1) = (v(0.5, -1.0, s), v(0.5, 1.0, s));
            let d = edge_edge_distance_sq(&a0, &a1, &b0, &b1);
            assert!((d - s * s).abs() <= 1e-15 * (1.0 + s * s), "s = {s}: {d}");
            // Nearly parallel by angle s.
            let (b0, b1) = (v(0.0, 1.0, 0.0), v(1.0, 1.0 + s, 0.0));
            let d = edge_edge_distance_sq(&a0, &a1, &b0, &b1);
            assert!((d - 1.0f64.min((1.0 + s) * (1.0 + s))).abs() < 1e-12, "s = {s}: {d}");
            // Both edges of length s, one unit apart.
            let (c0, c1) = (v(0.0, 0.0, 0.0), v(s, 0.0, 0.0));
            let (b0, b1) = (v(0.0, 0.0, 1.0), v(0.0, s, 1.0));
            let d = edge_edge_distance_sq(&c0, &c1, &b0, &b1);
            assert!((d - 1.0).abs() <= 1e-12, "s = {s}: {d}");
            let (p, q) = edge_edge_closest_parameters(&c0, &c1, &b0, &b1);
            assert!((0.0..=1.0).contains(&p) && (0.0..=1.0).contains(&q));
        }
        // Both edges collapsed to points.
        let p = v(1.0, 2.0, 3.0);
        let q = v(1.0, 2.0, 6.0);
        assert_eq!(edge_edge_distance_sq(&p, &p, &q, &q), 9.0);
        assert_eq!(edge_edge_distance_sq_typed(&p, &p, &q, &q, Ee::EaEb), 9.0);
        assert_eq!(edge_edge_distance_type(&p, &p, &q, &q), Ee::Ea0Eb0);
    }

    #[test]
    fn nan_does_not_panic() {
        let n = v(f64::NAN, 0.0, 0.0);
        let a = v(0.0, 0.0, 0.0);
        let b = v(1.0, 1.0, 0.0);
        let _ = edge_edge_distance_type(&n, &a, &a, &b);
        assert!(edge_edge_distance_sq(&n, &a, &a, &b).is_nan());
        let _ = edge_edge_closest_parameters(&a, &n, &a, &b);
        assert!(edge_edge_mollifier(f64::NAN, 1.0).is_nan());
    }

    #[test]
    fn random_against_sampling() {
        let mut rng = StdRng::seed_from_u64(3);
        const N: usize = 400;
        for k in 0..100 {
            let mut e = [(); 4].map(|_| random_point(&mut rng));
            if k % 4 == 0 {
                // Make the edges parallel (or nearly) to exercise the boundary path.
                let dir = e[1] - e[0];
                e[3] = e[2] + rng.random_range(-1.5..1.5) * dir + 1e-10 * random_point(&mut rng);
            }
            let [a0, a1, b0, b1] = e;
            let d = edge_edge_distance_sq(&a0, &a1, &b0, &b1);
            let ty = edge_edge_distance_type(&a0, &a1, &b0, &b1);
            assert_eq!(d, edge_edge_distance_sq_typed(&a0, &a1, &b0, &b1, ty));
            let mut brute = f64::INFINITY;
            for i in 0..=N {
                let pa = a0 + (i as f64 / N as f64) * (a1 - a0);
                for j in 0..=N {
                    let pb = b0 + (j as f64 / N as f64) * (b1 - b0);
                    brute = brute.min((pa - pb).norm_squared());
                }
            }
            assert!(d <= brute + 1e-14, "{d} > {brute}");
            let h = ((a1 - a0).norm() + (b1 - b0).norm()) / N as f64;
            assert!(brute.sqrt() - d.sqrt() <= h, "{d} vs {brute}");
            let (s, t) = edge_edge_closest_parameters(&a0, &a1, &b0, &b1);
            let gap = (a0 + s * (a1 - a0)) - (b0 + t * (b1 - b0));
            assert!((gap.norm_squared() - d).abs() < 1e-12);
        }
    }

    #[test]
    fn mollifier_values_and_derivatives() {
        let a0 = v(0.0, 0.0, 0.0);
        let a1 = v(2.0, 0.0, 0.0);
        let b0 = v(0.0, 0.0, 1.0);
        let b1 = v(0.0, 3.0, 1.0);
        let eps = edge_edge_mollifier_threshold(&a0, &a1, &b0, &b1);
        assert!((eps - 1e-3 * 4.0 * 9.0).abs() < 1e-15);
        assert_eq!(edge_edge_cross_norm_sq(&a0, &a1, &b0, &b1), 36.0);
        assert_eq!(edge_edge_mollifier(0.0, eps), 0.0);
        assert_eq!(edge_edge_mollifier(eps, eps), 1.0);
        assert_eq!(edge_edge_mollifier(2.0 * eps, eps), 1.0);
        assert!((edge_edge_mollifier(0.5 * eps, eps) - 0.75).abs() < 1e-15);
        // Degenerate rest edges: no mollification.
        assert_eq!(edge_edge_mollifier(0.0, 0.0), 1.0);
        assert_eq!(edge_edge_mollifier_derivative(0.0, 0.0), 0.0);
        // C1 at the threshold, and derivatives match central differences.
        assert!(edge_edge_mollifier_derivative(eps * (1.0 - 1e-12), eps).abs() < 1e-6);
        for &x in &[0.1 * eps, 0.5 * eps, 0.9 * eps, 1.5 * eps] {
            let h = 1e-6 * eps;
            let fd = (edge_edge_mollifier(x + h, eps) - edge_edge_mollifier(x - h, eps)) / (2.0 * h);
            let an = edge_edge_mollifier_derivative(x, eps);
            assert!((fd - an).abs() <= 1e-6 * (1.0 + an.abs()), "{fd} vs {an}");
            let fd2 =
                (edge_edge_mollifier_derivative(x + h, eps) - edge_edge_mollifier_derivative(x - h, eps)) / (2.0 * h);
            let an2 = edge_edge_mollifier_second_derivative(x, eps);
            assert!((fd2 - an2).abs() <= 1e-6 * (1.0 + an2.abs()), "{fd2} vs {an2}");
        }
    }
}

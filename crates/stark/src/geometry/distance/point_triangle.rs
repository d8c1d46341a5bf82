//! Point–triangle squared distance.
//!
//! With `n = (t1 − t0) × (t2 − t0)`, the closest point of the closed triangle to `p` is the
//! projection of `p` onto the plane if that projection lies inside the triangle, at squared
//! distance `((p − t0)·n)² / |n|²`. Otherwise the closest point lies on the boundary, and the
//! answer is the nearest of the three point–edge distances (each of which may be a vertex). This is
//! the same partition as the Voronoi-region classification of the IPC Toolkit
//! (`point_triangle_distance_type`; ipc-notes B.1), computed by minimising over the boundary
//! instead of testing wedge regions, which keeps it exact for obtuse and degenerate triangles.

use nalgebra::Vector3;

use super::point_edge::{
    point_edge_closest_parameter_typed, point_edge_distance_sq_typed, point_edge_distance_type, point_line_distance_sq,
    PointEdgeDistanceType,
};
use super::point_point::point_point_distance_sq;

/// A triangle is treated as degenerate (a segment or a point) when
/// `|n|² ≤ DEGENERATE_TRIANGLE_REL · (max edge length²)²`, i.e. when the sine of its largest
/// angle-like ratio is below 1e-10. Its interior then lies within `1e-10 · max edge length` of its
/// boundary, and the boundary distance is used; the cross product of such a sliver is too
/// inaccurate to define a plane.
const DEGENERATE_TRIANGLE_REL: f64 = 1e-20;

/// Region of the closest point on a triangle (IPC `PointTriangleDistanceType`).
///
/// Edge `i` joins `t_i` and `t_(i+1 mod 3)`: edge 0 = (t0, t1), edge 1 = (t1, t2), edge 2 = (t2, t0).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PointTriangleDistanceType {
    /// Closest to vertex `t0` (IPC `P_T0`).
    PointT0,
    /// Closest to vertex `t1` (IPC `P_T1`).
    PointT1,
    /// Closest to vertex `t2` (IPC `P_T2`).
    PointT2,
    /// Closest to the interior of edge (t0, t1) (IPC `P_E0`).
    PointEdge0,
    /// Closest to the interior of edge (t1, t2) (IPC `P_E1`).
    PointEdge1,
    /// Closest to the interior of edge (t2, t0) (IPC `P_E2`).
    PointEdge2,
    /// Closest to the triangle interior: point–plane distance (IPC `P_T`).
    PointTriangle,
}

/// Whether `t0, t1, t2` span a plane well enough to use its normal (see
/// [`DEGENERATE_TRIANGLE_REL`]); returns the unnormalised normal when they do.
fn triangle_normal(t0: &Vector3<f64>, t1: &Vector3<f64>, t2: &Vector3<f64>) -> Option<Vector3<f64>> {
    let e0 = t1 - t0;
    let e1 = t2 - t1;
    let e2 = t0 - t2;
    let n = e0.cross(&(t2 - t0));
    let emax_sq = e0.norm_squared().max(e1.norm_squared()).max(e2.norm_squared());
    let n_sq = n.norm_squared();
    // `>` is false for NaN, zero and an underflowed normal: all take the boundary path.
    if n_sq > DEGENERATE_TRIANGLE_REL * emax_sq * emax_sq && n_sq.is_finite() {
        Some(n)
    } else {
        None
    }
}

/// The closest boundary feature: the nearest of the three point–edge distances, mapped to the
/// triangle's types. Ties go to the earlier edge.
fn closest_on_boundary(p: &Vector3<f64>, t: [&Vector3<f64>; 3]) -> (PointTriangleDistanceType, f64) {
    use PointEdgeDistanceType as Pe;
    use PointTriangleDistanceType as Pt;
    const MAP: [[PointTriangleDistanceType; 3]; 3] = [
        [Pt::PointT0, Pt::PointT1, Pt::PointEdge0],
        [Pt::PointT1, Pt::PointT2, Pt::PointEdge1],
        [Pt::PointT2, Pt::PointT0, Pt::PointEdge2],
    ];
    let mut best = (Pt::PointT0, f64::INFINITY);
    for i in 0..3 {
        let (a, b) = (t[i], t[(i + 1) % 3]);
        let ty = point_edge_distance_type(p, a, b);
        let d = point_edge_distance_sq_typed(p, a, b, ty);
        let mapped = MAP[i][match ty {
            Pe::PointE0 => 0,
            Pe::PointE1 => 1,
            Pe::PointEdge => 2,
        }];
        // The first candidate is always taken, so NaN input still yields a type.
        if i == 0 || d < best.1 {
            best = (mapped, d);
        }
    }
    best
}

/// Classifies which feature of the closed triangle `(t0, t1, t2)` is closest to `p`.
///
/// Inside test: with `n = (t1 − t0) × (t2 − t0)`, the projection of `p` is inside (or on the
/// boundary) when `((t_(i+1) − t_i) × n)·(p − t_i) ≤ 0` for all three edges; then the type is
/// [`PointTriangle`](PointTriangleDistanceType::PointTriangle). Otherwise the nearest edge or vertex
/// wins (ties go to edge 0, then 1, then 2, and to vertices over edge interiors). Degenerate
/// (collinear or point) triangles never return `PointTriangle`. NaN input gives some type.
pub fn point_triangle_distance_type(
    p: &Vector3<f64>,
    t0: &Vector3<f64>,
    t1: &Vector3<f64>,
    t2: &Vector3<f64>,
) -> PointTriangleDistanceType {
    if let Some(n) = triangle_normal(t0, t1, t2) {
        let t = [t0, t1, t2];
        let inside = (0..3).all(|i| {
            let (a, b) = (t[i], t[(i + 1) % 3]);
            (b - a).cross(&n).dot(&(p - a)) <= 0.0
        });
        if inside {
            return PointTriangleDistanceType::PointTriangle;
        }
    }
    closest_on_boundary(p, [t0, t1, t2]).0
}

/// Squared distance from `p` to the plane through `t0, t1, t2`: `((p − t0)·n)² / |n|²` with
/// `n = (t1 − t0) × (t2 − t0)`.
///
/// For a degenerate triangle (no well-defined plane) this returns the distance to the triangle's
/// boundary instead, so finite input always gives a finite result.
pub fn point_plane_distance_sq(p: &Vector3<f64>, t0: &Vector3<f64>, t1: &Vector3<f64>, t2: &Vector3<f64>) -> f64 {
    match triangle_normal(t0, t1, t2) {
        Some(n) => {
            let h = (p - t0).dot(&n);
            h * h / n.norm_squared()
        }
        None => closest_on_boundary(p, [t0, t1, t2]).1,
    }
}

/// Squared distance from `p` to the triangle for a given region type.
///
/// Vertex types give point–point, edge types point–line
/// ([`point_line_distance_sq`]), `PointTriangle` gives [`point_plane_distance_sq`].
pub fn point_triangle_distance_sq_typed(
    p: &Vector3<f64>,
    t0: &Vector3<f64>,
    t1: &Vector3<f64>,
    t2: &Vector3<f64>,
    ty: PointTriangleDistanceType,
) -> f64 {
    use PointTriangleDistanceType as Pt;
    match ty {
        Pt::PointT0 => point_point_distance_sq(p, t0),
        Pt::PointT1 => point_point_distance_sq(p, t1),
        Pt::PointT2 => point_point_distance_sq(p, t2),
        Pt::PointEdge0 => point_line_distance_sq(p, t0, t1),
        Pt::PointEdge1 => point_line_distance_sq(p, t1, t2),
        Pt::PointEdge2 => point_line_distance_sq(p, t2, t0),
        Pt::PointTriangle => point_plane_distance_sq(p, t0, t1, t2),
    }
}

/// Squared distance from `p` to the closed triangle `(t0, t1, t2)` (classifies with
/// [`point_triangle_distance_type`] first).
pub fn point_triangle_distance_sq(p: &Vector3<f64>, t0: &Vector3<f64>, t1: &Vector3<f64>, t2: &Vector3<f64>) -> f64 {
    let ty = point_triangle_distance_type(p, t0, t1, t2);
    point_triangle_distance_sq_typed(p, t0, t1, t2, ty)
}

/// Barycentric coordinates `(β1, β2)` of the closest point `t0 + β1 (t1 − t0) + β2 (t2 − t0)` of
/// the closed triangle to `p` (both in `[0, 1]`, `β1 + β2 ≤ 1`).
pub fn point_triangle_closest_barycentric(
    p: &Vector3<f64>,
    t0: &Vector3<f64>,
    t1: &Vector3<f64>,
    t2: &Vector3<f64>,
) -> (f64, f64) {
    let ty = point_triangle_distance_type(p, t0, t1, t2);
    point_triangle_closest_barycentric_typed(p, t0, t1, t2, ty)
}

/// Barycentric coordinates `(β1, β2)` of the closest point for a fixed region type, so that
/// closest = `t0 + β1 (t1 − t0) + β2 (t2 − t0)`.
///
/// For `PointTriangle` these are the *unclamped* coordinates of the projection onto the plane,
/// `β1 = ((p − t0) × (t2 − t0))·n / |n|²`, `β2 = ((t1 − t0) × (p − t0))·n / |n|²` (what lagged
/// friction of a face–vertex collision uses); edge types use the unclamped point–line parameter.
/// A degenerate triangle with type `PointTriangle` falls back to the closest boundary point.
pub fn point_triangle_closest_barycentric_typed(
    p: &Vector3<f64>,
    t0: &Vector3<f64>,
    t1: &Vector3<f64>,
    t2: &Vector3<f64>,
    ty: PointTriangleDistanceType,
) -> (f64, f64) {
    use PointEdgeDistanceType::PointEdge;
    use PointTriangleDistanceType as Pt;
    match ty {
        Pt::PointT0 => (0.0, 0.0),
        Pt::PointT1 => (1.0, 0.0),
        Pt::PointT2 => (0.0, 1.0),
        Pt::PointEdge0 => (point_edge_closest_parameter_typed(p, t0, t1, PointEdge), 0.0),
        Pt::PointEdge1 => {
            let a = point_edge_closest_parameter_typed(p, t1, t2, PointEdge);
            (1.0 - a, a)
        }
        Pt::PointEdge2 => {
            let a = point_edge_closest_parameter_typed(p, t2, t0, PointEdge);
            (0.0, 1.0 - a)
        }
        Pt::PointTriangle => match triangle_normal(t0, t1, t2) {
            Some(n) => {
                let n_sq = n.norm_squared();
                let w = p - t0;
                let b1 = w.cross(&(t2 - t0)).dot(&n) / n_sq;
                let b2 = (t1 - t0).cross(&w).dot(&n) / n_sq;
                (b1, b2)
            }
            None => {
                let ty = closest_on_boundary(p, [t0, t1, t2]).0;
                point_triangle_closest_barycentric_typed(p, t0, t1, t2, ty)
            }
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::distance::test_util::{random_point, SCALES};
    use rand::rngs::StdRng;
    use rand::{Rng, SeedableRng};
    use PointTriangleDistanceType as Pt;

    fn v(x: f64, y: f64, z: f64) -> Vector3<f64> {
        Vector3::new(x, y, z)
    }

    /// Right triangle in the z = 0 plane: t0 = origin, t1 = (2,0,0), t2 = (0,2,0).
    fn tri() -> [Vector3<f64>; 3] {
        [v(0.0, 0.0, 0.0), v(2.0, 0.0, 0.0), v(0.0, 2.0, 0.0)]
    }

    fn check(p: Vector3<f64>, t: &[Vector3<f64>; 3], ty: Pt, d: f64, bary: (f64, f64)) {
        assert_eq!(point_triangle_distance_type(&p, &t[0], &t[1], &t[2]), ty, "p = {p:?}");
        let got = point_triangle_distance_sq(&p, &t[0], &t[1], &t[2]);
        assert!((got - d).abs() <= 1e-14 * (1.0 + d), "p = {p:?}: {got} vs {d}");
        let (b1, b2) = point_triangle_closest_barycentric(&p, &t[0], &t[1], &t[2]);
        assert!((b1 - bary.0).abs() < 1e-14 && (b2 - bary.1).abs() < 1e-14, "{b1} {b2}");
    }

    #[test]
    fn every_region_closed_form() {
        let t = tri();
        // Interior, above and below.
        check(v(0.5, 0.5, 3.0), &t, Pt::PointTriangle, 9.0, (0.25, 0.25));
        check(v(0.5, 0.5, -3.0), &t, Pt::PointTriangle, 9.0, (0.25, 0.25));
        // Vertex regions.
        check(v(-1.0, -1.0, 1.0), &t, Pt::PointT0, 3.0, (0.0, 0.0));
        check(v(3.0, -1.0, 0.0), &t, Pt::PointT1, 2.0, (1.0, 0.0));
        check(v(-1.0, 3.0, 2.0), &t, Pt::PointT2, 6.0, (0.0, 1.0));
        // Edge regions.
        check(v(1.0, -2.0, 1.0), &t, Pt::PointEdge0, 5.0, (0.5, 0.0));
        check(v(2.0, 2.0, 0.0), &t, Pt::PointEdge1, 2.0, (0.5, 0.5));
        check(v(-3.0, 1.5, 4.0), &t, Pt::PointEdge2, 25.0, (0.0, 0.75));
    }

    #[test]
    fn obtuse_triangle_regions() {
        // Obtuse at t0: points outside edge 0 but in the span of edge 2 must go to the right edge.
        let t = [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(-3.0, 0.5, 0.0)];
        let p = v(-1.0, -0.1, 0.0);
        let ty = point_triangle_distance_type(&p, &t[0], &t[1], &t[2]);
        let d = point_triangle_distance_sq(&p, &t[0], &t[1], &t[2]);
        let d_edges = [
            super::super::point_edge_distance_sq(&p, &t[0], &t[1]),
            super::super::point_edge_distance_sq(&p, &t[1], &t[2]),
            super::super::point_edge_distance_sq(&p, &t[2], &t[0]),
        ];
        let min = d_edges.iter().cloned().fold(f64::INFINITY, f64::min);
        assert_eq!(d, min);
        assert_eq!(ty, Pt::PointEdge2);
    }

    #[test]
    fn point_on_boundary_and_in_plane() {
        let t = tri();
        // On the interior, on an edge, at a vertex: distance exactly 0.
        for p in [v(0.5, 0.5, 0.0), v(1.0, 0.0, 0.0), v(1.0, 1.0, 0.0), t[2]] {
            assert_eq!(point_triangle_distance_sq(&p, &t[0], &t[1], &t[2]), 0.0, "{p:?}");
        }
        // In-plane but outside.
        check(v(1.0, -0.5, 0.0), &t, Pt::PointEdge0, 0.25, (0.5, 0.0));
    }

    #[test]
    fn degenerate_scales() {
        let [t0, _, _] = tri();
        for &s in &SCALES {
            // Height `s` above the interior: distance s².
            let t = tri();
            let p = v(0.5, 0.5, s);
            let d = point_triangle_distance_sq(&p, &t[0], &t[1], &t[2]);
            assert!((d - s * s).abs() <= 1e-15 * (1.0 + s * s), "s = {s}: {d}");
            // Slightly outside edge 0 in the plane (by s): distance s² (or 0 when inside).
            let p = v(0.5, -s, 0.0);
            let d = point_triangle_distance_sq(&p, &t[0], &t[1], &t[2]);
            let expected = if s > 0.0 { s * s } else { 0.0 };
            assert!((d - expected).abs() <= 1e-15, "s = {s}: {d}");
            // Collapsing triangle: t2 at height s above t0 (a segment when s = 0).
            let t2 = v(0.0, s, 0.0);
            let t1 = v(2.0, 0.0, 0.0);
            let p = v(1.0, 0.0, 1.0);
            let d = point_triangle_distance_sq(&p, &t0, &t1, &t2);
            assert!((d - 1.0).abs() <= 1e-12, "s = {s}: {d}");
            let (b1, b2) = point_triangle_closest_barycentric(&p, &t0, &t1, &t2);
            let q = t0 + b1 * (t1 - t0) + b2 * (t2 - t0);
            assert!(((p - q).norm_squared() - d).abs() < 1e-12);
            // Tiny triangle of size s around the origin, point at distance 1.
            let (a, b, c) = (v(0.0, 0.0, 0.0), v(s, 0.0, 0.0), v(0.0, s, 0.0));
            let d = point_triangle_distance_sq(&v(0.0, 0.0, 1.0), &a, &b, &c);
            assert!((d - 1.0).abs() <= 1e-12, "s = {s}: {d}");
        }
        // Fully collapsed triangle (a point) and a collinear one.
        let q = v(1.0, 1.0, 1.0);
        let p = v(1.0, 1.0, 3.0);
        assert_eq!(point_triangle_distance_type(&p, &q, &q, &q), Pt::PointT0);
        assert_eq!(point_triangle_distance_sq(&p, &q, &q, &q), 4.0);
        assert_eq!(point_triangle_distance_sq_typed(&p, &q, &q, &q, Pt::PointTriangle), 4.0);
        let (a, b, c) = (v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(3.0, 0.0, 0.0));
        let p = v(2.0, 1.0, 0.0);
        assert_eq!(point_triangle_distance_sq(&p, &a, &b, &c), 1.0);
        assert_ne!(point_triangle_distance_type(&p, &a, &b, &c), Pt::PointTriangle);
    }

    #[test]
    fn nan_does_not_panic() {
        let t = tri();
        let n = v(f64::NAN, 0.0, 0.0);
        let _ = point_triangle_distance_type(&n, &t[0], &t[1], &t[2]);
        assert!(point_triangle_distance_sq(&n, &t[0], &t[1], &t[2]).is_nan());
        let _ = point_triangle_distance_type(&t[0], &n, &t[1], &t[2]);
        let _ = point_triangle_closest_barycentric(&t[0], &n, &t[1], &t[2]);
        let i = v(f64::INFINITY, 0.0, 0.0);
        let _ = point_triangle_distance_sq(&t[0], &i, &t[1], &t[2]);
    }

    #[test]
    fn typed_matches_auto_and_barycentric() {
        let mut rng = StdRng::seed_from_u64(1);
        for _ in 0..1000 {
            let p = 2.0 * random_point(&mut rng);
            let t = [random_point(&mut rng), random_point(&mut rng), random_point(&mut rng)];
            let ty = point_triangle_distance_type(&p, &t[0], &t[1], &t[2]);
            let d = point_triangle_distance_sq(&p, &t[0], &t[1], &t[2]);
            assert_eq!(d, point_triangle_distance_sq_typed(&p, &t[0], &t[1], &t[2], ty));
            let (b1, b2) = point_triangle_closest_barycentric(&p, &t[0], &t[1], &t[2]);
            assert!(b1 >= -1e-12 && b2 >= -1e-12 && b1 + b2 <= 1.0 + 1e-12);
            let q = t[0] + b1 * (t[1] - t[0]) + b2 * (t[2] - t[0]);
            assert!(((p - q).norm_squared() - d).abs() <= 1e-12 * (1.0 + d));
        }
    }

    #[test]
    fn random_against_sampling() {
        let mut rng = StdRng::seed_from_u64(2);
        const N: usize = 300;
        for _ in 0..100 {
            let p = 1.5 * random_point(&mut rng);
            let t = [random_point(&mut rng), random_point(&mut rng), random_point(&mut rng)];
            // Sometimes put the point near the plane or make the triangle a sliver.
            let p = if rng.random_bool(0.3) {
                let (b1, b2): (f64, f64) = (rng.random(), rng.random());
                t[0] + b1 * (t[1] - t[0]) + b2 * (t[2] - t[0])
            } else {
                p
            };
            let d = point_triangle_distance_sq(&p, &t[0], &t[1], &t[2]);
            let mut brute = f64::INFINITY;
            for i in 0..=N {
                for j in 0..=(N - i) {
                    let (b1, b2) = (i as f64 / N as f64, j as f64 / N as f64);
                    let q = t[0] + b1 * (t[1] - t[0]) + b2 * (t[2] - t[0]);
                    brute = brute.min((p - q).norm_squared());
                }
            }
            assert!(d <= brute + 1e-14, "{d} > {brute}");
            // Every point of the triangle is within one grid cell diameter of a sample.
            let h = ((t[1] - t[0]).norm() + (t[2] - t[0]).norm()) / N as f64;
            assert!(brute.sqrt() - d.sqrt() <= h, "{d} vs {brute}");
        }
    }
}

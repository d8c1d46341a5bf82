//! Point–edge squared distance.
//!
//! With `e = e1 − e0` and `r = e·(p − e0) / |e|²` (the parameter of the projection of `p` onto the
//! edge's line), the closest point is `e0` for `r ≤ 0`, `e1` for `r ≥ 1`, and otherwise the
//! projection, at squared distance `|(e0 − p) × (e1 − p)|² / |e|²` (IPC Toolkit
//! `point_edge_distance`).

use nalgebra::Vector3;

use super::point_point::point_point_distance_sq;

/// Region of the closest point on an edge (IPC `PointEdgeDistanceType`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PointEdgeDistanceType {
    /// Closest to the end vertex `e0` (IPC `P_E0`).
    PointE0,
    /// Closest to the end vertex `e1` (IPC `P_E1`).
    PointE1,
    /// Closest to the edge interior: point–line distance (IPC `P_E`).
    PointEdge,
}

/// Classifies which feature of the closed edge `[e0, e1]` is closest to `p`.
///
/// With `r = (e1 − e0)·(p − e0) / |e1 − e0|²`: `r ≤ 0` → [`PointE0`](PointEdgeDistanceType::PointE0),
/// `r ≥ 1` → [`PointE1`](PointEdgeDistanceType::PointE1), otherwise
/// [`PointEdge`](PointEdgeDistanceType::PointEdge). Ties go to the vertex (same distance, exact
/// formula). A zero-length edge gives `PointE0`. NaN input gives some type without panicking.
pub fn point_edge_distance_type(p: &Vector3<f64>, e0: &Vector3<f64>, e1: &Vector3<f64>) -> PointEdgeDistanceType {
    let e = e1 - e0;
    let len_sq = e.norm_squared();
    // Zero, underflowed (edges shorter than ~1e-154), infinite or NaN lengths: use e0.
    let usable = len_sq > 0.0 && len_sq.is_finite();
    let r = if usable { e.dot(&(p - e0)) / len_sq } else { 0.0 };
    if r <= 0.0 {
        PointEdgeDistanceType::PointE0
    } else if r >= 1.0 {
        PointEdgeDistanceType::PointE1
    } else {
        PointEdgeDistanceType::PointEdge
    }
}

/// Squared distance from `p` to the infinite line through `e0` and `e1`:
/// `|(e0 − p) × (e1 − p)|² / |e1 − e0|²`.
///
/// For a zero-length edge (including one whose squared length underflows) this returns
/// `|p − e0|²` instead of `0/0`, so finite input always gives a finite result.
#[inline]
pub fn point_line_distance_sq(p: &Vector3<f64>, e0: &Vector3<f64>, e1: &Vector3<f64>) -> f64 {
    let len_sq = (e1 - e0).norm_squared();
    if len_sq > 0.0 {
        (e0 - p).cross(&(e1 - p)).norm_squared() / len_sq
    } else {
        point_point_distance_sq(p, e0)
    }
}

/// Squared distance from `p` to the closed edge `[e0, e1]` for a given region type.
///
/// `PointE0` → `|p − e0|²`, `PointE1` → `|p − e1|²`, `PointEdge` → [`point_line_distance_sq`].
#[inline]
pub fn point_edge_distance_sq_typed(
    p: &Vector3<f64>,
    e0: &Vector3<f64>,
    e1: &Vector3<f64>,
    ty: PointEdgeDistanceType,
) -> f64 {
    match ty {
        PointEdgeDistanceType::PointE0 => point_point_distance_sq(p, e0),
        PointEdgeDistanceType::PointE1 => point_point_distance_sq(p, e1),
        PointEdgeDistanceType::PointEdge => point_line_distance_sq(p, e0, e1),
    }
}

/// Squared distance from `p` to the closed edge `[e0, e1]` (classifies with
/// [`point_edge_distance_type`] first).
#[inline]
pub fn point_edge_distance_sq(p: &Vector3<f64>, e0: &Vector3<f64>, e1: &Vector3<f64>) -> f64 {
    point_edge_distance_sq_typed(p, e0, e1, point_edge_distance_type(p, e0, e1))
}

/// Parameter `α ∈ [0, 1]` of the closest point `e0 + α (e1 − e0)` on the closed edge to `p`.
///
/// A zero-length edge gives `0`.
#[inline]
pub fn point_edge_closest_parameter(p: &Vector3<f64>, e0: &Vector3<f64>, e1: &Vector3<f64>) -> f64 {
    point_edge_closest_parameter_typed(p, e0, e1, point_edge_distance_type(p, e0, e1))
}

/// Parameter `α` of the closest point `e0 + α (e1 − e0)` for a fixed region type.
///
/// `PointE0` → 0, `PointE1` → 1, `PointEdge` → the *unclamped* projection parameter
/// `(e1 − e0)·(p − e0) / |e1 − e0|²` onto the line (what lagged friction of an edge–vertex
/// collision uses). A zero-length edge gives `0`.
pub fn point_edge_closest_parameter_typed(
    p: &Vector3<f64>,
    e0: &Vector3<f64>,
    e1: &Vector3<f64>,
    ty: PointEdgeDistanceType,
) -> f64 {
    match ty {
        PointEdgeDistanceType::PointE0 => 0.0,
        PointEdgeDistanceType::PointE1 => 1.0,
        PointEdgeDistanceType::PointEdge => {
            let e = e1 - e0;
            let len_sq = e.norm_squared();
            if len_sq > 0.0 {
                e.dot(&(p - e0)) / len_sq
            } else {
                0.0
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::distance::test_util::{random_point, SCALES};
    use rand::rngs::StdRng;
    use rand::SeedableRng;

    fn v(x: f64, y: f64, z: f64) -> Vector3<f64> {
        Vector3::new(x, y, z)
    }

    #[test]
    fn every_region_closed_form() {
        let e0 = v(0.0, 0.0, 0.0);
        let e1 = v(2.0, 0.0, 0.0);
        // Before e0.
        let p = v(-1.0, 1.0, 0.0);
        assert_eq!(point_edge_distance_type(&p, &e0, &e1), PointEdgeDistanceType::PointE0);
        assert_eq!(point_edge_distance_sq(&p, &e0, &e1), 2.0);
        assert_eq!(point_edge_closest_parameter(&p, &e0, &e1), 0.0);
        // Past e1.
        let p = v(3.0, 0.0, 2.0);
        assert_eq!(point_edge_distance_type(&p, &e0, &e1), PointEdgeDistanceType::PointE1);
        assert_eq!(point_edge_distance_sq(&p, &e0, &e1), 5.0);
        assert_eq!(point_edge_closest_parameter(&p, &e0, &e1), 1.0);
        // Interior.
        let p = v(0.5, 3.0, 4.0);
        assert_eq!(point_edge_distance_type(&p, &e0, &e1), PointEdgeDistanceType::PointEdge);
        assert!((point_edge_distance_sq(&p, &e0, &e1) - 25.0).abs() < 1e-14);
        assert!((point_edge_closest_parameter(&p, &e0, &e1) - 0.25).abs() < 1e-15);
        // Unclamped typed parameter extrapolates along the line.
        let p = v(3.0, 1.0, 0.0);
        let a = point_edge_closest_parameter_typed(&p, &e0, &e1, PointEdgeDistanceType::PointEdge);
        assert_eq!(a, 1.5);
        assert_eq!(
            point_edge_distance_sq_typed(&p, &e0, &e1, PointEdgeDistanceType::PointEdge),
            1.0
        );
    }

    #[test]
    fn point_on_edge_and_at_vertices() {
        let e0 = v(1.0, 1.0, 1.0);
        let e1 = v(3.0, 1.0, 1.0);
        assert_eq!(point_edge_distance_sq(&v(2.0, 1.0, 1.0), &e0, &e1), 0.0);
        assert_eq!(point_edge_distance_sq(&e0, &e0, &e1), 0.0);
        assert_eq!(point_edge_distance_sq(&e1, &e0, &e1), 0.0);
        assert_eq!(point_edge_distance_type(&e0, &e0, &e1), PointEdgeDistanceType::PointE0);
        assert_eq!(point_edge_distance_type(&e1, &e0, &e1), PointEdgeDistanceType::PointE1);
    }

    #[test]
    fn degenerate_scales() {
        // Edge of length `s` along x, point at height 1 above the middle.
        for &s in &SCALES {
            let e0 = v(0.0, 0.0, 0.0);
            let e1 = v(s, 0.0, 0.0);
            let p = v(0.5 * s, 1.0, 0.0);
            let d = point_edge_distance_sq(&p, &e0, &e1);
            assert!(d.is_finite(), "s = {s}");
            assert!((d - 1.0).abs() <= 1e-12, "s = {s}: {d}");
            let a = point_edge_closest_parameter(&p, &e0, &e1);
            assert!((0.0..=1.0).contains(&a));
        }
        // Point at scale `s` relative to a unit edge, on the line and off it.
        for &s in &SCALES {
            let e0 = v(0.0, 0.0, 0.0);
            let e1 = v(1.0, 0.0, 0.0);
            let p = v(0.5, s, 0.0);
            let d = point_edge_distance_sq(&p, &e0, &e1);
            assert!((d - s * s).abs() <= 1e-15 * (1.0 + s * s), "s = {s}: {d}");
        }
        // Zero-length edge: falls back to the point.
        let e = v(1.0, 2.0, 3.0);
        let p = v(1.0, 2.0, 5.0);
        assert_eq!(point_edge_distance_type(&p, &e, &e), PointEdgeDistanceType::PointE0);
        assert_eq!(point_edge_distance_sq(&p, &e, &e), 4.0);
        assert_eq!(
            point_edge_distance_sq_typed(&p, &e, &e, PointEdgeDistanceType::PointEdge),
            4.0
        );
        assert_eq!(point_edge_closest_parameter(&p, &e, &e), 0.0);
        // An edge so short that its squared length underflows.
        let e1 = e + v(1e-170, 0.0, 0.0);
        let d = point_edge_distance_sq_typed(&p, &e, &e1, PointEdgeDistanceType::PointEdge);
        assert!((d - 4.0).abs() < 1e-14);
    }

    #[test]
    fn nan_does_not_panic() {
        let n = v(f64::NAN, 0.0, 0.0);
        let a = v(0.0, 0.0, 0.0);
        let b = v(1.0, 0.0, 0.0);
        let _ = point_edge_distance_type(&n, &a, &b);
        assert!(point_edge_distance_sq(&n, &a, &b).is_nan());
        let _ = point_edge_distance_type(&a, &n, &b);
        let _ = point_edge_closest_parameter(&a, &n, &b);
    }

    #[test]
    fn random_against_sampling() {
        let mut rng = StdRng::seed_from_u64(0);
        const N: usize = 2000;
        for _ in 0..200 {
            let p = random_point(&mut rng);
            let e0 = random_point(&mut rng);
            let e1 = random_point(&mut rng);
            let d = point_edge_distance_sq(&p, &e0, &e1);
            let mut brute = f64::INFINITY;
            for i in 0..=N {
                let a = i as f64 / N as f64;
                brute = brute.min((p - (e0 + a * (e1 - e0))).norm_squared());
            }
            assert!(d <= brute + 1e-14, "{d} > {brute}");
            // The sampling step is |e|/N ≤ 2√3/N, so the sampled distance is at most that far off.
            let h = (e1 - e0).norm() / N as f64;
            assert!(brute.sqrt() - d.sqrt() <= h, "{d} vs {brute}");
            // The closest parameter reproduces the distance.
            let a = point_edge_closest_parameter(&p, &e0, &e1);
            let q = e0 + a * (e1 - e0);
            assert!(((p - q).norm_squared() - d).abs() < 1e-13);
        }
    }
}

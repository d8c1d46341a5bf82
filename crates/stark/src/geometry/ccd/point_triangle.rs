//! Point–triangle CCD.

use nalgebra::Vector3;

use super::root_finder::Stencil;
use super::{max_step, run_ccd, CcdParams};

/// Time of impact of a point and a triangle whose vertices move linearly from their `_t0` to their
/// `_t1` positions, with the default [`CcdParams`].
///
/// Returns `Some(toi)` with `toi ∈ [0, tmax]` such that the point stays farther than
/// `min_distance` from the triangle for all `t ∈ [0, toi)` (and, when `toi > 0`, also at `toi`),
/// or `None` if it provably does so for all `t ∈ [0, tmax]`. Conservative: a contact is never
/// missed; near misses within about [`CcdParams::tolerance`] may be reported. `Some(0.0)` means the
/// primitives are already in contact at `t = 0` (see the [module doc](super)).
#[allow(clippy::too_many_arguments)]
pub fn point_triangle_ccd(
    p_t0: &Vector3<f64>,
    t0_t0: &Vector3<f64>,
    t1_t0: &Vector3<f64>,
    t2_t0: &Vector3<f64>,
    p_t1: &Vector3<f64>,
    t0_t1: &Vector3<f64>,
    t1_t1: &Vector3<f64>,
    t2_t1: &Vector3<f64>,
    min_distance: f64,
    tmax: f64,
) -> Option<f64> {
    point_triangle_ccd_with_params(
        &[*p_t0, *t0_t0, *t1_t0, *t2_t0],
        &[*p_t1, *t0_t1, *t1_t1, *t2_t1],
        min_distance,
        tmax,
        &CcdParams::default(),
    )
}

/// [`point_triangle_ccd`] with explicit parameters; vertices in the order `[p, t0, t1, t2]`.
pub fn point_triangle_ccd_with_params(
    x_t0: &[Vector3<f64>; 4],
    x_t1: &[Vector3<f64>; 4],
    min_distance: f64,
    tmax: f64,
    params: &CcdParams,
) -> Option<f64> {
    run_ccd(Stencil::PointTriangle, x_t0, x_t1, min_distance, tmax, params).toi
}

/// Largest safe line-search step `α ∈ [0, tmax]` for a point–triangle candidate moving from `x_t0`
/// to `x_t1` (vertex order `[p, t0, t1, t2]`).
///
/// `tmax` when the pair provably stays farther than `min_distance` (plus the extra gap of
/// [`CcdParams::gap_fraction`]) up to `tmax`; otherwise `conservative_rescaling · toi`, which is
/// positive unless the pair is already in contact at `t = 0`. Pass the smallest step found so far
/// as `tmax` to shorten later searches (IPC Toolkit practice).
pub fn point_triangle_max_step(
    x_t0: &[Vector3<f64>; 4],
    x_t1: &[Vector3<f64>; 4],
    min_distance: f64,
    tmax: f64,
    params: &CcdParams,
) -> f64 {
    max_step(Stencil::PointTriangle, x_t0, x_t1, min_distance, tmax, params)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::ccd::run_ccd;
    use crate::geometry::distance::point_triangle_distance_sq;
    use rand::rngs::StdRng;
    use rand::{Rng, SeedableRng};

    fn v(x: f64, y: f64, z: f64) -> Vector3<f64> {
        Vector3::new(x, y, z)
    }

    /// A random vector with coordinates uniform in `[-s, s)`.
    fn rp(rng: &mut StdRng, s: f64) -> Vector3<f64> {
        v(
            rng.random_range(-s..s),
            rng.random_range(-s..s),
            rng.random_range(-s..s),
        )
    }

    fn tri() -> [Vector3<f64>; 3] {
        [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0)]
    }

    /// CCD of a point moving `p0 → p1` against a static triangle.
    fn ccd_static(p0: Vector3<f64>, p1: Vector3<f64>, t: &[Vector3<f64>; 3], d: f64) -> Option<f64> {
        point_triangle_ccd(&p0, &t[0], &t[1], &t[2], &p1, &t[0], &t[1], &t[2], d, 1.0)
    }

    fn dist_at(x0: &[Vector3<f64>; 4], x1: &[Vector3<f64>; 4], t: f64) -> f64 {
        let x: Vec<_> = (0..4).map(|i| x0[i] + t * (x1[i] - x0[i])).collect();
        point_triangle_distance_sq(&x[0], &x[1], &x[2], &x[3]).sqrt()
    }

    /// Asserts `toi` is within `[t_true − slack, t_true)`.
    fn assert_just_before(toi: Option<f64>, t_true: f64, slack: f64) {
        let toi = toi.expect("impact expected");
        assert!(toi < t_true && toi > t_true - slack, "toi {toi}, true {t_true}");
    }

    #[test]
    fn falls_through_interior() {
        let t = tri();
        let toi = ccd_static(v(0.25, 0.25, 1.0), v(0.25, 0.25, -1.0), &t, 0.0);
        assert_just_before(toi, 0.5, 1e-5);
        // Moving triangle, static point: same relative motion.
        let p = v(0.25, 0.25, 0.0);
        let up = v(0.0, 0.0, 2.0);
        let down = v(0.0, 0.0, -1.0);
        let toi = point_triangle_ccd(
            &p,
            &(t[0] + down),
            &(t[1] + down),
            &(t[2] + down),
            &p,
            &(t[0] + up),
            &(t[1] + up),
            &(t[2] + up),
            0.0,
            1.0,
        );
        assert_just_before(toi, 1.0 / 3.0, 1e-5);
    }

    #[test]
    fn misses() {
        let t = tri();
        assert_eq!(ccd_static(v(2.0, 2.0, 1.0), v(2.0, 2.0, -1.0), &t, 0.0), None);
        // Stops short of the plane.
        assert_eq!(ccd_static(v(0.2, 0.2, 1.0), v(0.2, 0.2, 0.01), &t, 0.0), None);
        // tmax before the crossing.
        let r = point_triangle_ccd(
            &v(0.25, 0.25, 1.0),
            &t[0],
            &t[1],
            &t[2],
            &v(0.25, 0.25, -1.0),
            &t[0],
            &t[1],
            &t[2],
            0.0,
            0.4,
        );
        assert_eq!(r, None);
    }

    #[test]
    fn zero_motion() {
        let t = tri();
        assert_eq!(ccd_static(v(0.2, 0.2, 0.5), v(0.2, 0.2, 0.5), &t, 0.0), None);
        assert_eq!(ccd_static(v(0.2, 0.2, 0.5), v(0.2, 0.2, 0.5), &t, 0.4), None);
        assert_eq!(ccd_static(v(0.2, 0.2, 0.5), v(0.2, 0.2, 0.5), &t, 0.5), Some(0.0));
        assert_eq!(ccd_static(v(0.2, 0.2, 0.0), v(0.2, 0.2, 0.0), &t, 0.0), Some(0.0));
        // Tiny but positive gap at rest: no impact.
        assert_eq!(ccd_static(v(0.2, 0.2, 1e-9), v(0.2, 0.2, 1e-9), &t, 0.0), None);
    }

    #[test]
    fn grazing_and_in_plane_motion() {
        let t = tri();
        // Sliding parallel to the plane just above it: no impact.
        assert_eq!(ccd_static(v(-1.0, 0.25, 1e-4), v(2.0, 0.25, 1e-4), &t, 0.0), None);
        // In the plane, entering through edge 2 (x = 0) at t = 0.5.
        assert_just_before(ccd_static(v(-1.0, 0.25, 0.0), v(1.0, 0.25, 0.0), &t, 0.0), 0.5, 1e-5);
        // Moving along the line of edge 0, reaching vertex t0 at t = 0.25.
        assert_just_before(ccd_static(v(-1.0, 0.0, 0.0), v(3.0, 0.0, 0.0), &t, 0.0), 0.25, 1e-5);
        // Moving along the edge line but starting beyond t1: no impact.
        assert_eq!(ccd_static(v(1.5, 0.0, 0.0), v(3.0, 0.0, 0.0), &t, 0.0), None);
        // Grazing the vertex t2 from above and along the diagonal.
        assert_just_before(ccd_static(v(-1.0, 2.0, 1.0), v(1.0, 0.0, -1.0), &t, 0.0), 0.5, 1e-5);
    }

    #[test]
    fn degenerate_triangles() {
        // Collinear triangle (a segment along x): point crossing its middle at t = 0.5.
        let seg = [v(0.0, 0.0, 0.0), v(2.0, 0.0, 0.0), v(1.0, 0.0, 0.0)];
        assert_just_before(ccd_static(v(1.5, -1.0, 0.0), v(1.5, 1.0, 0.0), &seg, 0.0), 0.5, 1e-5);
        assert_eq!(ccd_static(v(1.5, -1.0, 0.1), v(1.5, 1.0, 0.1), &seg, 0.0), None);
        // Triangle collapsing to a point during the motion while the point passes through it.
        let p = v(0.5, 0.5, 0.5);
        let toi = point_triangle_ccd(
            &v(0.5, 0.5, -0.5),
            &v(0.0, 0.0, 0.0),
            &v(1.0, 0.0, 0.0),
            &v(0.0, 1.0, 0.0),
            &v(0.5, 0.5, 1.5),
            &p,
            &p,
            &p,
            0.0,
            1.0,
        );
        assert!(toi.is_some());
    }

    #[test]
    fn min_distance() {
        let t = tri();
        // Distance 1 − 2t reaches 0.1 at t = 0.45.
        let x0 = [v(0.25, 0.25, 1.0), t[0], t[1], t[2]];
        let x1 = [v(0.25, 0.25, -1.0), t[0], t[1], t[2]];
        let toi = point_triangle_ccd_with_params(&x0, &x1, 0.1, 1.0, &CcdParams::default());
        assert_just_before(toi, 0.45, 1e-5);
        assert!(dist_at(&x0, &x1, toi.unwrap()) > 0.1);
        // Passing beside the triangle at distance 0.2 (beyond edge 1, x + y = 1): only within 0.25.
        let x0 = [
            v(0.5 + 0.2 / 2f64.sqrt(), 0.5 + 0.2 / 2f64.sqrt(), 1.0),
            t[0],
            t[1],
            t[2],
        ];
        let mut x1 = x0;
        x1[0].z = -1.0;
        let p = CcdParams::default();
        assert_eq!(point_triangle_ccd_with_params(&x0, &x1, 0.19, 1.0, &p), None);
        assert!(point_triangle_ccd_with_params(&x0, &x1, 0.21, 1.0, &p).is_some());
    }

    #[test]
    fn invalid_inputs() {
        let t = tri();
        let n = v(f64::NAN, 0.0, 0.0);
        assert_eq!(ccd_static(n, v(0.0, 0.0, 1.0), &t, 0.0), Some(0.0));
        assert_eq!(
            ccd_static(v(0.2, 0.2, 1.0), v(0.2, 0.2, -1.0), &t, f64::INFINITY),
            Some(0.0)
        );
        // Negative and NaN min_distance act as 0; tmax is clamped.
        let a = ccd_static(v(0.2, 0.2, 1.0), v(0.2, 0.2, -1.0), &t, -1.0);
        assert_eq!(a, ccd_static(v(0.2, 0.2, 1.0), v(0.2, 0.2, -1.0), &t, f64::NAN));
        let r = point_triangle_ccd(
            &v(0.25, 0.25, 1.0),
            &t[0],
            &t[1],
            &t[2],
            &v(0.25, 0.25, -1.0),
            &t[0],
            &t[1],
            &t[2],
            0.0,
            7.0,
        );
        assert_just_before(r, 0.5, 1e-5);
        // Everything at the origin.
        let z = v(0.0, 0.0, 0.0);
        assert_eq!(point_triangle_ccd(&z, &z, &z, &z, &z, &z, &z, &z, 0.0, 1.0), Some(0.0));
    }

    #[test]
    fn scale_invariance() {
        // Power-of-two scalings are exact, so the answer must be bit-identical.
        let t = tri();
        let x0 = [v(0.3, 0.2, 1.0), t[0], t[1], t[2]];
        let x1 = [
            v(0.1, 0.4, -0.7),
            t[0] + v(0.0, 0.0, 0.1),
            t[1],
            t[2] - v(0.0, 0.0, 0.2),
        ];
        let p = CcdParams::default();
        let base = point_triangle_ccd_with_params(&x0, &x1, 0.0, 1.0, &p);
        assert!(base.is_some());
        for e in [-900, -300, -40, 40, 300, 900] {
            let s = 2f64.powi(e);
            let params = CcdParams {
                tolerance: p.tolerance * s,
                ..p
            };
            let r = point_triangle_ccd_with_params(&x0.map(|x| x * s), &x1.map(|x| x * s), 0.0, 1.0, &params);
            assert_eq!(r, base, "scale 2^{e}");
        }
    }

    /// Regression: a tangential approach to the `δ`-sphere (`δ = 0.1`, tolerance `1e-6`) needed
    /// ~6e5 boxes with plain bisection (the region within the tolerance of contact is a disk of
    /// radius `√(2δ·tol)`); the directional time split and the start-corner acceptance bring it to
    /// a few thousand.
    #[test]
    fn tangential_approach_with_min_distance_is_cheap() {
        let x0 = [
            v(-0.35465299739211753, 0.5008929139556098, -0.5643357840284517),
            v(-0.7232215510385456, -0.5989269608716512, -0.02779165907751846),
            v(0.7693168346075443, -0.16307585603090446, -0.955402010484864),
            v(0.1922559118663889, 0.6030060462221178, 0.6568260549822349),
        ];
        let x1 = [
            v(0.09000174023437563, -0.7425253517186735, 0.32535967420798023),
            v(-0.7228087648307822, -0.9258891010137442, 0.188459924583406),
            v(0.2988230751845138, -0.5058463069125336, -0.9635149830612799),
            v(-0.29297471925814667, 0.7584566027541595, 1.017937895020154),
        ];
        let params = CcdParams::default();
        let r = run_ccd(Stencil::PointTriangle, &x0, &x1, 0.1, 1.0, &params);
        let toi = r.toi.expect("impact");
        assert!(r.iterations < 10_000, "{}", r.iterations);
        // Safe, and within the tolerance of the first time the distance is 0.1.
        let d = dist_at(&x0, &x1, toi);
        assert!(d > 0.1 && d < 0.1 + 1e-5, "{d}");
    }

    #[test]
    fn max_step() {
        let t = tri();
        let p = CcdParams::default();
        let x0 = [v(0.25, 0.25, 1.0), t[0], t[1], t[2]];
        let x1 = [v(0.25, 0.25, -1.0), t[0], t[1], t[2]];
        // Contact at t = 0.5: the step stops safely short of it, but not far short.
        let a = point_triangle_max_step(&x0, &x1, 0.0, 1.0, &p);
        assert!(a < 0.5 && a > 0.35, "{a}");
        assert!(dist_at(&x0, &x1, a) > 1e-4);
        // No collision: the full step (or tmax).
        let mut far = x1;
        far[0].z = 0.5;
        assert_eq!(point_triangle_max_step(&x0, &far, 0.0, 1.0, &p), 1.0);
        assert_eq!(point_triangle_max_step(&x0, &far, 0.0, 0.3, &p), 0.3);
        // Already in contact: 0. Very close but separated: positive.
        let touching = [v(0.25, 0.25, 0.0), t[0], t[1], t[2]];
        assert_eq!(point_triangle_max_step(&touching, &x1, 0.0, 1.0, &p), 0.0);
        let close = [v(0.25, 0.25, 1e-10), t[0], t[1], t[2]];
        let a = point_triangle_max_step(&close, &x1, 0.0, 1.0, &p);
        assert!(a > 0.0 && a < 1e-10, "{a}");
        assert!(dist_at(&close, &x1, a) > 0.0);
    }

    /// Random trajectories, checked against dense time sampling: whenever a sampled configuration
    /// is within `δ`, the TOI must be at or before that time, and the configuration at the TOI
    /// must be farther than `δ` (up to rounding of the sampling itself).
    #[test]
    fn random_conservative_against_sampling() {
        let mut rng = StdRng::seed_from_u64(30);
        let params = CcdParams::default();
        let (mut hits, mut total_iter) = (0, 0);
        for k in 0..400 {
            let x0 = [
                rp(&mut rng, 1.0),
                rp(&mut rng, 1.0),
                rp(&mut rng, 1.0),
                rp(&mut rng, 1.0),
            ];
            let mut x1 = [
                x0[0] + rp(&mut rng, 1.5),
                x0[1] + rp(&mut rng, 0.5),
                x0[2] + rp(&mut rng, 0.5),
                x0[3] + rp(&mut rng, 0.5),
            ];
            if k % 3 != 0 {
                // Aim the point through the triangle's centroid region, so contacts are common.
                let c = (x0[1] + x0[2] + x0[3] + x1[1] + x1[2] + x1[3]) / 6.0;
                x1[0] = 2.0 * c - x0[0] + rp(&mut rng, 0.3);
            }
            let delta = if k % 2 == 0 { 0.0 } else { 0.1 };
            let report = run_ccd(Stencil::PointTriangle, &x0, &x1, delta, 1.0, &params);
            total_iter += report.iterations;
            const N: usize = 2000;
            let first = (0..=N)
                .map(|j| j as f64 / N as f64)
                .find(|&t| dist_at(&x0, &x1, t) <= delta);
            if let Some(ts) = first {
                let toi = report.toi.expect("missed a sampled contact");
                assert!(toi <= ts, "toi {toi} after sampled contact at {ts}");
                hits += 1;
            }
            if let Some(toi) = report.toi {
                if toi > 0.0 {
                    assert!(dist_at(&x0, &x1, toi) >= delta - 1e-12, "unsafe toi {toi}");
                }
            }
        }
        assert!(hits > 100, "{hits}");
        // Tangential approaches with δ > 0 used to cost ~1e6 boxes; keep them cheap.
        println!("{hits} contacts, {} boxes per query on average", total_iter / 400);
        assert!(total_iter < 400 * 2_000, "{total_iter}");
    }

    /// Trajectories constructed to touch at a chosen time (up to the rounding of the
    /// construction, which the error bound must absorb).
    #[test]
    fn random_constructed_contacts() {
        let mut rng = StdRng::seed_from_u64(31);
        for _ in 0..300 {
            let t0 = [rp(&mut rng, 1.0), rp(&mut rng, 1.0), rp(&mut rng, 1.0)];
            let t1 = [
                t0[0] + rp(&mut rng, 0.5),
                t0[1] + rp(&mut rng, 0.5),
                t0[2] + rp(&mut rng, 0.5),
            ];
            let p0 = rp(&mut rng, 1.0);
            let ts: f64 = rng.random_range(0.05..1.0);
            let (mut b1, mut b2): (f64, f64) = (rng.random(), rng.random());
            if b1 + b2 > 1.0 {
                (b1, b2) = (1.0 - b1, 1.0 - b2);
            }
            // Sometimes exactly on an edge or a vertex.
            match rng.random_range(0..4) {
                0 => b2 = 0.0,
                1 => (b1, b2) = (1.0, 0.0),
                _ => {}
            }
            let at = |i: usize| t0[i] + ts * (t1[i] - t0[i]);
            let q = at(0) + b1 * (at(1) - at(0)) + b2 * (at(2) - at(0));
            let p1 = p0 + (q - p0) / ts;
            let toi = point_triangle_ccd(&p0, &t0[0], &t0[1], &t0[2], &p1, &t1[0], &t1[1], &t1[2], 0.0, 1.0);
            let toi = toi.expect("constructed contact missed");
            assert!(toi <= ts + 1e-9, "toi {toi} vs {ts}");
        }
    }
}

//! Edge–edge CCD.

use nalgebra::Vector3;

use super::root_finder::Stencil;
use super::{max_step, run_ccd, CcdParams};

/// Time of impact of two edges whose end vertices move linearly from their `_t0` to their `_t1`
/// positions, with the default [`CcdParams`].
///
/// Same contract as [`point_triangle_ccd`](super::point_triangle_ccd): `Some(toi)` with the edges
/// farther apart than `min_distance` on `[0, toi)`, or `None` if they provably stay so on
/// `[0, tmax]`; never misses a contact. Parallel, collinear and zero-length edges need no special
/// treatment.
#[allow(clippy::too_many_arguments)]
pub fn edge_edge_ccd(
    ea0_t0: &Vector3<f64>,
    ea1_t0: &Vector3<f64>,
    eb0_t0: &Vector3<f64>,
    eb1_t0: &Vector3<f64>,
    ea0_t1: &Vector3<f64>,
    ea1_t1: &Vector3<f64>,
    eb0_t1: &Vector3<f64>,
    eb1_t1: &Vector3<f64>,
    min_distance: f64,
    tmax: f64,
) -> Option<f64> {
    edge_edge_ccd_with_params(
        &[*ea0_t0, *ea1_t0, *eb0_t0, *eb1_t0],
        &[*ea0_t1, *ea1_t1, *eb0_t1, *eb1_t1],
        min_distance,
        tmax,
        &CcdParams::default(),
    )
}

/// [`edge_edge_ccd`] with explicit parameters; vertices in the order `[ea0, ea1, eb0, eb1]`.
pub fn edge_edge_ccd_with_params(
    x_t0: &[Vector3<f64>; 4],
    x_t1: &[Vector3<f64>; 4],
    min_distance: f64,
    tmax: f64,
    params: &CcdParams,
) -> Option<f64> {
    run_ccd(Stencil::EdgeEdge, x_t0, x_t1, min_distance, tmax, params).toi
}

/// Largest safe line-search step `α ∈ [0, tmax]` for an edge–edge candidate moving from `x_t0` to
/// `x_t1` (vertex order `[ea0, ea1, eb0, eb1]`); same rule as
/// [`point_triangle_max_step`](super::point_triangle_max_step).
pub fn edge_edge_max_step(
    x_t0: &[Vector3<f64>; 4],
    x_t1: &[Vector3<f64>; 4],
    min_distance: f64,
    tmax: f64,
    params: &CcdParams,
) -> f64 {
    max_step(Stencil::EdgeEdge, x_t0, x_t1, min_distance, tmax, params)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::ccd::run_ccd;
    use crate::geometry::distance::edge_edge_distance_sq;
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

    fn ccd(x0: [Vector3<f64>; 4], x1: [Vector3<f64>; 4], d: f64) -> Option<f64> {
        edge_edge_ccd_with_params(&x0, &x1, d, 1.0, &CcdParams::default())
    }

    fn dist_at(x0: &[Vector3<f64>; 4], x1: &[Vector3<f64>; 4], t: f64) -> f64 {
        let x: Vec<_> = (0..4).map(|i| x0[i] + t * (x1[i] - x0[i])).collect();
        edge_edge_distance_sq(&x[0], &x[1], &x[2], &x[3]).sqrt()
    }

    fn assert_just_before(toi: Option<f64>, t_true: f64, slack: f64) {
        let toi = toi.expect("impact expected");
        assert!(toi < t_true && toi > t_true - slack, "toi {toi}, true {t_true}");
    }

    /// Edge a along x at height `z0 → z1`; edge b static along y at z = 0.
    fn crossing(z0: f64, z1: f64) -> ([Vector3<f64>; 4], [Vector3<f64>; 4]) {
        let b = [v(0.5, -1.0, 0.0), v(0.5, 1.0, 0.0)];
        (
            [v(0.0, 0.0, z0), v(1.0, 0.0, z0), b[0], b[1]],
            [v(0.0, 0.0, z1), v(1.0, 0.0, z1), b[0], b[1]],
        )
    }

    #[test]
    fn crossing_edges() {
        let (x0, x1) = crossing(1.0, -1.0);
        assert_just_before(ccd(x0, x1, 0.0), 0.5, 1e-5);
        let (x0, x1) = crossing(1.0, 0.1);
        assert_eq!(ccd(x0, x1, 0.0), None);
        // Both edges moving.
        let toi = edge_edge_ccd(
            &v(0.0, 0.0, 1.0),
            &v(1.0, 0.0, 1.0),
            &v(0.5, -1.0, -1.0),
            &v(0.5, 1.0, -1.0),
            &v(0.0, 0.0, -1.0),
            &v(1.0, 0.0, -1.0),
            &v(0.5, -1.0, 1.0),
            &v(0.5, 1.0, 1.0),
            0.0,
            1.0,
        );
        assert_just_before(toi, 0.5, 1e-5);
        // Passing beside the end of edge b.
        let mut x0 = crossing(1.0, -1.0).0;
        let mut x1 = crossing(1.0, -1.0).1;
        for x in [&mut x0, &mut x1] {
            x[2].x = 1.5;
            x[3].x = 1.5;
        }
        assert_eq!(ccd(x0, x1, 0.0), None);
    }

    #[test]
    fn parallel_and_coplanar() {
        // Parallel edges, one above the other, approaching: contact at t = 0.5.
        let x0 = [v(0.0, 0.0, 1.0), v(1.0, 0.0, 1.0), v(0.5, 0.0, 0.0), v(2.0, 0.0, 0.0)];
        let mut x1 = x0;
        x1[0].z = -1.0;
        x1[1].z = -1.0;
        assert_just_before(ccd(x0, x1, 0.0), 0.5, 1e-5);
        // Parallel, sliding along each other at a constant gap: no impact.
        let x0 = [v(0.0, 0.0, 1e-3), v(1.0, 0.0, 1e-3), v(0.5, 0.0, 0.0), v(2.0, 0.0, 0.0)];
        let mut x1 = x0;
        x1[0].x += 3.0;
        x1[1].x += 3.0;
        assert_eq!(ccd(x0, x1, 0.0), None);
        // Collinear, sliding into each other: end ea1 meets eb0 at t = 0.5.
        let x0 = [v(-2.0, 0.0, 0.0), v(-1.0, 0.0, 0.0), v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0)];
        let mut x1 = x0;
        x1[0].x += 2.0;
        x1[1].x += 2.0;
        assert_just_before(ccd(x0, x1, 0.0), 0.5, 1e-5);
        // Coplanar (z = 0), a sweeping segment x = −1 + 2t meets eb0 = (0.5, 0) at t = 0.75.
        let x0 = [
            v(-1.0, -1.0, 0.0),
            v(-1.0, 1.0, 0.0),
            v(0.5, 0.0, 0.0),
            v(1.0, 1.0, 0.0),
        ];
        let mut x1 = x0;
        x1[0].x = 1.0;
        x1[1].x = 1.0;
        assert_just_before(ccd(x0, x1, 0.0), 0.75, 1e-5);
    }

    #[test]
    fn degenerate_edges_and_zero_motion() {
        // Zero-length edge a (a point) falling onto edge b.
        let x0 = [v(0.5, 0.0, 1.0), v(0.5, 0.0, 1.0), v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0)];
        let mut x1 = x0;
        x1[0].z = -1.0;
        x1[1].z = -1.0;
        assert_just_before(ccd(x0, x1, 0.0), 0.5, 1e-5);
        // Both edges points, passing by each other at distance 0.1 / meeting.
        let p = |x: f64, y: f64| v(x, y, 0.0);
        let x0 = [p(-1.0, 0.1), p(-1.0, 0.1), p(0.0, 0.0), p(0.0, 0.0)];
        let x1 = [p(1.0, 0.1), p(1.0, 0.1), p(0.0, 0.0), p(0.0, 0.0)];
        assert_eq!(ccd(x0, x1, 0.0), None);
        assert!(ccd(x0, x1, 0.11).is_some());
        // Zero motion: separated → None; touching → Some(0).
        let (x0, _) = crossing(0.3, 0.3);
        assert_eq!(ccd(x0, x0, 0.0), None);
        let (x0, _) = crossing(0.0, 0.0);
        assert_eq!(ccd(x0, x0, 0.0), Some(0.0));
    }

    #[test]
    fn min_distance_and_max_step() {
        let (x0, x1) = crossing(1.0, -1.0);
        // Distance |1 − 2t| reaches 0.2 at t = 0.4.
        let toi = ccd(x0, x1, 0.2);
        assert_just_before(toi, 0.4, 1e-5);
        assert!(dist_at(&x0, &x1, toi.unwrap()) > 0.2);
        let p = CcdParams::default();
        let a = edge_edge_max_step(&x0, &x1, 0.2, 1.0, &p);
        // Safe (farther than 0.2, reached at t = 0.4) and not overly timid.
        assert!(a < 0.4 && a > 0.3 && dist_at(&x0, &x1, a) > 0.2, "{a}");
        let (y0, y1) = crossing(1.0, 0.5);
        assert_eq!(edge_edge_max_step(&y0, &y1, 0.2, 1.0, &p), 1.0);
        let (z0, _) = crossing(0.1, 0.1);
        assert_eq!(edge_edge_max_step(&z0, &x1, 0.2, 1.0, &p), 0.0);
    }

    #[test]
    fn random_conservative_against_sampling() {
        let mut rng = StdRng::seed_from_u64(40);
        let params = CcdParams::default();
        let mut hits = 0;
        for k in 0..400 {
            let x0 = [
                rp(&mut rng, 1.0),
                rp(&mut rng, 1.0),
                rp(&mut rng, 1.0),
                rp(&mut rng, 1.0),
            ];
            let x1 = [
                x0[0] + rp(&mut rng, 1.0),
                x0[1] + rp(&mut rng, 1.0),
                x0[2] + rp(&mut rng, 0.5),
                x0[3] + rp(&mut rng, 0.5),
            ];
            let delta = if k % 2 == 0 { 0.0 } else { 0.05 };
            let report = run_ccd(Stencil::EdgeEdge, &x0, &x1, delta, 1.0, &params);
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
        assert!(hits > 20, "{hits}");
    }

    #[test]
    fn random_constructed_contacts() {
        let mut rng = StdRng::seed_from_u64(41);
        for k in 0..300 {
            let ea_t0 = [rp(&mut rng, 1.0), rp(&mut rng, 1.0)];
            let ea_t1 = [ea_t0[0] + rp(&mut rng, 0.5), ea_t0[1] + rp(&mut rng, 0.5)];
            let mut eb0_t0 = rp(&mut rng, 1.0);
            let ts: f64 = rng.random_range(0.05..1.0);
            let a: f64 = if k % 5 == 0 { 1.0 } else { rng.random() };
            let b: f64 = if k % 7 == 0 { 0.0 } else { rng.random() };
            let dir = rp(&mut rng, 1.0);
            if k % 3 == 0 {
                // Make edge b parallel to edge a at the contact time.
                let ea = ea_t0[1] + ts * (ea_t1[1] - ea_t0[1]) - (ea_t0[0] + ts * (ea_t1[0] - ea_t0[0]));
                eb0_t0 = ea_t0[0] - 0.3 * ea;
            }
            // Point of edge a at the contact time; place eb's point β there at `ts`.
            let at = |i: usize| ea_t0[i] + ts * (ea_t1[i] - ea_t0[i]);
            let q = at(0) + a * (at(1) - at(0));
            let eb_dir = if k % 3 == 0 { at(1) - at(0) } else { dir };
            let eb0_ts = q - b * eb_dir;
            let eb0_t1 = eb0_t0 + (eb0_ts - eb0_t0) / ts;
            let eb1_t0 = eb0_t0 + eb_dir;
            let eb1_t1 = eb0_t1 + eb_dir;
            let toi = edge_edge_ccd(
                &ea_t0[0], &ea_t0[1], &eb0_t0, &eb1_t0, &ea_t1[0], &ea_t1[1], &eb0_t1, &eb1_t1, 0.0, 1.0,
            );
            let toi = toi.expect("constructed contact missed");
            assert!(toi <= ts + 1e-9, "toi {toi} vs {ts}");
        }
    }
}

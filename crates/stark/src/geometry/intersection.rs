//! Exact edge–triangle intersection tests (the line-search validity check of Stark).
//!
//! All decisions are signs of orientation determinants computed exactly with Shewchuk's adaptive
//! predicates (`robust::orient3d`, `robust::orient2d`; Shewchuk 1997, "Adaptive precision
//! floating-point arithmetic and fast robust geometric predicates"), so the answer is exact as
//! long as no intermediate product overflows or underflows: in practice for coordinates, and
//! non-zero coordinate differences, between about `1e-80` and `1e100` in magnitude.
//!
//! Edges and triangles are **closed** sets: touching counts as intersecting (an edge end on the
//! triangle, an edge through a triangle vertex or along a triangle edge). **Coplanar** input counts
//! as intersecting whenever the segment and the triangle share a point in their common plane
//! (overlap, crossing or touching); it is decided in 2D after dropping a coordinate axis along
//! which the plane projects one-to-one. Degenerate triangles (collinear corners or a point) are
//! the union of their three edges, and zero-length edges are points; both are handled exactly.
//!
//! Non-finite input (NaN or ±∞ anywhere) is reported as intersecting: a state with a NaN vertex
//! must not be accepted as valid.

use nalgebra::Vector3;
use rayon::prelude::*;
use robust::{orient2d, orient3d, Coord, Coord3D};

use super::aabb::{edge_aabb, triangle_aabbs};
use super::bvh::Bvh;
use super::GeometryError;

#[inline]
fn c3(p: &Vector3<f64>) -> Coord3D<f64> {
    Coord3D { x: p.x, y: p.y, z: p.z }
}

/// Exact sign of the orientation of `(a, b, c, d)` (`robust::orient3d`; positive when `d` lies
/// below the plane of `a, b, c` in Shewchuk's convention). Only the sign is used.
#[inline]
fn orient3(a: &Vector3<f64>, b: &Vector3<f64>, c: &Vector3<f64>, d: &Vector3<f64>) -> f64 {
    orient3d(c3(a), c3(b), c3(c), c3(d))
}

/// Whether `a` and `b` are both strictly positive or both strictly negative. (Not `a * b > 0`:
/// exact orientations of tiny inputs can be tiny, and their product can underflow to 0.)
#[inline]
fn same_strict_sign(a: f64, b: f64) -> bool {
    (a > 0.0 && b > 0.0) || (a < 0.0 && b < 0.0)
}

/// Projection dropping coordinate `axis`.
#[inline]
fn proj(p: &Vector3<f64>, axis: usize) -> Coord<f64> {
    match axis {
        0 => Coord { x: p.y, y: p.z },
        1 => Coord { x: p.z, y: p.x },
        _ => Coord { x: p.x, y: p.y },
    }
}

/// Exact 2D orientation of the projections of `a, b, c` after dropping `axis`.
#[inline]
fn orient2(a: &Vector3<f64>, b: &Vector3<f64>, c: &Vector3<f64>, axis: usize) -> f64 {
    orient2d(proj(a, axis), proj(b, axis), proj(c, axis))
}

/// An axis along which `a, b, c` project to a non-degenerate triangle, if they are not collinear.
fn non_degenerate_axis(a: &Vector3<f64>, b: &Vector3<f64>, c: &Vector3<f64>) -> Option<usize> {
    (0..3).find(|&axis| orient2(a, b, c, axis) != 0.0)
}

/// Closed-interval overlap of collinear segments `[p0, p1]` and `[q0, q1]`, tested on the
/// coordinate axis with the largest spread (which the common line projects onto one-to-one).
fn collinear_overlap(p0: &Vector3<f64>, p1: &Vector3<f64>, q0: &Vector3<f64>, q1: &Vector3<f64>) -> bool {
    let pts = [p0, p1, q0, q1];
    let spread = |k: usize| {
        let lo = pts.iter().map(|p| p[k]).fold(f64::INFINITY, f64::min);
        let hi = pts.iter().map(|p| p[k]).fold(f64::NEG_INFINITY, f64::max);
        hi - lo
    };
    let k = (0..3).max_by(|&i, &j| spread(i).total_cmp(&spread(j))).unwrap_or(0);
    let (plo, phi) = (p0[k].min(p1[k]), p0[k].max(p1[k]));
    let (qlo, qhi) = (q0[k].min(q1[k]), q0[k].max(q1[k]));
    plo <= qhi && qlo <= phi
}

/// Whether the closed segments `[p0, p1]` and `[q0, q1]` intersect, in the 2D projection that
/// drops `axis` (which must be one-to-one on the points' common plane).
fn segments_intersect_2d(
    p0: &Vector3<f64>,
    p1: &Vector3<f64>,
    q0: &Vector3<f64>,
    q1: &Vector3<f64>,
    axis: usize,
) -> bool {
    let o1 = orient2(p0, p1, q0, axis);
    let o2 = orient2(p0, p1, q1, axis);
    let o3 = orient2(q0, q1, p0, axis);
    let o4 = orient2(q0, q1, p1, axis);
    if o1 == 0.0 && o2 == 0.0 && o3 == 0.0 && o4 == 0.0 {
        // All four points on one line (or degenerate segments on it).
        return collinear_overlap(p0, p1, q0, q1);
    }
    // Otherwise the segments meet iff neither one lies strictly on one side of the other's line
    // (a zero means an end point lies on the other line, where the lines meet).
    !(same_strict_sign(o1, o2) || same_strict_sign(o3, o4))
}

/// Whether the closed segments `[p0, p1]` and `[q0, q1]` in 3D intersect (exact).
fn segments_intersect_3d(p0: &Vector3<f64>, p1: &Vector3<f64>, q0: &Vector3<f64>, q1: &Vector3<f64>) -> bool {
    if orient3(p0, p1, q0, q1) != 0.0 {
        return false;
    }
    // Coplanar: find a non-collinear triple; its plane projects one-to-one along some axis.
    let triples = [(p0, p1, q0), (p0, p1, q1), (q0, q1, p0), (q0, q1, p1)];
    for (a, b, c) in triples {
        if let Some(axis) = non_degenerate_axis(a, b, c) {
            return segments_intersect_2d(p0, p1, q0, q1, axis);
        }
    }
    // All four points are collinear (or coincide).
    collinear_overlap(p0, p1, q0, q1)
}

/// Whether `x` lies in the closed triangle `(t0, t1, t2)`, all projected along `axis` (the
/// projected triangle must be non-degenerate).
fn point_in_triangle_2d(
    x: &Vector3<f64>,
    t0: &Vector3<f64>,
    t1: &Vector3<f64>,
    t2: &Vector3<f64>,
    axis: usize,
) -> bool {
    let a = orient2(t0, t1, x, axis);
    let b = orient2(t1, t2, x, axis);
    let c = orient2(t2, t0, x, axis);
    !((a < 0.0 || b < 0.0 || c < 0.0) && (a > 0.0 || b > 0.0 || c > 0.0))
}

/// Exact test whether the closed edge `[e0, e1]` and the closed triangle `(t0, t1, t2)` share a
/// point.
///
/// 1. Degenerate triangle (collinear corners): test the edge against the triangle's three edges.
/// 2. `s0 = orient3d(t0, t1, t2, e0)`, `s1 = orient3d(t0, t1, t2, e1)`. Both non-zero with the same
///    sign: the edge is strictly on one side, no intersection.
/// 3. Both zero (coplanar): in the projection where the triangle is non-degenerate, an end point
///    lies in the triangle or the edge meets one of the triangle's edges.
/// 4. Otherwise the edge meets the plane in exactly one point, which lies in the triangle iff the
///    three orientations `orient3d(e0, e1, t_i, t_(i+1))` do not have strictly opposite signs.
///
/// Non-finite input returns `true` (see the module doc).
pub fn edge_triangle_intersect(
    e0: &Vector3<f64>,
    e1: &Vector3<f64>,
    t0: &Vector3<f64>,
    t1: &Vector3<f64>,
    t2: &Vector3<f64>,
) -> bool {
    if ![e0, e1, t0, t1, t2].iter().all(|p| p.iter().all(|c| c.is_finite())) {
        return true;
    }
    let Some(axis) = non_degenerate_axis(t0, t1, t2) else {
        return segments_intersect_3d(e0, e1, t0, t1)
            || segments_intersect_3d(e0, e1, t1, t2)
            || segments_intersect_3d(e0, e1, t2, t0);
    };
    let s0 = orient3(t0, t1, t2, e0);
    let s1 = orient3(t0, t1, t2, e1);
    if same_strict_sign(s0, s1) {
        return false;
    }
    if s0 == 0.0 && s1 == 0.0 {
        return point_in_triangle_2d(e0, t0, t1, t2, axis)
            || point_in_triangle_2d(e1, t0, t1, t2, axis)
            || segments_intersect_2d(e0, e1, t0, t1, axis)
            || segments_intersect_2d(e0, e1, t1, t2, axis)
            || segments_intersect_2d(e0, e1, t2, t0, axis);
    }
    let a = orient3(e0, e1, t0, t1);
    let b = orient3(e0, e1, t1, t2);
    let c = orient3(e0, e1, t2, t0);
    !((a < 0.0 || b < 0.0 || c < 0.0) && (a > 0.0 || b > 0.0 || c > 0.0))
}

/// All pairs `(edge index, triangle index)` whose closed edge and triangle intersect
/// ([`edge_triangle_intersect`]), sorted.
///
/// Pairs that share a vertex index are skipped (adjacent primitives always touch), and so are
/// pairs for which `filter(edge, triangle)` returns `false` (e.g. primitives of objects that may
/// not collide). Candidates come from a [`Bvh`] over the triangle boxes; edges are processed in
/// parallel with rayon, and the result is the same for any thread count.
///
/// # Errors
/// [`GeometryError::VertexIndexOutOfRange`] if an edge or triangle refers to a missing vertex.
pub fn find_edge_triangle_intersections<F>(
    positions: &[Vector3<f64>],
    edges: &[[usize; 2]],
    triangles: &[[usize; 3]],
    filter: F,
) -> Result<Vec<(usize, usize)>, GeometryError>
where
    F: Fn(usize, usize) -> bool + Sync,
{
    let boxes = triangle_aabbs(positions, triangles, 0.0)?;
    for (index, e) in edges.iter().enumerate() {
        if let Some(&vertex) = e.iter().find(|&&v| v >= positions.len()) {
            return Err(GeometryError::VertexIndexOutOfRange {
                primitive: "edge",
                index,
                vertex,
                num_vertices: positions.len(),
            });
        }
    }
    let bvh = Bvh::build(&boxes);
    let mut hits: Vec<(usize, usize)> = edges
        .par_iter()
        .enumerate()
        .flat_map_iter(|(ei, e)| {
            let (a, b) = (&positions[e[0]], &positions[e[1]]);
            let mut local = Vec::new();
            bvh.query_aabb(&edge_aabb(a, b, 0.0), |ti| {
                let t = triangles[ti];
                if t.contains(&e[0]) || t.contains(&e[1]) || !filter(ei, ti) {
                    return;
                }
                let (t0, t1, t2) = (&positions[t[0]], &positions[t[1]], &positions[t[2]]);
                if edge_triangle_intersect(a, b, t0, t1, t2) {
                    local.push((ei, ti));
                }
            });
            local
        })
        .collect();
    hits.par_sort_unstable();
    hits.dedup();
    Ok(hits)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::rngs::StdRng;
    use rand::{Rng, SeedableRng};
    use std::collections::HashMap;

    fn v(x: f64, y: f64, z: f64) -> Vector3<f64> {
        Vector3::new(x, y, z)
    }

    /// Unit right triangle in z = 0.
    fn tri() -> [Vector3<f64>; 3] {
        [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0)]
    }

    fn hit(e0: Vector3<f64>, e1: Vector3<f64>, t: &[Vector3<f64>; 3]) -> bool {
        let r = edge_triangle_intersect(&e0, &e1, &t[0], &t[1], &t[2]);
        // The answer must not depend on the edge direction or the triangle's vertex order.
        assert_eq!(r, edge_triangle_intersect(&e1, &e0, &t[1], &t[2], &t[0]));
        assert_eq!(r, edge_triangle_intersect(&e0, &e1, &t[0], &t[2], &t[1]));
        r
    }

    #[test]
    fn transversal_cases() {
        let t = tri();
        // Through the interior.
        assert!(hit(v(0.2, 0.2, -1.0), v(0.2, 0.2, 1.0), &t));
        // Misses beside the triangle, and stops short of it.
        assert!(!hit(v(0.8, 0.8, -1.0), v(0.8, 0.8, 1.0), &t));
        assert!(!hit(v(0.2, 0.2, 0.1), v(0.2, 0.2, 1.0), &t));
        // End point exactly on the interior, on an edge, at a vertex.
        assert!(hit(v(0.2, 0.2, 0.0), v(0.2, 0.2, 1.0), &t));
        assert!(hit(v(0.5, 0.0, 0.0), v(0.3, 0.7, 1.0), &t));
        assert!(hit(t[2], v(3.0, 1.0, 1.0), &t));
        // Passing exactly through a triangle edge and through a vertex.
        assert!(hit(v(0.5, 0.5, -1.0), v(0.5, 0.5, 1.0), &t));
        assert!(hit(v(1.0, 0.0, -1.0), v(1.0, 0.0, 1.0), &t));
        // Just outside the edge at the representable limit.
        let x = 0.5f64.next_up();
        assert!(!hit(v(x, 0.5, -1.0), v(x, 0.5, 1.0), &t));
        // Parallel above the plane.
        assert!(!hit(v(-1.0, 0.2, 1e-300), v(2.0, 0.2, 1e-300), &t));
    }

    #[test]
    fn coplanar_cases() {
        let t = tri();
        // Crossing the triangle in its plane, fully inside, disjoint.
        assert!(hit(v(-1.0, 0.25, 0.0), v(2.0, 0.25, 0.0), &t));
        assert!(hit(v(0.1, 0.1, 0.0), v(0.2, 0.3, 0.0), &t));
        assert!(!hit(v(0.6, 0.6, 0.0), v(2.0, 0.6, 0.0), &t));
        // Touching a vertex, and lying along a triangle edge (overlapping / beyond it).
        assert!(hit(v(1.0, 0.0, 0.0), v(2.0, 1.0, 0.0), &t));
        assert!(hit(v(0.5, 0.0, 0.0), v(3.0, 0.0, 0.0), &t));
        assert!(!hit(v(1.5, 0.0, 0.0), v(3.0, 0.0, 0.0), &t));
        // Zero-length edge (a point) inside and outside, in and off the plane.
        assert!(hit(v(0.2, 0.2, 0.0), v(0.2, 0.2, 0.0), &t));
        assert!(!hit(v(0.7, 0.7, 0.0), v(0.7, 0.7, 0.0), &t));
        assert!(!hit(v(0.2, 0.2, 1e-12), v(0.2, 0.2, 1e-12), &t));
        // A plane that is not axis-aligned: x + y + z = 1.
        let t2 = [v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0), v(0.0, 0.0, 1.0)];
        assert!(hit(v(0.5, 0.5, 0.0), v(0.0, 0.5, 0.5), &t2));
        assert!(!hit(v(1.0, 1.0, -1.0), v(2.0, 0.0, -1.0), &t2));
    }

    #[test]
    fn degenerate_triangles() {
        // Collinear triangle along x (a segment from 0 to 2).
        let t = [v(0.0, 0.0, 0.0), v(2.0, 0.0, 0.0), v(1.0, 0.0, 0.0)];
        assert!(hit(v(1.5, -1.0, 0.0), v(1.5, 1.0, 0.0), &t));
        assert!(hit(v(1.5, -1.0, -1.0), v(1.5, 1.0, 1.0), &t));
        assert!(!hit(v(1.5, -1.0, 0.1), v(1.5, 1.0, 0.1), &t));
        assert!(hit(v(2.0, 0.0, 0.0), v(5.0, 0.0, 0.0), &t));
        assert!(!hit(v(2.5, 0.0, 0.0), v(5.0, 0.0, 0.0), &t));
        // Point triangle.
        let p = v(0.3, 0.3, 0.3);
        let t = [p, p, p];
        assert!(hit(v(0.0, 0.0, 0.0), v(0.6, 0.6, 0.6), &t));
        assert!(!hit(v(0.0, 0.0, 0.0), v(0.6, 0.6, 0.7), &t));
        assert!(hit(p, p, &t));
    }

    #[test]
    fn tiny_and_large_scales() {
        // Orientation determinants of these configurations are ~1e-210 or smaller, so products
        // of two of them underflow; the answers must match the unit-scale ones.
        for s in [1e-70, 1e-30, 1e30, 1e90] {
            let t = tri().map(|p| p * s);
            assert!(hit(v(0.2, 0.2, -1.0) * s, v(0.2, 0.2, 1.0) * s, &t));
            assert!(!hit(v(0.8, 0.8, -1.0) * s, v(0.8, 0.8, 1.0) * s, &t));
            assert!(!hit(v(0.2, 0.2, 0.1) * s, v(0.2, 0.2, 1.0) * s, &t));
            assert!(!hit(v(0.6, 0.6, 0.0) * s, v(2.0, 0.6, 0.0) * s, &t));
            assert!(hit(v(-1.0, 0.25, 0.0) * s, v(2.0, 0.25, 0.0) * s, &t));
        }
    }

    #[test]
    fn non_finite_counts_as_intersecting() {
        let t = tri();
        assert!(hit(v(f64::NAN, 0.0, 0.0), v(5.0, 5.0, 5.0), &t));
        assert!(hit(v(9.0, 9.0, 9.0), v(5.0, f64::INFINITY, 5.0), &t));
    }

    /// Floating-point reference for generic configurations: returns `None` when the
    /// configuration is too close to a boundary case to trust the float answer.
    fn float_reference(e0: &Vector3<f64>, e1: &Vector3<f64>, t: &[Vector3<f64>; 3]) -> Option<bool> {
        let n = (t[1] - t[0]).cross(&(t[2] - t[0]));
        let s0 = n.dot(&(e0 - t[0]));
        let s1 = n.dot(&(e1 - t[0]));
        if s0.abs() < 1e-6 || s1.abs() < 1e-6 {
            return None;
        }
        if same_strict_sign(s0, s1) {
            return Some(false);
        }
        let x = e0 + (s0 / (s0 - s1)) * (e1 - e0);
        let mut sign = [0.0; 3];
        for i in 0..3 {
            let (a, b) = (t[i], t[(i + 1) % 3]);
            sign[i] = (b - a).cross(&(x - a)).dot(&n);
            if sign[i].abs() < 1e-6 {
                return None;
            }
        }
        Some(sign.iter().all(|&s| s > 0.0) || sign.iter().all(|&s| s < 0.0))
    }

    #[test]
    fn random_against_float_reference() {
        let mut rng = StdRng::seed_from_u64(20);
        let mut p = || {
            v(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            )
        };
        let (mut checked, mut hits) = (0, 0);
        for _ in 0..20_000 {
            let (e0, e1) = (p(), p());
            let t = [p(), p(), p()];
            if let Some(expected) = float_reference(&e0, &e1, &t) {
                assert_eq!(hit(e0, e1, &t), expected);
                checked += 1;
                hits += expected as usize;
            }
        }
        assert!(checked > 15_000 && hits > 1000, "{checked} {hits}");
    }

    #[test]
    fn random_exact_touching() {
        // Edges through exactly representable points of the triangle (a vertex, or the midpoint
        // of an edge with small-integer coordinates) must always intersect.
        let mut rng = StdRng::seed_from_u64(21);
        let q = |rng: &mut StdRng| {
            v(
                rng.random_range(-8..8) as f64,
                rng.random_range(-8..8) as f64,
                rng.random_range(-8..8) as f64,
            )
        };
        for _ in 0..2000 {
            let t = [q(&mut rng), q(&mut rng), q(&mut rng)];
            let through = if rng.random_bool(0.5) {
                t[1]
            } else {
                0.5 * (t[0] + t[2])
            };
            let dir = q(&mut rng);
            let e0 = through - dir;
            let e1 = through + dir;
            assert!(hit(e0, e1, &t), "{e0:?} {e1:?} {t:?}");
            assert!(hit(through, through + dir, &t));
        }
    }

    /// Positions, edges and triangles of a surface mesh.
    type Surface = (Vec<Vector3<f64>>, Vec<[usize; 2]>, Vec<[usize; 3]>);

    /// Tetrahedral mesh of an `n³` grid of unit cubes (6 tets per cube, Kuhn subdivision) and
    /// its boundary surface (triangles and edges).
    fn cube_surface(n: usize) -> Surface {
        let idx = |i: usize, j: usize, k: usize| (i * (n + 1) + j) * (n + 1) + k;
        let mut x = Vec::new();
        for i in 0..=n {
            for j in 0..=n {
                for k in 0..=n {
                    x.push(v(i as f64, j as f64, k as f64));
                }
            }
        }
        let mut tets = Vec::new();
        // The 6 Kuhn tets share the cube diagonal 000–111; each follows one axis permutation.
        let perms = [[0, 1, 2], [0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0]];
        for i in 0..n {
            for j in 0..n {
                for k in 0..n {
                    for p in perms {
                        let mut c = [i, j, k];
                        let mut tet = [idx(c[0], c[1], c[2]); 4];
                        for (s, &axis) in p.iter().enumerate() {
                            c[axis] += 1;
                            tet[s + 1] = idx(c[0], c[1], c[2]);
                        }
                        tets.push(tet);
                    }
                }
            }
        }
        let mut faces: HashMap<[usize; 3], (usize, [usize; 3])> = HashMap::new();
        for t in &tets {
            for f in [
                [t[0], t[1], t[2]],
                [t[0], t[1], t[3]],
                [t[0], t[2], t[3]],
                [t[1], t[2], t[3]],
            ] {
                let mut key = f;
                key.sort_unstable();
                faces.entry(key).or_insert((0, f)).0 += 1;
            }
        }
        let mut tris: Vec<[usize; 3]> = faces.values().filter(|(c, _)| *c == 1).map(|(_, f)| *f).collect();
        tris.sort_unstable();
        let mut edges: Vec<[usize; 2]> = tris
            .iter()
            .flat_map(|t| [[t[0], t[1]], [t[1], t[2]], [t[0], t[2]]])
            .map(|[a, b]| [a.min(b), a.max(b)])
            .collect();
        edges.sort_unstable();
        edges.dedup();
        (x, edges, tris)
    }

    fn brute_force(x: &[Vector3<f64>], edges: &[[usize; 2]], tris: &[[usize; 3]]) -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        for (ei, e) in edges.iter().enumerate() {
            for (ti, t) in tris.iter().enumerate() {
                if t.contains(&e[0]) || t.contains(&e[1]) {
                    continue;
                }
                if edge_triangle_intersect(&x[e[0]], &x[e[1]], &x[t[0]], &x[t[1]], &x[t[2]]) {
                    out.push((ei, ti));
                }
            }
        }
        out
    }

    #[test]
    fn tet_mesh_surface() {
        let (mut x, edges, tris) = cube_surface(2);
        assert_eq!(tris.len(), 6 * 4 * 2);
        // The surface is intersection-free although many of its triangles are coplanar and touch.
        let found = find_edge_triangle_intersections(&x, &edges, &tris, |_, _| true).unwrap();
        assert!(found.is_empty(), "{found:?}");
        assert_eq!(brute_force(&x, &edges, &tris), found);
        // Push the centre vertex of the top face (z = 2) down through the bottom face.
        let top = (3 + 1) * 3 + 2; // grid index (1, 1, 2)
        assert_eq!(x[top], v(1.0, 1.0, 2.0));
        x[top] = v(1.0, 1.0, -0.5);
        let found = find_edge_triangle_intersections(&x, &edges, &tris, |_, _| true).unwrap();
        assert!(!found.is_empty());
        assert_eq!(brute_force(&x, &edges, &tris), found);
        // Every reported edge touches the moved vertex or a triangle that does.
        for &(e, t) in &found {
            assert!(edges[e].contains(&top) || tris[t].contains(&top));
        }
        // Exactly onto the bottom face plane: touching still counts.
        x[top] = v(1.0, 1.0, 0.0);
        let found = find_edge_triangle_intersections(&x, &edges, &tris, |_, _| true).unwrap();
        assert!(!found.is_empty());
        assert_eq!(brute_force(&x, &edges, &tris), found);
        // The filter removes pairs.
        let none = find_edge_triangle_intersections(&x, &edges, &tris, |_, _| false).unwrap();
        assert!(none.is_empty());
    }

    #[test]
    fn random_soup_matches_brute_force() {
        let mut rng = StdRng::seed_from_u64(22);
        let x: Vec<_> = (0..300)
            .map(|_| {
                v(
                    rng.random_range(0.0..1.0),
                    rng.random_range(0.0..1.0),
                    rng.random_range(0.0..1.0),
                )
            })
            .collect();
        let mut pick = |k: usize| -> Vec<usize> { (0..k).map(|_| rng.random_range(0..300)).collect() };
        let tris: Vec<[usize; 3]> = (0..200)
            .map(|_| {
                let p = pick(3);
                [p[0], p[1], p[2]]
            })
            .collect();
        let edges: Vec<[usize; 2]> = (0..200)
            .map(|_| {
                let p = pick(2);
                [p[0], p[1]]
            })
            .collect();
        // Shrink the triangles so that the answer is not "everything".
        let x: Vec<_> = x.iter().map(|p| 0.5 * p + v(0.25, 0.25, 0.25)).collect();
        let found = find_edge_triangle_intersections(&x, &edges, &tris, |_, _| true).unwrap();
        assert_eq!(found, brute_force(&x, &edges, &tris));
        assert!(!found.is_empty());
    }

    #[test]
    fn bad_indices_are_errors() {
        let x = vec![v(0.0, 0.0, 0.0); 3];
        let err = find_edge_triangle_intersections(&x, &[[0, 5]], &[[0, 1, 2]], |_, _| true);
        assert!(matches!(
            err,
            Err(GeometryError::VertexIndexOutOfRange { vertex: 5, .. })
        ));
        let err = find_edge_triangle_intersections(&x, &[[0, 1]], &[[0, 1, 3]], |_, _| true);
        assert!(matches!(
            err,
            Err(GeometryError::VertexIndexOutOfRange {
                primitive: "triangle",
                ..
            })
        ));
    }
}

//! Axis-aligned bounding boxes and the box constructors of the broad phase.
//!
//! Contact candidates come from boxes at the current positions, inflated by a radius (IPC uses
//! `0.5·(d̂ + d_min)` per box, ipc-notes B.1); CCD candidates come from *swept* boxes that cover a
//! primitive at both `_t0` and `_t1` (for linear motion the convex hull of the end positions covers
//! the whole trajectory, so the box of all end positions does too).
//!
//! Inflation rounds outward (`next_down`/`next_up`), so an inflated box always contains the exact
//! inflated box. A primitive with a non-finite coordinate gets [`Aabb::everything`], so it becomes a
//! candidate for every other primitive and the (conservative) narrow phase sees it.

use nalgebra::Vector3;

use super::GeometryError;

/// A closed axis-aligned box `[min, max]`.
///
/// The *empty* box has `min = +∞`, `max = −∞`; it overlaps nothing and is the identity of
/// [`Aabb::union`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    /// Lower corner.
    pub min: Vector3<f64>,
    /// Upper corner.
    pub max: Vector3<f64>,
}

impl Default for Aabb {
    fn default() -> Self {
        Self::empty()
    }
}

impl Aabb {
    /// A box from its corners (not checked; `min > max` on an axis makes it empty).
    #[inline]
    pub fn new(min: Vector3<f64>, max: Vector3<f64>) -> Self {
        Self { min, max }
    }

    /// The empty box (`min = +∞`, `max = −∞`).
    #[inline]
    pub fn empty() -> Self {
        Self {
            min: Vector3::repeat(f64::INFINITY),
            max: Vector3::repeat(f64::NEG_INFINITY),
        }
    }

    /// The box covering all of space (`[−∞, ∞]³`).
    #[inline]
    pub fn everything() -> Self {
        Self {
            min: Vector3::repeat(f64::NEG_INFINITY),
            max: Vector3::repeat(f64::INFINITY),
        }
    }

    /// The degenerate box of one point. A non-finite point gives [`Aabb::everything`].
    #[inline]
    pub fn from_point(p: &Vector3<f64>) -> Self {
        if p.iter().all(|c| c.is_finite()) {
            Self { min: *p, max: *p }
        } else {
            Self::everything()
        }
    }

    /// The smallest box containing all `points` (empty for no points). Any non-finite coordinate
    /// gives [`Aabb::everything`].
    pub fn from_points<'a>(points: impl IntoIterator<Item = &'a Vector3<f64>>) -> Self {
        points
            .into_iter()
            .fold(Self::empty(), |b, p| b.union(&Self::from_point(p)))
    }

    /// Whether the box contains no point (`min > max` on some axis, or NaN).
    #[inline]
    pub fn is_empty(&self) -> bool {
        !(0..3).all(|k| self.min[k] <= self.max[k])
    }

    /// The smallest box containing both boxes.
    #[inline]
    pub fn union(&self, other: &Aabb) -> Aabb {
        Aabb {
            min: self.min.inf(&other.min),
            max: self.max.sup(&other.max),
        }
    }

    /// The box grown by `radius` on every side, rounded outward. A negative or NaN radius is
    /// treated as 0; the empty box stays empty.
    pub fn inflated(&self, radius: f64) -> Aabb {
        if self.is_empty() {
            return *self;
        }
        let r = if radius > 0.0 { radius } else { 0.0 };
        if r == 0.0 {
            return *self;
        }
        Aabb {
            min: self.min.map(|c| (c - r).next_down()),
            max: self.max.map(|c| (c + r).next_up()),
        }
    }

    /// Whether the closed boxes share at least one point (touching counts). Empty boxes overlap
    /// nothing.
    #[inline]
    pub fn intersects(&self, other: &Aabb) -> bool {
        // The intersection box is non-empty on every axis; unlike `a.min <= b.max && b.min <= a.max`
        // this is also false when one box is empty and the other unbounded.
        self.min.x.max(other.min.x) <= self.max.x.min(other.max.x)
            && self.min.y.max(other.min.y) <= self.max.y.min(other.max.y)
            && self.min.z.max(other.min.z) <= self.max.z.min(other.max.z)
    }

    /// Whether the boxes are within `margin` of each other on every axis, i.e. whether they overlap
    /// after each is grown by `margin / 2`.
    ///
    /// Conservative under rounding: if the exact gap on every axis is `≤ margin`, this returns
    /// `true` (rounding to nearest is monotone). A negative margin is allowed (requires overlap by
    /// that much).
    #[inline]
    pub fn intersects_within(&self, other: &Aabb, margin: f64) -> bool {
        self.min.x.max(other.min.x) <= self.max.x.min(other.max.x) + margin
            && self.min.y.max(other.min.y) <= self.max.y.min(other.max.y) + margin
            && self.min.z.max(other.min.z) <= self.max.z.min(other.max.z) + margin
    }

    /// Whether the closed box contains `p`.
    #[inline]
    pub fn contains_point(&self, p: &Vector3<f64>) -> bool {
        (0..3).all(|k| self.min[k] <= p[k] && p[k] <= self.max[k])
    }

    /// Whether this box contains all of `other` (an empty `other` is contained in anything).
    #[inline]
    pub fn contains(&self, other: &Aabb) -> bool {
        other.is_empty() || (self.contains_point(&other.min) && self.contains_point(&other.max))
    }

    /// Centre `(min + max)/2`; may be non-finite for unbounded or empty boxes.
    #[inline]
    pub fn center(&self) -> Vector3<f64> {
        0.5 * self.min + 0.5 * self.max
    }

    /// Side lengths `max − min`.
    #[inline]
    pub fn extent(&self) -> Vector3<f64> {
        self.max - self.min
    }
}

/// Box of a point inflated by `radius`.
#[inline]
pub fn point_aabb(p: &Vector3<f64>, radius: f64) -> Aabb {
    Aabb::from_point(p).inflated(radius)
}

/// Box of the edge `[e0, e1]` inflated by `radius`.
#[inline]
pub fn edge_aabb(e0: &Vector3<f64>, e1: &Vector3<f64>, radius: f64) -> Aabb {
    Aabb::from_points([e0, e1]).inflated(radius)
}

/// Box of the triangle `(t0, t1, t2)` inflated by `radius`.
#[inline]
pub fn triangle_aabb(t0: &Vector3<f64>, t1: &Vector3<f64>, t2: &Vector3<f64>, radius: f64) -> Aabb {
    Aabb::from_points([t0, t1, t2]).inflated(radius)
}

/// Swept box of a point moving linearly from `p_t0` to `p_t1`, inflated by `radius`.
#[inline]
pub fn point_swept_aabb(p_t0: &Vector3<f64>, p_t1: &Vector3<f64>, radius: f64) -> Aabb {
    Aabb::from_points([p_t0, p_t1]).inflated(radius)
}

/// Swept box of an edge whose ends move linearly from `(e0_t0, e1_t0)` to `(e0_t1, e1_t1)`,
/// inflated by `radius`.
#[inline]
pub fn edge_swept_aabb(
    e0_t0: &Vector3<f64>,
    e1_t0: &Vector3<f64>,
    e0_t1: &Vector3<f64>,
    e1_t1: &Vector3<f64>,
    radius: f64,
) -> Aabb {
    Aabb::from_points([e0_t0, e1_t0, e0_t1, e1_t1]).inflated(radius)
}

/// Swept box of a triangle whose corners move linearly from `t*_t0` to `t*_t1`, inflated by
/// `radius`.
#[inline]
pub fn triangle_swept_aabb(
    t0_t0: &Vector3<f64>,
    t1_t0: &Vector3<f64>,
    t2_t0: &Vector3<f64>,
    t0_t1: &Vector3<f64>,
    t1_t1: &Vector3<f64>,
    t2_t1: &Vector3<f64>,
    radius: f64,
) -> Aabb {
    Aabb::from_points([t0_t0, t1_t0, t2_t0, t0_t1, t1_t1, t2_t1]).inflated(radius)
}

/// Checks that every index of every primitive is `< num_vertices`.
fn check_indices<const N: usize>(
    primitive: &'static str,
    indices: &[[usize; N]],
    num_vertices: usize,
) -> Result<(), GeometryError> {
    for (index, prim) in indices.iter().enumerate() {
        if let Some(&vertex) = prim.iter().find(|&&v| v >= num_vertices) {
            return Err(GeometryError::VertexIndexOutOfRange {
                primitive,
                index,
                vertex,
                num_vertices,
            });
        }
    }
    Ok(())
}

/// Checks that `t0` and `t1` position arrays have the same length.
fn check_same_len(a: &[Vector3<f64>], b: &[Vector3<f64>]) -> Result<(), GeometryError> {
    if a.len() != b.len() {
        return Err(GeometryError::LengthMismatch {
            what: "positions_t1 vs positions_t0",
            expected: a.len(),
            found: b.len(),
        });
    }
    Ok(())
}

/// Boxes of all vertices, inflated by `radius`.
pub fn vertex_aabbs(positions: &[Vector3<f64>], radius: f64) -> Vec<Aabb> {
    positions.iter().map(|p| point_aabb(p, radius)).collect()
}

/// Boxes of all edges `[v0, v1]` (vertex indices into `positions`), inflated by `radius`.
///
/// # Errors
/// [`GeometryError::VertexIndexOutOfRange`] if an edge refers to a missing vertex.
pub fn edge_aabbs(positions: &[Vector3<f64>], edges: &[[usize; 2]], radius: f64) -> Result<Vec<Aabb>, GeometryError> {
    check_indices("edge", edges, positions.len())?;
    Ok(edges
        .iter()
        .map(|e| edge_aabb(&positions[e[0]], &positions[e[1]], radius))
        .collect())
}

/// Boxes of all triangles `[v0, v1, v2]`, inflated by `radius`.
///
/// # Errors
/// [`GeometryError::VertexIndexOutOfRange`] if a triangle refers to a missing vertex.
pub fn triangle_aabbs(
    positions: &[Vector3<f64>],
    triangles: &[[usize; 3]],
    radius: f64,
) -> Result<Vec<Aabb>, GeometryError> {
    check_indices("triangle", triangles, positions.len())?;
    Ok(triangles
        .iter()
        .map(|t| triangle_aabb(&positions[t[0]], &positions[t[1]], &positions[t[2]], radius))
        .collect())
}

/// Swept boxes of all vertices moving from `positions_t0` to `positions_t1`, inflated by `radius`.
///
/// # Errors
/// [`GeometryError::LengthMismatch`] if the two position arrays differ in length.
pub fn vertex_swept_aabbs(
    positions_t0: &[Vector3<f64>],
    positions_t1: &[Vector3<f64>],
    radius: f64,
) -> Result<Vec<Aabb>, GeometryError> {
    check_same_len(positions_t0, positions_t1)?;
    Ok(positions_t0
        .iter()
        .zip(positions_t1)
        .map(|(a, b)| point_swept_aabb(a, b, radius))
        .collect())
}

/// Swept boxes of all edges moving from `positions_t0` to `positions_t1`, inflated by `radius`.
///
/// # Errors
/// [`GeometryError::LengthMismatch`] or [`GeometryError::VertexIndexOutOfRange`].
pub fn edge_swept_aabbs(
    positions_t0: &[Vector3<f64>],
    positions_t1: &[Vector3<f64>],
    edges: &[[usize; 2]],
    radius: f64,
) -> Result<Vec<Aabb>, GeometryError> {
    check_same_len(positions_t0, positions_t1)?;
    check_indices("edge", edges, positions_t0.len())?;
    let (x0, x1) = (positions_t0, positions_t1);
    Ok(edges
        .iter()
        .map(|e| edge_swept_aabb(&x0[e[0]], &x0[e[1]], &x1[e[0]], &x1[e[1]], radius))
        .collect())
}

/// Swept boxes of all triangles moving from `positions_t0` to `positions_t1`, inflated by
/// `radius`.
///
/// # Errors
/// [`GeometryError::LengthMismatch`] or [`GeometryError::VertexIndexOutOfRange`].
pub fn triangle_swept_aabbs(
    positions_t0: &[Vector3<f64>],
    positions_t1: &[Vector3<f64>],
    triangles: &[[usize; 3]],
    radius: f64,
) -> Result<Vec<Aabb>, GeometryError> {
    check_same_len(positions_t0, positions_t1)?;
    check_indices("triangle", triangles, positions_t0.len())?;
    let (x0, x1) = (positions_t0, positions_t1);
    Ok(triangles
        .iter()
        .map(|t| triangle_swept_aabb(&x0[t[0]], &x0[t[1]], &x0[t[2]], &x1[t[0]], &x1[t[1]], &x1[t[2]], radius))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f64, y: f64, z: f64) -> Vector3<f64> {
        Vector3::new(x, y, z)
    }

    #[test]
    fn construction_union_and_overlap() {
        let a = triangle_aabb(&v(0.0, 0.0, 0.0), &v(1.0, 2.0, 0.0), &v(-1.0, 0.5, 3.0), 0.0);
        assert_eq!(a.min, v(-1.0, 0.0, 0.0));
        assert_eq!(a.max, v(1.0, 2.0, 3.0));
        assert!(!a.is_empty());
        // Touching boxes overlap (closed boxes).
        let b = Aabb::new(v(1.0, 2.0, 3.0), v(2.0, 3.0, 4.0));
        assert!(a.intersects(&b) && b.intersects(&a));
        let c = Aabb::new(v(1.0 + 1e-15, 0.0, 0.0), v(2.0, 1.0, 1.0));
        assert!(!a.intersects(&c));
        assert!(a.inflated(1e-15).intersects(&c));
        assert!(a.intersects_within(&c, 2e-15) && !a.intersects_within(&c, 0.5e-15));
        assert!(!Aabb::empty().intersects_within(&Aabb::everything(), 1.0));
        let u = a.union(&b);
        assert!(u.contains(&a) && u.contains(&b));
        assert!(Aabb::empty().union(&a) == a);
        assert!(!Aabb::empty().intersects(&a) && !Aabb::empty().intersects(&Aabb::everything()));
        assert!(Aabb::everything().intersects(&a));
        assert_eq!(a.center(), v(0.0, 1.0, 1.5));
        assert_eq!(a.extent(), v(2.0, 2.0, 3.0));
    }

    #[test]
    fn inflation_rounds_outward() {
        let a = point_aabb(&v(0.1, 0.2, 0.3), 0.7);
        for k in 0..3 {
            let c = [0.1, 0.2, 0.3][k];
            assert!(a.min[k] < c - 0.7 + 1e-15 && a.min[k] <= c - 0.7);
            assert!(a.max[k] >= c + 0.7);
        }
        // Negative and NaN radii are ignored; empty stays empty.
        let p = point_aabb(&v(1.0, 1.0, 1.0), -1.0);
        assert_eq!(p.min, p.max);
        assert_eq!(point_aabb(&v(1.0, 1.0, 1.0), f64::NAN), p);
        assert!(Aabb::empty().inflated(1.0).is_empty());
    }

    #[test]
    fn swept_boxes_cover_both_ends() {
        let b = edge_swept_aabb(
            &v(0.0, 0.0, 0.0),
            &v(1.0, 0.0, 0.0),
            &v(0.0, 5.0, 0.0),
            &v(1.0, 5.0, -1.0),
            0.0,
        );
        assert_eq!(b.min, v(0.0, 0.0, -1.0));
        assert_eq!(b.max, v(1.0, 5.0, 0.0));
        let t = triangle_swept_aabb(
            &v(0.0, 0.0, 0.0),
            &v(1.0, 0.0, 0.0),
            &v(0.0, 1.0, 0.0),
            &v(0.0, 0.0, 2.0),
            &v(1.0, 0.0, 2.0),
            &v(0.0, 1.0, 2.0),
            0.5,
        );
        assert!(t.contains_point(&v(0.5, 0.5, 1.0)));
        assert!(t.contains_point(&v(-0.5, -0.5, -0.5)));
    }

    #[test]
    fn non_finite_covers_everything() {
        let b = point_aabb(&v(f64::NAN, 0.0, 0.0), 0.1);
        assert_eq!(b, Aabb::everything());
        let e = edge_aabb(&v(0.0, 0.0, 0.0), &v(f64::INFINITY, 0.0, 0.0), 0.0);
        assert!(e.intersects(&point_aabb(&v(-5.0, 7.0, 1e10), 0.0)));
    }

    #[test]
    fn mesh_helpers_check_indices() {
        let x = vec![v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0)];
        assert_eq!(vertex_aabbs(&x, 0.0).len(), 3);
        assert_eq!(triangle_aabbs(&x, &[[0, 1, 2]], 0.0).unwrap().len(), 1);
        let err = edge_aabbs(&x, &[[0, 1], [1, 3]], 0.0).unwrap_err();
        assert_eq!(
            err,
            GeometryError::VertexIndexOutOfRange {
                primitive: "edge",
                index: 1,
                vertex: 3,
                num_vertices: 3
            }
        );
        assert!(err.to_string().contains("edge 1 refers to vertex 3"));
        let y = vec![v(0.0, 0.0, 1.0); 2];
        assert!(matches!(
            triangle_swept_aabbs(&x, &y, &[[0, 1, 2]], 0.0),
            Err(GeometryError::LengthMismatch { .. })
        ));
        let y: Vec<_> = x.iter().map(|p| p + v(0.0, 0.0, 1.0)).collect();
        let s = edge_swept_aabbs(&x, &y, &[[0, 2]], 0.0).unwrap();
        assert_eq!(s[0].max, v(0.0, 1.0, 1.0));
        assert_eq!(vertex_swept_aabbs(&x, &y, 0.0).unwrap().len(), 3);
    }
}

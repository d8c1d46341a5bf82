//! Squared distances between contact primitives, their region classification, and closest-point
//! parameters.
//!
//! All distances are **squared** (every function name ends in `_distance_sq`). Following the IPC
//! Toolkit (Li et al. 2020, "Incremental Potential Contact", §4 and supplement), a candidate pair is
//! first *classified* by the region of the closest point (`*_distance_type`); the distance, its
//! derivatives and the friction basis are then evaluated for that fixed type (`*_typed`). The
//! auto-typed functions classify and evaluate in one call.
//!
//! Region names map to the IPC Toolkit enums as follows:
//!
//! | here | IPC | closest feature pair |
//! |---|---|---|
//! | [`PointEdgeDistanceType::PointE0`] / `PointE1` / `PointEdge` | `P_E0` / `P_E1` / `P_E` | vertex e0 / vertex e1 / edge interior |
//! | [`PointTriangleDistanceType::PointT0`] .. `PointT2` | `P_T0` .. `P_T2` | triangle vertex |
//! | [`PointTriangleDistanceType::PointEdge0`] .. `PointEdge2` | `P_E0` .. `P_E2` | edge i = (t_i, t_(i+1 mod 3)) |
//! | [`PointTriangleDistanceType::PointTriangle`] | `P_T` | triangle interior (plane) |
//! | [`EdgeEdgeDistanceType::Ea0Eb0`] .. `Ea1Eb1` | `EA0_EB0` .. `EA1_EB1` | two end vertices |
//! | [`EdgeEdgeDistanceType::EaEb0`], `EaEb1`, `Ea0Eb`, `Ea1Eb` | `EA_EB0`, `EA_EB1`, `EA0_EB`, `EA1_EB` | edge interior – vertex |
//! | [`EdgeEdgeDistanceType::EaEb`] | `EA_EB` | both interiors (line–line) |
//!
//! Degenerate input (zero-length edges, collinear triangles, parallel edges) is classified into the
//! lower-dimensional type that is correct for it, so the auto-typed distance is always the true
//! minimum over the closed primitives. NaN input never panics: classifiers return some type and
//! distances return NaN.

mod edge_edge;
mod point_edge;
mod point_point;
mod point_triangle;

pub use edge_edge::{
    edge_edge_closest_parameters, edge_edge_closest_parameters_typed, edge_edge_cross_norm_sq, edge_edge_distance_sq,
    edge_edge_distance_sq_typed, edge_edge_distance_type, edge_edge_mollifier, edge_edge_mollifier_derivative,
    edge_edge_mollifier_second_derivative, edge_edge_mollifier_threshold, EdgeEdgeDistanceType,
    EDGE_EDGE_PARALLEL_THRESHOLD,
};
pub use point_edge::{
    point_edge_closest_parameter, point_edge_closest_parameter_typed, point_edge_distance_sq,
    point_edge_distance_sq_typed, point_edge_distance_type, point_line_distance_sq, PointEdgeDistanceType,
};
pub use point_point::point_point_distance_sq;
pub use point_triangle::{
    point_plane_distance_sq, point_triangle_closest_barycentric, point_triangle_closest_barycentric_typed,
    point_triangle_distance_sq, point_triangle_distance_sq_typed, point_triangle_distance_type,
    PointTriangleDistanceType,
};

#[cfg(test)]
pub(crate) mod test_util {
    //! Helpers shared by the distance tests.
    use nalgebra::Vector3;
    use rand::rngs::StdRng;
    use rand::Rng;

    /// A random point with coordinates uniform in `[-1, 1]`.
    pub fn random_point(rng: &mut StdRng) -> Vector3<f64> {
        Vector3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        )
    }

    /// The scales swept by the degenerate-input tests (IPC Toolkit style `GENERATE`).
    pub const SCALES: [f64; 7] = [-1.0, -1e-12, 0.0, 1e-12, 1.0, 1e-300, -1e-300];
}

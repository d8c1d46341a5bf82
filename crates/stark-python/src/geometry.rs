//! The `geometry` submodule: the contact geometry toolkit on NumPy arrays.
//!
//! Squared distances between points, edges and triangles with their IPC region type, gradient
//! and Hessian; continuous collision detection with time of impact; the exact edge–triangle
//! intersection test; broad-phase candidate pairs; mesh topology helpers. Region types are the
//! IPC Toolkit's names: point–edge `P_E0`, `P_E1`, `P_E`; point–triangle `P_T0`, `P_T1`, `P_T2`,
//! `P_E0`, `P_E1`, `P_E2`, `P_T`; edge–edge `EA0_EB0`, `EA0_EB1`, `EA1_EB0`, `EA1_EB1`, `EA_EB0`,
//! `EA_EB1`, `EA0_EB`, `EA1_EB`, `EA_EB`. Every distance is squared.

use crate::convert::{elements_out, guarded, stark_err, Elements, Points, V3};
use numpy::ndarray::{Array1, Array2};
use numpy::{IntoPyArray, PyArray1, PyArray2};
use pyo3::prelude::*;
use stark::contact::pairs::{Distance, PairKind};
use stark::geometry::ccd::{self, CcdParams};
use stark::geometry::distance::{
    self as dist, EdgeEdgeDistanceType as Ee, PointEdgeDistanceType as Pe, PointTriangleDistanceType as Pt,
};
use stark::geometry::{aabb, bvh::Bvh, intersection, mesh};

const PE_NAMES: [(&str, Pe); 3] = [("P_E0", Pe::PointE0), ("P_E1", Pe::PointE1), ("P_E", Pe::PointEdge)];
const PT_NAMES: [(&str, Pt); 7] = [
    ("P_T0", Pt::PointT0),
    ("P_T1", Pt::PointT1),
    ("P_T2", Pt::PointT2),
    ("P_E0", Pt::PointEdge0),
    ("P_E1", Pt::PointEdge1),
    ("P_E2", Pt::PointEdge2),
    ("P_T", Pt::PointTriangle),
];
const EE_NAMES: [(&str, Ee); 9] = [
    ("EA0_EB0", Ee::Ea0Eb0),
    ("EA0_EB1", Ee::Ea0Eb1),
    ("EA1_EB0", Ee::Ea1Eb0),
    ("EA1_EB1", Ee::Ea1Eb1),
    ("EA_EB0", Ee::EaEb0),
    ("EA_EB1", Ee::EaEb1),
    ("EA0_EB", Ee::Ea0Eb),
    ("EA1_EB", Ee::Ea1Eb),
    ("EA_EB", Ee::EaEb),
];

fn name_of<T: PartialEq + Copy>(table: &[(&'static str, T)], t: T) -> &'static str {
    table.iter().find(|(_, v)| *v == t).map(|(n, _)| *n).unwrap_or("?")
}

fn parse<T: Copy>(table: &[(&'static str, T)], name: &str) -> PyResult<T> {
    table.iter().find(|(n, _)| *n == name).map(|(_, v)| *v).ok_or_else(|| {
        let names: Vec<_> = table.iter().map(|(n, _)| *n).collect();
        stark_err(format!(
            "unknown distance type '{name}' (expected one of {})",
            names.join(", ")
        ))
    })
}

/// The distance formula of a region type and the stencil nodes it uses, in its order.
fn formula_pe(t: Pe) -> (Distance, Vec<usize>) {
    match t {
        Pe::PointE0 => (Distance::PointPoint, vec![0, 1]),
        Pe::PointE1 => (Distance::PointPoint, vec![0, 2]),
        Pe::PointEdge => (Distance::PointLine, vec![0, 1, 2]),
    }
}

fn formula_pt(t: Pt) -> (Distance, Vec<usize>) {
    match t {
        Pt::PointT0 => (Distance::PointPoint, vec![0, 1]),
        Pt::PointT1 => (Distance::PointPoint, vec![0, 2]),
        Pt::PointT2 => (Distance::PointPoint, vec![0, 3]),
        Pt::PointEdge0 => (Distance::PointLine, vec![0, 1, 2]),
        Pt::PointEdge1 => (Distance::PointLine, vec![0, 2, 3]),
        Pt::PointEdge2 => (Distance::PointLine, vec![0, 3, 1]),
        Pt::PointTriangle => (Distance::PointPlane, vec![0, 1, 2, 3]),
    }
}

fn formula_ee(t: Ee) -> (Distance, Vec<usize>) {
    let (d, idx) = PairKind::EdgeEdgeMollified(t).distance();
    (d, idx[..d.len()].to_vec())
}

fn kernel(d: Distance) -> stark::energy::Kernel {
    match d {
        Distance::PointPoint => stark::generated::distance_point_point,
        Distance::PointLine => stark::generated::distance_point_line,
        Distance::PointPlane => stark::generated::distance_point_plane,
        Distance::LineLine => stark::generated::distance_line_line,
    }
}

/// Value, gradient (3n) and Hessian (3n × 3n) of the squared distance of formula `d` on the
/// stencil nodes `idx` of `x`, scattered into the full stencil of `x.len()` points.
fn derivatives(x: &[nalgebra::Vector3<f64>], d: Distance, idx: &[usize]) -> (f64, Vec<f64>, Vec<f64>) {
    let k = idx.len();
    let sub: Vec<f64> = idx.iter().flat_map(|&i| [x[i].x, x[i].y, x[i].z]).collect();
    let mut g = vec![0.0; 3 * k];
    let mut h = vec![0.0; 9 * k * k];
    let value = kernel(d)(&sub, &[], &mut g, &mut h);
    let n = 3 * x.len();
    let mut grad = vec![0.0; n];
    let mut hess = vec![0.0; n * n];
    for (a, &ia) in idx.iter().enumerate() {
        for r in 0..3 {
            grad[3 * ia + r] += g[3 * a + r];
            for (b, &ib) in idx.iter().enumerate() {
                for c in 0..3 {
                    hess[(3 * ia + r) * n + 3 * ib + c] += h[(3 * a + r) * 3 * k + 3 * b + c];
                }
            }
        }
    }
    (value, grad, hess)
}

/// Two (k, 2) index arrays.
type IndexPairs<'py> = (Bound<'py, PyArray2<i64>>, Bound<'py, PyArray2<i64>>);

type Derivs<'py> = (f64, Bound<'py, PyArray1<f64>>, Bound<'py, PyArray2<f64>>, &'static str);

fn derivs_out<'py>(py: Python<'py>, (v, g, h): (f64, Vec<f64>, Vec<f64>), name: &'static str) -> Derivs<'py> {
    let n = g.len();
    (
        v,
        Array1::from(g).into_pyarray(py),
        Array2::from_shape_vec((n, n), h).expect("square").into_pyarray(py),
        name,
    )
}

/// Squared distance between two points.
#[pyfunction]
fn point_point_distance_sq(p0: V3, p1: V3) -> f64 {
    dist::point_point_distance_sq(&p0.0, &p1.0)
}

/// Squared distance, gradient (6,) and Hessian (6, 6) between two points: `(d², grad, hess, "P_P")`.
#[pyfunction]
fn point_point_distance_sq_derivatives(py: Python<'_>, p0: V3, p1: V3) -> Derivs<'_> {
    derivs_out(py, derivatives(&[p0.0, p1.0], Distance::PointPoint, &[0, 1]), "P_P")
}

/// Region of the closest point of edge (e0, e1) to p: "P_E0", "P_E1" or "P_E".
#[pyfunction]
fn point_edge_distance_type(p: V3, e0: V3, e1: V3) -> &'static str {
    name_of(&PE_NAMES, dist::point_edge_distance_type(&p.0, &e0.0, &e1.0))
}

/// Squared distance from p to the edge (e0, e1); `dtype` forces a region type.
#[pyfunction]
#[pyo3(signature = (p, e0, e1, dtype=None))]
fn point_edge_distance_sq(p: V3, e0: V3, e1: V3, dtype: Option<&str>) -> PyResult<f64> {
    Ok(match dtype {
        None => dist::point_edge_distance_sq(&p.0, &e0.0, &e1.0),
        Some(t) => dist::point_edge_distance_sq_typed(&p.0, &e0.0, &e1.0, parse(&PE_NAMES, t)?),
    })
}

/// `(d², gradient (9,), Hessian (9, 9), type)` of the point–edge squared distance, for the
/// classified region or the forced `dtype`; variables ordered p, e0, e1.
#[pyfunction]
#[pyo3(signature = (p, e0, e1, dtype=None))]
fn point_edge_distance_sq_derivatives<'py>(
    py: Python<'py>,
    p: V3,
    e0: V3,
    e1: V3,
    dtype: Option<&str>,
) -> PyResult<Derivs<'py>> {
    let t = match dtype {
        None => dist::point_edge_distance_type(&p.0, &e0.0, &e1.0),
        Some(t) => parse(&PE_NAMES, t)?,
    };
    let (d, idx) = formula_pe(t);
    Ok(derivs_out(
        py,
        derivatives(&[p.0, e0.0, e1.0], d, &idx),
        name_of(&PE_NAMES, t),
    ))
}

/// Parameter `s ∈ [0, 1]` of the point of edge (e0, e1) closest to p.
#[pyfunction]
fn point_edge_closest_parameter(p: V3, e0: V3, e1: V3) -> f64 {
    dist::point_edge_closest_parameter(&p.0, &e0.0, &e1.0)
}

/// Region of the closest point of triangle (t0, t1, t2) to p: "P_T0", ..., "P_E2", "P_T".
#[pyfunction]
fn point_triangle_distance_type(p: V3, t0: V3, t1: V3, t2: V3) -> &'static str {
    name_of(&PT_NAMES, dist::point_triangle_distance_type(&p.0, &t0.0, &t1.0, &t2.0))
}

/// Squared distance from p to the triangle (t0, t1, t2); `dtype` forces a region type.
#[pyfunction]
#[pyo3(signature = (p, t0, t1, t2, dtype=None))]
fn point_triangle_distance_sq(p: V3, t0: V3, t1: V3, t2: V3, dtype: Option<&str>) -> PyResult<f64> {
    Ok(match dtype {
        None => dist::point_triangle_distance_sq(&p.0, &t0.0, &t1.0, &t2.0),
        Some(t) => dist::point_triangle_distance_sq_typed(&p.0, &t0.0, &t1.0, &t2.0, parse(&PT_NAMES, t)?),
    })
}

/// `(d², gradient (12,), Hessian (12, 12), type)` of the point–triangle squared distance;
/// variables ordered p, t0, t1, t2.
#[pyfunction]
#[pyo3(signature = (p, t0, t1, t2, dtype=None))]
fn point_triangle_distance_sq_derivatives<'py>(
    py: Python<'py>,
    p: V3,
    t0: V3,
    t1: V3,
    t2: V3,
    dtype: Option<&str>,
) -> PyResult<Derivs<'py>> {
    let t = match dtype {
        None => dist::point_triangle_distance_type(&p.0, &t0.0, &t1.0, &t2.0),
        Some(t) => parse(&PT_NAMES, t)?,
    };
    let (d, idx) = formula_pt(t);
    Ok(derivs_out(
        py,
        derivatives(&[p.0, t0.0, t1.0, t2.0], d, &idx),
        name_of(&PT_NAMES, t),
    ))
}

/// Barycentric coordinates `(u, v)` of the point of the triangle closest to p (the point is
/// `t0 + u (t1 − t0) + v (t2 − t0)`).
#[pyfunction]
fn point_triangle_closest_barycentric(p: V3, t0: V3, t1: V3, t2: V3) -> (f64, f64) {
    dist::point_triangle_closest_barycentric(&p.0, &t0.0, &t1.0, &t2.0)
}

/// Region of the closest points of edges (ea0, ea1) and (eb0, eb1): "EA0_EB0", ..., "EA_EB".
#[pyfunction]
fn edge_edge_distance_type(ea0: V3, ea1: V3, eb0: V3, eb1: V3) -> &'static str {
    name_of(&EE_NAMES, dist::edge_edge_distance_type(&ea0.0, &ea1.0, &eb0.0, &eb1.0))
}

/// Squared distance between edges (ea0, ea1) and (eb0, eb1); `dtype` forces a region type.
#[pyfunction]
#[pyo3(signature = (ea0, ea1, eb0, eb1, dtype=None))]
fn edge_edge_distance_sq(ea0: V3, ea1: V3, eb0: V3, eb1: V3, dtype: Option<&str>) -> PyResult<f64> {
    Ok(match dtype {
        None => dist::edge_edge_distance_sq(&ea0.0, &ea1.0, &eb0.0, &eb1.0),
        Some(t) => dist::edge_edge_distance_sq_typed(&ea0.0, &ea1.0, &eb0.0, &eb1.0, parse(&EE_NAMES, t)?),
    })
}

/// `(d², gradient (12,), Hessian (12, 12), type)` of the edge–edge squared distance; variables
/// ordered ea0, ea1, eb0, eb1.
#[pyfunction]
#[pyo3(signature = (ea0, ea1, eb0, eb1, dtype=None))]
fn edge_edge_distance_sq_derivatives<'py>(
    py: Python<'py>,
    ea0: V3,
    ea1: V3,
    eb0: V3,
    eb1: V3,
    dtype: Option<&str>,
) -> PyResult<Derivs<'py>> {
    let t = match dtype {
        None => dist::edge_edge_distance_type(&ea0.0, &ea1.0, &eb0.0, &eb1.0),
        Some(t) => parse(&EE_NAMES, t)?,
    };
    let (d, idx) = formula_ee(t);
    Ok(derivs_out(
        py,
        derivatives(&[ea0.0, ea1.0, eb0.0, eb1.0], d, &idx),
        name_of(&EE_NAMES, t),
    ))
}

/// Parameters `(s, t)` of the closest points `ea0 + s (ea1 − ea0)` and `eb0 + t (eb1 − eb0)`.
#[pyfunction]
fn edge_edge_closest_parameters(ea0: V3, ea1: V3, eb0: V3, eb1: V3) -> (f64, f64) {
    dist::edge_edge_closest_parameters(&ea0.0, &ea1.0, &eb0.0, &eb1.0)
}

/// `‖(ea1 − ea0) × (eb1 − eb0)‖²`, the argument of the edge–edge mollifier.
#[pyfunction]
fn edge_edge_cross_norm_sq(ea0: V3, ea1: V3, eb0: V3, eb1: V3) -> f64 {
    dist::edge_edge_cross_norm_sq(&ea0.0, &ea1.0, &eb0.0, &eb1.0)
}

/// Mollifier threshold `ε = 1e-3 ‖ea0 − ea1‖² ‖eb0 − eb1‖²` from rest positions.
#[pyfunction]
fn edge_edge_mollifier_threshold(ea0_rest: V3, ea1_rest: V3, eb0_rest: V3, eb1_rest: V3) -> f64 {
    dist::edge_edge_mollifier_threshold(&ea0_rest.0, &ea1_rest.0, &eb0_rest.0, &eb1_rest.0)
}

/// The edge–edge mollifier `m(x)` with its first and second derivatives: `(m, m', m'')`.
#[pyfunction]
fn edge_edge_mollifier(x: f64, eps_x: f64) -> (f64, f64, f64) {
    (
        dist::edge_edge_mollifier(x, eps_x),
        dist::edge_edge_mollifier_derivative(x, eps_x),
        dist::edge_edge_mollifier_second_derivative(x, eps_x),
    )
}

fn ccd_params(tolerance: f64, max_iterations: usize) -> CcdParams {
    CcdParams {
        tolerance,
        max_iterations,
        ..CcdParams::default()
    }
}

/// Time of impact of a point and a triangle moving linearly from their `_t0` to their `_t1`
/// positions: `toi ∈ [0, tmax]` such that they stay farther than `min_distance` on `[0, toi)`,
/// or None when they provably do on all of `[0, tmax]`. Conservative (never misses a contact);
/// 0 means already in contact.
#[pyfunction]
#[pyo3(signature = (p_t0, t0_t0, t1_t0, t2_t0, p_t1, t0_t1, t1_t1, t2_t1, min_distance=0.0, tmax=1.0, tolerance=1e-6, max_iterations=1_000_000))]
fn point_triangle_ccd(
    p_t0: V3,
    t0_t0: V3,
    t1_t0: V3,
    t2_t0: V3,
    p_t1: V3,
    t0_t1: V3,
    t1_t1: V3,
    t2_t1: V3,
    min_distance: f64,
    tmax: f64,
    tolerance: f64,
    max_iterations: usize,
) -> PyResult<Option<f64>> {
    guarded(|| {
        Ok(ccd::point_triangle_ccd_with_params(
            &[p_t0.0, t0_t0.0, t1_t0.0, t2_t0.0],
            &[p_t1.0, t0_t1.0, t1_t1.0, t2_t1.0],
            min_distance,
            tmax,
            &ccd_params(tolerance, max_iterations),
        ))
    })
}

/// Time of impact of two edges moving linearly (same contract as `point_triangle_ccd`).
#[pyfunction]
#[pyo3(signature = (ea0_t0, ea1_t0, eb0_t0, eb1_t0, ea0_t1, ea1_t1, eb0_t1, eb1_t1, min_distance=0.0, tmax=1.0, tolerance=1e-6, max_iterations=1_000_000))]
fn edge_edge_ccd(
    ea0_t0: V3,
    ea1_t0: V3,
    eb0_t0: V3,
    eb1_t0: V3,
    ea0_t1: V3,
    ea1_t1: V3,
    eb0_t1: V3,
    eb1_t1: V3,
    min_distance: f64,
    tmax: f64,
    tolerance: f64,
    max_iterations: usize,
) -> PyResult<Option<f64>> {
    guarded(|| {
        Ok(ccd::edge_edge_ccd_with_params(
            &[ea0_t0.0, ea1_t0.0, eb0_t0.0, eb1_t0.0],
            &[ea0_t1.0, ea1_t1.0, eb0_t1.0, eb1_t1.0],
            min_distance,
            tmax,
            &ccd_params(tolerance, max_iterations),
        ))
    })
}

/// Exact test whether the closed edge (e0, e1) and the closed triangle (t0, t1, t2) share a point.
#[pyfunction]
fn edge_triangle_intersect(e0: V3, e1: V3, t0: V3, t1: V3, t2: V3) -> bool {
    intersection::edge_triangle_intersect(&e0.0, &e1.0, &t0.0, &t1.0, &t2.0)
}

/// All intersecting (edge, triangle) index pairs of a mesh, sorted, as a (k, 2) array; pairs
/// that share a vertex are skipped.
#[pyfunction]
fn find_edge_triangle_intersections<'py>(
    py: Python<'py>,
    positions: Points,
    edges: Elements<2>,
    triangles: Elements<3>,
) -> PyResult<Bound<'py, PyArray2<i64>>> {
    let pairs = py.detach(|| {
        guarded(|| {
            intersection::find_edge_triangle_intersections(&positions.0, &edges.0, &triangles.0, |_, _| true)
                .map_err(|e| stark::StarkError::InvalidInput(e.to_string()))
        })
    })?;
    let pairs: Vec<[usize; 2]> = pairs.into_iter().map(|(a, b)| [a, b]).collect();
    Ok(elements_out(py, &pairs))
}

/// Broad-phase candidate pairs of a mesh: `(point_triangle, edge_edge)`, (k, 2) arrays of
/// (vertex, triangle) and (edge a, edge b) with a < b, whose boxes, inflated by
/// `inflation_radius`, overlap. With `positions_t1` the boxes sweep the linear motion from
/// `positions` to `positions_t1` (candidates for CCD). Pairs sharing a vertex are skipped.
#[pyfunction]
#[pyo3(signature = (positions, edges, triangles, inflation_radius=0.0, positions_t1=None))]
fn broad_phase<'py>(
    py: Python<'py>,
    positions: Points,
    edges: Elements<2>,
    triangles: Elements<3>,
    inflation_radius: f64,
    positions_t1: Option<Points>,
) -> PyResult<IndexPairs<'py>> {
    if !(inflation_radius >= 0.0 && inflation_radius.is_finite()) {
        return Err(stark_err(format!(
            "inflation_radius must be non-negative and finite, got {inflation_radius}"
        )));
    }
    let (pt, ee) = py.detach(|| {
        guarded(|| {
            let x0 = &positions.0;
            let x1 = positions_t1.as_ref().map(|p| &p.0).unwrap_or(x0);
            let err = |e: stark::geometry::GeometryError| stark::StarkError::InvalidInput(e.to_string());
            let r = inflation_radius;
            let vertex_boxes = aabb::vertex_swept_aabbs(x0, x1, r).map_err(err)?;
            let edge_boxes = aabb::edge_swept_aabbs(x0, x1, &edges.0, r).map_err(err)?;
            let tri_boxes = aabb::triangle_swept_aabbs(x0, x1, &triangles.0, r).map_err(err)?;
            let vertices = Bvh::build(&vertex_boxes);
            let tris = Bvh::build(&tri_boxes);
            let pt: Vec<[usize; 2]> = vertices
                .pairs_with(&tris, 0.0)
                .into_iter()
                .filter(|&(v, t)| !triangles.0[t].contains(&v))
                .map(|(v, t)| [v, t])
                .collect();
            let ee: Vec<[usize; 2]> = Bvh::build(&edge_boxes)
                .self_pairs(0.0)
                .into_iter()
                .filter(|&(a, b)| {
                    let (ea, eb) = (edges.0[a], edges.0[b]);
                    !ea.iter().any(|v| eb.contains(v))
                })
                .map(|(a, b)| [a, b])
                .collect();
            Ok((pt, ee))
        })
    })?;
    Ok((elements_out(py, &pt), elements_out(py, &ee)))
}

/// The unique edges (m, 2) of a triangle mesh.
#[pyfunction]
fn edges_from_triangles(py: Python<'_>, triangles: Elements<3>) -> Bound<'_, PyArray2<i64>> {
    elements_out(py, &mesh::edges_from_triangles(&triangles.0))
}

/// The unique edges (m, 2) of a tet mesh.
#[pyfunction]
fn edges_from_tets(py: Python<'_>, tets: Elements<4>) -> Bound<'_, PyArray2<i64>> {
    elements_out(py, &mesh::edges_from_tets(&tets.0))
}

/// The boundary triangles (m, 3) of a tet mesh, oriented outward.
#[pyfunction]
fn find_surface_triangles(py: Python<'_>, tets: Elements<4>) -> PyResult<Bound<'_, PyArray2<i64>>> {
    let t = mesh::find_surface_triangles(&tets.0).map_err(|e| stark_err(e.to_string()))?;
    Ok(elements_out(py, &t))
}

/// The boundary edges (m, 2) of a triangle mesh (edges with one adjacent triangle).
#[pyfunction]
fn perimeter_edges(py: Python<'_>, triangles: Elements<3>) -> Bound<'_, PyArray2<i64>> {
    elements_out(py, &mesh::perimeter_edges(&triangles.0))
}

/// Build the submodule.
pub fn module(py: Python<'_>) -> PyResult<Bound<'_, PyModule>> {
    let m = PyModule::new(py, "geometry")?;
    m.add(
        "__doc__",
        "Contact geometry on NumPy arrays: squared distances with type, gradient and Hessian; CCD; \
         the exact edge-triangle test; broad-phase candidate pairs; mesh topology.",
    )?;
    m.add_function(wrap_pyfunction!(point_point_distance_sq, &m)?)?;
    m.add_function(wrap_pyfunction!(point_point_distance_sq_derivatives, &m)?)?;
    m.add_function(wrap_pyfunction!(point_edge_distance_type, &m)?)?;
    m.add_function(wrap_pyfunction!(point_edge_distance_sq, &m)?)?;
    m.add_function(wrap_pyfunction!(point_edge_distance_sq_derivatives, &m)?)?;
    m.add_function(wrap_pyfunction!(point_edge_closest_parameter, &m)?)?;
    m.add_function(wrap_pyfunction!(point_triangle_distance_type, &m)?)?;
    m.add_function(wrap_pyfunction!(point_triangle_distance_sq, &m)?)?;
    m.add_function(wrap_pyfunction!(point_triangle_distance_sq_derivatives, &m)?)?;
    m.add_function(wrap_pyfunction!(point_triangle_closest_barycentric, &m)?)?;
    m.add_function(wrap_pyfunction!(edge_edge_distance_type, &m)?)?;
    m.add_function(wrap_pyfunction!(edge_edge_distance_sq, &m)?)?;
    m.add_function(wrap_pyfunction!(edge_edge_distance_sq_derivatives, &m)?)?;
    m.add_function(wrap_pyfunction!(edge_edge_closest_parameters, &m)?)?;
    m.add_function(wrap_pyfunction!(edge_edge_cross_norm_sq, &m)?)?;
    m.add_function(wrap_pyfunction!(edge_edge_mollifier_threshold, &m)?)?;
    m.add_function(wrap_pyfunction!(edge_edge_mollifier, &m)?)?;
    m.add_function(wrap_pyfunction!(point_triangle_ccd, &m)?)?;
    m.add_function(wrap_pyfunction!(edge_edge_ccd, &m)?)?;
    m.add_function(wrap_pyfunction!(edge_triangle_intersect, &m)?)?;
    m.add_function(wrap_pyfunction!(find_edge_triangle_intersections, &m)?)?;
    m.add_function(wrap_pyfunction!(broad_phase, &m)?)?;
    m.add_function(wrap_pyfunction!(edges_from_triangles, &m)?)?;
    m.add_function(wrap_pyfunction!(edges_from_tets, &m)?)?;
    m.add_function(wrap_pyfunction!(find_surface_triangles, &m)?)?;
    m.add_function(wrap_pyfunction!(perimeter_edges, &m)?)?;
    Ok(m)
}

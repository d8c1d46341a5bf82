"""Contact geometry on NumPy arrays: squared distances with their IPC region type, gradient and
Hessian; continuous collision detection with time of impact; the exact edge-triangle
intersection test; broad-phase candidate pairs; mesh topology helpers.

Every distance is squared. Region types are the IPC Toolkit's names: point-edge ``P_E0``,
``P_E1``, ``P_E``; point-triangle ``P_T0``, ``P_T1``, ``P_T2``, ``P_E0``, ``P_E1``, ``P_E2``,
``P_T``; edge-edge ``EA0_EB0``, ``EA0_EB1``, ``EA1_EB0``, ``EA1_EB1``, ``EA_EB0``, ``EA_EB1``,
``EA0_EB``, ``EA1_EB``, ``EA_EB``. ``*_derivatives`` return ``(d², gradient, Hessian, type)``
with the variables of the arguments in order (x, y, z of each point).
"""

from typing import Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray

_Vector = ArrayLike
_Derivatives = tuple[float, NDArray[np.float64], NDArray[np.float64], str]

def point_point_distance_sq(p0: _Vector, p1: _Vector) -> float:
    """Squared distance between two points."""
def point_point_distance_sq_derivatives(p0: _Vector, p1: _Vector) -> _Derivatives:
    """Squared distance, gradient (6,) and Hessian (6, 6) between two points."""
def point_edge_distance_type(p: _Vector, e0: _Vector, e1: _Vector) -> str:
    """Region of the closest point of edge (e0, e1) to p: "P_E0", "P_E1" or "P_E"."""
def point_edge_distance_sq(p: _Vector, e0: _Vector, e1: _Vector, dtype: Optional[str] = None) -> float:
    """Squared distance from p to the edge (e0, e1); `dtype` forces a region type."""
def point_edge_distance_sq_derivatives(p: _Vector, e0: _Vector, e1: _Vector, dtype: Optional[str] = None) -> _Derivatives:
    """`(d², gradient (9,), Hessian (9, 9), type)` of the point-edge squared distance."""
def point_edge_closest_parameter(p: _Vector, e0: _Vector, e1: _Vector) -> float:
    """Parameter `s ∈ [0, 1]` of the point of edge (e0, e1) closest to p."""
def point_triangle_distance_type(p: _Vector, t0: _Vector, t1: _Vector, t2: _Vector) -> str:
    """Region of the closest point of triangle (t0, t1, t2) to p."""
def point_triangle_distance_sq(p: _Vector, t0: _Vector, t1: _Vector, t2: _Vector, dtype: Optional[str] = None) -> float:
    """Squared distance from p to the triangle (t0, t1, t2); `dtype` forces a region type."""
def point_triangle_distance_sq_derivatives(
    p: _Vector, t0: _Vector, t1: _Vector, t2: _Vector, dtype: Optional[str] = None
) -> _Derivatives:
    """`(d², gradient (12,), Hessian (12, 12), type)` of the point-triangle squared distance."""
def point_triangle_closest_barycentric(p: _Vector, t0: _Vector, t1: _Vector, t2: _Vector) -> tuple[float, float]:
    """Barycentric coordinates `(u, v)` of the closest point `t0 + u (t1 − t0) + v (t2 − t0)`."""
def edge_edge_distance_type(ea0: _Vector, ea1: _Vector, eb0: _Vector, eb1: _Vector) -> str:
    """Region of the closest points of edges (ea0, ea1) and (eb0, eb1)."""
def edge_edge_distance_sq(ea0: _Vector, ea1: _Vector, eb0: _Vector, eb1: _Vector, dtype: Optional[str] = None) -> float:
    """Squared distance between two edges; `dtype` forces a region type."""
def edge_edge_distance_sq_derivatives(
    ea0: _Vector, ea1: _Vector, eb0: _Vector, eb1: _Vector, dtype: Optional[str] = None
) -> _Derivatives:
    """`(d², gradient (12,), Hessian (12, 12), type)` of the edge-edge squared distance."""
def edge_edge_closest_parameters(ea0: _Vector, ea1: _Vector, eb0: _Vector, eb1: _Vector) -> tuple[float, float]:
    """Parameters `(s, t)` of the closest points on the two edges."""
def edge_edge_cross_norm_sq(ea0: _Vector, ea1: _Vector, eb0: _Vector, eb1: _Vector) -> float:
    """`‖(ea1 − ea0) × (eb1 − eb0)‖²`, the argument of the edge-edge mollifier."""
def edge_edge_mollifier_threshold(ea0_rest: _Vector, ea1_rest: _Vector, eb0_rest: _Vector, eb1_rest: _Vector) -> float:
    """Mollifier threshold `ε = 1e-3 ‖ea0 − ea1‖² ‖eb0 − eb1‖²` from rest positions."""
def edge_edge_mollifier(x: float, eps_x: float) -> tuple[float, float, float]:
    """The edge-edge mollifier `m(x)` with its first and second derivatives."""
def point_triangle_ccd(
    p_t0: _Vector,
    t0_t0: _Vector,
    t1_t0: _Vector,
    t2_t0: _Vector,
    p_t1: _Vector,
    t0_t1: _Vector,
    t1_t1: _Vector,
    t2_t1: _Vector,
    min_distance: float = 0.0,
    tmax: float = 1.0,
    tolerance: float = 1e-6,
    max_iterations: int = 1000000,
) -> Optional[float]:
    """Time of impact of a point and a triangle moving linearly, or None (never misses a contact)."""
def edge_edge_ccd(
    ea0_t0: _Vector,
    ea1_t0: _Vector,
    eb0_t0: _Vector,
    eb1_t0: _Vector,
    ea0_t1: _Vector,
    ea1_t1: _Vector,
    eb0_t1: _Vector,
    eb1_t1: _Vector,
    min_distance: float = 0.0,
    tmax: float = 1.0,
    tolerance: float = 1e-6,
    max_iterations: int = 1000000,
) -> Optional[float]:
    """Time of impact of two edges moving linearly, or None (never misses a contact)."""
def edge_triangle_intersect(e0: _Vector, e1: _Vector, t0: _Vector, t1: _Vector, t2: _Vector) -> bool:
    """Exact test whether the closed edge and the closed triangle share a point."""
def find_edge_triangle_intersections(positions: ArrayLike, edges: ArrayLike, triangles: ArrayLike) -> NDArray[np.int64]:
    """All intersecting (edge, triangle) index pairs of a mesh as a (k, 2) array."""
def broad_phase(
    positions: ArrayLike,
    edges: ArrayLike,
    triangles: ArrayLike,
    inflation_radius: float = 0.0,
    positions_t1: Optional[ArrayLike] = None,
) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Candidate (vertex, triangle) and (edge, edge) pairs whose (swept) boxes overlap."""
def edges_from_triangles(triangles: ArrayLike) -> NDArray[np.int64]:
    """The unique edges (m, 2) of a triangle mesh."""
def edges_from_tets(tets: ArrayLike) -> NDArray[np.int64]:
    """The unique edges (m, 2) of a tet mesh."""
def find_surface_triangles(tets: ArrayLike) -> NDArray[np.int64]:
    """The boundary triangles (m, 3) of a tet mesh, oriented outward."""
def perimeter_edges(triangles: ArrayLike) -> NDArray[np.int64]:
    """The boundary edges (m, 2) of a triangle mesh."""

"""The geometry toolkit: distances against brute force, derivatives against finite differences,
CCD, the intersection test and the broad phase against brute force."""

import itertools

import numpy as np
import pytest

from starkrs import geometry as g

RNG = np.random.default_rng(7)


def brute_point_triangle(p, t0, t1, t2, n=400):
    best = np.inf
    for u in np.linspace(0, 1, n):
        v = np.linspace(0, 1 - u, max(2, int(n * (1 - u))))
        q = t0 + u * (t1 - t0) + v[:, None] * (t2 - t0)
        best = min(best, ((q - p) ** 2).sum(axis=1).min())
    return best


def brute_edge_edge(a0, a1, b0, b1, n=600):
    s = np.linspace(0, 1, n)
    pa = a0 + s[:, None] * (a1 - a0)
    pb = b0 + s[:, None] * (b1 - b0)
    return ((pa[:, None, :] - pb[None, :, :]) ** 2).sum(axis=2).min()


def test_point_triangle_distance_type_and_derivatives():
    for _ in range(20):
        p, t0, t1, t2 = RNG.uniform(-1, 1, (4, 3))
        d = g.point_triangle_distance_sq(p, t0, t1, t2)
        assert d == pytest.approx(brute_point_triangle(p, t0, t1, t2), rel=2e-2, abs=1e-4)
        value, grad, hess, dtype = g.point_triangle_distance_sq_derivatives(p, t0, t1, t2)
        assert value == pytest.approx(d, rel=1e-12)
        assert dtype == g.point_triangle_distance_type(p, t0, t1, t2)
        assert grad.shape == (12,) and hess.shape == (12, 12)
        np.testing.assert_allclose(hess, hess.T, atol=1e-9)
        x = np.concatenate([p, t0, t1, t2])
        h = 1e-6

        def typed(y):
            return g.point_triangle_distance_sq(*np.split(y, 4), dtype=dtype)

        def typed_grad(y):
            return g.point_triangle_distance_sq_derivatives(*np.split(y, 4), dtype=dtype)[1]

        fd = np.array([(typed(x + h * e) - typed(x - h * e)) / (2 * h) for e in np.eye(12)])
        np.testing.assert_allclose(grad, fd, rtol=1e-5, atol=1e-7)
        fdh = np.array([(typed_grad(x + h * e) - typed_grad(x - h * e)) / (2 * h) for e in np.eye(12)])
        np.testing.assert_allclose(hess, fdh, rtol=1e-4, atol=1e-5)


def test_point_triangle_regions():
    t0, t1, t2 = np.array([0.0, 0, 0]), np.array([1.0, 0, 0]), np.array([0.0, 1, 0])
    cases = {
        "P_T": [0.2, 0.2, 1.0],
        "P_T0": [-1.0, -1.0, 0.5],
        "P_T1": [2.0, -0.5, 0.0],
        "P_T2": [-0.5, 2.0, 0.0],
        "P_E0": [0.5, -1.0, 0.0],
        "P_E1": [1.0, 1.0, 0.0],
        "P_E2": [-1.0, 0.5, 0.0],
    }
    for name, p in cases.items():
        assert g.point_triangle_distance_type(p, t0, t1, t2) == name
    assert g.point_triangle_distance_sq([0.2, 0.2, 1.0], t0, t1, t2) == pytest.approx(1.0)
    assert g.point_triangle_distance_sq([0.2, 0.2, 1.0], t0, t1, t2, dtype="P_T0") == pytest.approx(1.08)
    assert g.point_triangle_closest_barycentric([0.2, 0.3, 1.0], t0, t1, t2) == pytest.approx((0.2, 0.3))
    with pytest.raises(Exception, match="unknown distance type"):
        g.point_triangle_distance_sq([0, 0, 1], t0, t1, t2, dtype="PT")


def test_edge_edge_and_point_edge():
    for _ in range(20):
        a0, a1, b0, b1 = RNG.uniform(-1, 1, (4, 3))
        d = g.edge_edge_distance_sq(a0, a1, b0, b1)
        assert d == pytest.approx(brute_edge_edge(a0, a1, b0, b1), rel=2e-2, abs=1e-4)
        value, grad, hess, dtype = g.edge_edge_distance_sq_derivatives(a0, a1, b0, b1)
        assert value == pytest.approx(d, rel=1e-9) and dtype == g.edge_edge_distance_type(a0, a1, b0, b1)
        x = np.concatenate([a0, a1, b0, b1])
        h = 1e-6
        fd = np.array(
            [
                (g.edge_edge_distance_sq(*np.split(x + h * e, 4), dtype=dtype)
                 - g.edge_edge_distance_sq(*np.split(x - h * e, 4), dtype=dtype)) / (2 * h)
                for e in np.eye(12)
            ]
        )
        np.testing.assert_allclose(grad, fd, rtol=1e-5, atol=1e-7)
        p, e0, e1 = RNG.uniform(-1, 1, (3, 3))
        value, grad, hess, dtype = g.point_edge_distance_sq_derivatives(p, e0, e1)
        assert dtype in ("P_E0", "P_E1", "P_E") and grad.shape == (9,) and hess.shape == (9, 9)
        s = g.point_edge_closest_parameter(p, e0, e1)
        assert value == pytest.approx(((e0 + s * (e1 - e0) - p) ** 2).sum())
    assert g.edge_edge_distance_type([0, 0, 0], [1, 0, 0], [0.5, -1, 1], [0.5, 1, 1]) == "EA_EB"
    assert g.edge_edge_closest_parameters([0, 0, 0], [1, 0, 0], [0.5, -1, 1], [0.5, 1, 1]) == pytest.approx((0.5, 0.5))
    assert g.point_point_distance_sq([0, 0, 0], [1, 2, 2]) == 9.0
    value, grad, hess, dtype = g.point_point_distance_sq_derivatives([0, 0, 0], [1, 2, 2])
    np.testing.assert_allclose(grad, [-2, -4, -4, 2, 4, 4])
    np.testing.assert_allclose(hess, 2 * np.block([[np.eye(3), -np.eye(3)], [-np.eye(3), np.eye(3)]]))
    eps = g.edge_edge_mollifier_threshold([0, 0, 0], [1, 0, 0], [0, 0, 1], [0, 1, 1])
    assert eps == pytest.approx(1e-3)
    assert g.edge_edge_mollifier(2 * eps, eps) == (1.0, 0.0, 0.0)
    assert g.edge_edge_cross_norm_sq([0, 0, 0], [1, 0, 0], [0, 0, 1], [0, 1, 1]) == 1.0


def test_ccd():
    # A point falling through a triangle from z = 1 to z = -1: impact at t = 0.5.
    t0, t1, t2 = [0.0, 0, 0], [1.0, 0, 0], [0.0, 1, 0]
    toi = g.point_triangle_ccd([0.2, 0.2, 1.0], t0, t1, t2, [0.2, 0.2, -1.0], t0, t1, t2)
    assert toi is not None and 0.49 < toi <= 0.5
    toi = g.point_triangle_ccd([0.2, 0.2, 1.0], t0, t1, t2, [0.2, 0.2, -1.0], t0, t1, t2, min_distance=0.1)
    assert 0.44 < toi <= 0.45
    assert g.point_triangle_ccd([2.0, 2.0, 1.0], t0, t1, t2, [2.0, 2.0, -1.0], t0, t1, t2) is None
    toi = g.edge_edge_ccd([0, 0, 1], [1, 0, 1], [0.5, -1, 0], [0.5, 1, 0],
                          [0, 0, -1], [1, 0, -1], [0.5, -1, 0], [0.5, 1, 0])
    assert 0.49 < toi <= 0.5
    assert g.edge_edge_ccd([0, 0, 1], [1, 0, 1], [0.5, -1, 0], [0.5, 1, 0],
                           [0, 0, 0.5], [1, 0, 0.5], [0.5, -1, 0], [0.5, 1, 0]) is None
    assert g.point_triangle_ccd([np.nan, 0, 0], t0, t1, t2, [0, 0, 0], t0, t1, t2) == 0.0


def test_intersections_and_broad_phase():
    assert g.edge_triangle_intersect([0.2, 0.2, -1], [0.2, 0.2, 1], [0, 0, 0], [1, 0, 0], [0, 1, 0])
    assert not g.edge_triangle_intersect([2, 2, -1], [2, 2, 1], [0, 0, 0], [1, 0, 0], [0, 1, 0])
    from starkrs import meshes

    v, t = meshes.triangle_grid([1.0, 1.0], [3, 3])
    e = g.edges_from_triangles(t)
    assert e.shape == (33, 2) and g.perimeter_edges(t).shape == (12, 2)
    # A vertical stick through the sheet.
    pos = np.vstack([v, [[0.1, 0.05, -0.5], [0.1, 0.05, 0.5]]])
    edges = np.vstack([e, [[16, 17]]])
    hits = g.find_edge_triangle_intersections(pos, edges, t)
    assert hits.shape == (1, 2) and hits[0, 0] == 33
    with pytest.raises(Exception, match="vertex"):
        g.find_edge_triangle_intersections(pos, [[0, 99]], t)
    # Broad phase against brute force on a crumpled random sheet.
    pos = v + RNG.uniform(-0.05, 0.05, v.shape)
    r = 0.05
    pt, ee = g.broad_phase(pos, e, t, inflation_radius=r)

    def box(ids):
        q = pos[ids]
        return q.min(axis=0) - r, q.max(axis=0) + r

    def overlap(a, b):
        return np.all(a[0] <= b[1]) and np.all(b[0] <= a[1])

    want_pt = {(p, k) for p in range(len(pos)) for k in range(len(t))
               if p not in t[k] and overlap(box([p]), box(t[k]))}
    want_ee = {(a, b) for a, b in itertools.combinations(range(len(e)), 2)
               if not set(e[a]) & set(e[b]) and overlap(box(e[a]), box(e[b]))}
    assert set(map(tuple, pt)) == want_pt
    assert set(map(tuple, ee)) == want_ee
    moved_pt, _ = g.broad_phase(pos, e, t, positions_t1=pos + [0, 0, 1.0])
    assert len(moved_pt) >= len(g.broad_phase(pos, e, t)[0])
    tv, tt = meshes.tet_grid([1, 1, 1], [1, 1, 1])
    assert g.find_surface_triangles(tt).shape == (12, 3)
    assert g.edges_from_tets(tt).shape[1] == 2

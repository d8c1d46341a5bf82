"""Your own energy from Python (issue 18): `starkrs.sym` and `Simulation.add_energy`.

Checked against analytic equilibria (a body hanging from user springs sags by M g / k), against
NumPy (the vector and matrix helpers), and for clear errors on bad input."""

import math

import numpy as np
import pytest

import starkrs
from starkrs import sym

G = 9.81


def spring_to_anchor(x, v, dt, p):
    """½ k ‖x − a‖² plus a damper ½ c dt ‖v‖² (Rayleigh dissipation in the velocity form)."""
    d = x[0] - p.anchor
    return 0.5 * p.k * sym.dot(d, d) + 0.5 * p.c * dt * v[0].norm_sq()


def test_deformable_nodes_hang_from_python_springs_by_m_g_over_k(settings):
    sim = starkrs.Simulation(settings)
    cube = sim.add_volume_grid("cube", [0.1, 0.1, 0.1], [2, 2, 2], starkrs.VolumeMaterial.soft_rubber())
    rest = sim.positions(cube)
    n = len(rest)
    k = 100.0
    h = sim.add_energy("tether", cube, None, spring_to_anchor, {"k": k, "c": 2.0, "anchor": rest})
    assert (h.nodes_per_element, h.num_elements, h.params) == (1, n, ["k", "c", "anchor"])
    sim.run(2.0)
    mass = 1000.0 * 0.1**3
    # Σ k (x_i − a_i) = M g: internal elastic forces cancel in the sum.
    sag = (rest - sim.positions(cube))[:, 2].mean()
    assert sag == pytest.approx(mass * G / (k * n), rel=1e-3)
    # Parameters change between steps: a stiffer tether halves the sag.
    sim.set_energy_params(h, {"k": 2 * k})
    assert sim.energy_params(h)["k"] == pytest.approx([2 * k] * n)
    sim.run(1.0)
    sag = (rest - sim.positions(cube))[:, 2].mean()
    assert sag == pytest.approx(mass * G / (2 * k * n), rel=1e-3)


def test_a_rigid_body_point_hangs_from_a_python_spring(settings):
    sim = starkrs.Simulation(settings)
    box = sim.add_rigid_body_with("box", starkrs.MassProperties.cuboid(2.0, [0.1, 0.1, 0.1]), [0.0, 0.0, 0.0])
    anchor = np.array([0.0, 0.0, 0.05])
    k = 400.0
    sim.add_energy("hook", [(box, [0.0, 0.0, 0.05])], [[0]], spring_to_anchor, {"k": k, "c": 20.0, "anchor": anchor})
    sim.run(3.0)
    # The hook point sits below the anchor by M g / k, straight under it (no torque at rest).
    assert sim.body_position(box)[2] + 0.05 == pytest.approx(anchor[2] - 2.0 * G / k, abs=1e-5)
    assert abs(sim.body_position(box)[0]) < 1e-9


def test_two_node_energy_between_deformable_and_rigid_nodes(settings):
    # A spring of rest length L between a rigid box's centre and one cube corner: one element
    # energy on a rigid-body point and a deformable node (the kinematic map).
    settings.gravity_m_s2 = [0.0, 0.0, 0.0]
    sim = starkrs.Simulation(settings)
    box = sim.add_rigid_body_with("box", starkrs.MassProperties.cuboid(1.0, [0.1, 0.1, 0.1]), [0.0, 0.0, 0.0])
    cube = sim.add_volume_grid("cube", [0.1, 0.1, 0.1], [1, 1, 1], starkrs.VolumeMaterial.soft_rubber())
    corner = cube.nodes.first  # node 0 of the cube

    def spring(x, v, dt, p):
        length = sym.norm(x[1] - x[0])
        return 0.5 * p.k * (length - p.rest_m) ** 2 + 0.5 * p.c * dt * (v[1] - v[0]).norm_sq()

    start = sim.positions(cube)[0]
    sim.add_energy("link", [(box, [0.0, 0.0, 0.0]), corner], [[0, 1]], spring, {"k": 50.0, "c": 5.0, "rest_m": 0.4})
    sim.run(3.0)
    gap = np.linalg.norm(sim.positions(cube)[0] - sim.body_position(box))
    assert gap == pytest.approx(0.4, rel=1e-3)
    assert np.linalg.norm(start) < 0.4  # it really stretched


def test_every_symbolic_operation_traces_compiles_and_steps(settings):
    sim = starkrs.Simulation(settings)
    cube = sim.add_volume_grid("cube", [0.1, 0.1, 0.1], [1, 1, 1], starkrs.VolumeMaterial.soft_rubber())

    def energy(x, v, dt, p):
        a, b, c, d = x[0], x[1], x[2], x[3]
        m = sym.Mat3.from_columns(b - a, c - a, d - a)
        j = sym.det(m)
        inv = sym.inverse(m)
        e = (inv @ (b - a)).norm() + sym.cross(b - a, c - a).dot(d - a) / j
        e = e + sym.log(sym.sqrt(1.0 + j * j)) + sym.exp(-v[0].norm_sq() * dt) + sym.pow(j, 2) + (1.0 + j * j) ** 2.5
        e = e + sym.max(j, 0.5) - sym.min(j, 0.5) + sym.select(j > p.limit, j - p.limit, 0.0) ** 3
        return p.k * (e + sym.sin(j) * sym.cos(j) + sym.atan2(j, 1.0) + abs(j - 1) + 2 ** j)

    elements = [[0, 1, 2, 4]]
    h = sim.add_energy("everything", cube, elements, energy, {"k": 1e-3, "limit": 2.0})
    trace_ms, diff_ms, compile_ms, from_disk = h.compile_info
    assert trace_ms >= 0 and compile_ms > 0 and isinstance(from_disk, bool)
    sim.run(0.1)
    assert np.isfinite(sim.positions(cube)).all()


def test_vector_and_matrix_helpers_match_numpy():
    # The helpers are generic: on floats they compute numbers, the same code that traces.
    rng = np.random.default_rng(0)
    for _ in range(5):
        a, b = rng.normal(size=3), rng.normal(size=3)
        m = rng.normal(size=(3, 3))
        va, vb = sym.Vec3(*a), sym.Vec3(*b)
        assert sym.dot(va, vb) == pytest.approx(a @ b)
        assert list(sym.cross(va, vb)) == pytest.approx(np.cross(a, b))
        assert sym.norm(va) == pytest.approx(np.linalg.norm(a))
        mm = sym.Mat3(m.tolist())
        assert sym.det(mm) == pytest.approx(np.linalg.det(m))
        inv = sym.inverse(mm)
        assert np.array([list(r) for r in inv.r]) == pytest.approx(np.linalg.inv(m))
        assert list(mm @ va) == pytest.approx(m @ a)
        assert sym.min(1.0, 2.0) == 1.0 and sym.max(1.0, 2.0) == 2.0
        assert sym.sqrt(4.0) == 2.0 and sym.log(math.e) == pytest.approx(1.0)


def test_the_same_energy_traced_twice_is_compiled_once(settings):
    sim = starkrs.Simulation(settings)
    cube = sim.add_volume_grid("cube", [0.1, 0.1, 0.1], [1, 1, 1], starkrs.VolumeMaterial.soft_rubber())
    params = {"k": 1.0, "c": 0.0, "anchor": [0.0, 0.0, 0.0]}
    first = sim.add_energy("a", cube, None, spring_to_anchor, params)
    again = sim.add_energy("b", cube, None, spring_to_anchor, params)
    # The memory cache hands back the same compiled kernel (with the timings of its one compile).
    assert again.compile_info[1:] == first.compile_info[1:]
    assert sim.energy_params(again)["anchor[2]"] == pytest.approx([0.0] * len(sim.positions(cube)))


def test_bad_energies_are_clear_errors(settings):
    sim = starkrs.Simulation(settings)
    cube = sim.add_volume_grid("cube", [0.1, 0.1, 0.1], [1, 1, 1], starkrs.VolumeMaterial.soft_rubber())
    ok = {"k": 1.0, "c": 0.0, "anchor": [0.0, 0.0, 0.0]}

    with pytest.raises(starkrs.StarkError, match="energy 'vec': the function must return a scalar"):
        sim.add_energy("vec", cube, None, lambda x, v, dt, p: x[0] * p.k, ok)
    with pytest.raises(starkrs.StarkError, match="energy 'none': the function must return a scalar"):
        sim.add_energy("none", cube, None, lambda x, v, dt, p: None, ok)
    with pytest.raises(starkrs.StarkError, match=r"energy 'far' refers to x\[1\], but its elements have 1 node"):
        sim.add_energy("far", cube, None, lambda x, v, dt, p: sym.norm(x[1] - x[0]), ok)
    with pytest.raises(starkrs.StarkError, match="energy 'idx': element 0 refers to node 9, but element_nodes has 9 entries"):
        sim.add_energy("idx", cube, [[0, 9]], lambda x, v, dt, p: sym.norm(x[1] - x[0]), ok)
    with pytest.raises(starkrs.StarkError, match="energy 'nan': parameter 'k' is NaN"):
        sim.add_energy("nan", cube, None, spring_to_anchor, dict(ok, k=float("nan")))
    with pytest.raises(starkrs.StarkError, match="energy 'q' has no parameter 'q'"):
        sim.add_energy("q", cube, None, lambda x, v, dt, p: p.q * x[0].x, ok)
    with pytest.raises(TypeError, match="no truth value"):
        sim.add_energy("if", cube, None, lambda x, v, dt, p: x[0].x if x[0].x > 0 else -x[0].x, ok)
    with pytest.raises(ValueError, match="user bug"):
        sim.add_energy("raises", cube, None, lambda x, v, dt, p: (_ for _ in ()).throw(ValueError("user bug")), ok)
    with pytest.raises(starkrs.StarkError, match="1 to 4 nodes"):
        sim.add_energy("big", cube, [[0, 1, 2, 3, 4]], lambda x, v, dt, p: x[0].x, ok)
    with pytest.raises(starkrs.StarkError, match="shape"):
        sim.add_energy("shape", cube, None, spring_to_anchor, dict(ok, anchor=[0.0, 1.0]))

    kept = []
    sim.add_energy("leak", cube, None, lambda x, v, dt, p: kept.append(x[0].x) or x[0].x * p.k, ok)
    with pytest.raises(starkrs.StarkError, match="outside the energy function"):
        kept[0] + 1.0

    with pytest.raises(starkrs.StarkError, match="cannot be called inside another energy"):
        sim.add_energy("outer", cube, None, lambda x, v, dt, p: sim.add_energy("inner", cube, None, spring_to_anchor, ok), ok)
    with pytest.raises(starkrs.StarkError, match="outside the energy function"):
        sim.add_energy("stale", cube, None, lambda x, v, dt, p: kept[0], ok)

    h = sim.add_energy("fine", cube, None, spring_to_anchor, ok)
    with pytest.raises(starkrs.StarkError, match="energy 'fine': parameter 'c' is NaN"):
        sim.set_energy_params(h, {"c": float("nan")})
    with pytest.raises(starkrs.StarkError, match="no parameter 'stiffness'"):
        sim.set_energy_params(h, {"stiffness": 1.0})
    other = starkrs.Simulation(settings)
    with pytest.raises(starkrs.InvalidHandleError):
        other.set_energy_params(h, {"k": 1.0})
    # Nothing above broke the simulation.
    sim.run(0.05)
    assert np.isfinite(sim.positions(cube)).all()

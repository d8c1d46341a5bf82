"""Bad input raises Python exceptions with the library's message; nothing crashes."""

import numpy as np
import pytest

import starkrs


def test_nan_and_out_of_range_parameters(settings):
    sim = starkrs.Simulation(settings)
    m = starkrs.SurfaceMaterial.cotton_fabric()
    m.strain.youngs_modulus = float("nan")
    with pytest.raises(starkrs.StarkError, match="youngs_modulus"):
        sim.add_surface_grid("a", [1, 1], [2, 2], m)
    m = starkrs.SurfaceMaterial.cotton_fabric()
    m.inertia.density = -1.0
    with pytest.raises(starkrs.StarkError, match="density"):
        sim.add_surface_grid("b", [1, 1], [2, 2], m)
    v = starkrs.VolumeMaterial.soft_rubber()
    v.strain.poissons_ratio = 0.5
    with pytest.raises(starkrs.StarkError, match="poissons_ratio"):
        sim.add_volume_grid("c", [1, 1, 1], [1, 1, 1], v)
    cloth = sim.add_surface_grid("cloth", [1, 1], [2, 2], starkrs.SurfaceMaterial.cotton_fabric())
    with pytest.raises(starkrs.StarkError, match="stiffness"):
        sim.prescribe_in_box(cloth, [0.5, 0.5, 0], [0.01] * 3, starkrs.PrescribedParams(stiffness=float("nan")))
    with pytest.raises(starkrs.StarkError):
        sim.set_transform_deg(sim.prescribe_nodes(cloth, [0]), [0, 0, 0], float("nan"), [0, 0, 1])
    with pytest.raises(starkrs.StarkError, match="finite"):
        sim.gravity = [0.0, float("inf"), 0.0]
    with pytest.raises(starkrs.StarkError, match="non-finite"):
        sim.add_nodes("nan", [[0.0, float("nan"), 0.0]])


def test_bad_meshes(settings):
    sim = starkrs.Simulation(settings)
    cotton = starkrs.SurfaceMaterial.cotton_fabric()
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=float)
    with pytest.raises(starkrs.StarkError, match="refers to node 3"):
        sim.add_surface("a", v, [[0, 1, 3]], cotton)
    with pytest.raises(starkrs.StarkError, match="negative"):
        sim.add_surface("b", v, [[0, 1, -1]], cotton)
    with pytest.raises(ValueError, match=r"\(m, 3\)"):
        sim.add_surface("c", v, [[0, 1]], cotton)
    with pytest.raises(ValueError, match=r"\(n, 3\)"):
        sim.add_surface("d", v[:, :2], [[0, 1, 2]], cotton)
    with pytest.raises(starkrs.StarkError):
        sim.add_surface("e", np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0]], float), [[0, 1, 2]], cotton)
    with pytest.raises(starkrs.StarkError, match="already used"):
        sim.add_surface_grid("f", [1, 1], [1, 1], cotton)
        sim.add_surface_grid("f", [1, 1], [1, 1], cotton)
    with pytest.raises(starkrs.StarkError):
        sim.add_surface_grid("g", [1, 1], [0, 1], cotton)
    with pytest.raises(ValueError):
        sim.add_surface("h", "not an array", [[0, 1, 2]], cotton)


def test_handles_of_another_simulation(settings):
    a, b = starkrs.Simulation(settings), starkrs.Simulation(settings)
    cloth = a.add_surface_grid("cloth", [1, 1], [2, 2], starkrs.SurfaceMaterial.cotton_fabric())
    b.add_surface_grid("cloth", [1, 1], [2, 2], starkrs.SurfaceMaterial.cotton_fabric())
    with pytest.raises(starkrs.InvalidHandleError):
        b.positions(cloth)
    with pytest.raises(starkrs.InvalidHandleError):
        b.params(cloth.strain)
    body = a.add_rigid_body("box", 1.0, np.eye(3))
    with pytest.raises(starkrs.InvalidHandleError):
        b.body_position(body)
    with pytest.raises(TypeError):
        a.positions(42)


def test_bad_rotations_and_vectors(settings):
    sim = starkrs.Simulation(settings)
    with pytest.raises(starkrs.StarkError, match="not a rotation"):
        sim.add_rigid_body("a", 1.0, np.eye(3), [0, 0, 0], np.diag([1.0, 1.0, -1.0]))
    with pytest.raises(starkrs.StarkError):
        sim.add_rigid_body("b", 1.0, np.eye(3), [0, 0, 0], [0, 0, 0, 0])
    with pytest.raises(ValueError):
        sim.add_rigid_body("c", 1.0, np.eye(3), [0, 0])
    with pytest.raises(starkrs.StarkError, match="positive definite"):
        sim.add_rigid_body("d", 1.0, -np.eye(3))
    with pytest.raises(starkrs.StarkError, match="mass"):
        sim.add_rigid_body("e", float("nan"), np.eye(3))


def test_initially_intersecting_objects_and_failed_steps(settings):
    settings.contact.default_thickness_m = 0.001
    sim = starkrs.Simulation(settings)
    sim.add_surface_grid("a", [1, 1], [2, 2], starkrs.SurfaceMaterial.cotton_fabric())
    v, t = starkrs.meshes.box_mesh([0.2, 0.2, 0.2])
    sim.add_prescribed_surface("box", v, t, 0.001)
    with pytest.raises(starkrs.StarkError, match="intersecting"):
        sim.step()
    s = starkrs.Settings()
    s.output.frames = False
    s.output.step_log = False
    s.newton.max_iterations = 1
    s.adaptive_time_step = False
    sim = starkrs.Simulation(s)
    sim.add_volume_grid("block", [0.1, 0.1, 0.1], [2, 2, 2], starkrs.VolumeMaterial.soft_rubber())
    with pytest.raises(starkrs.StepFailedError):
        sim.run(0.5)

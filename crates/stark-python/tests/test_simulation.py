"""The Simulation class: objects, NumPy round trips, handles and their parameters."""

import os

import numpy as np
import pytest

import starkrs
from starkrs import meshes


def test_step_and_run_report(hanging_cloth):
    sim, cloth, pin = hanging_cloth
    report = sim.step()
    assert report["step"] == 0 and report["newton_iterations"] >= 1
    assert report["residual_n"] < 1e-6
    assert sim.time == pytest.approx(1 / 30) and sim.dt == pytest.approx(1 / 30)
    summary = sim.run(2 / 30)
    assert summary["steps"] == 3 and sim.time == pytest.approx(0.1)
    assert sim.summary()["steps"] == 3
    assert sim.run_one_step()["step"] == 3
    x = sim.positions(cloth)
    assert x.shape == (81, 3) and x.dtype == np.float64
    assert x[:, 2].min() < -0.01  # it falls
    assert sim.max_violation(pin) < 1e-3


def test_numpy_round_trips(hanging_cloth):
    sim, cloth, _ = hanging_cloth
    x = sim.positions(cloth)
    np.testing.assert_array_equal(x, sim.rest_positions(cloth.nodes))
    moved = x + np.array([0.0, 0.0, 0.25])
    sim.set_positions(cloth, moved)
    np.testing.assert_array_equal(sim.positions(cloth), moved)
    v = np.random.default_rng(0).normal(size=(81, 3))
    sim.set_velocities(cloth, v)
    np.testing.assert_array_equal(sim.velocities(cloth), v)
    sim.set_velocities(cloth, [0.0, 1.0, 0.0])
    np.testing.assert_array_equal(sim.velocities(cloth), np.tile([0.0, 1.0, 0.0], (81, 1)))
    sim.set_velocity(cloth, np.zeros(3))
    assert not sim.velocities(cloth).any()
    f = np.arange(243, dtype=float).reshape(81, 3)
    sim.set_forces(cloth, f)
    np.testing.assert_array_equal(sim.forces(cloth), f)
    sim.set_accelerations(cloth, [0.0, 0.0, 1.0])
    # Lists and integer arrays are converted.
    sim.set_positions(cloth, moved.tolist())
    np.testing.assert_array_equal(sim.positions(cloth), moved)
    # Returned arrays are copies.
    y = sim.positions(cloth)
    y[:] = 0
    assert sim.positions(cloth).any()
    m = sim.masses(cloth)
    assert m.shape == (81,) and m.sum() == pytest.approx(0.2)
    assert sim.mass(cloth) == pytest.approx(0.2)
    with pytest.raises(starkrs.StarkError, match="81 nodes"):
        sim.set_positions(cloth, np.zeros((5, 3)))
    with pytest.raises(ValueError):
        sim.set_positions(cloth, np.zeros((81, 2)))


def test_objects_and_their_handles(settings):
    sim = starkrs.Simulation(settings)
    v, t = meshes.triangle_grid([0.5, 0.5], [4, 4])
    surf = sim.add_surface("sheet", v, t, starkrs.SurfaceMaterial.cotton_fabric())
    assert isinstance(surf.bending, starkrs.FlatBendingHandle) and surf.contact is None
    vol = sim.add_volume_grid("block", [0.2, 0.2, 0.2], [2, 2, 2], starkrs.VolumeMaterial.soft_rubber())
    vv, tt = meshes.tet_grid([0.1, 0.1, 0.1], [1, 1, 1], center=[0.0, 0.0, 1.0])
    vol2 = sim.add_volume("cube", vv, tt, starkrs.VolumeMaterial.soft_rubber())
    line = sim.add_line_segments("rope", [0, 0, 2], [1, 0, 2], 10, starkrs.LineMaterial.elastic_rubber_band())
    lv, ls = meshes.segment_line([0, 0, 3], [1, 0, 3], 4)
    line2 = sim.add_line("rope2", lv, ls, starkrs.LineMaterial.elastic_rubber_band())
    nodes = sim.add_nodes("points", np.zeros((2, 3)))
    assert len(nodes) == 2 and sim.node_set("points") == nodes
    assert sim.node_set_labels() == ["sheet", "block", "cube", "rope", "rope2", "points"]
    assert (len(vol.nodes), len(line.nodes), len(line2.nodes)) == (35, 11, 5)
    assert vol2.label == "cube" and sim.num_nodes == 25 + 35 + 9 + 11 + 5 + 2
    # Parameters by handle: read, change, write back; checked.
    for handle, cls in [
        (surf.inertia, starkrs.InertiaParams),
        (surf.strain, starkrs.TriangleStrainParams),
        (surf.bending, starkrs.FlatBendingParams),
        (vol.strain, starkrs.TetStrainParams),
        (line.strain, starkrs.SegmentStrainParams),
    ]:
        p = sim.params(handle)
        assert isinstance(p, cls)
        sim.set_params(handle, p)
        assert sim.params(handle) == p
    p = sim.params(surf.strain)
    p.inflation_pa = 10.0
    sim.set_params(surf.strain, p)
    assert sim.params(surf.strain).inflation_pa == 10.0
    p.poissons_ratio = 0.7
    with pytest.raises(starkrs.StarkError, match="poissons_ratio"):
        sim.set_params(surf.strain, p)
    with pytest.raises(TypeError):
        sim.set_params(surf.strain, starkrs.InertiaParams())
    with pytest.raises(TypeError):
        sim.params("cloth")
    m = starkrs.SurfaceMaterial()
    m.bending = starkrs.DihedralBendingParams()
    shell = sim.add_surface_grid("shell", [1, 1], [2, 2], m)
    assert isinstance(shell.bending, starkrs.DihedralBendingHandle)
    assert isinstance(sim.params(shell.bending), starkrs.DihedralBendingParams)
    assert sim.count_inverted_tets() == 0
    sim.step()


def test_prescribed_positions(hanging_cloth):
    sim, cloth, pin = hanging_cloth
    assert sim.prescribed_nodes(pin) == [80]
    np.testing.assert_array_equal(sim.targets(pin), [[0.5, 0.5, 0.0]])
    sim.set_transform(pin, [0.0, 0.0, 0.1])
    np.testing.assert_allclose(sim.targets(pin), [[0.5, 0.5, 0.1]])
    sim.set_transform(pin, [0.0, 0.0, 0.0], np.diag([-1.0, -1.0, 1.0]))
    np.testing.assert_allclose(sim.targets(pin), [[-0.5, -0.5, 0.0]], atol=1e-15)
    sim.set_transform(pin, [0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0])  # quaternion (w, x, y, z): 180° about z
    np.testing.assert_allclose(sim.targets(pin), [[-0.5, -0.5, 0.0]], atol=1e-15)
    sim.set_transform_deg(pin, [0.0, 0.0, 0.0], 90.0, [0, 0, 1])
    np.testing.assert_allclose(sim.targets(pin), [[-0.5, 0.5, 0.0]], atol=1e-15)
    sim.set_target(pin, 0, [0.1, 0.2, 0.3])
    np.testing.assert_array_equal(sim.targets(pin), [[0.1, 0.2, 0.3]])
    params = sim.params(pin)
    assert params.stiffness == 1e6
    edge = sim.prescribe_nodes(cloth, [0, 1, 2])
    assert sim.prescribed_nodes(edge) == [0, 1, 2]
    outside = sim.prescribe_outside_box(cloth, [0, 0, 0], [0.9, 0.9, 1.0])
    assert len(sim.prescribed_nodes(outside)) == 32


def test_attachments(settings):
    sim = starkrs.Simulation(settings)
    a = sim.add_surface_grid("a", [1, 1], [2, 2], starkrs.SurfaceMaterial.cotton_fabric())
    b = sim.add_surface_grid("b", [1, 1], [2, 2], starkrs.SurfaceMaterial.cotton_fabric())
    sim.set_positions(b, sim.positions(b) + [0.0, 0.0, 0.01])
    pp = sim.add_attachment_point_point("pp", a, [0, 1], b, [0, 1], starkrs.AttachmentParams(stiffness=1e5))
    pe = sim.add_attachment_point_edge("pe", a, [4], b, [[3, 4]], [0.5])
    pt = sim.add_attachment_point_triangle("pt", a, [8], b, [[6, 7, 8]], [[0.2, 0.3, 0.5]])
    assert (pp.kind, pe.kind, pt.kind) == ("point_point", "point_edge", "point_triangle")
    assert sim.attachment_gap(pp) == pytest.approx(0.01)
    sim.run(0.2)
    assert sim.attachment_gap(pp) < 0.005
    with pytest.raises(starkrs.StarkError, match="sum to 1"):
        sim.add_attachment_point_triangle("bad", a, [0], b, [[0, 1, 2]], [[0.2, 0.2, 0.2]])


def test_outputs(tmp_path):
    s = starkrs.Settings(name="out")
    s.output.directory = str(tmp_path)
    s.output.fps = 30.0
    sim = starkrs.Simulation(s)
    sim.add_surface_grid("cloth", [1, 1], [2, 2], starkrs.SurfaceMaterial.cotton_fabric())
    sim.run(2 / 30)
    files = sorted(os.listdir(tmp_path))
    assert "out.steps.jsonl" in files
    assert [f for f in files if f.endswith(".vtu")] == [f"out_cloth_0000{i}.vtu" for i in range(3)]
    assert "out.pvd" in files
    assert sim.summary()["frames"] == 3
    written = sim.write_frame()
    assert written and written[0].endswith("out_cloth_00003.vtu")
    s2 = starkrs.Settings(name="quiet")
    s2.output.directory = str(tmp_path / "quiet")
    s2.output.frames = False
    s2.output.step_log = False
    sim2 = starkrs.Simulation(s2)
    sim2.add_surface_grid("cloth", [1, 1], [2, 2], starkrs.SurfaceMaterial.cotton_fabric())
    sim2.step()
    assert not (tmp_path / "quiet").exists()


def test_gravity_and_time_properties(hanging_cloth):
    sim, cloth, _ = hanging_cloth
    np.testing.assert_array_equal(sim.gravity, [0.0, 0.0, -9.81])
    sim.gravity = [0.0, 0.0, 0.0]
    sim.set_velocity(cloth, [0.0, 0.0, 0.0])
    sim.step()
    np.testing.assert_allclose(sim.velocities(cloth), 0.0, atol=1e-9)
    assert "Simulation('simulation'" in repr(sim)


def test_state_check_finds_crossing_sheets(settings):
    settings.contact.default_thickness_m = 1e-3
    sim = starkrs.Simulation(settings)
    v, t = meshes.triangle_grid([0.5, 0.5], [4, 4])
    sim.add_surface("flat", v, t, starkrs.SurfaceMaterial.cotton_fabric())
    assert sim.state_check() == {"intersections": [], "inverted_tets": 0}
    # The same sheet turned upright (y ↔ z) through the first one.
    upright = np.asarray(v)[:, [0, 2, 1]]
    sim.add_surface("upright", upright, t, starkrs.SurfaceMaterial.cotton_fabric())
    c = sim.state_check()
    assert len(c["intersections"]) > 0 and c["inverted_tets"] == 0
    assert "'flat'" in c["intersections"][0] and "'upright'" in c["intersections"][0], c["intersections"][0]

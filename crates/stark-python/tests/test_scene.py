"""Scene files and built-in scenes; a scene built in Python equals the same scene file."""

import numpy as np
import pytest

import starkrs
from starkrs import meshes

from conftest import REPO


def cloth_on_sphere_in_python(tmp_path):
    """scenes/cloth_on_sphere.toml, written with the Python API."""
    s = starkrs.Settings(name="cloth_on_sphere")
    s.contact.default_thickness_m = 0.002
    s.newton.residual_tolerance_n = 2.9999999999999997e-5
    s.newton.step_tolerance_m_s = 1e-3
    s.output.directory = str(tmp_path)
    s.output.frames = False
    s.output.step_log = False
    sim = starkrs.Simulation(s)
    cotton = starkrs.SurfaceMaterial.cotton_fabric()
    cotton.contact_thickness_m = 0.002
    cloth = sim.add_surface_grid("cloth", [1.0, 1.0], [32, 32], cotton)
    v, t = meshes.sphere_mesh(0.25, 3)
    sphere = sim.add_prescribed_surface("sphere", v + [0.0, 0.0, -0.3], t, 0.002, 1e6)
    sim.set_friction(cloth, sphere, 0.5)
    return sim, cloth, sphere


def test_python_scene_matches_the_scene_file(tmp_path):
    scene = starkrs.load_scene(REPO / "scenes" / "cloth_on_sphere.toml", output_directory=str(tmp_path),
                               frames=False, step_log=False)
    assert scene.name == "cloth_on_sphere" and scene.duration_s == 3.0
    assert set(scene.objects) == {"cloth", "sphere"}
    file_sim = scene.simulation
    py_sim, cloth, sphere = cloth_on_sphere_in_python(tmp_path)
    assert file_sim.settings == py_sim.settings
    file_cloth = scene.objects["cloth"]
    assert isinstance(file_cloth, starkrs.Surface) and isinstance(scene.objects["sphere"], starkrs.Obstacle)
    assert file_sim.friction(file_cloth, scene.objects["sphere"]) == 0.5
    np.testing.assert_array_equal(file_sim.positions(scene.objects["sphere"]), py_sim.positions(sphere))
    for _ in range(5):
        file_sim.step()
        py_sim.step()
    a, b = file_sim.positions(file_cloth), py_sim.positions(cloth)
    assert np.abs(a - b).max() <= 1e-12
    assert a[:, 2].min() < -0.04  # the cloth reached the sphere's top
    assert file_sim.contact_stats()["active_pairs"] > 0
    assert file_sim.find_intersections() == []


def test_scene_file_errors(tmp_path):
    with pytest.raises(starkrs.SceneError, match="cannot read the scene file"):
        starkrs.load_scene(tmp_path / "missing.toml")
    text = (REPO / "scenes" / "cloth_on_sphere.toml").read_text().replace("quads = [32, 32]", "quadz = [32, 32]")
    (tmp_path / "typo.toml").write_text(text)
    with pytest.raises(starkrs.SceneError, match=r"typo\.toml:\d+:\d+: .*quadz"):
        starkrs.load_scene(tmp_path / "typo.toml")
    assert issubclass(starkrs.SceneError, starkrs.StarkError)


def test_parse_scene_text_and_json(tmp_path):
    toml = """
duration_s = 0.1
[settings]
output.frames = false
output.step_log = false
[[surface]]
name = "cloth"
grid = { size_m = [1.0, 1.0], quads = [4, 4] }
material = "cotton_fabric"
[[prescribed]]
object = "cloth"
inside_box = { center_m = [0.5, 0.5, 0.0], size_m = [0.01, 0.01, 0.01] }
stiffness = 1e6
motion = { velocity_m_s = [0.0, 0.0, 1.0] }
"""
    scene = starkrs.parse_scene(toml, "doc.toml", output_directory=str(tmp_path))
    assert scene.name == "doc" and len(scene.prescribed) == 1
    entry = scene.prescribed[0]
    assert entry["object"] == "cloth" and entry["nodes"] == 1
    summary = scene.run()
    assert summary["steps"] == 3
    np.testing.assert_allclose(scene.simulation.targets(entry["handle"]), [[0.5, 0.5, 0.1]], atol=1e-12)
    js = '{"duration_s": 0.1, "settings": {"output": {"frames": false, "step_log": false}}, ' \
         '"surface": [{"name": "c", "grid": {"size_m": [1, 1], "quads": [2, 2]}, "material": "cotton_fabric"}]}'
    assert set(starkrs.parse_scene(js, "s.json").objects) == {"c"}


def test_builtin_scenes(settings):
    names = [s["name"] for s in starkrs.builtin_scenes()]
    assert {"default", "cloth_on_sphere", "twisting_cloth", "soft_cubes"} <= set(names)
    scene = starkrs.builtin_scene("twisting_cloth", settings)
    assert scene.name == "twisting_cloth" and scene.duration_s > 5
    scene.simulation.step()  # Rust time events of the scene run
    with pytest.raises(starkrs.StarkError, match="unknown scene"):
        starkrs.builtin_scene("nope")

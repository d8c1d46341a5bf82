"""A floor fixed in the world (`add_fixed_surface`): it never moves and carries a resting ball."""

import numpy as np
import pytest
import starkrs


def test_a_fixed_floor_stays_put_and_carries_a_ball(tmp_path):
    settings = starkrs.Settings(name="fixed_floor")
    settings.time_step_s = 0.01
    settings.output.directory = str(tmp_path)
    settings.output.frames = False
    settings.contact.default_thickness_m = 5e-4
    sim = starkrs.Simulation(settings)
    floor = sim.add_fixed_surface(
        "floor", [[-0.1, -0.1, 0], [0.2, -0.1, 0], [0.2, 0.1, 0], [-0.1, 0.1, 0]], [[0, 1, 2], [0, 2, 3]], 5e-4)
    assert repr(floor) == "FixedSurface('floor', nodes=4)"
    ball = sim.add_sphere("ball", 0.004, 0.005, 2, [0.03, 0.0, 0.01])
    sim.set_friction(ball.mesh, floor.contact, 0.5)
    start = sim.positions(floor).copy()
    summary = sim.run(0.5)
    assert sim.positions(floor).tobytes() == start.tobytes()
    assert np.all(sim.velocities(floor) == 0.0)
    # Only the ball's six velocities are unknowns.
    assert summary["unknowns"] == 6
    # At rest on the floor: its centre a radius (and the contact gap, under d̂ = 1 mm) above it.
    assert sim.body_position(ball)[2] == pytest.approx(0.005, abs=1e-3)
    assert np.linalg.norm(sim.body_velocity(ball)) < 1e-4
    assert sim.find_intersections() == []


def test_a_scene_files_fixed_obstacle_is_a_fixed_surface(tmp_path):
    path = tmp_path / "fixed.toml"
    path.write_text("""
duration_s = 0.05
[settings]
contact.default_thickness_m = 0.001
output.frames = false
[[obstacle]]
name = "floor"
grid = { size_m = [1.0, 1.0], quads = [1, 1] }
fixed = true
""")
    scene = starkrs.load_scene(str(path), output_directory=str(tmp_path / "out"))
    floor = scene.objects["floor"]
    assert isinstance(floor, starkrs.FixedSurface)
    sim = scene.simulation
    start = sim.positions(floor).copy()
    sim.run(0.05)
    assert sim.positions(floor).tobytes() == start.tobytes()

"""Objects added during a run from Python (`add_spawn`), and a resumed run that replays them."""

import numpy as np
import pytest
import starkrs


def build(out):
    settings = starkrs.Settings(name="spawn_balls")
    settings.time_step_s = 0.01
    settings.output.directory = str(out)
    settings.output.frames = False
    settings.contact.default_thickness_m = 5e-4
    sim = starkrs.Simulation(settings)
    floor = sim.add_prescribed_surface(
        "floor", [[-0.1, -0.1, 0], [0.2, -0.1, 0], [0.2, 0.1, 0], [-0.1, 0.1, 0]], [[0, 1, 2], [0, 2, 3]], 5e-4, 1e7)

    def spawn(k):
        def action(sim):
            ball = sim.add_sphere(f"ball{k}", 0.004, 0.005, 2, [0.03 * k, 0.0, 0.05])
            sim.set_friction(ball.mesh, sim.contact_object("floor"), 0.5)
        return action

    for k, t in enumerate([0.1, 0.2]):
        sim.add_spawn(t, f"ball {k}", spawn(k))
    return sim


def test_spawned_balls_appear_at_their_time_and_resume_bit_identically(tmp_path):
    whole = build(tmp_path / "whole")
    whole.run(0.15)
    assert whole.num_rigid_bodies == 1
    assert whole.spawns() == [(0.1, "ball 0", True), (0.2, "ball 1", False)]
    whole.run(0.1)
    assert whole.num_rigid_bodies == 2
    whole.save_checkpoint(tmp_path / "a.ckpt")
    whole.run(0.3)
    ball = whole.rigid_body("ball0")
    assert whole.body_position(ball)[2] == pytest.approx(0.005, abs=1e-3)

    resumed = build(tmp_path / "resumed")
    resumed.restore_checkpoint(tmp_path / "a.ckpt")
    assert resumed.num_rigid_bodies == 2
    resumed.run(0.3)
    for label in ["ball0", "ball1"]:
        a = whole.body_position(whole.rigid_body(label))
        b = resumed.body_position(resumed.rigid_body(label))
        assert np.asarray(a).tobytes() == np.asarray(b).tobytes()
    assert whole.find_intersections() == []


def test_a_failing_spawn_stops_the_run_naming_it(tmp_path):
    sim = build(tmp_path)

    def broken(sim):
        raise ValueError("no such ball")

    sim.add_spawn(0.05, "broken", broken)
    with pytest.raises(ValueError, match="no such ball"):
        sim.run(0.1)
    with pytest.raises(TypeError):
        sim.add_spawn(0.3, "not callable", 3)

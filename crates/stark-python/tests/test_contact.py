"""Contact objects: thickness, friction per pair, collisions on and off."""

import pytest

import starkrs
from starkrs import meshes


def test_contact_settings_per_pair(settings):
    settings.contact.default_thickness_m = 0.001
    sim = starkrs.Simulation(settings)
    cloth = sim.add_surface_grid("cloth", [1, 1], [4, 4], starkrs.SurfaceMaterial.cotton_fabric())
    v, t = meshes.sphere_mesh(0.2, 1)
    ball = sim.add_prescribed_surface("ball", v + [0, 0, -0.3], t, 0.003)
    assert sim.contact_objects() == [cloth.contact, ball.contact]
    assert sim.contact_object("ball") == ball.contact and sim.contact_object("nope") is None
    assert sim.contact_label(ball) == "ball"
    assert (sim.contact_thickness(cloth), sim.contact_thickness(ball)) == (0.001, 0.003)
    sim.set_contact_thickness(cloth, 0.002)
    assert sim.contact_thickness(cloth.contact) == 0.002
    assert sim.friction(cloth, ball) == 0.0
    sim.set_friction(cloth, ball, 0.4)
    assert sim.friction(ball, cloth) == 0.4
    sim.set_friction(cloth, cloth, 0.1)
    with pytest.raises(starkrs.StarkError, match="friction"):
        sim.set_friction(cloth, ball, -1.0)
    with pytest.raises(starkrs.StarkError, match="thickness"):
        sim.set_contact_thickness(cloth, float("nan"))
    sim.disable_collision(cloth, ball)
    sim.set_collision(cloth, cloth, False)
    sim.set_collision(cloth, cloth, True)
    assert sim.contact_stiffness == 0.0
    sim.run(0.4)  # without collisions the cloth falls through the ball
    assert sim.positions(cloth)[:, 2].min() < -0.5
    assert sim.contact_stiffness > 0.0
    assert set(sim.contact_stats()) >= {"active_pairs", "min_distance_m", "stiffness"}
    no_contact = starkrs.Simulation()
    plain = no_contact.add_surface_grid("plain", [1, 1], [1, 1], starkrs.SurfaceMaterial.cotton_fabric())
    with pytest.raises(TypeError, match="contact"):
        no_contact.set_friction(plain, plain, 0.1)

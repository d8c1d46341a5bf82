"""Rigid bodies: mass properties, state getters and setters, collision meshes, free fall."""

import numpy as np
import pytest

import starkrs
from starkrs import meshes


def test_mass_properties():
    box = starkrs.MassProperties.cuboid(2.0, [1.0, 2.0, 3.0])
    assert box.mass_kg == 2.0
    np.testing.assert_allclose(np.diag(box.inertia_kg_m2), 2.0 / 12 * np.array([13.0, 10.0, 5.0]))
    v, t = meshes.box_mesh([1.0, 2.0, 3.0])
    mesh = starkrs.MassProperties.from_mesh(v + [1.0, 0.0, 0.0], t, 1000.0)
    assert mesh.mass_kg == pytest.approx(6000.0)
    np.testing.assert_allclose(mesh.center_of_mass_m, [1.0, 0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(mesh.inertia_kg_m2, starkrs.MassProperties.cuboid(6000.0, [1, 2, 3]).inertia_kg_m2)
    assert starkrs.MassProperties.sphere(1.0, 0.5).inertia_kg_m2[0, 0] == pytest.approx(0.1)
    assert starkrs.MassProperties.cylinder(1.0, 0.5, 1.0).inertia_kg_m2[2, 2] == pytest.approx(0.125)
    assert starkrs.MassProperties.torus(1.0, 1.0, 0.1).mass_kg == 1.0
    custom = starkrs.MassProperties(3.0, [0, 0, 0], np.eye(3))
    assert custom.mass_kg == 3.0
    with pytest.raises(starkrs.StarkError, match="closed"):
        starkrs.MassProperties.from_mesh(v, t[:, ::-1], 1.0)


def test_free_fall_matches_backward_euler(settings):
    sim = starkrs.Simulation(settings)
    body = sim.add_rigid_body_with("ball", starkrs.MassProperties.sphere(1.0, 0.1), [0.0, 0.0, 1.0])
    assert sim.num_rigid_bodies == 1 and sim.rigid_body("ball") == body and sim.rigid_bodies() == [body]
    n, dt, g = 6, 1 / 30, 9.81
    for _ in range(n):
        sim.step()
    # Backward Euler: v_k = -g k dt, z_n = 1 - g dt² n(n+1)/2.
    assert sim.body_velocity(body)[2] == pytest.approx(-g * n * dt, rel=1e-9)
    assert sim.body_position(body)[2] == pytest.approx(1.0 - g * dt * dt * n * (n + 1) / 2, rel=1e-9)
    np.testing.assert_allclose(sim.body_orientation(body), [1, 0, 0, 0])
    np.testing.assert_allclose(sim.body_rotation(body), np.eye(3))


def test_state_setters_and_frames(settings):
    settings.gravity_m_s2 = [0.0, 0.0, 0.0]
    sim = starkrs.Simulation(settings)
    inertia = np.diag([1.0, 2.0, 3.0])
    body = sim.add_rigid_body("box", 2.0, inertia, [1.0, 2.0, 3.0], [np.cos(np.pi / 4), 0, 0, np.sin(np.pi / 4)])
    assert sim.body_mass(body) == 2.0
    np.testing.assert_array_equal(sim.body_inertia(body), inertia)
    np.testing.assert_allclose(sim.body_point_to_world(body, [1.0, 0.0, 0.0]), [1.0, 3.0, 3.0], atol=1e-12)
    pts = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    world = sim.body_point_to_world(body, pts)
    assert world.shape == (2, 3)
    np.testing.assert_allclose(sim.body_point_to_local(body, world), pts, atol=1e-12)
    np.testing.assert_allclose(sim.body_direction_to_world(body, [1.0, 0.0, 0.0]), [0.0, 1.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(sim.body_direction_to_local(body, [0.0, 1.0, 0.0]), [1.0, 0.0, 0.0], atol=1e-12)
    sim.set_body_pose(body, [0.0, 0.0, 0.0], np.eye(3))
    np.testing.assert_array_equal(sim.body_position(body), [0.0, 0.0, 0.0])
    sim.set_body_velocity(body, [1.0, 0.0, 0.0])
    sim.set_body_angular_velocity(body, [0.0, 0.0, 2.0])
    np.testing.assert_allclose(sim.body_velocity_at(body, [1.0, 0.0, 0.0]), [1.0, 2.0, 0.0])
    np.testing.assert_allclose(sim.body_angular_momentum(body), [0.0, 0.0, 6.0])
    sim.set_body_force(body, [2.0, 0.0, 0.0])
    sim.set_body_torque(body, [0.0, 0.0, 0.0])
    sim.add_body_force_at(body, [0.0, 1.0, 0.0], [1.0, 0.0, 0.0])
    np.testing.assert_allclose(sim.body_force(body), [2.0, 1.0, 0.0])
    np.testing.assert_allclose(sim.body_torque(body), [0.0, 0.0, 1.0])
    sim.set_body_force(body, [0.0, 0.0, 0.0])
    sim.set_body_torque(body, [0.0, 0.0, 0.0])
    sim.set_body_acceleration(body, [0.0, 0.0, 0.0])
    sim.set_body_angular_acceleration(body, [0.0, 0.0, 0.0])
    p = sim.params(body)
    assert isinstance(p, starkrs.RigidBodyParams)
    p.linear_damping_1_s = -1.0
    with pytest.raises(starkrs.StarkError, match="linear_damping_1_s"):
        sim.set_params(body, p)
    sim.set_params(body, starkrs.RigidBodyParams(angular_damping_1_s=0.5))
    assert sim.params(body).angular_damping_1_s == 0.5
    sim.set_body_mass(body, 3.0, np.eye(3))
    assert sim.body_mass(body) == 3.0
    sim.set_params(body, starkrs.RigidBodyParams())
    sim.step()
    np.testing.assert_allclose(sim.body_velocity(body), [1.0, 0.0, 0.0], atol=1e-8)
    np.testing.assert_allclose(sim.body_angular_velocity(body), [0.0, 0.0, 2.0], atol=1e-8)


def test_box_falls_on_cloth_and_its_mesh_follows(settings):
    settings.contact.default_thickness_m = 0.002
    sim = starkrs.Simulation(settings)
    cloth = sim.add_surface_grid("cloth", [1, 1], [8, 8], starkrs.SurfaceMaterial.cotton_fabric())
    for x in (-0.5, 0.5):
        for y in (-0.5, 0.5):
            sim.prescribe_in_box(cloth, [x, y, 0], [1e-3] * 3, starkrs.PrescribedParams(stiffness=1e6))
    body = sim.add_rigid_body_with("box", starkrs.MassProperties.cuboid(0.1, [0.2] * 3), [0.0, 0.0, 0.15])
    v, t = meshes.box_mesh([0.2] * 3)
    mesh = sim.add_rigid_collision_mesh(body, v, t)
    assert mesh.body == body and len(mesh.nodes) == 8
    sim.set_friction(cloth, mesh, 0.5)
    assert sim.friction(mesh.contact, cloth.contact) == 0.5
    np.testing.assert_allclose(sim.rest_positions(mesh), v)
    with pytest.raises(starkrs.StarkError, match="rigid body"):
        sim.set_positions(mesh, v)
    sim.run(0.5)
    z = sim.body_position(body)[2]
    assert z < 0.0  # fell into the cloth, which sags under it
    assert sim.positions(cloth)[40, 2] < z - 0.1  # the cloth's centre stays below the box's bottom
    np.testing.assert_allclose(sim.positions(mesh), sim.body_point_to_world(mesh, v), atol=1e-12)
    assert sim.find_intersections() == []

"""`Simulation.add_joint`: every joint from one dict (a scene file's `[[joint]]` fields), the
same joint as the per-joint methods build, bit for bit; misspelt fields are named."""

import numpy as np
import pytest

import starkrs


def pendulum(settings, build):
    """A 0.2 m rod hinged at one end to the world, released from 30°, run 50 steps: its
    positions and orientations, as bits."""
    settings.time_step_s = 1e-2
    sim = starkrs.Simulation(settings)
    props = starkrs.MassProperties.cuboid(0.2, [0.2, 0.02, 0.02])
    c, s = np.cos(np.radians(30.0)), np.sin(np.radians(30.0))
    rod = sim.add_rigid_body_with("rod", props, [0.1 * c, 0.0, -0.1 * s])
    joint = build(sim, rod)
    history = []
    for _ in range(50):
        sim.step()
        history.append(np.concatenate([sim.body_position(rod), sim.body_orientation(rod)]))
    return joint, np.array(history)


def test_hinge_from_a_dict_equals_add_hinge_joint_bit_for_bit(settings):
    kind = {"type": "hinge", "point_m": np.zeros(3), "axis": [0.0, 1.0, 0.0]}
    j1, by_dict = pendulum(settings, lambda sim, rod: sim.add_joint("pivot", None, rod, kind))
    j2, by_method = pendulum(settings, lambda sim, rod: sim.add_hinge_joint("pivot", None, rod, [0, 0, 0], [0, 1, 0]))
    assert j1.has_coordinate and j2.has_coordinate
    assert np.array_equal(by_dict.view(np.uint64), by_method.view(np.uint64))
    # The rod swings (the comparison is not of a body at rest).
    assert np.ptp(by_dict[:, 0]) > 0.01


def test_motor_with_parameters_and_a_joint_spring_from_dicts(settings):
    settings.gravity_m_s2 = [0.0, 0.0, 0.0]
    settings.time_step_s = 1e-2
    sim = starkrs.Simulation(settings)
    wheel = sim.add_rigid_body_with("wheel", starkrs.MassProperties.cuboid(1.0, [0.1, 0.1, 0.1]), [0, 0, 0])
    params = starkrs.JointParams(stiffness=2e6)
    kind = {"type": "motor", "point_m": [0, 0, 0], "axis": [0, 0, 1], "target_velocity_deg_s": 90.0, "max_torque_n_m": 5.0}
    motor = sim.add_joint("motor", None, wheel, kind, params)
    assert motor.has_driver and motor.has_coordinate
    sim.run(0.5)
    # 90°/s reached against the wheel's inertia within the first steps, then held.
    assert sim.joint_state(motor).coordinate_rate == pytest.approx(np.radians(90.0), rel=1e-3)
    damper = sim.add_joint("damper", None, None, {"type": "joint_spring", "joint": "motor", "spring_stiffness": 0.0, "damping": 0.01})
    assert damper.label == "damper"


def test_misspelt_missing_and_unknown_fields_are_value_errors_naming_them(settings):
    sim = starkrs.Simulation(settings)
    rod = sim.add_rigid_body_with("rod", starkrs.MassProperties.cuboid(1.0, [0.2, 0.02, 0.02]), [0.1, 0, 0])
    with pytest.raises(ValueError, match=r"joint 'h': kind: unknown field `axs`, expected `point_m` or `axis`"):
        sim.add_joint("h", None, rod, {"type": "hinge", "point_m": [0, 0, 0], "axs": [0, 1, 0]})
    with pytest.raises(ValueError, match="missing field `axis`"):
        sim.add_joint("h", None, rod, {"type": "hinge", "point_m": [0, 0, 0]})
    with pytest.raises(ValueError, match="unknown variant `hing`"):
        sim.add_joint("h", None, rod, {"type": "hing"})
    # Values the library rejects name the field by the same name.
    with pytest.raises(starkrs.StarkError, match="`limit_deg` = 200"):
        sim.add_joint("c", None, rod, {"type": "ball_cone", "point_m": [0, 0, 0], "axis": [0, 0, 1], "limit_deg": 200})
    with pytest.raises(starkrs.StarkError, match="no joint is labelled 'nope'"):
        sim.add_joint("s", None, None, {"type": "joint_spring", "joint": "nope", "spring_stiffness": 1.0})

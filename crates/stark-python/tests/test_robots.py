"""Robots from URDF files through `Simulation.add_robot`: the public Franka hand in
../shared/data/robots, its fingers closed by a force-limited press given as an override dict."""

import pytest

import starkrs
from conftest import REPO

ROBOTS = REPO.parent / "shared" / "data" / "robots"
FRANKA = ROBOTS / "franka_description" / "urdf" / "franka_hand.urdf"


@pytest.mark.skipif(not FRANKA.exists(), reason="../shared/data/robots is not beside the project")
def test_franka_hand_loads_and_its_press_closes_the_mimicked_fingers(settings):
    settings.time_step_s = 2e-3
    settings.gravity_m_s2 = [0.0, 0.0, -9.81]
    sim = starkrs.Simulation(settings)
    hand = sim.add_robot(
        "franka",
        FRANKA,
        package_paths=[ROBOTS],
        fixed_base=True,
        joints={
            "fr3_finger_joint1": {"position": 0.03, "actuator": {"type": "press", "target_m_s": -0.05}},
            "fr3_finger_joint2": {"position": 0.03},
        },
    )
    assert hand.name == "franka"
    assert set(hand.joints) >= {"fr3_finger_joint1", "fr3_finger_joint2"}
    fingers = [hand.links["fr3_leftfinger"], hand.links["fr3_rightfinger"]]
    assert all(isinstance(f, starkrs.RigidBody) for f in fingers)
    assert fingers[0].label == "franka/fr3_leftfinger"
    press = hand.joints["fr3_finger_joint1"]
    for _ in range(25):
        sim.step()
    q1 = sim.joint_state(press).coordinate
    q2 = sim.joint_state(hand.joints["fr3_finger_joint2"]).coordinate
    # Closing at 5 cm/s for 0.05 s (a joint's coordinate counts from where it was made, here the
    # fingers' 30 mm start); the mimic keeps the other finger with it.
    assert q1 == pytest.approx(-0.05 * 0.05, abs=5e-4)
    assert q2 == pytest.approx(q1, abs=1e-5)


def test_add_robot_names_bad_overrides_and_missing_files(settings, tmp_path):
    sim = starkrs.Simulation(settings)
    with pytest.raises(starkrs.StarkError, match="joints"):
        sim.add_robot("r", FRANKA, package_paths=[ROBOTS], joints={"fr3_finger_joint1": {"positon": 0.1}})
    with pytest.raises(starkrs.StarkError, match="missing.urdf"):
        sim.add_robot("r", tmp_path / "missing.urdf")

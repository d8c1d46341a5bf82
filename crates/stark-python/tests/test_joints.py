"""Joints, motors and servos, rigid presets and deformable–rigid attachments from Python,
checked against analytic answers."""

import math

import numpy as np
import pytest

import starkrs
from starkrs import meshes

from conftest import REPO


def rod(sim, label, mass, length, centre):
    """A thin box along x with its centre of mass at `centre` (no contact)."""
    props = starkrs.MassProperties.cuboid(mass, [length, 0.02, 0.02])
    return sim.add_rigid_body_with(label, props, centre)


def test_hinge_pendulum_period(settings):
    # A 0.2 kg, 0.2 m rod hinged at one end, released 5° from the vertical: T = 2π√(I/(m g d))
    # with I about the hinge = m L²/3 (plus the small thickness term) and d = L/2.
    settings.time_step_s = 1e-3
    sim = starkrs.Simulation(settings)
    m, length, g = 0.2, 0.2, 9.81
    theta0 = math.radians(5.0)
    d = length / 2
    centre = [d * math.sin(theta0), 0.0, -d * math.cos(theta0)]
    phi = -(math.pi / 2 + theta0)  # about y: the body's +x points from the centre to the pivot
    rotation = [math.cos(phi / 2), 0.0, math.sin(phi / 2), 0.0]
    props = starkrs.MassProperties.cuboid(m, [length, 0.02, 0.02])
    body = sim.add_rigid_body_with("rod", props, centre, rotation)
    np.testing.assert_allclose(sim.body_point_to_world(body, [d, 0, 0]), [0, 0, 0], atol=1e-12)
    hinge = sim.add_hinge_joint("pivot", None, body, [0.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    assert isinstance(hinge, starkrs.Joint) and hinge.label == "pivot" and hinge.has_coordinate
    inertia = props.inertia_kg_m2[1, 1] + m * d * d
    period = 2 * math.pi * math.sqrt(inertia / (m * g * d))
    # Time the first two crossings of the vertical from +x to −x (a full period apart).
    crossings, previous = [], sim.body_position(body)[0]
    while len(crossings) < 2 and sim.time < 2.0:
        sim.step()
        x = sim.body_position(body)[0]
        if previous > 0.0 >= x:
            crossings.append(sim.time - sim.settings.time_step_s * x / (x - previous))
        previous = x
    assert len(crossings) == 2
    assert crossings[1] - crossings[0] == pytest.approx(period, rel=0.01)
    state = sim.joint_state(hinge)
    assert isinstance(state, starkrs.JointState)
    assert state.violation_m < 1e-3


def test_motor_lifts_then_stalls_at_its_max_torque(settings):
    # A 1 kg point-like arm 0.1 m from the motor axis needs up to m g r = 0.981 N·m.
    settings.time_step_s = 0.01
    sim = starkrs.Simulation(settings)
    arm = rod(sim, "arm", 1.0, 0.2, [0.1, 0.0, 0.0])
    motor = sim.add_motor("motor", None, arm, [0.0, 0.0, 0.0], [0.0, -1.0, 0.0], 1.0, 5.0)
    assert motor.has_driver
    sim.run(0.3)
    state = sim.joint_state(motor)
    assert state.coordinate_rate == pytest.approx(1.0, rel=5e-3)
    # The arm is lifted (turning about −y raises +x towards +z).
    assert sim.body_position(arm)[2] > 0.0
    # Now a cap below the gravity torque: it stalls, at exactly its max torque, and falls back.
    sim.set_joint_max_effort(motor, 0.2)
    sim.run(0.3)
    state = sim.joint_state(motor)
    assert state.driver_effort == pytest.approx(0.2, rel=1e-6)
    assert state.coordinate_rate < 0.0


def test_callback_changes_a_motor_target_mid_run(settings):
    # A free wheel (no gravity) on a motor: the target changes from 2 to −1 rad/s at t = 0.5 s,
    # from a time event calling back into Python, and the wheel follows.
    settings.gravity_m_s2 = [0.0, 0.0, 0.0]
    settings.time_step_s = 0.01
    sim = starkrs.Simulation(settings)
    wheel = sim.add_rigid_body_with("wheel", starkrs.MassProperties.cylinder(1.0, 0.1, 0.02), [0.0, 0.0, 0.0])
    motor = sim.add_motor("motor", None, wheel, [0.0, 0.0, 0.0], [0.0, 0.0, 1.0], 2.0, 10.0)
    changed_at = []

    def reverse(s, t):
        if not changed_at:
            changed_at.append(t)
            s.set_joint_target_velocity(motor, -1.0)

    sim.add_time_event(0.5, 10.0, reverse)
    rates = []
    sim.run(1.0, lambda s: rates.append((s.time, s.joint_state(motor).coordinate_rate)))
    assert changed_at and changed_at[0] == pytest.approx(0.5, abs=0.011)
    before = [w for t, w in rates if 0.3 < t < 0.49]
    after = [w for t, w in rates if t > 0.8]
    assert before and after
    assert np.allclose(before, 2.0, rtol=5e-3)
    assert np.allclose(after, -1.0, rtol=5e-3)
    np.testing.assert_allclose(sim.body_angular_velocity(wheel), [0.0, 0.0, -1.0], atol=5e-3)


def test_servo_reaches_and_holds_its_target(settings):
    settings.gravity_m_s2 = [0.0, 0.0, 0.0]
    settings.time_step_s = 0.01
    sim = starkrs.Simulation(settings)
    arm = rod(sim, "arm", 0.5, 0.2, [0.1, 0.0, 0.0])
    servo = sim.add_hinge_servo("servo", None, arm, [0, 0, 0], [0, 0, 1], 30.0, 2.0, 0.1)
    sim.run(1.5)
    assert math.degrees(sim.joint_state(servo).coordinate) == pytest.approx(30.0, abs=0.5)
    sim.set_servo_target(servo, -20.0)
    sim.run(1.5)
    assert math.degrees(sim.joint_state(servo).coordinate) == pytest.approx(-20.0, abs=0.5)
    press = sim.add_prismatic_servo(
        "slide", None, sim.add_box("slider", 1.0, [0.1] * 3, [0, 1, 0], thickness_m=1e-3).body, [0, 1, 0], [1, 0, 0], 0.05, 5.0, 0.1
    )
    sim.run(1.0)
    assert sim.joint_state(press).coordinate == pytest.approx(0.05, abs=5e-4)


def test_joints_are_listed_and_switched(settings):
    sim = starkrs.Simulation(settings)
    a = rod(sim, "a", 1.0, 0.2, [0.1, 0.0, 0.0])
    b = rod(sim, "b", 1.0, 0.2, [0.3, 0.0, 0.0])
    params = starkrs.JointParams(stiffness=1e7, tolerance_m=1e-4)
    ball = sim.add_ball_joint("ball", None, a, [0, 0, 0], params)
    hinge = sim.add_hinge_joint_with_limit("elbow", a, b, [0.2, 0, 0], [0, 1, 0], 45.0)
    spring = sim.add_spring("spring", None, b, [0.4, 0, 0.2], [0.4, 0, 0], 100.0, 1.0, (0.1, 0.3))
    assert [j.label for j in sim.joints()] == ["ball", "elbow", "spring"]
    assert sim.joint("elbow").label == "elbow" and sim.joint("nope") is None
    sim.set_joint_stiffness(ball, 2e7)
    sim.set_joint_tolerance(ball, 1e-4, 0.5)
    sim.set_spring(spring, 0.15, 2.0)
    sim.run(0.3)
    assert sim.joint_state(ball).violation_m < 1e-4
    assert sim.joint_state(hinge).coordinate is not None
    assert sim.joint_state(spring).driver_effort != 0.0
    # Off, the ball joint lets the chain fall.
    sim.set_joint_enabled(ball, False)
    z = sim.body_position(a)[2]
    sim.run(0.2)
    assert sim.body_position(a)[2] < z - 0.05
    # The other constructors take the same bodies and return joints.
    made = [
        sim.add_ball_joint_with_cone_limit("cone", a, b, [0.2, 0, 0], [1, 0, 0], 30.0),
        sim.add_point_on_axis_joint("poa", a, b, [0.2, 0, 0], [1, 0, 0]),
        sim.add_distance_joint("dist", a, b, [0.1, 0, 0], [0.3, 0, 0]),
        sim.add_distance_limits("limits", a, b, [0.1, 0, 0], [0.3, 0, 0], 0.1, 0.3),
        sim.add_direction_joint("dir", a, b, [0, 0, 1]),
        sim.add_angle_limit("angle", a, b, [0, 0, 1], 10.0),
        sim.add_attachment_joint("glue", a, b),
        sim.add_universal_joint("cardan", a, b, [0.2, 0, 0], [0, 1, 0], [0, 0, 1]),
        sim.add_slider_joint("slider", a, b, [0.2, 0, 0], [1, 0, 0]),
        sim.add_prismatic_joint("prismatic", a, b, [0.2, 0, 0], [1, 0, 0]),
        sim.add_prismatic_press("press", a, b, [0.2, 0, 0], [1, 0, 0], 0.1, 1.0),
        sim.add_angular_velocity_controller("wctl", a, b, [0, 0, 1], 0.0, 1.0),
        sim.add_linear_velocity_controller("vctl", a, b, [0.2, 0, 0], [1, 0, 0], 0.0, 1.0),
    ]
    assert all(isinstance(j, starkrs.Joint) for j in made)
    assert len(sim.joints()) == 3 + len(made)


def test_primitive_readouts_add_up_to_the_joint_state(settings):
    # A 0.5 kg rod hanging at rest from a hinge: the hinge's point primitive carries m g, its
    # direction primitive nothing, and the per-primitive readouts sum to the joint's state.
    settings.time_step_s = 0.01
    sim = starkrs.Simulation(settings)
    m, g = 0.5, 9.81
    rod_body = sim.add_rigid_body_with("rod", starkrs.MassProperties.cuboid(m, [0.02, 0.02, 0.2]), [0, 0, -0.1])
    hinge = sim.add_hinge_joint("pivot", None, rod_body, [0, 0, 0], [0, 1, 0])
    assert sim.joint_stiffness(hinge) == starkrs.JointParams().stiffness
    sim.run(0.5)
    rows = sim.joint_primitive_readouts(hinge)
    assert [r["primitive"]["kind"] for r in rows] == ["point", "direction"]
    np.testing.assert_allclose(rows[0]["force_b_n"], [0.0, 0.0, m * g], rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(rows[0]["force_a_n"], [0.0, 0.0, 0.0])  # a is the world
    state = sim.joint_state(hinge)
    np.testing.assert_allclose(state.force_on_b_n, np.sum([r["force_b_n"] for r in rows], axis=0), atol=1e-12)
    np.testing.assert_allclose(state.torque_on_b_n_m, np.sum([r["torque_b_n_m"] for r in rows], axis=0), atol=1e-12)
    assert state.violation_m == rows[0]["violation"] == pytest.approx(m * g / sim.joint_stiffness(hinge), rel=1e-3)
    assert "coordinate=0" in repr(state) and "Some" not in repr(state)
    # Every joint at once, and the worst violations.
    spring = sim.add_spring("spring", None, rod_body, [0, 0, 0.1], [0, 0, -0.2], 10.0)
    sim.step()
    states = sim.joint_states()
    assert list(states) == ["pivot", "spring"]
    assert states["pivot"].coordinate == sim.joint_state(hinge).coordinate
    assert states["spring"].driver_effort == sim.joint_state(spring).driver_effort
    assert sim.max_joint_violations() == (states["pivot"].violation_m, states["pivot"].violation_rad)
    spring_rows = sim.joint_primitive_readouts(spring)
    assert spring_rows[0]["primitive"] == {"kind": "spring", "rest_length_m": pytest.approx(0.3), "damping_n_s_m": 0.0}
    sim.set_joint_stiffness(hinge, 2e7)
    assert sim.joint_stiffness(hinge) == 2e7
    # Body states, as in the body log.
    body = sim.body_states()["rod"]
    np.testing.assert_array_equal(body["position_m"], sim.body_position(rod_body))
    np.testing.assert_array_equal(body["orientation_wxyz"], sim.body_orientation(rod_body))
    np.testing.assert_array_equal(body["angular_velocity_rad_s"], sim.body_angular_velocity(rod_body))


def test_fix_joint_drives_a_body_kinematically(settings):
    settings.time_step_s = 0.01
    sim = starkrs.Simulation(settings)
    paddle = sim.add_box("paddle", 1.0, [0.2, 0.02, 0.2], [0.0, 0.0, 0.0], thickness_m=1e-3)
    fix = sim.add_fix_joint("drive", paddle)
    sim.set_fixed_transform_deg(fix, [0.0, 0.0, 0.1], 90.0, [0, 0, 1])
    sim.run(0.3)
    np.testing.assert_allclose(sim.body_position(paddle), [0.0, 0.0, 0.1], atol=2e-3)
    np.testing.assert_allclose(
        sim.body_direction_to_world(paddle, [1.0, 0.0, 0.0]), [0.0, 1.0, 0.0], atol=0.02
    )
    sim.set_fixed_transform(fix, [0.0, 0.0, 0.0], np.eye(3))
    sim.run(0.3)
    np.testing.assert_allclose(sim.body_position(paddle), [0.0, 0.0, 0.0], atol=2e-3)


def test_presets_have_the_textbook_mass_properties(settings):
    settings.contact.default_thickness_m = 1e-3
    sim = starkrs.Simulation(settings)
    box = sim.add_box("box", 2.0, [0.1, 0.2, 0.3], [0, 0, 1])
    assert isinstance(box, starkrs.RigidObject) and box.body.label == "box"
    np.testing.assert_allclose(np.diag(sim.body_inertia(box.body)), 2.0 / 12 * np.array([0.13, 0.10, 0.05]))
    ball = sim.add_sphere("ball", 1.0, 0.1, position_m=[1, 0, 1])
    assert sim.body_inertia(ball.body)[0, 0] == pytest.approx(0.4 * 1.0 * 0.01)
    can = sim.add_cylinder("can", 1.0, 0.1, 0.2, position_m=[2, 0, 1])
    assert sim.body_inertia(can.body)[2, 2] == pytest.approx(0.5 * 0.01)
    ring = sim.add_torus("ring", 1.0, 0.2, 0.05, position_m=[3, 0, 1])
    # Solid torus about its symmetry axis: m (R² + ¾ r²).
    assert sim.body_inertia(ring.body)[2, 2] == pytest.approx(0.2**2 + 0.75 * 0.05**2)
    v, t = meshes.box_mesh([0.1, 0.1, 0.1])
    cube = sim.add_rigid_mesh("cube", v + [4.0, 0.0, 1.0], t, 1000.0)
    assert sim.body_mass(cube.body) == pytest.approx(1.0)
    np.testing.assert_allclose(sim.body_position(cube.body), [4.0, 0.0, 1.0], atol=1e-12)
    nodes = sim.add_rigid_output_mesh(box.body, v, t)
    assert sim.positions(nodes).shape == (8, 3)
    assert sim.body_collision_meshes(box) == [box.mesh.contact]
    assert sim.body_collision_meshes(cube.body) == [cube.mesh.contact]
    with pytest.raises(starkrs.StarkError, match="mass_kg"):
        sim.add_box("bad", -1.0, [0.1] * 3)


def test_attach_to_body_carries_a_cloth(settings):
    # A cloth strip glued along one edge to a bar held by a fix joint: the joint carries the
    # bar's and the cloth's weight.
    settings.time_step_s = 0.01
    sim = starkrs.Simulation(settings)
    bar = sim.add_rigid_body_with("bar", starkrs.MassProperties.cuboid(1.0, [0.5, 0.02, 0.02]), [0, 0, 0])
    fix = sim.add_fix_joint("hold", bar)
    cotton = starkrs.SurfaceMaterial.cotton_fabric()
    cotton.inertia.damping = 10.0  # settles in ~2 s, so the joint carries the static weight
    cloth = sim.add_surface_grid("cloth", [0.5, 0.5], [4, 4], cotton)
    x = sim.positions(cloth)
    edge = np.flatnonzero(np.isclose(x[:, 1], 0.25))
    assert len(edge) == 5
    sim.set_positions(cloth, x - [0.0, 0.25, 0.0])
    glue = sim.attach_to_body("glue", bar, cloth, edge)
    assert isinstance(glue, starkrs.RigidAttachmentHandle)
    sim.run(2.5)
    cloth_mass = 0.2 * 0.25  # cotton 0.2 kg/m², 0.5 × 0.5 m
    assert sim.mass(cloth.inertia) == pytest.approx(cloth_mass)
    force = sim.joint_state(fix).force_on_b_n
    np.testing.assert_allclose(force, [0.0, 0.0, (1.0 + cloth_mass) * 9.81], rtol=1e-4, atol=1e-4)
    assert sim.rigid_attachment_gap(glue) < 1e-3
    assert sim.positions(cloth)[:, 2].min() < -0.2  # the cloth hangs


def test_scene_file_joints_from_python(tmp_path):
    scene = starkrs.load_scene(REPO / "scenes" / "rb_pendulum_chain.toml", output_directory=str(tmp_path), frames=False)
    assert "motor" in scene.joints and "hinge4" in scene.joints
    wheel = scene.objects["wheel"]
    assert isinstance(wheel, starkrs.SceneRigidBody) and wheel.label == "wheel"
    sim = scene.simulation
    assert wheel.body == sim.rigid_body("wheel") and wheel.contact is None  # no contact thickness
    assert sim.positions(wheel).shape == (len(wheel.nodes), 3)
    local_at_start = sim.body_point_to_local(wheel, sim.positions(wheel))
    q_at_start = sim.body_orientation(wheel)
    sim.run(0.5)
    assert list(sim.joint_states()) == list(scene.joints)
    # The wheel's drawn mesh turns with it: its vertices keep their body-frame coordinates.
    assert np.abs(sim.positions(wheel) - sim.body_point_to_world(wheel, local_at_start)).max() < 1e-12
    assert abs(sim.body_orientation(wheel) @ q_at_start) == pytest.approx(math.cos(math.radians(45.0) / 2), abs=1e-2)
    motor = sim.joint_state(scene.joints["motor"])
    assert motor.coordinate_rate == pytest.approx(math.radians(90.0), rel=1e-2)
    for label, joint in scene.joints.items():
        assert sim.joint_state(joint).violation_m < 2e-3, label


def test_bad_joint_input(settings):
    sim = starkrs.Simulation(settings)
    other = starkrs.Simulation(settings)
    a = rod(sim, "a", 1.0, 0.2, [0.1, 0.0, 0.0])
    foreign = rod(other, "f", 1.0, 0.2, [0.1, 0.0, 0.0])
    with pytest.raises(starkrs.InvalidHandleError):
        sim.add_hinge_joint("h", None, foreign, [0, 0, 0], [0, 1, 0])
    with pytest.raises(starkrs.StarkError, match="axis"):
        sim.add_hinge_joint("h", None, a, [0, 0, 0], [0, 0, 0])
    with pytest.raises(starkrs.StarkError, match="stiffness"):
        sim.add_ball_joint("b", None, a, [0, 0, 0], starkrs.JointParams(stiffness=-1.0))
    with pytest.raises(starkrs.StarkError, match="perpendicular"):
        sim.add_universal_joint("u", None, a, [0, 0, 0], [1, 0, 0], [1, 0, 0])
    joint = other.add_ball_joint("b", None, foreign, [0, 0, 0])
    with pytest.raises(starkrs.InvalidHandleError):
        sim.joint_state(joint)
    with pytest.raises(starkrs.InvalidHandleError):
        sim.joint_primitive_readouts(joint)
    with pytest.raises(starkrs.InvalidHandleError):
        sim.body_collision_meshes(foreign)
    with pytest.raises(TypeError, match="RigidBody"):
        sim.body_collision_meshes(joint)
    # An unknown body: by label there is none to pass; in a scene file it is named.
    assert sim.rigid_body("ghost") is None
    with pytest.raises(TypeError, match="RigidBody"):
        sim.add_hinge_joint("h", None, sim.rigid_body("ghost"), [0, 0, 0], [0, 1, 0])
    with pytest.raises(starkrs.StarkError, match="mass of rigid body 'neg' must be positive"):
        sim.add_rigid_body("neg", -1.0, np.eye(3))
    scene = """duration_s = 1.0
[[rigid_body]]
name = "a"
box = { size_m = [0.1, 0.1, 0.1] }
mass_kg = 1.0
[[joint]]
name = "j"
type = "hinge"
b = "ghost"
point_m = [0.0, 0.0, 0.0]
axis = [0.0, 1.0, 0.0]
"""
    with pytest.raises(starkrs.SceneError, match=r"scene\.toml:\d+:\d+: unknown rigid body 'ghost' in joint 'j'"):
        starkrs.parse_scene(scene)


def test_attachment_parameters_read_and_written(settings):
    sim = starkrs.Simulation(settings)
    bar = sim.add_rigid_body_with("bar", starkrs.MassProperties.cuboid(1.0, [0.5, 0.02, 0.02]), [0, 0, 0])
    cloth = sim.add_surface_grid("cloth", [0.5, 0.5], [2, 2], starkrs.SurfaceMaterial.cotton_fabric())
    glue = sim.attach_to_body("glue", bar, cloth, [0, 1], starkrs.AttachmentParams(stiffness=1e5))
    assert sim.params(glue).stiffness == 1e5
    p = sim.params(glue)
    p.stiffness = 2e5
    sim.set_params(glue, p)
    assert sim.params(glue).stiffness == 2e5
    knot = sim.add_attachment_point_point("knot", cloth, [0], cloth, [1])
    assert sim.params(knot).stiffness == starkrs.AttachmentParams().stiffness
    q = sim.params(knot)
    q.stiffness = -1.0
    with pytest.raises(starkrs.StarkError, match="stiffness"):
        sim.set_params(knot, q)


def test_pendulum_chain_built_in_python_matches_its_scene_file(tmp_path):
    # scenes/rb_pendulum_chain.toml (five hinged links and a motor-driven wheel) built with the
    # Python API: the same bodies, joints and trajectory to 1e-12.
    scene = starkrs.load_scene(REPO / "scenes" / "rb_pendulum_chain.toml", output_directory=str(tmp_path),
                               frames=False, step_log=False)
    from_file = scene.simulation
    sim = starkrs.Simulation(from_file.settings)
    size = [0.2, 0.03, 0.03]
    v, t = meshes.box_mesh(size)
    links = []
    for i, x in enumerate([0.1, 0.3, 0.5, 0.7, 0.9]):
        link = sim.add_rigid_body_with(f"link{i}", starkrs.MassProperties.cuboid(0.2, size), [x, 0.0, 0.0])
        sim.add_rigid_output_mesh(link, v, t)
        links.append(link)
    r, h = 0.15, 0.02
    quarter = [math.cos(math.pi / 4), math.sin(math.pi / 4), 0.0, 0.0]  # 90° about x
    wheel = sim.add_rigid_body_with(
        "wheel", starkrs.MassProperties.cylinder(1000.0 * (math.pi * r * r * h), r, h), [0.0, 0.5, 0.0], quarter)
    dv, dt = meshes.cylinder_mesh(r, h, 24, 1)
    sim.add_rigid_output_mesh(wheel, dv, dt)
    sim.add_hinge_joint("pivot", None, links[0], [0, 0, 0], [0, 1, 0])
    for i, x in enumerate([0.2, 0.4, 0.6, 0.8], start=1):
        sim.add_hinge_joint(f"hinge{i}", links[i - 1], links[i], [x, 0.0, 0.0], [0, 1, 0])
    sim.add_motor("motor", None, wheel, [0.0, 0.5, 0.0], [0, 1, 0], math.radians(90.0), 1.0)
    assert [j.label for j in sim.joints()] == list(scene.joints)
    for _ in range(20):
        from_file.step()
        sim.step()
    for a, b in zip(from_file.rigid_bodies(), sim.rigid_bodies()):
        assert a.label == b.label
        np.testing.assert_allclose(sim.body_position(b), from_file.body_position(a), rtol=0, atol=1e-12)
        np.testing.assert_allclose(sim.body_orientation(b), from_file.body_orientation(a), rtol=0, atol=1e-12)
        np.testing.assert_allclose(sim.body_angular_velocity(b), from_file.body_angular_velocity(a), rtol=0,
                                   atol=1e-12)
    for j in sim.joints():
        ours, theirs = sim.joint_state(j), from_file.joint_state(scene.joints[j.label])
        assert ours.coordinate == pytest.approx(theirs.coordinate, abs=1e-12)

"""Time events and run callbacks with Python callables: timing, lending the simulation,
exceptions."""

import numpy as np
import pytest

import starkrs


def test_event_moves_the_target_at_the_right_step(hanging_cloth):
    sim, cloth, pin = hanging_cloth
    seen = []

    def lift(s, t):
        seen.append((round(t, 12), s.time))
        s.set_transform(pin, [0.0, 0.0, 0.05])

    sim.add_time_event(0.05, 1.0, lift)
    sim.step()  # ends at 1/30 < 0.05: no event
    assert seen == [] and sim.targets(pin)[0, 2] == 0.0
    z_before = sim.positions(cloth)[80, 2]
    sim.step()  # ends at 2/30 ≥ 0.05: the event runs before it, the target is met at its end
    assert seen == [(round(2 / 30, 12), pytest.approx(1 / 30))]
    assert sim.targets(pin)[0, 2] == pytest.approx(0.05)
    assert z_before == pytest.approx(0.0, abs=1e-4)
    assert sim.positions(cloth)[80, 2] == pytest.approx(0.05, abs=1e-4)


def test_run_callback_changes_the_transform_mid_run(hanging_cloth):
    sim, cloth, pin = hanging_cloth
    heights = []

    def before_step(s):
        # Called before every step: from the fourth step on, the corner goes up.
        if len(heights) == 3:
            s.set_transform(pin, [0.0, 0.0, 0.1])
        heights.append(s.positions(cloth)[80, 2])

    summary = sim.run(6 / 30, before_step)
    assert summary["steps"] == 6 and len(heights) == 6
    assert max(abs(h) for h in heights[:4]) < 1e-4  # before the change took effect
    assert heights[4] == pytest.approx(0.1, abs=1e-4)  # after the fourth step
    assert sim.positions(cloth)[80, 2] == pytest.approx(0.1, abs=1e-4)


def test_events_can_change_parameters_and_gravity(hanging_cloth):
    sim, cloth, _ = hanging_cloth

    def weightless(s, t):
        s.gravity = [0.0, 0.0, 0.0]
        p = s.params(cloth.inertia)
        p.damping = 0.5
        s.set_params(cloth.inertia, p)

    sim.add_time_event(0.0, 1.0, weightless)
    sim.step()
    np.testing.assert_array_equal(sim.gravity, [0.0, 0.0, 0.0])
    assert sim.params(cloth.inertia).damping == 0.5


def test_exceptions_in_callbacks_propagate_unchanged(hanging_cloth):
    sim, _, _ = hanging_cloth

    class Stop(Exception):
        pass

    def fail(s, t):
        raise Stop("from the event")

    sim.add_time_event(0.1, 0.2, fail)
    with pytest.raises(Stop, match="from the event"):
        sim.run(1.0)
    assert sim.time == pytest.approx(2 / 30)  # the step that would end at 0.1 did not happen
    with pytest.raises(ZeroDivisionError):
        sim.run(0.1, lambda s: 1 / 0)
    # The simulation is still usable.
    sim.positions(sim.node_set("cloth"))


def test_callbacks_cannot_step_or_run_the_simulation_they_are_called_from(hanging_cloth):
    sim, _, _ = hanging_cloth
    with pytest.raises(starkrs.StarkError, match="cannot be called from a callback"):
        sim.run(0.1, lambda s: s.step())
    with pytest.raises(TypeError):
        sim.add_time_event(0.0, 1.0, "not callable")
    with pytest.raises(TypeError):
        sim.run(0.1, 42)


def test_events_added_by_events_run(hanging_cloth):
    sim, _, _ = hanging_cloth
    calls = []

    def first(s, t):
        if not calls:
            s.add_time_event(0.0, 1.0, lambda s2, t2: calls.append(t2))
        calls.append(-1.0)

    sim.add_time_event(0.0, 0.04, first)
    sim.run(3 / 30)
    assert calls[0] == -1.0 and len(calls) == 3

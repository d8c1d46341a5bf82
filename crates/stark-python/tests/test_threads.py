"""The GIL is released while solving; a running simulation refuses other threads; Ctrl-C stops
a run between steps."""

import _thread
import signal
import threading
import time

import pytest

import starkrs


def make(settings, n=24):
    sim = starkrs.Simulation(settings)
    cloth = sim.add_surface_grid("cloth", [1, 1], [n, n], starkrs.SurfaceMaterial.cotton_fabric())
    sim.prescribe_in_box(cloth, [0.5, 0.5, 0.0], [1e-3] * 3, starkrs.PrescribedParams(stiffness=1e6))
    return sim, cloth


def test_the_gil_is_released_while_running(settings):
    sim, cloth = make(settings)
    errors = []
    thread = threading.Thread(target=lambda: sim.run(0.3))
    ticks = 0
    thread.start()
    while thread.is_alive():
        ticks += 1
        try:
            sim.positions(cloth)
        except starkrs.StarkError as e:
            errors.append(str(e))
        time.sleep(0.001)
    thread.join()
    assert ticks > 20, "the main thread did not get to run while the simulation was stepping"
    assert errors and "running" in errors[0]
    assert sim.time >= 0.3 - 1e-9


def test_two_simulations_run_in_parallel_threads(settings):
    sims = [make(settings, 8)[0] for _ in range(2)]
    threads = [threading.Thread(target=lambda s=s: s.run(0.2)) for s in sims]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert all(s.time >= 0.2 - 1e-9 for s in sims)


def test_keyboard_interrupt_stops_a_run_between_steps(settings):
    sim, _ = make(settings, 8)
    # Python leaves SIGINT ignored when it starts ignored (a background job): handle it here.
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    timer = threading.Timer(0.2, _thread.interrupt_main)
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            sim.run(60.0)
    finally:
        timer.cancel()
        signal.signal(signal.SIGINT, previous)
    assert 0 < sim.time < 30.0
    sim.step()  # still usable

"""Shared fixtures of the starkrs test suite."""

from pathlib import Path

import pytest

import starkrs

REPO = Path(__file__).resolve().parents[3]


@pytest.fixture
def settings(tmp_path):
    """Default settings writing nothing (output goes to a temporary directory if enabled)."""
    s = starkrs.Settings()
    s.output.directory = str(tmp_path / "output")
    s.output.frames = False
    s.output.step_log = False
    return s


@pytest.fixture
def hanging_cloth(settings):
    """An 8 × 8 cotton cloth pinned at one corner: (sim, cloth, pin)."""
    sim = starkrs.Simulation(settings)
    cloth = sim.add_surface_grid("cloth", [1.0, 1.0], [8, 8], starkrs.SurfaceMaterial.cotton_fabric())
    pin = sim.prescribe_in_box(cloth, [0.5, 0.5, 0.0], [1e-3] * 3, starkrs.PrescribedParams(stiffness=1e6))
    return sim, cloth, pin

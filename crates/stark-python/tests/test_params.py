"""Settings, parameters and materials: every field reads and writes, nested objects are shared,
values are checked when they enter a simulation."""

import copy
import math

import numpy as np
import pytest

import starkrs

CLASSES = [
    starkrs.Settings,
    starkrs.NewtonSettings,
    starkrs.OutputSettings,
    starkrs.ContactSettings,
    starkrs.InertiaParams,
    starkrs.TriangleStrainParams,
    starkrs.TetStrainParams,
    starkrs.SegmentStrainParams,
    starkrs.FlatBendingParams,
    starkrs.DihedralBendingParams,
    starkrs.PrescribedParams,
    starkrs.AttachmentParams,
    starkrs.RigidBodyParams,
    starkrs.JointParams,
    starkrs.LineMaterial,
    starkrs.VolumeMaterial,
    starkrs.SurfaceMaterial,
]


@pytest.mark.parametrize("cls", CLASSES)
def test_every_field_round_trips_through_the_rust_struct(cls):
    obj = cls()
    d = obj.to_dict()
    # Parameter classes have getset descriptors; settings and materials wrap pyo3's in a property
    # that carries the library's doc.
    attributes = {n for n, v in vars(cls).items()
                  if isinstance(v, property) or type(v).__name__ == "getset_descriptor"}
    assert set(d) == attributes
    for name, value in d.items():
        if isinstance(value, bool):
            setattr(obj, name, not value)
            assert obj.to_dict()[name] == (not value)
        elif isinstance(value, float) and math.isfinite(value):
            setattr(obj, name, value * 2 + 1)
            assert obj.to_dict()[name] == value * 2 + 1
        elif isinstance(value, int) and not isinstance(value, bool):
            setattr(obj, name, value + 3)
            assert obj.to_dict()[name] == value + 3
        assert cls.__doc__
        assert getattr(cls, name).__doc__, f"{cls.__name__}.{name} has no docstring"
    twin = obj.copy()
    assert twin == obj and twin is not obj
    assert copy.deepcopy(obj) == obj


def test_keyword_constructor_and_unknown_fields():
    p = starkrs.InertiaParams(density=0.3, damping=0.2)
    assert (p.density, p.damping, p.quasistatic) == (0.3, 0.2, False)
    with pytest.raises(AttributeError, match="no field 'densty'"):
        starkrs.InertiaParams(densty=1.0)
    with pytest.raises(AttributeError):
        p.densty = 1.0


def test_nested_settings_are_shared():
    s = starkrs.Settings()
    s.newton.max_iterations = 7
    s.contact.default_thickness_m = 0.002
    s.output.fps = 60.0
    d = s.to_dict()
    assert d["newton"]["max_iterations"] == 7
    assert d["contact"]["default_thickness_m"] == 0.002
    assert d["output"]["fps"] == 60.0
    m = starkrs.SurfaceMaterial.cotton_fabric()
    m.strain.youngs_modulus = 1e4
    m.bending.stiffness = 2e-6
    assert m.to_dict()["strain"]["youngs_modulus"] == 1e4
    assert m.to_dict()["bending"] == {"flat": {"stiffness": 2e-6, "damping": 1e-7}}


def test_enum_fields_take_names_and_reject_unknown_ones():
    n = starkrs.NewtonSettings()
    assert n.linear_solver == "pcg"
    n.linear_solver = "cholesky"
    assert n.to_dict()["linear_solver"] == "cholesky"
    with pytest.raises(ValueError, match="cholsky"):
        n.linear_solver = "cholsky"
    c = starkrs.ContactSettings()
    c.barrier = "cubic"
    c.hessian = "gauss_newton"
    assert (c.barrier, c.hessian) == ("cubic", "gauss_newton")


def test_vector_and_optional_fields():
    s = starkrs.Settings()
    s.gravity_m_s2 = np.array([0.0, -9.81, 0.0])
    assert isinstance(s.gravity_m_s2, np.ndarray)
    np.testing.assert_array_equal(s.gravity_m_s2, [0.0, -9.81, 0.0])
    with pytest.raises(ValueError):
        s.gravity_m_s2 = [1.0, 2.0]
    s.contact.stiffness = None
    s.contact.stiffness = 1e5
    assert s.contact.stiffness == 1e5


def test_bending_variants():
    m = starkrs.SurfaceMaterial()
    m.bending = None
    assert m.to_dict()["bending"] == "none"
    m.bending = starkrs.DihedralBendingParams(stiffness=1e-3)
    assert m.to_dict()["bending"]["dihedral"]["stiffness"] == 1e-3
    with pytest.raises(TypeError):
        m.bending = starkrs.InertiaParams()


def test_presets_match_the_library():
    c = starkrs.SurfaceMaterial.cotton_fabric()
    assert (c.inertia.density, c.strain.youngs_modulus, c.strain.damping) == (0.2, 5e3, 0.5)
    r = starkrs.VolumeMaterial.soft_rubber()
    assert (r.inertia.density, r.strain.youngs_modulus, r.strain.strain_limit) == (1000.0, 1e4, 1.0)
    b = starkrs.LineMaterial.elastic_rubber_band()
    assert (b.inertia.density, b.strain.section_radius_m) == (0.05, 0.002)


def test_settings_are_checked_when_they_enter_a_simulation():
    s = starkrs.Settings()
    s.time_step_s = float("nan")
    with pytest.raises(starkrs.StarkError, match="time_step_s"):
        s.validate()
    with pytest.raises(starkrs.StarkError, match="time_step_s"):
        starkrs.Simulation(s)
    s = starkrs.Settings()
    s.newton.armijo = 0.7
    with pytest.raises(starkrs.StarkError, match="newton.armijo"):
        starkrs.Simulation(s)
    sim = starkrs.Simulation()
    bad = sim.settings
    bad.contact.friction_iterations = 0
    with pytest.raises(starkrs.StarkError, match="friction_iterations"):
        sim.settings = bad


def test_simulation_settings_are_a_copy_to_assign_back(settings):
    sim = starkrs.Simulation(settings)
    s = sim.settings
    s.newton.max_iterations = 9
    assert sim.settings.newton.max_iterations == 100
    sim.settings = s
    assert sim.settings.newton.max_iterations == 9

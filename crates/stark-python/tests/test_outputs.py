"""What a run gives back, from Python: VTU frames and the .pvd read with meshio (fields, times,
the stress of a uniaxially stretched block against linear elasticity), checkpoints that resume
bit-identically, and the progress bar."""

import xml.etree.ElementTree as ET

import numpy as np
import pytest

import starkrs
from conftest import REPO

meshio = pytest.importorskip("meshio")

EPS = 1e-3  # axial strain of the stretched block


def stretched_block(tmp_path):
    s = starkrs.Settings()
    s.output.directory = str(tmp_path)
    s.output.fps = 30.0
    s.gravity_m_s2 = [0.0, 0.0, 0.0]
    s.name = "block"
    sim = starkrs.Simulation(s)
    material = starkrs.VolumeMaterial.soft_rubber()
    block = sim.add_volume_grid("block", [0.2, 0.1, 0.1], [4, 2, 2], material)
    cloth = sim.add_surface_grid("cloth", [0.2, 0.2], [4, 4], starkrs.SurfaceMaterial.cotton_fabric())
    sim.prescribe_in_box(cloth, [0.1, 0.1, 0.0], [1e-3] * 3, starkrs.PrescribedParams(stiffness=1e6))
    # The homogeneous uniaxial-stress state of linear elasticity: x = (X(1+ε), Y(1−νε), Z(1−νε)).
    nu = material.strain.poissons_ratio
    rest = sim.rest_positions(block)
    sim.set_positions(block, rest * np.array([1.0 + EPS, 1.0 - nu * EPS, 1.0 - nu * EPS]))
    return sim, material


def test_meshio_reads_every_vtu_and_the_pvd_with_fields_and_times(tmp_path):
    sim, material = stretched_block(tmp_path)
    sim.run(0.1)
    pvd = ET.parse(tmp_path / "block.pvd").getroot()
    entries = [(float(d.get("timestep")), int(d.get("part")), d.get("file")) for d in pvd.iter("DataSet")]
    vtus = sorted(tmp_path.glob("*.vtu"))
    assert len(vtus) == len(entries) == 2 * 4, "two objects, frames at t = 0, 1/30, 2/30, 3/30 s"
    for t, part, file in entries:
        frame = int(file.rsplit("_", 1)[1].split(".")[0])
        assert t == pytest.approx(frame / 30.0, abs=1e-12)
        mesh = meshio.read(tmp_path / file)
        assert mesh.field_data["TimeValue"][0] == pytest.approx(t, abs=1e-12)
        for f in ("velocity", "contact_force_n", "prescribed", "attached"):
            assert len(mesh.point_data[f]) == len(mesh.points), f
        for f in ("green_strain", "cauchy_stress_pa", "von_mises_pa", "principal_stress_pa", "strain_limit_active"):
            assert f in mesh.cell_data, f
        if "cloth" in file:
            assert mesh.point_data["prescribed"].sum() == 1, "one pinned corner"
    # Frame 0 is the stretched state: σ_xx = E ε in every tet (linear elasticity, small strain).
    first = meshio.read(tmp_path / "block_block_00000.vtu")
    expected = material.strain.youngs_modulus * EPS
    sigma = first.cell_data["cauchy_stress_pa"][0].reshape(-1, 3, 3)
    assert np.allclose(sigma[:, 0, 0], expected, rtol=2e-3)
    assert np.abs(sigma[:, 1, 1]).max() < 2e-3 * expected
    assert np.allclose(first.cell_data["von_mises_pa"][0], expected, rtol=2e-3)
    assert np.allclose(first.cell_data["principal_stress_pa"][0][:, 0], expected, rtol=2e-3)


def build(tmp_path, name):
    return starkrs.load_scene(
        REPO / "scenes" / "twisting_cloth_no_contact.toml",
        output_directory=str(tmp_path / name),
        frames=False,
        overrides=["surface.cloth.grid.quads=[6, 6]"],
    )


def test_checkpoint_resumes_bit_identically(tmp_path):
    whole = build(tmp_path, "whole")
    whole.simulation.run(0.4)
    first = build(tmp_path, "split")
    first.simulation.run(0.2)
    first.simulation.save_checkpoint(tmp_path / "a.ckpt")
    resumed = build(tmp_path, "split")
    resumed.simulation.restore_checkpoint(tmp_path / "a.ckpt")
    resumed.simulation.run(0.2)
    a = whole.simulation.positions(whole.objects["cloth"])
    b = resumed.simulation.positions(resumed.objects["cloth"])
    assert a.tobytes() == b.tobytes()
    assert whole.simulation.time == resumed.simulation.time

    other = starkrs.load_scene(
        REPO / "scenes" / "twisting_cloth_no_contact.toml", frames=False, step_log=False,
        overrides=["surface.cloth.grid.quads=[5, 6]"],
    )
    with pytest.raises(starkrs.StarkError, match="not of this scene"):
        other.simulation.restore_checkpoint(tmp_path / "a.ckpt")


def test_progress_bar_is_drawn_on_stderr(hanging_cloth, capsys):
    sim, _, _ = hanging_cloth
    sim.run(0.1, progress=True)
    err = capsys.readouterr().err
    assert "100%" in err and "0.100/0.100 s simulated" in err
    assert err.endswith("\n")

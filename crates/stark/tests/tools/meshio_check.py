#!/usr/bin/env python3
"""Cross-check our legacy VTK writer and reader against Python `meshio`.

Usage (from the crate root; needs `pip install meshio numpy`):

    python3 tests/meshio_check.py [DIR]

1. Runs `cargo run --release --example vtk_samples -- write DIR`, which writes every file
   kind the Rust tests write (tets, triangles, segments, point clouds; binary and ASCII;
   float64 and float32; point vectors/scalars and cell scalars) plus `manifest.json`.
2. Reads each file with `meshio.read` and compares counts, cell type, connectivity,
   positions and attribute sums with the manifest.
3. Writes tet/triangle meshes with meshio (VTK 5.1 and 4.2 layouts, binary and ASCII) and
   reads them back with our reader (`vtk_samples read FILE`).
4. If the `vtk` Python package is installed (`pip install vtk`), also reads every file with
   VTK's own `vtkUnstructuredGridReader`, the reader ParaView uses for legacy files.

Exits non-zero on the first mismatch. Not run by `cargo test` (no Python needed there).
"""

import json
import os
import subprocess
import sys
import tempfile

import meshio
import numpy as np

CRATE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def example(*args):
    out = subprocess.run(
        ["cargo", "run", "--quiet", "--release", "-p", "stark", "--example", "vtk_samples", "--", *args],
        cwd=CRATE,
        check=True,
        capture_output=True,
        text=True,
    )
    return out.stdout


def close(a, b, rtol):
    return abs(a - b) <= rtol * max(1.0, abs(a), abs(b))


def check_written(directory):
    print(example("write", directory).strip())
    with open(os.path.join(directory, "manifest.json")) as f:
        manifest = json.load(f)
    for entry in manifest:
        path = os.path.join(directory, entry["file"])
        mesh = meshio.read(path)
        rtol = 1e-6 if entry["float32"] else 1e-12
        where = entry["file"]
        assert mesh.points.shape == (entry["n_points"], 3), (where, mesh.points.shape)
        if entry["n_points"] == 0:
            assert len(mesh.cells) == 0 or len(mesh.cells[0].data) == 0, (where, mesh.cells)
            print(f"meshio read {where}: ok (empty)")
            continue
        assert len(mesh.cells) == 1, (where, mesh.cells)
        block = mesh.cells[0]
        assert block.type == entry["cell_type"], (where, block.type)
        assert len(block.data) == entry["n_cells"], (where, len(block.data))
        assert int(block.data.sum()) == entry["connectivity_sum"], where
        assert np.allclose(mesh.points[0], entry["first_point"], rtol=rtol, atol=0), where
        assert close(float(mesh.points.sum()), entry["point_sum"], rtol), where
        assert mesh.points.dtype.kind == "f" and mesh.points.dtype.itemsize == (4 if entry["float32"] else 8), where
        for name, (n_comp, total) in entry["point_data"].items():
            data = mesh.point_data[name]
            comps = 1 if data.ndim == 1 else data.shape[1]
            assert comps == n_comp, (where, name, data.shape)
            assert close(float(data.sum()), total, rtol), (where, name)
        for name, total in entry["cell_data"].items():
            data = mesh.cell_data[name][0]
            assert len(data) == entry["n_cells"], (where, name)
            assert close(float(data.sum()), total, rtol), (where, name)
        print(f"meshio read {where}: ok ({entry['n_points']} points, {entry['n_cells']} {block.type})")
    return len(manifest)


def check_read(directory):
    rng = np.random.default_rng(0)
    points = rng.random((9, 3))
    tets = np.array([[0, 1, 2, 3], [4, 5, 6, 7], [1, 2, 3, 8]])
    tris = np.array([[0, 1, 2], [2, 3, 4]])
    mesh = meshio.Mesh(
        points,
        [("tetra", tets), ("triangle", tris)],
        point_data={"v": points * 2.0, "s": np.arange(9.0)},
        cell_data={"c": [np.array([1.0, 2.0, 3.0]), np.array([4.0, 5.0])]},
    )
    count = 0
    for fmt in ["5.1", "4.2"]:
        for binary in [True, False]:
            path = os.path.join(directory, f"from_meshio_{fmt}_{'bin' if binary else 'ascii'}.vtk")
            meshio.vtk.write(path, mesh, fmt_version=fmt, binary=binary)
            summary = json.loads(example("read", path))
            assert "error" not in summary, (path, summary)
            assert summary["points"] == 9 and summary["tets"] == 3 and summary["triangles"] == 2, summary
            assert summary["connectivity_sum"] == int(tets.sum() + tris.sum()), summary
            assert close(summary["point_sum"], float(points.sum()), 1e-12), summary
            assert summary["point_data"]["v"][0] == 3, summary
            assert close(summary["point_data"]["v"][1], float(2 * points.sum()), 1e-12), summary
            assert close(summary["point_data"]["s"][1], 36.0, 1e-12), summary
            assert close(summary["cell_data"]["c"][1], 15.0, 1e-12), summary
            print(f"our reader read meshio {fmt} {'binary' if binary else 'ascii'}: ok")
            count += 1
    return count


def check_vtk_reader(directory):
    try:
        import vtk
        from vtk.util.numpy_support import vtk_to_numpy
    except ImportError:
        print("python package `vtk` not installed: skipping the VTK/ParaView reader check")
        return 0
    with open(os.path.join(directory, "manifest.json")) as f:
        manifest = json.load(f)
    for entry in manifest:
        where = entry["file"]
        reader = vtk.vtkUnstructuredGridReader()
        reader.SetFileName(os.path.join(directory, where))
        reader.ReadAllScalarsOn()
        reader.ReadAllVectorsOn()
        reader.Update()
        grid = reader.GetOutput()
        assert grid.GetNumberOfPoints() == entry["n_points"], where
        assert grid.GetNumberOfCells() == entry["n_cells"], where
        if entry["n_points"] == 0:
            continue
        rtol = 1e-6 if entry["float32"] else 1e-12
        points = vtk_to_numpy(grid.GetPoints().GetData())
        assert close(float(points.sum()), entry["point_sum"], rtol), where
        vtk_type = {"vertex": 1, "line": 3, "triangle": 5, "tetra": 10}[entry["cell_type"]]
        assert all(grid.GetCellType(i) == vtk_type for i in range(grid.GetNumberOfCells())), where
        for name, (n_comp, total) in entry["point_data"].items():
            data = vtk_to_numpy(grid.GetPointData().GetArray(name))
            assert close(float(data.sum()), total, rtol), (where, name)
        for name, total in entry["cell_data"].items():
            data = vtk_to_numpy(grid.GetCellData().GetArray(name))
            assert close(float(data.sum()), total, rtol), (where, name)
    print(f"VTK {vtk.vtkVersion.GetVTKVersion()} vtkUnstructuredGridReader read all {len(manifest)} files: ok")

    # And the other way: files written by VTK's own legacy writer, read by us.
    tets = next(e for e in manifest if e["file"] == "tets_binary.vtk")
    reader = vtk.vtkUnstructuredGridReader()
    reader.SetFileName(os.path.join(directory, "tets_binary.vtk"))
    reader.ReadAllScalarsOn()
    reader.ReadAllVectorsOn()
    reader.Update()
    for binary in [True, False]:
        for version in [51, 42]:
            path = os.path.join(directory, f"from_vtk_{version}_{'bin' if binary else 'ascii'}.vtk")
            writer = vtk.vtkUnstructuredGridWriter()
            writer.SetInputData(reader.GetOutput())
            writer.SetFileName(path)
            writer.SetFileVersion(version)
            if binary:
                writer.SetFileTypeToBinary()
            else:
                writer.SetFileTypeToASCII()
            writer.Write()
            summary = json.loads(example("read", path))
            assert "error" not in summary, (path, summary)
            assert summary["points"] == tets["n_points"] and summary["tets"] == tets["n_cells"], summary
            assert summary["connectivity_sum"] == tets["connectivity_sum"], summary
            rtol = 1e-12 if binary else 1e-9  # VTK's ASCII writer prints 11 digits
            assert close(summary["point_sum"], tets["point_sum"], rtol), summary
            for name, (n_comp, total) in tets["point_data"].items():
                assert summary["point_data"][name][0] == n_comp, (name, summary)
                assert close(summary["point_data"][name][1], total, rtol), (name, summary)
            assert close(summary["cell_data"]["tet_id"][1], tets["cell_data"]["tet_id"], rtol), summary
            print(f"our reader read VTK's writer output (version {version / 10}, "
                  f"{'binary' if binary else 'ascii'}): ok")
    return len(manifest)


def main():
    directory = sys.argv[1] if len(sys.argv) > 1 else tempfile.mkdtemp(prefix="vtk_meshio_")
    os.makedirs(directory, exist_ok=True)
    written = check_written(directory)
    read = check_read(directory)
    check_vtk_reader(directory)
    print(f"meshio {meshio.__version__}: {written} files written by us read by meshio, "
          f"{read} files written by meshio read by us: all ok")


if __name__ == "__main__":
    main()

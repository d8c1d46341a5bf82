"""Mesh generators and mesh files: each function returns ``(vertices (n, 3) float64,
elements (m, k) int64)``."""

import os
from typing import Optional, Union

import numpy as np
from numpy.typing import ArrayLike, NDArray

_Mesh = tuple[NDArray[np.float64], NDArray[np.int64]]

def triangle_grid(
    size: tuple[float, float], quads: tuple[int, int], center: tuple[float, float] = ..., z: float = 0.0
) -> _Mesh:
    """A rectangular triangle grid of `size` centred at `center` in the plane z = `z`, `quads` per side."""
def tet_grid(size: ArrayLike, hexes: tuple[int, int, int], center: Optional[ArrayLike] = None) -> _Mesh:
    """A tet grid of `size` centred at `center`, `hexes` cells per side, 12 tets per cell."""
def segment_line(begin: ArrayLike, end: ArrayLike, n_segments: int) -> _Mesh:
    """A straight line of `n_segments` segments from `begin` to `end`."""
def box_mesh(size: ArrayLike) -> _Mesh:
    """The closed surface of a box of `size` centred at the origin (12 triangles)."""
def sphere_mesh(radius: float, subdivisions: int = 2) -> _Mesh:
    """An icosphere of `radius` with `subdivisions` refinements."""
def cylinder_mesh(radius: float, height: float, slices: int = 16, stacks: int = 1) -> _Mesh:
    """A closed cylinder of `radius` and `height` along z, centred."""
def torus_mesh(major_radius: float, minor_radius: float, major_segments: int = 32, minor_segments: int = 16) -> _Mesh:
    """A torus in the xy plane: major radius (tube centre), minor (tube) radius."""
def cylindrical_triangle_grid(radius: float, height: float, quads: tuple[int, int]) -> _Mesh:
    """An open cylindrical triangle grid of `radius` and `height` along z."""
def load_triangle_mesh(path: Union[str, os.PathLike[str]]) -> _Mesh:
    """Load a triangle mesh (OBJ, STL, VTK, Gmsh .msh): `(vertices, triangles)`."""
def load_tet_mesh(path: Union[str, os.PathLike[str]]) -> _Mesh:
    """Load a tet mesh (VTK, Gmsh .msh): `(vertices, tets)`."""

"""Stark-rs from Python: strongly coupled rigid bodies, cloth, FEM solids and IPC contact.

Build a scene with :class:`Simulation` (or load a scene file with :func:`load_scene`), run it,
and read positions and velocities as NumPy arrays. ``starkrs.geometry`` is the contact geometry
toolkit (distances with derivatives, CCD, intersection tests, broad phase) and
``starkrs.meshes`` the mesh generators; ``starkrs.sym`` writes your own energy
(``Simulation.add_energy``).
"""

from . import _starkrs
from ._starkrs import *  # noqa: F401,F403
from ._starkrs import __version__  # noqa: F401
from . import geometry, meshes, sym  # noqa: F401

__all__ = [name for name in dir(_starkrs) if not name.startswith("_")] + ["geometry", "meshes", "sym"]

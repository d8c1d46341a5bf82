"""Mesh generators and mesh files: each function returns ``(vertices (n, 3) float64,
elements (m, k) int64)``."""

from . import _starkrs as _ext

_module = _ext.meshes
__all__ = [name for name in dir(_module) if not name.startswith("_")]
globals().update({name: getattr(_module, name) for name in __all__})

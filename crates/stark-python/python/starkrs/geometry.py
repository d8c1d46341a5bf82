"""Contact geometry on NumPy arrays: squared distances with their IPC region type, gradient and
Hessian; continuous collision detection with time of impact; the exact edge-triangle
intersection test; broad-phase candidate pairs; mesh topology helpers."""

from . import _starkrs as _ext

_module = _ext.geometry
__all__ = [name for name in dir(_module) if not name.startswith("_")]
globals().update({name: getattr(_module, name) for name in __all__})

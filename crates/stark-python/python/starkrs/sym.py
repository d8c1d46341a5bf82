"""Symbolic values for writing your own energy in Python (``Simulation.add_energy``).

The energy function is called **once**, with symbolic inputs; the library differentiates the
traced expression (gradient and Hessian) and compiles it to native code, so the simulation never
calls Python while it steps. Inside the function, use the operators ``+ - * / **`` and the
functions of this module; a comparison ``a > b`` is not a bool, it is a condition for
:func:`select` (``min``/``max`` are built on it).

>>> def magnet(x, v, dt, p):
...     return -p.k / sym.norm(x[0] - p.m)
"""

from . import _starkrs

_s = _starkrs._sym
Expr = _s.Expr
Condition = _s.Condition
EnergyHandle = _s.EnergyHandle
sqrt = _s.sqrt
log = _s.log
exp = _s.exp
sin = _s.sin
cos = _s.cos
acos = _s.acos
atan2 = _s.atan2
pow = _s.pow  # noqa: A001 (the issue's name)
select = _s.select
constant = _s.constant


def _is_scalar(a):
    return isinstance(a, (Expr, int, float)) and not isinstance(a, bool)


def min(a, b):  # noqa: A001
    """The smaller of two scalars (derivative of the smaller one)."""
    if isinstance(a, Expr) or isinstance(b, Expr):
        return select(_as_expr(a) > b, b, a)
    return a if a <= b else b


def max(a, b):  # noqa: A001
    """The larger of two scalars (derivative of the larger one)."""
    if isinstance(a, Expr) or isinstance(b, Expr):
        return select(_as_expr(a) > b, a, b)
    return a if a >= b else b


def _as_expr(a):
    return a if isinstance(a, Expr) else constant(float(a))


class Vec3:
    """A 3-vector of scalars: ``+ -`` with vectors, ``* /`` with scalars, ``v[i]``, ``v.x``."""

    __slots__ = ("c",)

    def __init__(self, x, y=None, z=None):
        if y is None and z is None:
            x, y, z = x
        self.c = (x, y, z)

    @property
    def x(self):
        return self.c[0]

    @property
    def y(self):
        return self.c[1]

    @property
    def z(self):
        return self.c[2]

    def __getitem__(self, i):
        return self.c[i]

    def __len__(self):
        return 3

    def __iter__(self):
        return iter(self.c)

    def __add__(self, o):
        o = _vec(o)
        return Vec3(self.c[0] + o.c[0], self.c[1] + o.c[1], self.c[2] + o.c[2])

    __radd__ = __add__

    def __sub__(self, o):
        o = _vec(o)
        return Vec3(self.c[0] - o.c[0], self.c[1] - o.c[1], self.c[2] - o.c[2])

    def __rsub__(self, o):
        return _vec(o) - self

    def __neg__(self):
        return Vec3(-self.c[0], -self.c[1], -self.c[2])

    def __mul__(self, s):
        if not _is_scalar(s):
            return NotImplemented
        return Vec3(self.c[0] * s, self.c[1] * s, self.c[2] * s)

    __rmul__ = __mul__

    def __truediv__(self, s):
        if not _is_scalar(s):
            return NotImplemented
        r = 1.0 / s
        return self * r

    def dot(self, o):
        return dot(self, o)

    def cross(self, o):
        return cross(self, o)

    def norm(self):
        return norm(self)

    def norm_sq(self):
        return dot(self, self)

    def __repr__(self):
        return f"Vec3{self.c!r}"


def _vec(o):
    if isinstance(o, Vec3):
        return o
    try:
        if len(o) == 3:
            return Vec3(o[0], o[1], o[2])
    except TypeError:
        pass
    raise TypeError(f"expected a 3-vector, got {type(o).__name__}")


def dot(a, b):
    """Dot product of two 3-vectors."""
    a, b = _vec(a), _vec(b)
    return a.c[0] * b.c[0] + a.c[1] * b.c[1] + a.c[2] * b.c[2]


def cross(a, b):
    """Cross product of two 3-vectors."""
    a, b = _vec(a), _vec(b)
    return Vec3(
        a.c[1] * b.c[2] - a.c[2] * b.c[1],
        a.c[2] * b.c[0] - a.c[0] * b.c[2],
        a.c[0] * b.c[1] - a.c[1] * b.c[0],
    )


def norm(a):
    """Euclidean norm of a 3-vector (or absolute value of a scalar)."""
    if _is_scalar(a):
        return abs(a)
    return sqrt(dot(a, a))


class Mat3:
    """A 3×3 matrix of scalars, row-major: ``m[i][j]``, ``m @ v``, ``m @ n``, ``+ -``, ``* s``."""

    __slots__ = ("r",)

    def __init__(self, rows):
        self.r = tuple(tuple(row) for row in rows)
        if len(self.r) != 3 or any(len(row) != 3 for row in self.r):
            raise TypeError("Mat3 needs 3 rows of 3 scalars")

    @staticmethod
    def from_columns(a, b, c):
        a, b, c = _vec(a), _vec(b), _vec(c)
        return Mat3([[a.c[i], b.c[i], c.c[i]] for i in range(3)])

    @staticmethod
    def identity():
        return Mat3([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])

    def __getitem__(self, i):
        return self.r[i]

    def transpose(self):
        return Mat3([[self.r[j][i] for j in range(3)] for i in range(3)])

    @property
    def T(self):  # noqa: N802
        return self.transpose()

    def __add__(self, o):
        return Mat3([[self.r[i][j] + o.r[i][j] for j in range(3)] for i in range(3)])

    def __sub__(self, o):
        return Mat3([[self.r[i][j] - o.r[i][j] for j in range(3)] for i in range(3)])

    def __mul__(self, s):
        if not _is_scalar(s):
            return NotImplemented
        return Mat3([[self.r[i][j] * s for j in range(3)] for i in range(3)])

    __rmul__ = __mul__

    def __matmul__(self, o):
        if isinstance(o, Mat3):
            return Mat3(
                [[sum_(self.r[i][k] * o.r[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
            )
        v = _vec(o)
        return Vec3(*(sum_(self.r[i][k] * v.c[k] for k in range(3)) for i in range(3)))

    def trace(self):
        return self.r[0][0] + self.r[1][1] + self.r[2][2]

    def frobenius_sq(self):
        return sum_(self.r[i][j] * self.r[i][j] for i in range(3) for j in range(3))

    def det(self):
        return det(self)

    def inverse(self):
        return inverse(self)

    def __repr__(self):
        return f"Mat3({self.r!r})"


def sum_(items):
    """Sum without Python's integer start value (keeps a pure symbolic sum)."""
    it = iter(items)
    total = next(it)
    for x in it:
        total = total + x
    return total


def det(m):
    """Determinant of a 3×3 matrix."""
    r = m.r if isinstance(m, Mat3) else Mat3(m).r
    return (
        r[0][0] * (r[1][1] * r[2][2] - r[1][2] * r[2][1])
        - r[0][1] * (r[1][0] * r[2][2] - r[1][2] * r[2][0])
        + r[0][2] * (r[1][0] * r[2][1] - r[1][1] * r[2][0])
    )


def inverse(m):
    """Inverse of a 3×3 matrix (adjugate over determinant)."""
    r = m.r if isinstance(m, Mat3) else Mat3(m).r
    inv_d = 1.0 / det(m if isinstance(m, Mat3) else Mat3(m))
    c = [
        [
            r[1][1] * r[2][2] - r[1][2] * r[2][1],
            r[0][2] * r[2][1] - r[0][1] * r[2][2],
            r[0][1] * r[1][2] - r[0][2] * r[1][1],
        ],
        [
            r[1][2] * r[2][0] - r[1][0] * r[2][2],
            r[0][0] * r[2][2] - r[0][2] * r[2][0],
            r[0][2] * r[1][0] - r[0][0] * r[1][2],
        ],
        [
            r[1][0] * r[2][1] - r[1][1] * r[2][0],
            r[0][1] * r[2][0] - r[0][0] * r[2][1],
            r[0][0] * r[1][1] - r[0][1] * r[1][0],
        ],
    ]
    return Mat3([[c[i][j] * inv_d for j in range(3)] for i in range(3)])


inv = inverse


class Nodes:
    """The positions (or velocities) of an element's nodes: ``x[a]`` is a :class:`Vec3`."""

    __slots__ = ("_name", "_what", "_v")

    def __init__(self, name, what, vecs):
        self._name, self._what, self._v = name, what, [Vec3(*c) for c in vecs]

    def __len__(self):
        return len(self._v)

    def __iter__(self):
        return iter(self._v)

    def __getitem__(self, a):
        n = len(self._v)
        if not isinstance(a, int) or isinstance(a, bool) or not -n <= a < n:
            raise _starkrs.StarkError(
                f"energy '{self._name}' refers to {self._what}[{a!r}], but its elements have {n} "
                f"node{'s' if n != 1 else ''} ({self._what}[0] to {self._what}[{n - 1}])"
            )
        return self._v[a]


class Params:
    """The energy's parameters by name: ``p.k`` or ``p["k"]`` (vectors are :class:`Vec3`)."""

    def __init__(self, name, values):
        object.__setattr__(self, "_name", name)
        object.__setattr__(self, "_values", values)

    def __getattr__(self, key):
        return self[key]

    def __getitem__(self, key):
        values = object.__getattribute__(self, "_values")
        if key not in values:
            name = object.__getattribute__(self, "_name")
            have = ", ".join(values) or "none"
            raise _starkrs.StarkError(f"energy '{name}' has no parameter '{key}' (it has: {have})")
        return values[key]

    def __setattr__(self, key, value):
        raise TypeError("parameters are read-only inside the energy")


def _shape(name, key, value, n_elements):
    """Classify a parameter value: ('s'|'v', per_element, flat rows)."""
    import numpy as np

    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise _starkrs.StarkError(
            f"energy '{name}': parameter '{key}' must be a number, a 3-vector or a per-element array"
        ) from None
    if np.isnan(a).any():
        raise _starkrs.StarkError(f"energy '{name}': parameter '{key}' is NaN")
    if not np.isfinite(a).all():
        raise _starkrs.StarkError(f"energy '{name}': parameter '{key}' is not finite")
    if a.ndim == 0:
        return "s", False, a.reshape(1, 1)
    if a.shape == (3,):
        return "v", False, a.reshape(1, 3)
    if a.shape == (n_elements,):
        return "s", True, a.reshape(n_elements, 1)
    if a.shape == (n_elements, 3):
        return "v", True, a
    raise _starkrs.StarkError(
        f"energy '{name}': parameter '{key}' has shape {a.shape}; give a number, a 3-vector, "
        f"or arrays of shape ({n_elements},) or ({n_elements}, 3) (one per element)"
    )


def _prepare_params(name, params, n_elements):
    """Flat parameter names, the layout for :func:`_call`, and flat values (shared or per element)."""
    import numpy as np

    flat, layout, columns, per_element = [], [], [], False
    for key, value in params.items():
        if not isinstance(key, str) or not key.isidentifier():
            raise _starkrs.StarkError(f"energy '{name}': parameter names must be identifiers, got {key!r}")
        kind, per, rows = _shape(name, key, value, n_elements)
        per_element |= per
        layout.append((key, kind, len(flat)))
        flat += [key] if kind == "s" else [f"{key}[{i}]" for i in range(3)]
        columns.append(rows)
    if not columns:
        return flat, layout, []
    if per_element:
        full = np.hstack([np.broadcast_to(c, (n_elements, c.shape[1])) for c in columns])
        return flat, layout, [float(v) for v in full.reshape(-1)]
    return flat, layout, [float(v) for v in np.hstack(columns).reshape(-1)]


def _update_params(name, params, n_elements):
    """``[(flat name, values)]`` for ``set_energy_params``."""
    out = []
    for key, value in params.items():
        kind, per, rows = _shape(name, key, value, n_elements)
        if kind == "s":
            out.append((key, [float(v) for v in rows[:, 0]]))
        else:
            out += [(f"{key}[{i}]", [float(v) for v in rows[:, i]]) for i in range(3)]
    return out


def _call(name, fn, xs, vs, dt, ps, layout):
    """Call the user's energy function with symbolic arguments (used by ``add_energy``)."""
    values = {}
    for key, kind, at in layout:
        values[key] = ps[at] if kind == "s" else Vec3(ps[at], ps[at + 1], ps[at + 2])
    return fn(Nodes(name, "x", xs), Nodes(name, "v", vs), dt, Params(name, values))


__all__ = [
    "Expr",
    "Condition",
    "EnergyHandle",
    "Vec3",
    "Mat3",
    "Nodes",
    "Params",
    "sqrt",
    "log",
    "exp",
    "sin",
    "cos",
    "acos",
    "atan2",
    "pow",
    "select",
    "constant",
    "min",
    "max",
    "dot",
    "cross",
    "norm",
    "det",
    "inverse",
    "inv",
    "sum_",
]

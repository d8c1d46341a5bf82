"""Stark-rs from Python: strongly coupled rigid bodies, cloth, FEM solids and IPC contact.

Type stubs of the ``starkrs`` package (the extension module ``starkrs._starkrs``).
Conventions: points, velocities and forces are ``(n, 3)`` float64 arrays; single vectors ``(3,)``;
element index arrays ``(m, k)`` integers; rotations are quaternions ``(w, x, y, z)`` or ``(3, 3)``
rotation matrices. Every array returned is a new array (changing it changes nothing else).
"""

import os
from typing import Any, Callable, Literal, Optional, Union, final, overload

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import geometry as geometry
from . import meshes as meshes
from . import sym as sym

__version__: str

_Vector = ArrayLike
"""Three numbers: a list, tuple or ``(3,)`` array."""
_Points = ArrayLike
"""An ``(n, 3)`` array of floats (lists of lists are converted)."""
_Indices = ArrayLike
"""An array of non-negative integer node indices."""
_Rotation = ArrayLike
"""A quaternion ``(w, x, y, z)`` (normalised on input) or a ``(3, 3)`` rotation matrix."""
_Report = dict[str, Any]
"""Plain data converted from the library's reports (JSON-like dicts)."""

class StarkError(Exception):
    """Every error of the simulator: the message names the object and the field at fault."""

class SceneError(StarkError):
    """A scene file is invalid: the message names the file, line, column, entry and field."""

class StepFailedError(StarkError):
    """A time step failed even at the smallest allowed step size."""

class InvalidHandleError(StarkError):
    """A handle does not belong to this simulation."""

# ------------------------------------------------------------------------------------------
# Settings, parameters and materials: every field of the Rust struct as an attribute.
# ------------------------------------------------------------------------------------------

# <generated> Settings, parameter and material classes, from the library's tables: `cargo run -p stark-codegen --bin gen_stubs`.

@final
class Settings:
    """Everything that configures a simulation run."""
    name: str
    """Name, used for output files (default: "simulation")."""
    time_step_s: float
    """Largest (and initial) time step, s (default: 1/30)."""
    adaptive_time_step: bool
    """Halve dt on a failed step and grow it back after successes (default: true)."""
    min_time_step_s: float
    """Smallest dt before the simulation gives up, s (default: 1e-6)."""
    time_step_growth: float
    """Factor dt grows by after each successful step, up to `time_step_s` (default: 1.5)."""
    gravity_m_s2: NDArray[np.float64]
    """Gravity, m/s² (default: (0, 0, −9.81))."""
    threads: int
    """Worker threads; 0 uses all cores (default: 0)."""
    newton: NewtonSettings
    """Newton solver."""
    output: OutputSettings
    """Output."""
    contact: ContactSettings
    """Contact."""
    max_hardening_retries: int
    """Largest number of times one step is repeated after a model hardened a stiffness
    (default: 40)."""
    def __new__(cls, *, name: str = ..., time_step_s: float = ..., adaptive_time_step: bool = ..., min_time_step_s: float = ..., time_step_growth: float = ..., gravity_m_s2: ArrayLike = ..., threads: int = ..., newton: NewtonSettings = ..., output: OutputSettings = ..., contact: ContactSettings = ..., max_hardening_retries: int = ...) -> Settings:
        """Defaults of the library, with the given fields replaced."""
    def to_dict(self) -> dict[str, Any]:
        """The fields as a plain dict (nested settings as nested dicts)."""
    def copy(self) -> Settings:
        """A deep copy (nested settings are copied too)."""
    def __copy__(self) -> Settings: ...
    def __deepcopy__(self, memo: Any) -> Settings: ...
    def validate(self) -> None:
        """Check the values; raises `StarkError` naming the field."""

@final
class NewtonSettings:
    """Newton solver settings."""
    residual_tolerance_n: float
    """A step converges when the force residual `‖∇ᵥE‖∞ / dt` falls below this, N (or N·m for
    rotational DOFs) (default: 1e-6, the paper's tolerance)."""
    step_tolerance_m_s: float
    """A step also converges when the Newton step `‖Δv‖∞` falls below this, m/s; 0 disables it
    (default: 0). The original Stark uses 1e-3 and its scenes rely on it."""
    max_iterations: int
    """Newton iterations before the step counts as failed and dt is halved (default: 100)."""
    linear_solver: Literal["pcg", "amg", "cholesky"]
    """Linear solver: `pcg` (block-Jacobi preconditioned CG), `amg` (CG preconditioned by
    algebraic multigrid) or `cholesky` (default: `pcg`)."""
    cg_max_iterations: int
    """Largest number of CG iterations per solve (default: 10000)."""
    cg_relative_tolerance: float
    """Relative CG tolerance at the first Newton iteration; it tightens as the residual falls
    (forcing sequence `min(this, √(r/r₀))`) (default: 1e-2)."""
    armijo: float
    """Armijo sufficient-decrease constant (default: 1e-4)."""
    max_line_search_iterations: int
    """Largest number of step halvings in the line search (default: 30)."""
    projection: Literal["always", "on_demand"]
    """When element Hessians are projected: `always` or `on_demand` (default: `on_demand`:
    after a linear solve found the exact Hessian indefinite, for the rest of the step or
    until the next switch to exact Hessians, see below)."""
    definite_far_from_solution: bool
    """Far from the solution, the contact barriers' positive semi-definite Hessian form
    (`contact.hessian`), and their exact Hessians once a step was taken in full
    (projection on demand starts over); back to the definite form after an exact step had
    to be cut below a quarter. Where the exact barrier Hessians make the total
    indefinite, their definite form until the residual fell tenfold (default: true). Off:
    exact Hessians throughout, the barriers' definite form and then projection on demand.
    (Named `majorizer_far_from_solution` before friction's Hessian became primal–dual;
    the old name is still read.)"""
    def __new__(cls, *, residual_tolerance_n: float = ..., step_tolerance_m_s: float = ..., max_iterations: int = ..., linear_solver: Literal["pcg", "amg", "cholesky"] = ..., cg_max_iterations: int = ..., cg_relative_tolerance: float = ..., armijo: float = ..., max_line_search_iterations: int = ..., projection: Literal["always", "on_demand"] = ..., definite_far_from_solution: bool = ...) -> NewtonSettings:
        """Defaults of the library, with the given fields replaced."""
    def to_dict(self) -> dict[str, Any]:
        """The fields as a plain dict (nested settings as nested dicts)."""
    def copy(self) -> NewtonSettings:
        """A deep copy (nested settings are copied too)."""
    def __copy__(self) -> NewtonSettings: ...
    def __deepcopy__(self, memo: Any) -> NewtonSettings: ...

@final
class OutputSettings:
    """Frame and log output."""
    directory: Union[str, os.PathLike[str]]
    """Directory for frames and logs (default: "output")."""
    fps: float
    """Frames per simulated second; 0 disables frames (default: 30)."""
    frames: bool
    """Write frames (default: true)."""
    frame_format: Literal["vtu", "legacy_vtk"]
    """File format of the frames: `vtu` or `legacy_vtk` (default: `vtu`, with a `.pvd` series
    carrying the times)."""
    step_log: bool
    """Write the per-step log `<name>.steps.jsonl` (default: true). Off, it also turns off the
    body and joint logs."""
    bodies_log: bool
    """Write `<name>.bodies.jsonl`, every rigid body's pose and velocity after each step, when
    the simulation has rigid bodies (default: true)."""
    joints_log: bool
    """Write `<name>.joints.jsonl`, every joint's state after each step, when the simulation has
    joints (default: true)."""
    def __new__(cls, *, directory: Union[str, os.PathLike[str]] = ..., fps: float = ..., frames: bool = ..., frame_format: Literal["vtu", "legacy_vtk"] = ..., step_log: bool = ..., bodies_log: bool = ..., joints_log: bool = ...) -> OutputSettings:
        """Defaults of the library, with the given fields replaced."""
    def to_dict(self) -> dict[str, Any]:
        """The fields as a plain dict (nested settings as nested dicts)."""
    def copy(self) -> OutputSettings:
        """A deep copy (nested settings are copied too)."""
    def __copy__(self) -> OutputSettings: ...
    def __deepcopy__(self, memo: Any) -> OutputSettings: ...

@final
class ContactSettings:
    """Contact settings (part of the simulation settings)."""
    default_thickness_m: Optional[float]
    """Contact thickness of objects that set none, m; objects with neither take no part in
    contact (default: none)."""
    barrier: Literal["log", "cubic"]
    """Barrier function: `log` (IPC, infinite at contact) or `cubic` (the original Stark's)
    (default: `log`)."""
    stiffness: Optional[float]
    """Barrier stiffness `κ` of every pair, N/m; `None` chooses one per pair of objects from the
    masses they carry, the time step, gravity and `d̂` (see `contact::stiffness`; default:
    automatic)."""
    min_distance_fraction: float
    """A pair of objects' `κ` doubles after a step in which one of their pairs came closer than
    this fraction of its `d̂`, up to `max_stiffness_factor` times its initial value
    (default: 1e-3)."""
    max_stiffness_factor: float
    """Upper bound of the adaptive `κ` relative to its initial value (default: 1e8)."""
    friction_stick_slide_threshold_m_s: float
    """Relative speed below which friction sticks (the smoothing `ε_v`), m/s (default: 1e-4: a
    body held below its friction limit creeps slower than this, and a grasp slips within a
    few percent of μN; 1e-3 costs fewer Newton iterations on cloth, see BENCHMARKS.md, but
    lets force-limited jaws slip early, at 0.85 μN)."""
    friction_iterations: int
    """Friction solves per step: 1 lags normal forces and tangents once from the start of the
    step; more re-lag them from the converged state and solve again (default: 1)."""
    hessian: Literal["exact", "projected", "gauss_newton", "adaptive"]
    """Positive semi-definite Hessian used for barrier pairs far from the solution and whenever
    the solver projects: `exact`, `projected`, `gauss_newton` or `adaptive` (default:
    `adaptive`; `adaptive` and `gauss_newton` turn `projected` for the rest of a time step
    once Newton's steps keep being cut short or keep raising the residual there); near the
    solution (once Newton took a full step, see `NewtonSettings::definite_far_from_solution`)
    the pairs take their exact Hessian."""
    ccd: bool
    """Continuous collision detection in the line search (default: true). Without it only the
    barrier keeps pairs apart, which fast motion can tunnel through."""
    def __new__(cls, *, default_thickness_m: Optional[float] = ..., barrier: Literal["log", "cubic"] = ..., stiffness: Optional[float] = ..., min_distance_fraction: float = ..., max_stiffness_factor: float = ..., friction_stick_slide_threshold_m_s: float = ..., friction_iterations: int = ..., hessian: Literal["exact", "projected", "gauss_newton", "adaptive"] = ..., ccd: bool = ...) -> ContactSettings:
        """Defaults of the library, with the given fields replaced."""
    def to_dict(self) -> dict[str, Any]:
        """The fields as a plain dict (nested settings as nested dicts)."""
    def copy(self) -> ContactSettings:
        """A deep copy (nested settings are copied too)."""
    def __copy__(self) -> ContactSettings: ...
    def __deepcopy__(self, memo: Any) -> ContactSettings: ...

@final
class InertiaParams:
    """Lumped inertia of a deformable object."""
    density: float
    """Density per unit length, area or volume of the elements the mass is lumped from: kg/m,
    kg/m² or kg/m³ (default: 1)."""
    damping: float
    """Inertial damping `d`, 1/s: a drag force `−m d v` (default: 0)."""
    quasistatic: bool
    """Drop the kinetic terms: each step solves for static equilibrium (default: false)."""
    def __new__(cls, *, density: float = ..., damping: float = ..., quasistatic: bool = ...) -> InertiaParams:
        """Defaults of the library, with the given fields replaced."""
    def to_dict(self) -> dict[str, Any]:
        """The fields as a plain dict (nested settings as nested dicts)."""
    def copy(self) -> InertiaParams:
        """A deep copy (nested settings are copied too)."""
    def __copy__(self) -> InertiaParams: ...
    def __deepcopy__(self, memo: Any) -> InertiaParams: ...

@final
class TriangleStrainParams:
    """Membrane strain of a shell or cloth (Neo-Hookean triangles with strain limiting)."""
    thickness_m: float
    """Shell thickness, m (default: 1e-3)."""
    youngs_modulus: float
    """Young's modulus, Pa (default: 1e3)."""
    poissons_ratio: float
    """Poisson's ratio, unitless in (0, 0.5) (default: 0.3)."""
    damping: float
    """Strain-rate damping coefficient `c`, Pa·s (default: 0)."""
    strain_limit: float
    """Principal Green strain above which strain limiting acts, unitless (default: ∞, off)."""
    strain_limit_stiffness: float
    """Stiffness of the strain-limiting penalty, Pa (default: 1e3)."""
    inflation_pa: float
    """Inflation pressure, Pa, along the triangle normal `(x₁ − x₀) × (x₂ − x₀)` (default: 0)."""
    scale: float
    """Uniform scale of the rest shape, unitless (default: 1)."""
    def __new__(cls, *, thickness_m: float = ..., youngs_modulus: float = ..., poissons_ratio: float = ..., damping: float = ..., strain_limit: float = ..., strain_limit_stiffness: float = ..., inflation_pa: float = ..., scale: float = ...) -> TriangleStrainParams:
        """Defaults of the library, with the given fields replaced."""
    def to_dict(self) -> dict[str, Any]:
        """The fields as a plain dict (nested settings as nested dicts)."""
    def copy(self) -> TriangleStrainParams:
        """A deep copy (nested settings are copied too)."""
    def __copy__(self) -> TriangleStrainParams: ...
    def __deepcopy__(self, memo: Any) -> TriangleStrainParams: ...

@final
class TetStrainParams:
    """Volumetric strain of a solid (Stable Neo-Hookean tets with strain limiting)."""
    youngs_modulus: float
    """Young's modulus, Pa (default: 1e3)."""
    poissons_ratio: float
    """Poisson's ratio, unitless in (0, 0.5) (default: 0.3)."""
    damping: float
    """Strain-rate damping coefficient `c`, Pa·s (default: 0)."""
    strain_limit: float
    """Green strain above which the strain-limiting penalty acts, unitless (default: ∞, off)."""
    strain_limit_stiffness: float
    """Stiffness of the strain-limiting penalty, Pa (default: 1e3)."""
    scale: float
    """Uniform scale of the rest shape (growth or shrinkage), unitless (default: 1)."""
    def __new__(cls, *, youngs_modulus: float = ..., poissons_ratio: float = ..., damping: float = ..., strain_limit: float = ..., strain_limit_stiffness: float = ..., scale: float = ...) -> TetStrainParams:
        """Defaults of the library, with the given fields replaced."""
    def to_dict(self) -> dict[str, Any]:
        """The fields as a plain dict (nested settings as nested dicts)."""
    def copy(self) -> TetStrainParams:
        """A deep copy (nested settings are copied too)."""
    def __copy__(self) -> TetStrainParams: ...
    def __deepcopy__(self, memo: Any) -> TetStrainParams: ...

@final
class SegmentStrainParams:
    """Axial strain of a rod or cable made of segments."""
    section_radius_m: float
    """Radius of the circular cross-section, m (default: 5e-3)."""
    youngs_modulus: float
    """Young's modulus, Pa (default: 1e3)."""
    damping: float
    """Strain-rate damping coefficient `c`, Pa·s (default: 0)."""
    strain_limit: float
    """Strain above which strain limiting acts, unitless (default: ∞, off)."""
    strain_limit_stiffness: float
    """Stiffness of the strain-limiting penalty, Pa (default: 1e3)."""
    scale: float
    """Uniform scale of the rest length, unitless (default: 1)."""
    def __new__(cls, *, section_radius_m: float = ..., youngs_modulus: float = ..., damping: float = ..., strain_limit: float = ..., strain_limit_stiffness: float = ..., scale: float = ...) -> SegmentStrainParams:
        """Defaults of the library, with the given fields replaced."""
    def to_dict(self) -> dict[str, Any]:
        """The fields as a plain dict (nested settings as nested dicts)."""
    def copy(self) -> SegmentStrainParams:
        """A deep copy (nested settings are copied too)."""
    def __copy__(self) -> SegmentStrainParams: ...
    def __deepcopy__(self, memo: Any) -> SegmentStrainParams: ...

@final
class FlatBendingParams:
    """Quadratic bending towards the flat state (cloth)."""
    stiffness: float
    """Bending stiffness `k`, N·m (default: 1e-6)."""
    damping: float
    """Bending damping `c`, N·m·s (default: 0)."""
    def __new__(cls, *, stiffness: float = ..., damping: float = ...) -> FlatBendingParams:
        """Defaults of the library, with the given fields replaced."""
    def to_dict(self) -> dict[str, Any]:
        """The fields as a plain dict (nested settings as nested dicts)."""
    def copy(self) -> FlatBendingParams:
        """A deep copy (nested settings are copied too)."""
    def __copy__(self) -> FlatBendingParams: ...
    def __deepcopy__(self, memo: Any) -> FlatBendingParams: ...

@final
class DihedralBendingParams:
    """Discrete-shell bending towards the rest dihedral angles (curved shells)."""
    stiffness: float
    """Bending stiffness `k`, N·m (default: 1e-6)."""
    damping: float
    """Bending damping `c`, N·m·s (default: 0)."""
    def __new__(cls, *, stiffness: float = ..., damping: float = ...) -> DihedralBendingParams:
        """Defaults of the library, with the given fields replaced."""
    def to_dict(self) -> dict[str, Any]:
        """The fields as a plain dict (nested settings as nested dicts)."""
    def copy(self) -> DihedralBendingParams:
        """A deep copy (nested settings are copied too)."""
    def __copy__(self) -> DihedralBendingParams: ...
    def __deepcopy__(self, memo: Any) -> DihedralBendingParams: ...

@final
class PrescribedParams:
    """Prescribed positions: nodes pulled to targets by stiff springs hardened to a tolerance."""
    stiffness: float
    """Spring stiffness `k`, N/m (default: 1e3)."""
    tolerance_m: float
    """Largest allowed distance to the target after a step, m; exceeding it doubles the stiffness
    and repeats the step (default: ∞, no hardening)."""
    def __new__(cls, *, stiffness: float = ..., tolerance_m: float = ...) -> PrescribedParams:
        """Defaults of the library, with the given fields replaced."""
    def to_dict(self) -> dict[str, Any]:
        """The fields as a plain dict (nested settings as nested dicts)."""
    def copy(self) -> PrescribedParams:
        """A deep copy (nested settings are copied too)."""
    def __copy__(self) -> PrescribedParams: ...
    def __deepcopy__(self, memo: Any) -> PrescribedParams: ...

@final
class AttachmentParams:
    """Attachments between deformable objects: stiff springs hardened to a tolerance."""
    stiffness: float
    """Spring stiffness `k`, N/m (default: 1e3)."""
    tolerance_m: float
    """Largest allowed gap after a step, m; exceeding it doubles the stiffness and repeats the
    step (default: ∞, no hardening)."""
    def __new__(cls, *, stiffness: float = ..., tolerance_m: float = ...) -> AttachmentParams:
        """Defaults of the library, with the given fields replaced."""
    def to_dict(self) -> dict[str, Any]:
        """The fields as a plain dict (nested settings as nested dicts)."""
    def copy(self) -> AttachmentParams:
        """A deep copy (nested settings are copied too)."""
    def __copy__(self) -> AttachmentParams: ...
    def __deepcopy__(self, memo: Any) -> AttachmentParams: ...

@final
class RigidBodyParams:
    """Damping of a rigid body."""
    linear_damping_1_s: float
    """Linear velocity damping ("drag"), 1/s (default: 0)."""
    angular_damping_1_s: float
    """Angular velocity damping, 1/s (default: 0)."""
    def __new__(cls, *, linear_damping_1_s: float = ..., angular_damping_1_s: float = ...) -> RigidBodyParams:
        """Defaults of the library, with the given fields replaced."""
    def to_dict(self) -> dict[str, Any]:
        """The fields as a plain dict (nested settings as nested dicts)."""
    def copy(self) -> RigidBodyParams:
        """A deep copy (nested settings are copied too)."""
    def __copy__(self) -> RigidBodyParams: ...
    def __deepcopy__(self, memo: Any) -> RigidBodyParams: ...

@final
class JointParams:
    """Parameters common to the composite joints: the penalty stiffness of their hard
    constraints and the tolerances they are hardened to."""
    stiffness: float
    """Stiffness of the hard primitives, N/m (default: 1e6)."""
    tolerance_m: float
    """Tolerance of the point primitives, m (default: 1e-3)."""
    tolerance_deg: float
    """Tolerance of the direction primitives, degrees (default: 1)."""
    def __new__(cls, *, stiffness: float = ..., tolerance_m: float = ..., tolerance_deg: float = ...) -> JointParams:
        """Defaults of the library, with the given fields replaced."""
    def to_dict(self) -> dict[str, Any]:
        """The fields as a plain dict (nested settings as nested dicts)."""
    def copy(self) -> JointParams:
        """A deep copy (nested settings are copied too)."""
    def __copy__(self) -> JointParams: ...
    def __deepcopy__(self, memo: Any) -> JointParams: ...

@final
class LineMaterial:
    """Material of a rod or cable made of segments."""
    inertia: InertiaParams
    """Inertia (density in kg/m)."""
    strain: SegmentStrainParams
    """Axial strain."""
    contact_thickness_m: Optional[float]
    """Contact thickness, m; `None` uses `settings.contact.default_thickness_m` (default: none)."""
    def __new__(cls, *, inertia: InertiaParams = ..., strain: SegmentStrainParams = ..., contact_thickness_m: Optional[float] = ...) -> LineMaterial:
        """Defaults of the library, with the given fields replaced."""
    def to_dict(self) -> dict[str, Any]:
        """The fields as a plain dict (nested settings as nested dicts)."""
    def copy(self) -> LineMaterial:
        """A deep copy (nested settings are copied too)."""
    def __copy__(self) -> LineMaterial: ...
    def __deepcopy__(self, memo: Any) -> LineMaterial: ...
    @staticmethod
    def elastic_rubber_band() -> LineMaterial:
        """Elastic rubber band: 0.05 kg/m, r = 2 mm, E = 1e4 Pa, strain limit 10%."""

@final
class VolumeMaterial:
    """Material of a volumetric solid made of tetrahedra."""
    inertia: InertiaParams
    """Inertia (density in kg/m³)."""
    strain: TetStrainParams
    """Volumetric strain."""
    contact_thickness_m: Optional[float]
    """Contact thickness, m; `None` uses `settings.contact.default_thickness_m` (default: none)."""
    def __new__(cls, *, inertia: InertiaParams = ..., strain: TetStrainParams = ..., contact_thickness_m: Optional[float] = ...) -> VolumeMaterial:
        """Defaults of the library, with the given fields replaced."""
    def to_dict(self) -> dict[str, Any]:
        """The fields as a plain dict (nested settings as nested dicts)."""
    def copy(self) -> VolumeMaterial:
        """A deep copy (nested settings are copied too)."""
    def __copy__(self) -> VolumeMaterial: ...
    def __deepcopy__(self, memo: Any) -> VolumeMaterial: ...
    @staticmethod
    def soft_rubber() -> VolumeMaterial:
        """Soft rubber: 1000 kg/m³, E = 1e4 Pa, ν = 0.3, strain limit 100%, inertial damping 0.1/s."""

@final
class SurfaceMaterial:
    """Material of a shell or cloth made of triangles."""
    inertia: InertiaParams
    """Inertia (density in kg/m²)."""
    strain: TriangleStrainParams
    """Membrane strain."""
    bending: Union[FlatBendingParams, DihedralBendingParams, None]
    """Bending: none, flat (cloth, towards the flat state) or dihedral (curved shells, towards
    the rest shape) (default: flat)."""
    contact_thickness_m: Optional[float]
    """Contact thickness, m; `None` uses `settings.contact.default_thickness_m` (default: none)."""
    def __new__(cls, *, inertia: InertiaParams = ..., strain: TriangleStrainParams = ..., bending: Union[FlatBendingParams, DihedralBendingParams, None] = ..., contact_thickness_m: Optional[float] = ...) -> SurfaceMaterial:
        """Defaults of the library, with the given fields replaced."""
    def to_dict(self) -> dict[str, Any]:
        """The fields as a plain dict (nested settings as nested dicts)."""
    def copy(self) -> SurfaceMaterial:
        """A deep copy (nested settings are copied too)."""
    def __copy__(self) -> SurfaceMaterial: ...
    def __deepcopy__(self, memo: Any) -> SurfaceMaterial: ...
    @staticmethod
    def cotton_fabric() -> SurfaceMaterial:
        """Cotton fabric: 0.2 kg/m², 1 mm thick, E = 5e3 Pa, ν = 0.3, strain limit 10%, flat bending 1e-6 N·m."""

# </generated>

# ------------------------------------------------------------------------------------------
# Handles: small immutable objects naming a part of one simulation.
# ------------------------------------------------------------------------------------------

@final
class NodeSet:
    """A contiguous range of nodes: one object's nodes."""
    @property
    def index(self) -> int:
        """Index of the set."""
    @property
    def first(self) -> int:
        """First node in the simulation's node arrays."""
    @property
    def len(self) -> int:
        """Number of nodes."""
    def __len__(self) -> int: ...

@final
class InertiaHandle:
    """The lumped inertia of one deformable object (`sim.params(h)`, `sim.mass(h)`)."""
    @property
    def index(self) -> int:
        """Index of the group in its model."""

@final
class TriangleStrainHandle:
    """The membrane strain of one surface (`sim.params(h)` is a `TriangleStrainParams`)."""
    @property
    def index(self) -> int:
        """Index of the group in its model."""

@final
class TetStrainHandle:
    """The tet strain of one volume (`sim.params(h)` is a `TetStrainParams`)."""
    @property
    def index(self) -> int:
        """Index of the group in its model."""

@final
class SegmentStrainHandle:
    """The segment strain of one line (`sim.params(h)` is a `SegmentStrainParams`)."""
    @property
    def index(self) -> int:
        """Index of the group in its model."""

@final
class FlatBendingHandle:
    """The flat bending of one surface (`sim.params(h)` is a `FlatBendingParams`)."""
    @property
    def index(self) -> int:
        """Index of the group in its model."""

@final
class DihedralBendingHandle:
    """The dihedral bending of one surface (`sim.params(h)` is a `DihedralBendingParams`)."""
    @property
    def index(self) -> int:
        """Index of the group in its model."""

@final
class PrescribedHandle:
    """A group of prescribed nodes (move it with `sim.set_transform(h, ...)`)."""
    @property
    def index(self) -> int:
        """Index of the group in its model."""

@final
class ContactHandle:
    """A contact object (`sim.set_friction(a, b, mu)`, `sim.disable_collision(a, b)`)."""
    @property
    def index(self) -> int:
        """Index of the group in its model."""

@final
class AttachmentHandle:
    """A group of attachments (`sim.attachment_gap(h)`)."""
    @property
    def kind(self) -> str:
        """"point_point", "point_edge" or "point_triangle"."""
    @property
    def index(self) -> int:
        """Index of the group among those of its kind."""

@final
class RigidBody:
    """A rigid body (joints, presets and attachments take it, or a RigidMesh, RigidObject or
    SceneRigidBody of it)."""
    @property
    def index(self) -> int:
        """Index of the body."""
    @property
    def label(self) -> str:
        """Its label."""

@final
class RigidMesh:
    """The collision mesh of a rigid body: its vertices are nodes that move with the body."""
    @property
    def body(self) -> RigidBody:
        """The body."""
    @property
    def nodes(self) -> NodeSet:
        """Its vertices in the node arrays."""
    @property
    def contact(self) -> ContactHandle:
        """Its contact object."""

@final
class RigidAttachmentHandle:
    """A group of deformable nodes glued to a rigid body (`attach_to_body`)."""
    @property
    def index(self) -> int:
        """Index of the group in its model."""

@final
class Robot:
    """A robot in a simulation: its bodies and joints by URDF name."""
    @property
    def name(self) -> str:
        """Its name (its bodies and joints are labelled `<name>/<link>` and `<name>/<joint>`)."""
    @property
    def links(self) -> dict[str, Optional[RigidBody]]:
        """The body of every link (links merged by fixed joints share one; None for links merged
        into the world by a fixed base)."""
    @property
    def joints(self) -> dict[str, Joint]:
        """The main joint of every URDF joint that became one (hinge, prismatic, actuator, ...)."""
    @property
    def extra_joints(self) -> list[Joint]:
        """The other joints it made: limits, mimic couplings, damping, springs, fix joints."""

@final
class RigidObject:
    """A rigid body made by a preset (`add_box`, ...): the body and its collision mesh."""
    @property
    def body(self) -> RigidBody:
        """The body."""
    @property
    def mesh(self) -> RigidMesh:
        """Its collision mesh."""

@final
class Joint:
    """A joint: returned by the `Simulation.add_*` joint methods and taken by the joint setters
    and `joint_state`."""
    @property
    def label(self) -> str:
        """Its label."""
    @property
    def has_driver(self) -> bool:
        """Whether it has a driver (motor, press, velocity controller, servo or spring)."""
    @property
    def has_coordinate(self) -> bool:
        """Whether it has a coordinate (a hinge angle or a slider position)."""

@final
class JointState:
    """A joint's state at the last accepted step (`Simulation.joint_state`)."""
    @property
    def violation_m(self) -> float:
        """Largest violation of its length constraints, m."""
    @property
    def violation_rad(self) -> float:
        """Largest violation of its angle constraints, rad."""
    @property
    def force_on_b_n(self) -> list[float]:
        """Total force of the joint on body b (world frame), N."""
    @property
    def torque_on_b_n_m(self) -> list[float]:
        """Total torque of the joint on body b about its centre of mass, N·m."""
    @property
    def driver_effort(self) -> float:
        """Its driver's effort: torque (N·m) or force (N) along the driver's axis for motors, presses,
        velocity controllers and servos (positive when driving b along +axis); a spring's tension (N)."""
    @property
    def coordinate(self) -> Optional[float]:
        """Its coordinate: hinge angle (rad) or slider position (m), or None."""
    @property
    def coordinate_rate(self) -> Optional[float]:
        """Rate of its coordinate, rad/s or m/s, or None."""

@final
class Surface:
    """A shell or cloth added by `add_surface` or `add_surface_grid`."""
    @property
    def label(self) -> str:
        """Its label."""
    @property
    def nodes(self) -> NodeSet:
        """Its nodes."""
    @property
    def inertia(self) -> InertiaHandle:
        """Its inertia."""
    @property
    def strain(self) -> TriangleStrainHandle:
        """Its membrane strain."""
    @property
    def bending(self) -> Union[FlatBendingHandle, DihedralBendingHandle, None]:
        """Its bending: a FlatBendingHandle, a DihedralBendingHandle or None."""
    @property
    def contact(self) -> Optional[ContactHandle]:
        """Its contact object, if it has a contact thickness."""

@final
class Volume:
    """A solid added by `add_volume` or `add_volume_grid`."""
    @property
    def label(self) -> str:
        """Its label."""
    @property
    def nodes(self) -> NodeSet:
        """Its nodes."""
    @property
    def inertia(self) -> InertiaHandle:
        """Its inertia."""
    @property
    def strain(self) -> TetStrainHandle:
        """Its tet strain."""
    @property
    def contact(self) -> Optional[ContactHandle]:
        """Its contact object (its boundary surface), if it has a contact thickness."""

@final
class Line:
    """A rod or cable added by `add_line` or `add_line_segments`."""
    @property
    def label(self) -> str:
        """Its label."""
    @property
    def nodes(self) -> NodeSet:
        """Its nodes."""
    @property
    def inertia(self) -> InertiaHandle:
        """Its inertia."""
    @property
    def strain(self) -> SegmentStrainHandle:
        """Its segment strain."""
    @property
    def contact(self) -> Optional[ContactHandle]:
        """Its contact object, if it has a contact thickness."""

@final
class FixedSurface:
    """A surface fixed in the world, added by `add_fixed_surface`."""
    @property
    def label(self) -> str:
        """Its label."""
    @property
    def nodes(self) -> NodeSet:
        """Its nodes."""
    @property
    def contact(self) -> ContactHandle:
        """Its contact object."""

@final
class Obstacle:
    """A kinematic obstacle added by `add_prescribed_surface`: move it with `sim.set_transform(obstacle, ...)`."""
    @property
    def label(self) -> str:
        """Its label."""
    @property
    def nodes(self) -> NodeSet:
        """Its nodes."""
    @property
    def prescribed(self) -> PrescribedHandle:
        """The prescribed positions moving it."""
    @property
    def contact(self) -> ContactHandle:
        """Its contact object."""

@final
class SceneRigidBody:
    """A `[[rigid_body]]` of a scene file: the body, the nodes of its mesh and its contact object.
    Functions taking a body, a node set or a contact object take it too."""
    @property
    def label(self) -> str:
        """Its label (the entry's name)."""
    @property
    def body(self) -> RigidBody:
        """The body."""
    @property
    def nodes(self) -> NodeSet:
        """The vertices of its mesh (they move with the body)."""
    @property
    def contact(self) -> Optional[ContactHandle]:
        """Its contact object, if it takes part in contact."""

_HasNodes = Union[NodeSet, Surface, Volume, Line, Obstacle, FixedSurface, RigidMesh, SceneRigidBody]
"""A node set, or any object handle with one."""
_HasContact = Union[ContactHandle, Surface, Volume, Line, Obstacle, FixedSurface, RigidMesh, SceneRigidBody]
"""A contact object, or any object handle with one."""
_HasPrescribed = Union[PrescribedHandle, Obstacle]
"""Prescribed positions, or an obstacle."""
_HasBody = Union[RigidBody, RigidMesh, RigidObject, SceneRigidBody]
"""A rigid body, or any object handle with one (its collision mesh, a preset's object, a scene's body)."""
_ModelHandle = Union[
    InertiaHandle,
    TriangleStrainHandle,
    TetStrainHandle,
    SegmentStrainHandle,
    FlatBendingHandle,
    DihedralBendingHandle,
    PrescribedHandle,
    RigidBody,
    AttachmentHandle,
    RigidAttachmentHandle,
]
"""A handle whose parameters `Simulation.params` reads and `Simulation.set_params` writes."""
_ModelParams = Union[
    InertiaParams,
    TriangleStrainParams,
    TetStrainParams,
    SegmentStrainParams,
    FlatBendingParams,
    DihedralBendingParams,
    PrescribedParams,
    RigidBodyParams,
    AttachmentParams,
]
"""The parameters matching a `_ModelHandle`."""

@final
class MassProperties:
    """Mass, centre of mass and inertia tensor of a solid with uniform density."""
    def __new__(cls, mass_kg: float, center_of_mass_m: _Vector, inertia_kg_m2: ArrayLike) -> MassProperties: ...
    @staticmethod
    def cuboid(mass_kg: float, size_m: _Vector) -> MassProperties:
        """Solid box of `mass_kg` with side lengths `size_m`, centred at the origin."""
    @staticmethod
    def sphere(mass_kg: float, radius_m: float) -> MassProperties:
        """Solid sphere of `mass_kg` and radius `radius_m`."""
    @staticmethod
    def cylinder(mass_kg: float, radius_m: float, height_m: float) -> MassProperties:
        """Solid cylinder of `mass_kg`, `radius_m` and `height_m` along z, centred."""
    @staticmethod
    def torus(mass_kg: float, major_radius_m: float, minor_radius_m: float) -> MassProperties:
        """Solid torus in the xy plane: `major_radius_m` (to the centre of the tube) and `minor_radius_m` (of the tube)."""
    @staticmethod
    def from_mesh(vertices_m: _Points, triangles: _Indices, density_kg_m3: float) -> MassProperties:
        """A closed, outward-oriented triangle mesh of uniform density (kg/m³)."""
    @property
    def mass_kg(self) -> float:
        """Mass, kg."""
    @property
    def center_of_mass_m(self) -> NDArray[np.float64]:
        """Centre of mass in the input frame, m (zero for the centred primitives)."""
    @property
    def inertia_kg_m2(self) -> NDArray[np.float64]:
        """Inertia tensor about the centre of mass, kg·m², (3, 3)."""

# ------------------------------------------------------------------------------------------
# The simulation
# ------------------------------------------------------------------------------------------

@final
class Simulation:
    """A simulation: objects, energies, settings and the time loop.

    `Simulation(settings=None)` starts empty with `Settings()` defaults. Add objects with the
    `add_*` methods (they return handles), then `step()` or `run(duration)`. `step` and `run`
    release the GIL while solving; other threads calling methods meanwhile get a `StarkError`.
    """

    def __new__(cls, settings: Optional[Settings] = None) -> Simulation: ...
    @property
    def settings(self) -> Settings:
        """A copy of the settings; assign a changed copy back. Changes take effect at the next step."""
    @settings.setter
    def settings(self, settings: Settings) -> None: ...
    @property
    def time(self) -> float:
        """Simulated time, s."""
    @property
    def dt(self) -> float:
        """Current time step, s (below settings.time_step_s after failures)."""
    @property
    def gravity(self) -> NDArray[np.float64]:
        """Gravity, m/s² (a (3,) array); assigning takes effect at the next step."""
    @gravity.setter
    def gravity(self, g: _Vector) -> None: ...
    @property
    def num_nodes(self) -> int:
        """Number of nodes (deformable nodes and rigid collision-mesh vertices)."""
    @property
    def num_rigid_bodies(self) -> int:
        """Number of rigid bodies."""
    @property
    def contact_stiffness(self) -> float:
        """Current barrier stiffness κ, N/m (0 before the first step)."""
    def summary(self) -> _Report:
        """Totals so far (steps, Newton iterations, residuals, wall time, frames ...) as a dict."""
    def state_check(self) -> dict[str, Any]:
        """An independent check of the current state, as `stark run --check` makes after every step:
        a dict with `intersections` (every contact edge crossing a contact triangle, described)
        and `inverted_tets` (their count)."""

    # Time stepping
    def step(self) -> _Report:
        """Advance by one accepted time step; returns the step report as a dict."""
    def run_one_step(self) -> _Report:
        """The same as `step()` (the original's name)."""
    def run(
        self, duration: float, callback: Optional[Callable[[Simulation], Any]] = None, progress: bool = False
    ) -> _Report:
        """Simulate `duration` more seconds, calling `callback(sim)` before every step if given.

        The GIL is released while solving; Ctrl-C stops the run between steps (KeyboardInterrupt);
        an exception raised by a callback stops the run and is re-raised. With `progress=True` a
        progress bar is drawn on `sys.stderr`. The last step is shortened to land on the end
        time. Returns the run summary.
        """
    def save_checkpoint(self, path: Union[str, os.PathLike[str]]) -> None:
        """Write a checkpoint of the whole state the next step depends on (postcard, versioned)."""
    def restore_checkpoint(self, path: Union[str, os.PathLike[str]]) -> None:
        """Restore a checkpoint into this freshly built, not yet stepped simulation of the same scene.

        Scene files rebuild their time events; closures added with `add_time_event` must be added
        again before restoring. Another scene, a truncated file or another format version raise
        `StarkError`.
        """
    def add_time_event(self, t0: float, t1: float, action: Callable[[Simulation, float], Any]) -> None:
        """Run `action(sim, t)` before every step whose end time `t` lies in `[t0, t1)`."""
    def add_spawn(self, time_s: float, label: str, action: Callable[[Simulation], Any]) -> None:
        """Add objects during the run: `action(sim)` runs once when the time first reaches `time_s`.

        It runs right after the step that reaches `time_s` (before the first step when
        `time_s <= 0`). What it adds must not intersect anything. `restore_checkpoint` fires the
        spawns due by the checkpoint's time first: add the same spawns before restoring.
        """
    def spawns(self) -> list[tuple[float, str, bool]]:
        """Spawns added with `add_spawn`: `(time_s, label, fired)`."""
    def add_energy(
        self,
        name: str,
        element_nodes: Any,
        elements: Optional[ArrayLike],
        fn: Callable[[sym.Nodes, sym.Nodes, sym.Expr, sym.Params], Any],
        params: Optional[dict[str, ArrayLike]] = None,
    ) -> sym.EnergyHandle:
        """Add your own energy written with `starkrs.sym`: `fn(x, v, dt, p)` is called once with
        symbolic node positions and velocities (`x[a]`, `v[a]`), the step and the parameters and
        returns the element's energy in J; it is differentiated and compiled to native code.
        `element_nodes`: node indices, node sets (or objects) and `(body, local_point_m)` rigid
        points; `elements`: index lists into them (1 to 4 nodes), or None for one per node;
        `params`: name → number, 3-vector or per-element array."""
    def set_energy_params(self, energy: sym.EnergyHandle, params: dict[str, ArrayLike]) -> None:
        """Change parameters of an `add_energy` energy (from the next step)."""
    def energy_params(self, energy: sym.EnergyHandle) -> dict[str, NDArray[np.float64]]:
        """An `add_energy` energy's parameter values per element (`m[0]`, `m[1]`, `m[2]` for a vector)."""
    def write_frame(self) -> list[str]:
        """Write one frame of every output mesh now (VTU, or legacy VTK per `settings.output.frame_format`); returns the file paths."""

    # Nodes
    def add_nodes(self, label: str, positions: _Points) -> NodeSet:
        """Add bare nodes (no energy) at `positions` (n, 3) as a labelled object."""
    def node_set(self, label: str) -> Optional[NodeSet]:
        """The node set labelled `label`, or None."""
    def node_set_labels(self) -> list[str]:
        """Labels of all node sets (objects and collision meshes), in creation order."""
    def positions(self, nodes: _HasNodes) -> NDArray[np.float64]:
        """Positions of an object's nodes, m: a new (n, 3) array."""
    def velocities(self, nodes: _HasNodes) -> NDArray[np.float64]:
        """Velocities of an object's nodes, m/s: a new (n, 3) array."""
    def rest_positions(self, nodes: _HasNodes) -> NDArray[np.float64]:
        """Rest positions of an object's nodes, m (body-frame positions for a rigid collision mesh)."""
    def forces(self, nodes: _HasNodes) -> NDArray[np.float64]:
        """External forces on an object's nodes, N."""
    def masses(self, nodes: _HasNodes) -> NDArray[np.float64]:
        """Lumped masses of an object's nodes, kg: a new (n,) array."""
    def set_positions(self, nodes: _HasNodes, positions: _Points) -> None:
        """Move an object's nodes to `positions` (n, 3), m (deformable objects only)."""
    def set_velocities(self, nodes: _HasNodes, velocities: Union[_Points, _Vector]) -> None:
        """Set the velocities of an object's nodes, m/s: an (n, 3) array or one (3,) vector for all."""
    def set_velocity(self, nodes: _HasNodes, velocity: _Vector) -> None:
        """Set the velocity of every node of an object, m/s."""
    def set_forces(self, nodes: _HasNodes, forces: Union[_Points, _Vector]) -> None:
        """Set the external forces on an object's nodes, N (persist until changed)."""
    def set_accelerations(self, nodes: _HasNodes, accelerations: Union[_Points, _Vector]) -> None:
        """Set the external accelerations of an object's nodes (added to gravity), m/s²."""

    # Deformable objects
    def add_surface(self, label: str, vertices: _Points, triangles: _Indices, material: SurfaceMaterial) -> Surface:
        """A shell or cloth from vertices (n, 3) and triangles (m, 3)."""
    def add_surface_grid(
        self, label: str, size: tuple[float, float], quads: tuple[int, int], material: SurfaceMaterial
    ) -> Surface:
        """A rectangular cloth of `size` (m) in the XY plane centred at the origin, `quads` per side."""
    def add_volume(self, label: str, vertices: _Points, tets: _Indices, material: VolumeMaterial) -> Volume:
        """A solid from vertices (n, 3) and tets (m, 4)."""
    def add_volume_grid(
        self, label: str, size: tuple[float, float, float], hexes: tuple[int, int, int], material: VolumeMaterial
    ) -> Volume:
        """A box of `size` (m) centred at the origin, `hexes` cells per side, 12 tets per cell."""
    def add_line(self, label: str, vertices: _Points, segments: _Indices, material: LineMaterial) -> Line:
        """A rod or cable from vertices (n, 3) and segments (m, 2)."""
    def add_line_segments(
        self, label: str, begin: _Vector, end: _Vector, n_segments: int, material: LineMaterial
    ) -> Line:
        """A straight line of `n_segments` from `begin` to `end`."""
    def add_prescribed_surface(
        self, label: str, vertices: _Points, triangles: _Indices, thickness_m: float, stiffness: float = 1e6
    ) -> Obstacle:
        """A kinematic obstacle: a triangle surface whose nodes all follow prescribed targets."""
    def add_fixed_surface(self, label: str, vertices: _Points, triangles: _Indices, thickness_m: float) -> FixedSurface:
        """A contact surface fixed in the world: its nodes never move and are not unknowns of the solve."""
    def prescribe_in_box(
        self, nodes: _HasNodes, center: _Vector, size: _Vector, params: Optional[PrescribedParams] = None
    ) -> PrescribedHandle:
        """Prescribe the nodes of an object inside the axis-aligned box of `center` and full `size` (m)."""
    def prescribe_outside_box(
        self, nodes: _HasNodes, center: _Vector, size: _Vector, params: Optional[PrescribedParams] = None
    ) -> PrescribedHandle:
        """Prescribe the nodes of an object outside the axis-aligned box of `center` and `size` (m)."""
    def prescribe_nodes(
        self, nodes: _HasNodes, indices: _Indices, params: Optional[PrescribedParams] = None
    ) -> PrescribedHandle:
        """Prescribe the nodes `indices` (local to the object); targets start at their positions."""
    def set_transform(
        self, prescribed: _HasPrescribed, translation: _Vector, rotation: Optional[_Rotation] = None
    ) -> None:
        """Targets become `R·p + translation` for the reference positions `p`."""
    def set_transform_deg(self, prescribed: _HasPrescribed, translation: _Vector, angle_deg: float, axis: _Vector) -> None:
        """`set_transform` with a rotation by `angle_deg` about `axis` through the origin."""
    def set_target(self, prescribed: _HasPrescribed, i: int, target: _Vector) -> None:
        """Set the target of the `i`-th node of a prescribed group, m."""
    def targets(self, prescribed: _HasPrescribed) -> NDArray[np.float64]:
        """Targets of a prescribed group, m: a new (n, 3) array."""
    def prescribed_nodes(self, prescribed: _HasPrescribed) -> list[int]:
        """Global node indices of a prescribed group."""
    def max_violation(self, prescribed: _HasPrescribed) -> float:
        """Largest distance of a prescribed group's nodes to their targets, m."""
    def mass(self, inertia: Union[InertiaHandle, Surface, Volume, Line]) -> float:
        """Total mass of an object's inertia group, kg."""
    def count_inverted_tets(self) -> int:
        """Number of inverted tets at the current positions."""

    # Parameters of any model
    @overload
    def params(self, handle: InertiaHandle) -> InertiaParams:
        """The parameters of a handle (a copy: change it and `set_params` it back)."""
    @overload
    def params(self, handle: TriangleStrainHandle) -> TriangleStrainParams: ...
    @overload
    def params(self, handle: TetStrainHandle) -> TetStrainParams: ...
    @overload
    def params(self, handle: SegmentStrainHandle) -> SegmentStrainParams: ...
    @overload
    def params(self, handle: FlatBendingHandle) -> FlatBendingParams: ...
    @overload
    def params(self, handle: DihedralBendingHandle) -> DihedralBendingParams: ...
    @overload
    def params(self, handle: PrescribedHandle) -> PrescribedParams: ...
    @overload
    def params(self, handle: RigidBody) -> RigidBodyParams: ...
    @overload
    def params(self, handle: Union[AttachmentHandle, RigidAttachmentHandle]) -> AttachmentParams: ...
    def set_params(self, handle: _ModelHandle, params: _ModelParams) -> None:
        """Replace the parameters of a handle (checked: raises StarkError naming the field)."""

    # Attachments
    def add_attachment_point_point(
        self,
        label: str,
        a: _HasNodes,
        points_a: _Indices,
        b: _HasNodes,
        points_b: _Indices,
        params: Optional[AttachmentParams] = None,
    ) -> AttachmentHandle:
        """Glue node `points_a[i]` of `a` to node `points_b[i]` of `b`."""
    def add_attachment_point_edge(
        self,
        label: str,
        a: _HasNodes,
        points: _Indices,
        b: _HasNodes,
        edges: _Indices,
        edge_parameters: ArrayLike,
        params: Optional[AttachmentParams] = None,
    ) -> AttachmentHandle:
        """Glue node `points[i]` of `a` to the point `(1 − t) e0 + t e1` of edge `edges[i]` of `b`."""
    def add_attachment_point_triangle(
        self,
        label: str,
        a: _HasNodes,
        points: _Indices,
        b: _HasNodes,
        triangles: _Indices,
        barycentric: _Points,
        params: Optional[AttachmentParams] = None,
    ) -> AttachmentHandle:
        """Glue node `points[i]` of `a` to the point with barycentric coordinates `barycentric[i]` of `triangles[i]`."""
    def attachment_gap(self, attachment: AttachmentHandle) -> float:
        """Largest gap of an attachment group at the current positions, m."""

    # Contact
    def contact_objects(self) -> list[ContactHandle]:
        """All contact objects, in creation order."""
    def contact_object(self, label: str) -> Optional[ContactHandle]:
        """The contact object labelled `label`, or None."""
    def contact_label(self, contact: _HasContact) -> str:
        """Label of a contact object."""
    def contact_thickness(self, contact: _HasContact) -> float:
        """Contact thickness of an object, m."""
    def set_contact_thickness(self, contact: _HasContact, thickness_m: float) -> None:
        """Change an object's contact thickness, m."""
    def set_friction(self, a: _HasContact, b: _HasContact, mu: float) -> None:
        """Friction coefficient μ between two objects (`a` = `b`: self-friction); unset pairs have 0."""
    def friction(self, a: _HasContact, b: _HasContact) -> float:
        """Friction coefficient between two objects."""
    def set_collision(self, a: _HasContact, b: _HasContact, enabled: bool) -> None:
        """Switch collisions between two objects (`a` = `b`: self-collision) on or off."""
    def disable_collision(self, a: _HasContact, b: _HasContact) -> None:
        """Switch collisions between two objects off."""
    def contact_stats(self) -> _Report:
        """Contact statistics of the last step (active pairs, smallest distance, κ, CCD) as a dict."""
    def find_intersections(self) -> list[str]:
        """Descriptions of all intersecting edge–triangle pairs of the contact surfaces now."""

    # Rigid bodies
    def add_rigid_body(
        self,
        label: str,
        mass_kg: float,
        inertia_kg_m2: ArrayLike,
        position_m: Optional[_Vector] = None,
        orientation: Optional[_Rotation] = None,
    ) -> RigidBody:
        """Add a rigid body of `mass_kg` and body-frame inertia tensor `inertia_kg_m2` (3, 3); it starts at rest."""
    def add_rigid_body_with(
        self,
        label: str,
        mass_properties: MassProperties,
        position_m: Optional[_Vector] = None,
        orientation: Optional[_Rotation] = None,
    ) -> RigidBody:
        """Add a rigid body from its mass properties; its centre of mass goes to `position_m`."""
    def add_rigid_collision_mesh(
        self, body: _HasBody, local_vertices_m: _Points, triangles: _Indices, thickness_m: Optional[float] = None
    ) -> RigidMesh:
        """Give a body a collision mesh (vertices in the body frame, relative to its centre of mass)."""
    def rigid_body(self, label: str) -> Optional[RigidBody]:
        """The rigid body labelled `label`, or None."""
    def rigid_bodies(self) -> list[RigidBody]:
        """All rigid bodies, in creation order."""
    def body_states(self) -> dict[str, dict[str, list[float]]]:
        """Every body's pose and velocity by label: dicts with `position_m`, `orientation_wxyz`,
        `velocity_m_s` and `angular_velocity_rad_s` (world frame), as in the body log."""
    def body_collision_meshes(self, body: _HasBody) -> list[ContactHandle]:
        """The contact objects of a body's collision meshes, in the order they were added."""
    def body_position(self, body: _HasBody) -> NDArray[np.float64]:
        """Centre of mass of a body, m."""
    def body_orientation(self, body: _HasBody) -> NDArray[np.float64]:
        """Orientation of a body (body → world) as a quaternion (w, x, y, z)."""
    def body_rotation(self, body: _HasBody) -> NDArray[np.float64]:
        """Rotation matrix of a body (body → world), (3, 3)."""
    def body_velocity(self, body: _HasBody) -> NDArray[np.float64]:
        """Linear velocity of a body's centre of mass, m/s."""
    def body_angular_velocity(self, body: _HasBody) -> NDArray[np.float64]:
        """Angular velocity of a body (world frame), rad/s."""
    def body_angular_momentum(self, body: _HasBody) -> NDArray[np.float64]:
        """Angular momentum of a body about its centre of mass (world), kg·m²/s."""
    def body_mass(self, body: _HasBody) -> float:
        """Mass of a body, kg."""
    def body_inertia(self, body: _HasBody) -> NDArray[np.float64]:
        """Body-frame inertia tensor of a body about its centre of mass, kg·m², (3, 3)."""
    def body_force(self, body: _HasBody) -> NDArray[np.float64]:
        """External force on a body's centre of mass, N."""
    def body_torque(self, body: _HasBody) -> NDArray[np.float64]:
        """External torque on a body, N·m."""
    def body_point_to_world(self, body: _HasBody, points_m: Union[_Vector, _Points]) -> NDArray[np.float64]:
        """World positions of body-frame points: (3,) → (3,), (n, 3) → (n, 3)."""
    def body_point_to_local(self, body: _HasBody, points_m: Union[_Vector, _Points]) -> NDArray[np.float64]:
        """Body-frame coordinates of world points: (3,) → (3,), (n, 3) → (n, 3)."""
    def body_direction_to_world(self, body: _HasBody, directions: Union[_Vector, _Points]) -> NDArray[np.float64]:
        """World directions of body-frame directions."""
    def body_direction_to_local(self, body: _HasBody, directions: Union[_Vector, _Points]) -> NDArray[np.float64]:
        """Body-frame directions of world directions."""
    def body_velocity_at(self, body: _HasBody, points_m: Union[_Vector, _Points]) -> NDArray[np.float64]:
        """Velocities of world points moving with the body, m/s."""
    def set_body_pose(self, body: _HasBody, position_m: _Vector, orientation: Optional[_Rotation] = None) -> None:
        """Move a body: centre of mass to `position_m`, orientation to `orientation` (default: unchanged); its meshes follow."""
    def set_body_velocity(self, body: _HasBody, velocity_m_s: _Vector) -> None:
        """Set the linear velocity of a body's centre of mass, m/s."""
    def set_body_angular_velocity(self, body: _HasBody, angular_velocity_rad_s: _Vector) -> None:
        """Set the angular velocity of a body (world frame), rad/s."""
    def set_body_force(self, body: _HasBody, force_n: _Vector) -> None:
        """Set the external force at a body's centre of mass (persists until changed), N."""
    def set_body_torque(self, body: _HasBody, torque_n_m: _Vector) -> None:
        """Set the external torque on a body (persists until changed), N·m."""
    def add_body_force_at(self, body: _HasBody, force_n: _Vector, at_m: _Vector) -> None:
        """Add a force `force_n` applied at the world point `at_m` (a force plus the torque (at − c) × f)."""
    def set_body_acceleration(self, body: _HasBody, acceleration_m_s2: _Vector) -> None:
        """Set the external acceleration of a body (added to gravity; persists), m/s²."""
    def set_body_angular_acceleration(self, body: _HasBody, angular_acceleration_rad_s2: _Vector) -> None:
        """Set the external angular acceleration of a body (persists), rad/s²."""
    def set_body_mass(self, body: _HasBody, mass_kg: float, inertia_kg_m2: ArrayLike) -> None:
        """Change the mass (kg) and body-frame inertia tensor (kg·m², (3, 3)) of a body."""

    # ---- Joints (body a None: the world; points and axes in world coordinates, now) ----
    def add_ball_joint(
        self, label: str, a: Optional[_HasBody], b: _HasBody, point_m: _Vector, params: Optional[JointParams] = None
    ) -> Joint:
        """Ball joint: body b's point at `point_m` (world, now) stays on a's (or the world's)."""
    def add_ball_joint_with_cone_limit(
        self, label: str, a: Optional[_HasBody], b: _HasBody, point_m: _Vector, direction: _Vector, limit_deg: float,
        params: Optional[JointParams] = None,
    ) -> Joint:
        """Ball joint whose `direction` (fixed in both bodies) may tilt by at most `limit_deg`."""
    def add_point_on_axis_joint(
        self, label: str, a: Optional[_HasBody], b: _HasBody, point_m: _Vector, axis: _Vector,
        params: Optional[JointParams] = None,
    ) -> Joint:
        """Body b's point at `point_m` stays on the line through it along `axis` fixed in a."""
    def add_distance_joint(
        self, label: str, a: Optional[_HasBody], b: _HasBody, point_a_m: _Vector, point_b_m: _Vector,
        params: Optional[JointParams] = None,
    ) -> Joint:
        """The distance between a's point `point_a_m` and b's point `point_b_m` stays what it is now."""
    def add_distance_limits(
        self, label: str, a: Optional[_HasBody], b: _HasBody, point_a_m: _Vector, point_b_m: _Vector, min_m: float,
        max_m: float, params: Optional[JointParams] = None,
    ) -> Joint:
        """The distance between the two points stays within `[min_m, max_m]`."""
    def add_spring(
        self, label: str, a: Optional[_HasBody], b: _HasBody, point_a_m: _Vector, point_b_m: _Vector,
        stiffness_n_m: float, damping_n_s_m: float = 0.0, limits_m: Optional[tuple[float, float]] = None,
        params: Optional[JointParams] = None,
    ) -> Joint:
        """Damped spring between the two points (rest length: their distance now), optionally limited."""
    def add_direction_joint(
        self, label: str, a: Optional[_HasBody], b: _HasBody, direction: _Vector, params: Optional[JointParams] = None
    ) -> Joint:
        """`direction` (world, now) stays the same in both bodies."""
    def add_angle_limit(
        self, label: str, a: Optional[_HasBody], b: _HasBody, direction: _Vector, limit_deg: float,
        params: Optional[JointParams] = None,
    ) -> Joint:
        """The angle between `direction` in a and in b stays below `limit_deg`."""
    def add_fix_joint(self, label: str, body: _HasBody, params: Optional[JointParams] = None) -> Joint:
        """Fix a body to the world where it is; `set_fixed_transform` then drives it kinematically."""
    def add_attachment_joint(self, label: str, a: _HasBody, b: _HasBody, params: Optional[JointParams] = None) -> Joint:
        """Glue body b to body a in their current relative pose."""
    def add_hinge_joint(
        self, label: str, a: Optional[_HasBody], b: _HasBody, point_m: _Vector, axis: _Vector,
        params: Optional[JointParams] = None,
    ) -> Joint:
        """Hinge about `axis` through `point_m` (world, now)."""
    def add_hinge_joint_with_limit(
        self, label: str, a: Optional[_HasBody], b: _HasBody, point_m: _Vector, axis: _Vector, limit_deg: float,
        params: Optional[JointParams] = None,
    ) -> Joint:
        """Hinge that turns at most `limit_deg` either way from its current angle."""
    def add_universal_joint(
        self, label: str, a: Optional[_HasBody], b: _HasBody, point_m: _Vector, axis_a: _Vector, axis_b: _Vector,
        params: Optional[JointParams] = None,
    ) -> Joint:
        """Universal (Cardan) joint at `point_m`: `axis_a` (in a) stays perpendicular to `axis_b` (in b)."""
    def add_slider_joint(
        self, label: str, a: Optional[_HasBody], b: _HasBody, point_m: _Vector, axis: _Vector,
        params: Optional[JointParams] = None,
    ) -> Joint:
        """Slider: b moves along `axis` through `point_m` and may turn about it."""
    def add_prismatic_joint(
        self, label: str, a: Optional[_HasBody], b: _HasBody, point_m: _Vector, axis: _Vector,
        params: Optional[JointParams] = None,
    ) -> Joint:
        """Prismatic joint: b only translates along `axis`."""
    def add_prismatic_press(
        self, label: str, a: Optional[_HasBody], b: _HasBody, point_m: _Vector, axis: _Vector, target_m_s: float,
        max_force_n: float, delay_m_s: float = 0.01, params: Optional[JointParams] = None,
    ) -> Joint:
        """Prismatic press: a prismatic joint driven at `target_m_s` along `axis` with at most `max_force_n`."""
    def add_motor(
        self, label: str, a: Optional[_HasBody], b: _HasBody, point_m: _Vector, axis: _Vector, target_rad_s: float,
        max_torque_n_m: float, delay_rad_s: float = 0.01, params: Optional[JointParams] = None,
    ) -> Joint:
        """Motor: a hinge driven at `target_rad_s` about `axis` with at most `max_torque_n_m`."""
    def add_angular_velocity_controller(
        self, label: str, a: Optional[_HasBody], b: _HasBody, axis: _Vector, target_rad_s: float,
        max_torque_n_m: float, delay_rad_s: float = 0.01,
    ) -> Joint:
        """Angular velocity controller alone: drives `(ω_b − ω_a)·axis` to `target_rad_s`."""
    def add_linear_velocity_controller(
        self, label: str, a: Optional[_HasBody], b: _HasBody, point_m: _Vector, axis: _Vector, target_m_s: float,
        max_force_n: float, delay_m_s: float = 0.01,
    ) -> Joint:
        """Linear velocity controller alone: drives the points' relative velocity along `axis` to `target_m_s`."""
    def add_hinge_servo(
        self, label: str, a: Optional[_HasBody], b: _HasBody, point_m: _Vector, axis: _Vector, target_deg: float,
        max_torque_n_m: float, response_time_s: float, params: Optional[JointParams] = None,
    ) -> Joint:
        """Hinge servo: turns to `target_deg` (relative to now) with at most `max_torque_n_m`."""
    def add_prismatic_servo(
        self, label: str, a: Optional[_HasBody], b: _HasBody, point_m: _Vector, axis: _Vector, target_m: float,
        max_force_n: float, response_time_s: float, params: Optional[JointParams] = None,
    ) -> Joint:
        """Prismatic servo: moves to `target_m` (relative to now) along `axis` with at most `max_force_n`."""
    def add_joint(
        self, label: str, a: Optional[_HasBody], b: Optional[_HasBody], kind: dict[str, Any],
        params: Optional[JointParams] = None,
    ) -> Joint:
        """Any joint, motor, servo, controller or coupling from one dict: `type` and the fields of
        that type as a scene file's `[[joint]]` spells them (docs/scene-format.md), e.g.
        `{"type": "hinge", "point_m": [0, 0, 0], "axis": [0, 1, 0]}`. `a` None is the world;
        `a` and `b` are None for `joint_coupling` and `joint_spring`, which name their joints by
        label. A misspelt or missing field is a ValueError naming it."""
    def joints(self) -> list[Joint]:
        """Every joint made so far, in creation order."""
    def joint(self, label: str) -> Optional[Joint]:
        """The joint labelled `label`, or None."""
    def joint_state(self, joint: Joint) -> JointState:
        """The joint's state at the last accepted step."""
    def joint_states(self) -> dict[str, JointState]:
        """The state of every joint at the last accepted step, by label (a repeated label gets `#2`,
        `#3`, ... as in the joint log)."""
    def max_joint_violations(self) -> tuple[float, float]:
        """Largest violation of any enabled hard joint constraint at the last accepted step: (m, rad)."""
    def joint_primitive_readouts(self, joint: Joint) -> list[dict[str, Any]]:
        """Each primitive of a joint at the last accepted step: dicts with `primitive` (its `kind`
        and parameters), `violation` (m or rad), `force_a_n`, `torque_a_n_m`, `force_b_n` and
        `torque_b_n_m` (N and N·m, world frame, torques about each body's centre of mass)."""
    def joint_stiffness(self, joint: Joint) -> float:
        """Largest stiffness of the joint's hard constraints (after hardening), N/m."""
    def set_joint_enabled(self, joint: Joint, enabled: bool) -> None:
        """Switch a joint on or off (off: it exerts nothing)."""
    def set_joint_stiffness(self, joint: Joint, stiffness: float) -> None:
        """Stiffness of the joint's hard constraints, N/m."""
    def set_joint_tolerance(self, joint: Joint, tolerance_m: float, tolerance_deg: float) -> None:
        """Tolerances the joint is hardened to: m and degrees."""
    def set_joint_target_velocity(self, joint: Joint, target: float) -> None:
        """Target velocity of a motor, press or velocity controller: rad/s or m/s."""
    def set_joint_max_effort(self, joint: Joint, max: float) -> None:
        """Largest torque (N·m) or force (N) of a motor, press, controller or servo."""
    def set_servo_target(self, joint: Joint, target: float) -> None:
        """Target of a servo: degrees for a hinge servo, metres for a prismatic one."""
    def set_spring(self, joint: Joint, rest_length_m: float, damping_n_s_m: float) -> None:
        """Rest length (m) and damping (N·s/m) of a spring."""
    def set_fixed_transform(self, joint: Joint, position_m: _Vector, orientation: _Rotation) -> None:
        """Target pose of a fix joint's body: centre of mass (m) and orientation."""
    def set_fixed_transform_deg(self, joint: Joint, position_m: _Vector, angle_deg: float, axis: _Vector) -> None:
        """Target pose of a fix joint's body: centre of mass at `position_m` (m), orientation a rotation of `angle_deg` about `axis`."""

    # ---- Rigid-body presets, drawn meshes, collisions between bodies ----
    def add_robot(
        self, name: str, urdf: Union[str, os.PathLike], package_paths: Optional[list[Union[str, os.PathLike]]] = None,
        position_m: Optional[_Vector] = None, orientation: Optional[_Rotation] = None, fixed_base: bool = False,
        merge_fixed_joints: bool = True, visual_meshes: bool = False, contact_thickness_m: Optional[float] = None,
        adjacent_links_collide: bool = False, self_collision: bool = True,
        links: Optional[dict[str, dict[str, Any]]] = None, joints: Optional[dict[str, dict[str, Any]]] = None,
    ) -> Robot:
        """Load a robot from a URDF file: links become rigid bodies, joints hinges, sliders and
        couplings, `<collision>` geometry collision meshes; `links` and `joints` are overrides by
        URDF name with the fields of the scene files' `[robot.links.<link>]` and
        `[robot.joints.<joint>]` tables."""
    def add_box(
        self, label: str, mass_kg: float, size_m: _Vector, position_m: Optional[_Vector] = None,
        orientation: Optional[_Rotation] = None, thickness_m: Optional[float] = None,
    ) -> RigidObject:
        """A solid box of `mass_kg` and side lengths `size_m` with its collision mesh."""
    def add_sphere(
        self, label: str, mass_kg: float, radius_m: float, subdivisions: int = 2, position_m: Optional[_Vector] = None,
        orientation: Optional[_Rotation] = None, thickness_m: Optional[float] = None,
    ) -> RigidObject:
        """A solid sphere (icosphere mesh with `subdivisions`)."""
    def add_cylinder(
        self, label: str, mass_kg: float, radius_m: float, height_m: float, slices: int = 16, stacks: int = 1,
        position_m: Optional[_Vector] = None, orientation: Optional[_Rotation] = None,
        thickness_m: Optional[float] = None,
    ) -> RigidObject:
        """A solid cylinder along z."""
    def add_torus(
        self, label: str, mass_kg: float, major_radius_m: float, minor_radius_m: float, major_segments: int = 32,
        minor_segments: int = 16, position_m: Optional[_Vector] = None, orientation: Optional[_Rotation] = None,
        thickness_m: Optional[float] = None,
    ) -> RigidObject:
        """A solid torus in the body's xy plane."""
    def add_rigid_mesh(
        self, label: str, vertices_m: _Points, triangles: _Indices, density_kg_m3: float,
        thickness_m: Optional[float] = None,
    ) -> RigidObject:
        """A body from a closed triangle mesh in world coordinates of uniform density, placed where the mesh is."""
    def add_rigid_output_mesh(self, body: _HasBody, local_vertices_m: _Points, triangles: _Indices) -> NodeSet:
        """Give a body a mesh that is only drawn (body frame); returns its node set."""
    def set_bodies_collision(self, a: _HasBody, b: _HasBody, enabled: bool) -> None:
        """Switch contact between all collision meshes of bodies a and b off or on."""

    # ---- Deformable–rigid attachments ----
    def attach_to_body(
        self, label: str, body: _HasBody, nodes: _HasNodes, points: _Indices, params: Optional[AttachmentParams] = None
    ) -> RigidAttachmentHandle:
        """Glue nodes `points` (local indices) of a deformable object to `body` where they are now."""
    def attach_to_body_by_distance(
        self, label: str, mesh: RigidMesh, mesh_triangles: _Indices, nodes: _HasNodes, distance_m: float,
        params: Optional[AttachmentParams] = None,
    ) -> tuple[RigidAttachmentHandle, int]:
        """Glue every node within `distance_m` of the body's collision mesh to the body; returns the handle and the count."""
    def rigid_attachment_gap(self, attachment: RigidAttachmentHandle) -> float:
        """Largest gap of a deformable–rigid attachment group at the current positions, m."""

# ------------------------------------------------------------------------------------------
# Scenes
# ------------------------------------------------------------------------------------------

@final
class Scene:
    """A simulation built from a scene file or a built-in scene, ready to `run(duration_s)`."""
    @property
    def simulation(self) -> Simulation:
        """The simulation with every object, boundary condition and event of the scene."""
    @property
    def duration_s(self) -> float:
        """Simulated time the scene asks for, s."""
    @property
    def name(self) -> str:
        """Scene name."""
    @property
    def objects(self) -> dict[str, Union[Surface, Volume, Line, Obstacle, FixedSurface, SceneRigidBody]]:
        """The objects by name (scene files only)."""
    @property
    def prescribed(self) -> list[dict[str, Any]]:
        """The `[[prescribed]]` entries in file order: dicts with `object`, `handle` and `nodes`."""
    @property
    def attachments(self) -> dict[str, AttachmentHandle]:
        """The `[[attachment]]` entries by label."""
    @property
    def joints(self) -> dict[str, Joint]:
        """The joints by label: the `[[joint]]` entries and the fix joints of fixed bodies (`<body>.fixed`)."""
    def run(
        self,
        duration: Optional[float] = None,
        callback: Optional[Callable[[Simulation], Any]] = None,
        progress: bool = False,
    ) -> _Report:
        """Run the scene for `duration` seconds (default: its own duration); returns the run summary."""

def load_scene(
    path: Union[str, os.PathLike[str]],
    output_directory: Optional[Union[str, os.PathLike[str]]] = None,
    threads: Optional[int] = None,
    frames: Optional[bool] = None,
    step_log: Optional[bool] = None,
    overrides: Optional[list[str]] = None,
) -> Scene:
    """Load a scene file (TOML, or JSON if the name ends in `.json`); the options override the file's.

    `overrides` are `key.path=value` strings applied to the file first (as `stark run --set`).
    """

def parse_scene(
    text: str,
    file_name: str = "scene.toml",
    base_dir: Union[str, os.PathLike[str]] = ...,
    output_directory: Optional[Union[str, os.PathLike[str]]] = None,
    threads: Optional[int] = None,
    frames: Optional[bool] = None,
    step_log: Optional[bool] = None,
) -> Scene:
    """Build a scene from its text; `file_name` names it in errors and picks the format."""

def builtin_scenes() -> list[dict[str, Any]]:
    """The built-in scenes: a list of dicts with `name`, `description` and `duration_s`."""

def builtin_scene(name: str, settings: Optional[Settings] = None) -> Scene:
    """Build the built-in scene `name`; `settings` provides the base settings."""

def grasp_outcome(log: str | os.PathLike[str], pour_start_s: float = 1.2) -> dict[str, Any]:
    """The grasp's break and slip from a `franka_cup` (or `franka_rigid_box`) probe log
    (`<out>/<scene>.grasp.jsonl`), as `stark run` reports them: a dict with `reference_time_s`,
    `break_time_s` and `at_break` (when static grasping broke: the cup slid faster than 1 mm/s
    with the jaws' friction at μ·ΣN; None: it never did), `slip_time_s` (the 1 mm slip; None: it
    held), `at` (the readouts at the slip, or at the end), `load_over_capacity`, `max_held_ratio`
    and `final_drop_m`."""
def classify_robot_towel(log: str | os.PathLike[str]) -> dict[str, Any]:
    """Classify a robot–towel run from its probe log (`<out>/<scene>.robot_towel.jsonl`): a dict
    with `outcome` ("P", "O" or "S"), `reason`, `robot_advance_m`, `towel_advance_m` and
    `mean_torque_fraction`."""

def robot_towel_lab_outcome(name: str) -> Optional[str]:
    """The lab's outcome (Table I) of a built-in robot–towel scene, or None for other names."""

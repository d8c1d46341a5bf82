//! Handles: small immutable Python objects naming a part of one simulation.
//!
//! Every handle remembers the simulation that issued it; passing it to another simulation raises
//! `InvalidHandleError` instead of reaching the wrong object. Functions that take a node set, a
//! contact object, prescribed positions or a body also accept an object handle that has one
//! (`sim.positions(cloth)` for `sim.positions(cloth.nodes)`).

use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};

static NEXT_SIMULATION_ID: AtomicU64 = AtomicU64::new(1);

/// A fresh simulation identity.
pub fn next_simulation_id() -> u64 {
    NEXT_SIMULATION_ID.fetch_add(1, Ordering::Relaxed)
}

/// Something issued by one simulation.
pub trait Issued {
    /// The identity of the simulation that issued it.
    fn simulation_id(&self) -> u64;
}

/// Defines a handle that is an index into one model of a simulation.
macro_rules! index_handle {
    ($(#[$doc:meta])* $name:ident => $rust:path) => {
        $(#[$doc])*
        #[pyclass(module = "starkrs", frozen, eq, hash, from_py_object)]
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub struct $name {
            /// Index of the group in its model.
            #[pyo3(get)]
            pub index: u32,
            /// The issuing simulation.
            pub sim: u64,
        }

        #[pymethods]
        impl $name {
            fn __repr__(&self) -> String {
                format!("{}({})", stringify!($name), self.index)
            }
        }

        impl Issued for $name {
            fn simulation_id(&self) -> u64 {
                self.sim
            }
        }

        impl $name {
            /// Wrap a library handle.
            pub fn new(sim: u64, h: $rust) -> Self {
                Self { index: h.0, sim }
            }
            /// The library handle.
            pub fn rust(&self) -> $rust {
                $rust(self.index)
            }
        }
    };
}

index_handle! {
    /// A group of deformable nodes glued to a rigid body (`attach_to_body`).
    RigidAttachmentHandle => stark::rigidbodies::attachments::RigidAttachmentHandle
}
index_handle! {
    /// The lumped inertia of one deformable object (`sim.params(h)`, `sim.mass(h)`).
    InertiaHandle => stark::deformables::InertiaHandle
}
index_handle! {
    /// The membrane strain of one surface (`sim.params(h)` is a `TriangleStrainParams`).
    TriangleStrainHandle => stark::deformables::TriangleStrainHandle
}
index_handle! {
    /// The tet strain of one volume (`sim.params(h)` is a `TetStrainParams`).
    TetStrainHandle => stark::deformables::TetStrainHandle
}
index_handle! {
    /// The segment strain of one line (`sim.params(h)` is a `SegmentStrainParams`).
    SegmentStrainHandle => stark::deformables::SegmentStrainHandle
}
index_handle! {
    /// The flat bending of one surface (`sim.params(h)` is a `FlatBendingParams`).
    FlatBendingHandle => stark::deformables::FlatBendingHandle
}
index_handle! {
    /// The dihedral bending of one surface (`sim.params(h)` is a `DihedralBendingParams`).
    DihedralBendingHandle => stark::deformables::DihedralBendingHandle
}
index_handle! {
    /// A group of prescribed nodes (move it with `sim.set_transform(h, ...)`).
    PrescribedHandle => stark::deformables::PrescribedHandle
}
index_handle! {
    /// A contact object (`sim.set_friction(a, b, mu)`, `sim.disable_collision(a, b)`).
    ContactHandle => stark::contact::ContactHandle
}

/// A contiguous range of nodes: one object's nodes.
#[pyclass(module = "starkrs", frozen, eq, hash, from_py_object)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct NodeSet {
    /// Index of the set.
    #[pyo3(get)]
    pub index: u32,
    /// First node in the simulation's node arrays.
    #[pyo3(get)]
    pub first: u32,
    /// Number of nodes.
    #[pyo3(get)]
    pub len: u32,
    /// The issuing simulation.
    pub sim: u64,
}

#[pymethods]
impl NodeSet {
    fn __repr__(&self) -> String {
        format!("NodeSet(index={}, first={}, len={})", self.index, self.first, self.len)
    }
    fn __len__(&self) -> usize {
        self.len as usize
    }
}

impl Issued for NodeSet {
    fn simulation_id(&self) -> u64 {
        self.sim
    }
}

impl NodeSet {
    /// Wrap a library handle.
    pub fn new(sim: u64, h: stark::deformables::NodeSetHandle) -> Self {
        NodeSet {
            index: h.index,
            first: h.first,
            len: h.len,
            sim,
        }
    }
    /// The library handle.
    pub fn rust(&self) -> stark::deformables::NodeSetHandle {
        stark::deformables::NodeSetHandle {
            index: self.index,
            first: self.first,
            len: self.len,
        }
    }
}

/// A group of attachments (`sim.attachment_gap(h)`, `sim.params(h)`).
#[pyclass(module = "starkrs", frozen, eq, hash, from_py_object)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct AttachmentHandle {
    /// The library handle.
    pub handle: stark::deformables::AttachmentHandle,
    /// The issuing simulation.
    pub sim: u64,
}

#[pymethods]
impl AttachmentHandle {
    /// "point_point", "point_edge" or "point_triangle".
    #[getter]
    fn kind(&self) -> &'static str {
        use stark::deformables::AttachmentHandle as A;
        match self.handle {
            A::PointPoint(_) => "point_point",
            A::PointEdge(_) => "point_edge",
            A::PointTriangle(_) => "point_triangle",
        }
    }
    /// Index of the group among those of its kind.
    #[getter]
    fn index(&self) -> u32 {
        use stark::deformables::AttachmentHandle as A;
        match self.handle {
            A::PointPoint(i) | A::PointEdge(i) | A::PointTriangle(i) => i,
        }
    }
    fn __repr__(&self) -> String {
        format!("AttachmentHandle({}, {})", self.kind(), self.index())
    }
}

impl Issued for AttachmentHandle {
    fn simulation_id(&self) -> u64 {
        self.sim
    }
}

/// A rigid body (joints, presets and attachments take it, or a RigidMesh, RigidObject or
/// SceneRigidBody of it).
#[pyclass(module = "starkrs", frozen, eq, hash, from_py_object)]
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct RigidBody {
    /// Index of the body.
    #[pyo3(get)]
    pub index: u32,
    /// Its label.
    #[pyo3(get)]
    pub label: String,
    /// The issuing simulation.
    pub sim: u64,
}

#[pymethods]
impl RigidBody {
    fn __repr__(&self) -> String {
        format!("RigidBody({}, '{}')", self.index, self.label)
    }
}

impl Issued for RigidBody {
    fn simulation_id(&self) -> u64 {
        self.sim
    }
}

impl RigidBody {
    /// Wrap a library handle issued by simulation `sim`.
    pub fn new(sim: u64, h: stark::rigidbodies::RigidBodyHandle, label: &str) -> Self {
        RigidBody {
            index: h.index,
            label: label.to_string(),
            sim,
        }
    }
    /// The library handle.
    pub fn rust(&self) -> stark::rigidbodies::RigidBodyHandle {
        stark::rigidbodies::RigidBodyHandle { index: self.index }
    }
}

/// The collision mesh of a rigid body: its vertices are nodes that move with the body.
#[pyclass(module = "starkrs", frozen, get_all, from_py_object)]
#[derive(Clone, Debug)]
pub struct RigidMesh {
    /// The body.
    pub body: RigidBody,
    /// Its vertices in the node arrays.
    pub nodes: NodeSet,
    /// Its contact object.
    pub contact: ContactHandle,
}

#[pymethods]
impl RigidMesh {
    fn __repr__(&self) -> String {
        format!("RigidMesh(body='{}', nodes={})", self.body.label, self.nodes.len)
    }
}

/// A shell or cloth added by `add_surface` or `add_surface_grid`.
#[pyclass(module = "starkrs", frozen, get_all)]
pub struct Surface {
    /// Its label.
    pub label: String,
    /// Its nodes.
    pub nodes: NodeSet,
    /// Its inertia.
    pub inertia: InertiaHandle,
    /// Its membrane strain.
    pub strain: TriangleStrainHandle,
    /// Its bending: a FlatBendingHandle, a DihedralBendingHandle or None.
    pub bending: Option<Py<PyAny>>,
    /// Its contact object, if it has a contact thickness.
    pub contact: Option<ContactHandle>,
}

#[pymethods]
impl Surface {
    fn __repr__(&self) -> String {
        format!("Surface('{}', nodes={})", self.label, self.nodes.len)
    }
}

impl Surface {
    /// Wrap the library's handles.
    pub fn new(py: Python<'_>, sim: u64, label: &str, h: &stark::presets::SurfaceHandle) -> PyResult<Self> {
        use stark::presets::objects::BendingHandle as B;
        let bending = match h.bending {
            None => None,
            Some(B::Flat(b)) => Some(Py::new(py, FlatBendingHandle::new(sim, b))?.into_any()),
            Some(B::Dihedral(b)) => Some(Py::new(py, DihedralBendingHandle::new(sim, b))?.into_any()),
        };
        Ok(Surface {
            label: label.to_string(),
            nodes: NodeSet::new(sim, h.nodes),
            inertia: InertiaHandle::new(sim, h.inertia),
            strain: TriangleStrainHandle::new(sim, h.strain),
            bending,
            contact: h.contact.map(|c| ContactHandle::new(sim, c)),
        })
    }
}

/// A solid added by `add_volume` or `add_volume_grid`.
#[pyclass(module = "starkrs", frozen, get_all)]
pub struct Volume {
    /// Its label.
    pub label: String,
    /// Its nodes.
    pub nodes: NodeSet,
    /// Its inertia.
    pub inertia: InertiaHandle,
    /// Its tet strain.
    pub strain: TetStrainHandle,
    /// Its contact object (its boundary surface), if it has a contact thickness.
    pub contact: Option<ContactHandle>,
}

#[pymethods]
impl Volume {
    fn __repr__(&self) -> String {
        format!("Volume('{}', nodes={})", self.label, self.nodes.len)
    }
}

impl Volume {
    /// Wrap the library's handles.
    pub fn new(sim: u64, label: &str, h: &stark::presets::VolumeHandle) -> Self {
        Volume {
            label: label.to_string(),
            nodes: NodeSet::new(sim, h.nodes),
            inertia: InertiaHandle::new(sim, h.inertia),
            strain: TetStrainHandle::new(sim, h.strain),
            contact: h.contact.map(|c| ContactHandle::new(sim, c)),
        }
    }
}

/// A rod or cable added by `add_line` or `add_line_segments`.
#[pyclass(module = "starkrs", frozen, get_all)]
pub struct Line {
    /// Its label.
    pub label: String,
    /// Its nodes.
    pub nodes: NodeSet,
    /// Its inertia.
    pub inertia: InertiaHandle,
    /// Its segment strain.
    pub strain: SegmentStrainHandle,
    /// Its contact object, if it has a contact thickness.
    pub contact: Option<ContactHandle>,
}

#[pymethods]
impl Line {
    fn __repr__(&self) -> String {
        format!("Line('{}', nodes={})", self.label, self.nodes.len)
    }
}

impl Line {
    /// Wrap the library's handles.
    pub fn new(sim: u64, label: &str, h: &stark::presets::LineHandle) -> Self {
        Line {
            label: label.to_string(),
            nodes: NodeSet::new(sim, h.nodes),
            inertia: InertiaHandle::new(sim, h.inertia),
            strain: SegmentStrainHandle::new(sim, h.strain),
            contact: h.contact.map(|c| ContactHandle::new(sim, c)),
        }
    }
}

/// A kinematic obstacle added by `add_prescribed_surface`: move it with `sim.set_transform(obstacle, ...)`.
#[pyclass(module = "starkrs", frozen, get_all)]
pub struct Obstacle {
    /// Its label.
    pub label: String,
    /// Its nodes.
    pub nodes: NodeSet,
    /// The prescribed positions moving it.
    pub prescribed: PrescribedHandle,
    /// Its contact object.
    pub contact: ContactHandle,
}

#[pymethods]
impl Obstacle {
    fn __repr__(&self) -> String {
        format!("Obstacle('{}', nodes={})", self.label, self.nodes.len)
    }
}

impl Obstacle {
    /// Wrap the library's handles.
    pub fn new(sim: u64, label: &str, h: &stark::presets::ObstacleHandle) -> Self {
        Obstacle {
            label: label.to_string(),
            nodes: NodeSet::new(sim, h.nodes),
            prescribed: PrescribedHandle::new(sim, h.prescribed),
            contact: ContactHandle::new(sim, h.contact),
        }
    }
}

/// A surface fixed in the world, added by `add_fixed_surface`.
#[pyclass(module = "starkrs", frozen, get_all)]
pub struct FixedSurface {
    /// Its label.
    pub label: String,
    /// Its nodes.
    pub nodes: NodeSet,
    /// Its contact object.
    pub contact: ContactHandle,
}

#[pymethods]
impl FixedSurface {
    fn __repr__(&self) -> String {
        format!("FixedSurface('{}', nodes={})", self.label, self.nodes.len)
    }
}

impl FixedSurface {
    /// Wrap the library's handles.
    pub fn new(sim: u64, label: &str, h: &stark::presets::FixedSurfaceHandle) -> Self {
        FixedSurface {
            label: label.to_string(),
            nodes: NodeSet::new(sim, h.nodes),
            contact: ContactHandle::new(sim, h.contact),
        }
    }
}

/// A `[[rigid_body]]` of a scene file: the body, the nodes of its mesh and its contact object.
/// Functions taking a body, a node set or a contact object take it too.
#[pyclass(module = "starkrs", frozen, get_all)]
pub struct SceneRigidBody {
    /// Its label (the entry's name).
    pub label: String,
    /// The body.
    pub body: RigidBody,
    /// The vertices of its mesh (they move with the body).
    pub nodes: NodeSet,
    /// Its contact object, if it takes part in contact.
    pub contact: Option<ContactHandle>,
}

#[pymethods]
impl SceneRigidBody {
    fn __repr__(&self) -> String {
        format!("SceneRigidBody('{}', nodes={})", self.label, self.nodes.len)
    }
}

impl SceneRigidBody {
    /// Wrap the library's handles.
    pub fn new(sim: u64, label: &str, h: &stark::io::scene::SceneRigidBody) -> Self {
        SceneRigidBody {
            label: label.to_string(),
            body: RigidBody::new(sim, h.body, label),
            nodes: NodeSet::new(sim, h.nodes),
            contact: h.contact.map(|c| ContactHandle::new(sim, c)),
        }
    }
}

/// Read attribute `name` of `obj` as a `T`, for arguments given as an object handle.
fn member<'py, T: pyo3::PyClass<Frozen = pyo3::pyclass::boolean_struct::True> + Sync + Clone>(
    obj: &Bound<'py, PyAny>,
    name: &str,
    what: &str,
) -> PyResult<T> {
    if let Ok(attr) = obj.getattr(name) {
        if let Ok(h) = attr.cast::<T>() {
            return Ok(h.get().clone());
        }
    }
    Err(PyTypeError::new_err(format!(
        "expected {what}, got {}",
        obj.repr().map(|r| r.to_string()).unwrap_or_default()
    )))
}

/// A node set, given directly or as any handle with a `nodes` attribute.
pub struct NodesArg(pub NodeSet);

impl<'a, 'py> FromPyObject<'a, 'py> for NodesArg {
    type Error = PyErr;
    fn extract(obj: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        if let Ok(h) = obj.cast::<NodeSet>() {
            return Ok(NodesArg(*h.get()));
        }
        member::<NodeSet>(&obj.to_owned(), "nodes", "a NodeSet or an object with nodes").map(NodesArg)
    }
}

/// A contact object, given directly or as any handle with a `contact` attribute.
pub struct ContactArg(pub ContactHandle);

impl<'a, 'py> FromPyObject<'a, 'py> for ContactArg {
    type Error = PyErr;
    fn extract(obj: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        if let Ok(h) = obj.cast::<ContactHandle>() {
            return Ok(ContactArg(*h.get()));
        }
        member::<ContactHandle>(
            &obj.to_owned(),
            "contact",
            "a ContactHandle or an object with a contact object (give it a contact thickness)",
        )
        .map(ContactArg)
    }
}

/// Prescribed positions, given directly or as any handle with a `prescribed` attribute.
pub struct PrescribedArg(pub PrescribedHandle);

impl<'a, 'py> FromPyObject<'a, 'py> for PrescribedArg {
    type Error = PyErr;
    fn extract(obj: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        if let Ok(h) = obj.cast::<PrescribedHandle>() {
            return Ok(PrescribedArg(*h.get()));
        }
        member::<PrescribedHandle>(&obj.to_owned(), "prescribed", "a PrescribedHandle or an Obstacle")
            .map(PrescribedArg)
    }
}

/// A rigid body, given directly or as a handle with a `body` attribute.
pub struct BodyArg(pub RigidBody);

impl<'a, 'py> FromPyObject<'a, 'py> for BodyArg {
    type Error = PyErr;
    fn extract(obj: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        if let Ok(h) = obj.cast::<RigidBody>() {
            return Ok(BodyArg(h.get().clone()));
        }
        member::<RigidBody>(&obj.to_owned(), "body", "a RigidBody or an object with a body").map(BodyArg)
    }
}

/// Register the classes.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<NodeSet>()?;
    m.add_class::<InertiaHandle>()?;
    m.add_class::<TriangleStrainHandle>()?;
    m.add_class::<TetStrainHandle>()?;
    m.add_class::<SegmentStrainHandle>()?;
    m.add_class::<FlatBendingHandle>()?;
    m.add_class::<DihedralBendingHandle>()?;
    m.add_class::<PrescribedHandle>()?;
    m.add_class::<ContactHandle>()?;
    m.add_class::<AttachmentHandle>()?;
    m.add_class::<RigidBody>()?;
    m.add_class::<RigidMesh>()?;
    m.add_class::<RigidAttachmentHandle>()?;
    m.add_class::<Surface>()?;
    m.add_class::<Volume>()?;
    m.add_class::<Line>()?;
    m.add_class::<Obstacle>()?;
    m.add_class::<FixedSurface>()?;
    m.add_class::<SceneRigidBody>()?;
    Ok(())
}

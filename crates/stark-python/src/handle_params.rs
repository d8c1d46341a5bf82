//! `Simulation.params(handle)` and `Simulation.set_params(handle, params)`: the handle kinds
//! whose models have parameters implement [`ParamsHandle`] (`params_handles!`, one entry per
//! kind), and `KINDS` lists them for the dispatch.

use crate::handles::*;
use crate::params::{self, ParamClass};
use crate::simulation::Simulation;
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;

/// A handle of a model with parameters.
pub(crate) trait ParamsHandle:
    pyo3::PyClass<Frozen = pyo3::pyclass::boolean_struct::True> + Issued + Clone + Sync
{
    /// The Python class of the parameters.
    type Params: ParamClass;
    /// The parameters of the model part `self` names.
    fn get(&self, sim: &mut stark::Simulation) -> stark::Result<Struct<Self>>;
    /// Replace them (checked by the library).
    fn set(&self, sim: &mut stark::Simulation, p: Struct<Self>) -> stark::Result<()>;
}

/// The library parameter struct of handle kind `H`.
type Struct<H> = <<H as ParamsHandle>::Params as ParamClass>::Struct;

/// `params` of one handle kind: None if the handle is of another kind.
type GetFn = for<'py> fn(&Simulation, &Bound<'py, PyAny>) -> Option<PyResult<Bound<'py, PyAny>>>;
/// `set_params` of one handle kind: None if the handle is of another kind.
type SetFn = fn(&Simulation, &Bound<'_, PyAny>, &Bound<'_, PyAny>) -> Option<PyResult<()>>;

/// `params` and `set_params` for one handle kind.
struct Kind {
    get: GetFn,
    set: SetFn,
}

const fn kind<H: ParamsHandle>() -> Kind {
    Kind {
        get: get_params::<H>,
        set: set_params::<H>,
    }
}

fn get_params<'py, H: ParamsHandle>(
    sim: &Simulation,
    handle: &Bound<'py, PyAny>,
) -> Option<PyResult<Bound<'py, PyAny>>> {
    let h = handle.cast::<H>().ok()?.get().clone();
    Some((|| {
        sim.own(&h)?;
        let p = sim.with(|s| h.get(s))?;
        H::Params::new_object(handle.py(), p)
    })())
}

fn set_params<H: ParamsHandle>(
    sim: &Simulation,
    handle: &Bound<'_, PyAny>,
    params: &Bound<'_, PyAny>,
) -> Option<PyResult<()>> {
    let h = handle.cast::<H>().ok()?.get().clone();
    Some((|| {
        sim.own(&h)?;
        let Ok(p) = params.cast::<H::Params>() else {
            let py = handle.py();
            return Err(PyTypeError::new_err(format!(
                "{} takes {}",
                handle.get_type().name()?,
                py.get_type::<H::Params>().name()?
            )));
        };
        let p = p.borrow().inner().clone();
        sim.with(|s| h.set(s, p))
    })())
}

/// Implements [`ParamsHandle`] for each handle kind (`get` and `set` take the simulation `s`,
/// the handle `h` and the parameters `p`) and lists the kinds in `KINDS`: a new kind is one entry.
macro_rules! params_handles {
    ($(
        $h:ty => $p:ty {
            get: |$s:ident, $hh:ident| $get:expr,
            set: |$s2:ident, $hh2:ident, $pp:ident| $set:expr $(,)?
        }
    ),* $(,)?) => {
        $(
            impl ParamsHandle for $h {
                type Params = $p;
                fn get(&self, $s: &mut stark::Simulation) -> stark::Result<Struct<Self>> {
                    let $hh = self;
                    $get
                }
                fn set(&self, $s2: &mut stark::Simulation, $pp: Struct<Self>) -> stark::Result<()> {
                    let $hh2 = self;
                    $set
                }
            }
        )*

        /// Every handle kind with parameters.
        const KINDS: &[Kind] = &[$(kind::<$h>()),*];
    };
}

params_handles! {
    InertiaHandle => params::InertiaParams {
        get: |s, h| s.deformables.inertia.params(h.rust()).cloned(),
        set: |s, h, p| s.deformables.inertia.set_params(h.rust(), p),
    },
    TriangleStrainHandle => params::TriangleStrainParams {
        get: |s, h| s.deformables.triangles.params(h.rust()).cloned(),
        set: |s, h, p| s.deformables.triangles.set_params(h.rust(), p),
    },
    TetStrainHandle => params::TetStrainParams {
        get: |s, h| s.deformables.tets.params(h.rust()).cloned(),
        set: |s, h, p| s.deformables.tets.set_params(h.rust(), p),
    },
    SegmentStrainHandle => params::SegmentStrainParams {
        get: |s, h| s.deformables.segments.params(h.rust()).cloned(),
        set: |s, h, p| s.deformables.segments.set_params(h.rust(), p),
    },
    FlatBendingHandle => params::FlatBendingParams {
        get: |s, h| s.deformables.flat_bending.params(h.rust()).cloned(),
        set: |s, h, p| s.deformables.flat_bending.set_params(h.rust(), p),
    },
    DihedralBendingHandle => params::DihedralBendingParams {
        get: |s, h| s.deformables.dihedral_bending.params(h.rust()).cloned(),
        set: |s, h, p| s.deformables.dihedral_bending.set_params(h.rust(), p),
    },
    PrescribedHandle => params::PrescribedParams {
        get: |s, h| s.deformables.prescribed.params(h.rust()).cloned(),
        set: |s, h, p| s.deformables.prescribed.set_params(h.rust(), p),
    },
    RigidBody => params::RigidBodyParams {
        get: |s, h| s.body_params(h.rust()),
        set: |s, h, p| s.set_body_params(h.rust(), p),
    },
    AttachmentHandle => params::AttachmentParams {
        get: |s, h| s.deformables.attachments.params(h.handle).cloned(),
        set: |s, h, p| s.deformables.attachments.set_params(h.handle, p),
    },
    RigidAttachmentHandle => params::AttachmentParams {
        get: |s, h| s.rigid_bodies.attachments.potential.params(h.rust()).cloned(),
        set: |s, h, p| s.rigid_bodies.attachments.potential.set_params(h.rust(), p),
    },
}

#[pymethods]
impl Simulation {
    /// The parameters of a handle: InertiaParams, TriangleStrainParams, TetStrainParams,
    /// SegmentStrainParams, FlatBendingParams, DihedralBendingParams, PrescribedParams,
    /// RigidBodyParams or AttachmentParams (of an AttachmentHandle or RigidAttachmentHandle); a
    /// copy: change it and `set_params` it back.
    fn params<'py>(&self, handle: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
        for k in KINDS {
            if let Some(r) = (k.get)(self, handle) {
                return r;
            }
        }
        Err(PyTypeError::new_err(format!(
            "params() takes a model handle (InertiaHandle, TriangleStrainHandle, ..., RigidBody), got {}",
            handle.repr()?
        )))
    }

    /// Replace the parameters of a handle (checked: raises StarkError naming the field).
    fn set_params(&self, handle: &Bound<'_, PyAny>, params: &Bound<'_, PyAny>) -> PyResult<()> {
        for k in KINDS {
            if let Some(r) = (k.set)(self, handle, params) {
                return r;
            }
        }
        Err(PyTypeError::new_err(format!(
            "set_params() takes a model handle (InertiaHandle, TriangleStrainHandle, ..., RigidBody), got {}",
            handle.repr()?
        )))
    }
}

//! The `Simulation` class: the library's `Simulation` with NumPy in and out.
//!
//! # Running, the GIL and callbacks
//!
//! `step()` and `run()` take the library simulation out of the Python object (it is "busy"
//! meanwhile: other threads calling its methods get a `StarkError`), release the GIL for the
//! solve, and put it back afterwards. Before every step the GIL is taken back briefly to check
//! for Ctrl-C (`KeyboardInterrupt` stops the run between steps) and to call Python: the `run`
//! callback and the time events. While Python code runs inside such a callback, the Python
//! object lends it the simulation being stepped, so the callback's `sim` argument works like
//! the simulation outside (except that it cannot `step` or `run` itself). An exception raised
//! in a callback stops the run and is re-raised by `step`/`run` unchanged. A panic inside the
//! library becomes a `StarkError`; if it happened mid-step the simulation is marked unusable.
//!
//! This file holds the class, its core (where the library simulation is, stepping with the GIL
//! released), settings and state; the methods by topic are in `run.rs`, `objects.rs`
//! (nodes, deformables), `interactions.rs` (attachments, contact) and `bodies.rs`; they use only
//! this file. `params`/`set_params` are in `handle_params.rs`.

use crate::convert::{guarded, points_out, stark_err, to_py_err, to_python, v3_out, Points, V3};
use crate::handles::*;
use crate::params::{self, Mirror};
use nalgebra::Vector3;
use pyo3::prelude::*;
use std::cell::RefCell;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::Mutex;

mod bodies;
mod interactions;
mod objects;
mod run;

/// A pointer to the library simulation being stepped, lent to Python callbacks.
struct Lent(*mut stark::Simulation);

// SAFETY: the pointer is set only while the thread that steps the simulation is inside a Python
// callback of that step (so the stepping code does not touch the simulation), and it is used
// only with the GIL held and the `core` mutex locked, one method call at a time; it is cleared
// before the callback returns to the stepping code.
unsafe impl Send for Lent {}

/// Where the library simulation is.
enum Core {
    /// Here, idle.
    Owned(Box<stark::Simulation>),
    /// Being stepped; a Python callback of that step may use it.
    Lent(Lent),
    /// Being stepped (GIL released).
    Busy,
    /// Lost to an internal error mid-step.
    Poisoned(String),
}

thread_local! {
    /// The Python simulations being stepped on this thread (innermost last).
    static STEPPING: RefCell<Vec<Py<Simulation>>> = const { RefCell::new(Vec::new()) };
    /// An exception raised by a Python callback, to re-raise when the step returns.
    static PENDING: RefCell<Option<PyErr>> = const { RefCell::new(None) };
}

/// Keep `e` to re-raise after the library returns, and give the library an error to stop on.
fn stash(e: PyErr) -> stark::StarkError {
    let msg = e.to_string();
    PENDING.with(|p| *p.borrow_mut() = Some(e));
    stark::StarkError::InvalidInput(format!("a Python callback raised: {msg}"))
}

/// A simulation: objects, energies, settings and the time loop.
///
/// `Simulation(settings=None)` starts empty with `Settings()` defaults. Add objects with the
/// `add_*` methods (they return handles), then `step()` or `run(duration)`.
#[pyclass(module = "starkrs", frozen)]
pub struct Simulation {
    core: Mutex<Core>,
    id: u64,
    /// Python callables of the time events, by index.
    events: Mutex<Vec<Option<Py<PyAny>>>>,
}

impl Simulation {
    /// Wrap a library simulation.
    pub fn wrap(sim: stark::Simulation) -> Self {
        Simulation {
            core: Mutex::new(Core::Owned(Box::new(sim))),
            id: next_simulation_id(),
            events: Mutex::new(Vec::new()),
        }
    }

    /// The identity handles carry.
    pub fn id(&self) -> u64 {
        self.id
    }

    /// Run `f` on the library simulation (idle, or lent to a callback).
    pub(crate) fn with<R>(&self, f: impl FnOnce(&mut stark::Simulation) -> stark::Result<R>) -> PyResult<R> {
        let mut core = self.core.lock().unwrap_or_else(|e| e.into_inner());
        match &mut *core {
            Core::Owned(sim) => guarded(|| f(sim)),
            // SAFETY: see `Lent`.
            Core::Lent(p) => guarded(|| f(unsafe { &mut *p.0 })),
            Core::Busy => Err(stark_err(
                "the simulation is running (in another thread); wait until step() or run() returns",
            )),
            Core::Poisoned(msg) => Err(stark_err(format!("the simulation is unusable: {msg}"))),
        }
    }

    /// [`Self::with`] for infallible access.
    pub(crate) fn get<R>(&self, f: impl FnOnce(&mut stark::Simulation) -> R) -> PyResult<R> {
        self.with(|s| Ok(f(s)))
    }

    /// Check that a handle was issued by this simulation.
    pub(crate) fn own(&self, h: &impl Issued) -> PyResult<()> {
        if h.simulation_id() == self.id {
            Ok(())
        } else {
            Err(crate::convert::InvalidHandleError::new_err(
                "the handle belongs to another simulation",
            ))
        }
    }

    /// Take the library simulation out to step it.
    fn take(&self) -> PyResult<Box<stark::Simulation>> {
        let mut core = self.core.lock().unwrap_or_else(|e| e.into_inner());
        match std::mem::replace(&mut *core, Core::Busy) {
            Core::Owned(sim) => Ok(sim),
            other => {
                let msg = match &other {
                    Core::Lent(_) => "step() and run() cannot be called from a callback of a running step".to_string(),
                    Core::Busy => "the simulation is already running (in another thread)".to_string(),
                    Core::Poisoned(m) => format!("the simulation is unusable: {m}"),
                    Core::Owned(_) => unreachable!(),
                };
                *core = other;
                Err(stark_err(msg))
            }
        }
    }

    fn set_core(&self, core: Core) {
        *self.core.lock().unwrap_or_else(|e| e.into_inner()) = core;
    }

    /// Step the library simulation with `f`, GIL released, Python callbacks served.
    fn drive<R: Send>(
        slf: &Bound<'_, Self>,
        f: impl FnOnce(&mut stark::Simulation) -> stark::Result<R> + Send,
    ) -> PyResult<R> {
        let py = slf.py();
        let me = slf.get();
        let mut sim = me.take()?;
        let handle = slf.clone().unbind();
        PENDING.with(|p| p.borrow_mut().take());
        let (sim, outcome) = py.detach(move || {
            STEPPING.with(|s| s.borrow_mut().push(handle));
            let outcome = catch_unwind(AssertUnwindSafe(|| f(&mut sim)));
            STEPPING.with(|s| s.borrow_mut().pop());
            (sim, outcome)
        });
        match outcome {
            Ok(result) => {
                me.set_core(Core::Owned(sim));
                let pending = PENDING.with(|p| p.borrow_mut().take());
                match (result, pending) {
                    (Err(_), Some(e)) => Err(e),
                    (r, _) => r.map_err(to_py_err),
                }
            }
            Err(panic) => {
                let msg = format!(
                    "internal error during a step: {}",
                    crate::convert::panic_message(&*panic)
                );
                me.set_core(Core::Poisoned(msg.clone()));
                Err(stark_err(msg))
            }
        }
    }

    /// Call Python with the Python simulation being stepped (lent `sim`): `call(sim_object)`.
    fn serve(
        sim: &mut stark::Simulation,
        call: impl FnOnce(Python<'_>, &Bound<'_, Simulation>) -> PyResult<()>,
    ) -> stark::Result<()> {
        Python::attach(|py| {
            let Some(obj) = STEPPING.with(|s| s.borrow().last().map(|o| o.clone_ref(py))) else {
                return Err(stark::StarkError::InvalidInput(
                    "a Python callback was called outside step()/run()".into(),
                ));
            };
            let obj = obj.into_bound(py);
            let me = obj.get();
            me.set_core(Core::Lent(Lent(sim as *mut stark::Simulation)));
            let result = call(py, &obj);
            me.set_core(Core::Busy);
            result.map_err(stash)
        })
    }
}

fn report_out<'py>(py: Python<'py>, r: &impl serde::Serialize) -> PyResult<Bound<'py, PyAny>> {
    to_python(py, r)
}

fn check_label(label: &str) -> PyResult<()> {
    if label.is_empty() {
        Err(stark_err("a label must not be empty"))
    } else {
        Ok(())
    }
}

#[pymethods]
impl Simulation {
    #[new]
    #[pyo3(signature = (settings=None))]
    fn py_new(py: Python<'_>, settings: Option<&Bound<'_, params::Settings>>) -> PyResult<Self> {
        let settings = params::settings_from(py, settings)?;
        Ok(Simulation::wrap(guarded(|| stark::Simulation::new(settings))?))
    }

    fn __repr__(&self) -> PyResult<String> {
        match self.get(|s| (s.settings.name.clone(), s.time(), s.nodes.len(), s.num_rigid_bodies())) {
            Ok((name, t, n, b)) => Ok(format!(
                "Simulation('{name}', time={t:.6} s, nodes={n}, rigid_bodies={b})"
            )),
            Err(_) => Ok("Simulation(<running>)".into()),
        }
    }

    // -----------------------------------------------------------------------------------------
    // Settings and state
    // -----------------------------------------------------------------------------------------

    /// A copy of the settings; assign a changed copy back (`s = sim.settings; s.x = ...; sim.settings = s`).
    /// Changes take effect at the next step (the thread count only at construction).
    #[getter]
    fn settings(&self, py: Python<'_>) -> PyResult<params::Settings> {
        let s = self.get(|s| s.settings.clone())?;
        params::Settings::from_rust(py, &s)
    }

    #[setter]
    fn set_settings(&self, py: Python<'_>, settings: &Bound<'_, params::Settings>) -> PyResult<()> {
        let s = settings.borrow().to_rust(py)?;
        s.validate().map_err(to_py_err)?;
        self.get(|sim| sim.settings = s)
    }

    /// Simulated time, s.
    #[getter]
    fn time(&self) -> PyResult<f64> {
        self.get(|s| s.time())
    }

    /// Current time step, s (below settings.time_step_s after failures).
    #[getter]
    fn dt(&self) -> PyResult<f64> {
        self.get(|s| s.dt())
    }

    /// Gravity, m/s² (a (3,) array); assigning takes effect at the next step.
    #[getter]
    fn gravity<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, numpy::PyArray1<f64>>> {
        Ok(v3_out(py, &self.get(|s| s.gravity())?))
    }

    #[setter]
    fn set_gravity(&self, g: V3) -> PyResult<()> {
        if !g.0.iter().all(|c| c.is_finite()) {
            return Err(stark_err(format!("gravity must be finite, got {:?}", g.0)));
        }
        self.get(|s| s.set_gravity(g.0))
    }

    /// Number of nodes (deformable nodes and rigid collision-mesh vertices).
    #[getter]
    fn num_nodes(&self) -> PyResult<usize> {
        self.get(|s| s.nodes.len())
    }

    /// Number of rigid bodies.
    #[getter]
    fn num_rigid_bodies(&self) -> PyResult<usize> {
        self.get(|s| s.num_rigid_bodies())
    }

    /// Totals so far (steps, Newton iterations, residuals, wall time, frames ...) as a dict.
    fn summary<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let s = self.get(|s| s.summary().clone())?;
        report_out(py, &s)
    }

    /// An independent check of the current state, as `stark run --check` makes after every step:
    /// a dict with `intersections` (every contact edge crossing a contact triangle, described)
    /// and `inverted_tets` (their count).
    fn state_check<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let c = self.get(|s| s.state_check())?;
        report_out(py, &c)
    }
}

impl Simulation {
    pub(crate) fn body(&self, body: &BodyArg) -> PyResult<stark::rigidbodies::RigidBodyHandle> {
        self.own(&body.0)?;
        Ok(body.0.rust())
    }

    /// Apply `f` to one point (3,) or to each row of (n, 3).
    fn map_points<'py>(
        &self,
        py: Python<'py>,
        points: &Bound<'py, PyAny>,
        f: impl Fn(&stark::Simulation, &Vector3<f64>) -> Vector3<f64>,
    ) -> PyResult<Bound<'py, PyAny>> {
        if let Ok(p) = points.extract::<V3>() {
            let out = self.get(|s| f(s, &p.0))?;
            return Ok(v3_out(py, &out).into_any());
        }
        let p: Points = points.extract()?;
        let out = self.get(|s| p.0.iter().map(|x| f(s, x)).collect::<Vec<_>>())?;
        Ok(points_out(py, &out).into_any())
    }

    /// Write `many` (one per node) or `one` (for all) into a node array of a deformable object.
    fn set_node_field(
        &self,
        nodes: NodesArg,
        many: Option<Points>,
        one: Option<Vector3<f64>>,
        field: impl FnOnce(&mut stark::Simulation) -> &mut Vec<Vector3<f64>>,
        what: &str,
    ) -> PyResult<()> {
        self.own(&nodes.0)?;
        let set = nodes.0.rust();
        let values: Vec<Vector3<f64>> = match (many, one) {
            (Some(p), _) => p.0,
            (None, Some(v)) => vec![v; set.len as usize],
            (None, None) => Vec::new(),
        };
        if values.len() != set.len as usize {
            return Err(stark_err(format!(
                "{what}: the object has {} nodes, got {} values",
                set.len,
                values.len()
            )));
        }
        if let Some(i) = values.iter().position(|v| !v.iter().all(|c| c.is_finite())) {
            return Err(stark_err(format!("{what}: value {i} is not finite")));
        }
        self.with(|s| {
            if set.range().any(|i| s.nodes.body[i] != stark::state::NO_BODY) {
                return Err(stark::StarkError::InvalidInput(format!(
                    "{what}: the nodes belong to a rigid body; move the body instead"
                )));
            }
            let target = field(s);
            target[set.range()].copy_from_slice(&values);
            Ok(())
        })
    }
}

/// An (n, 3) array or a single (3,) vector.
fn points_or_vector(obj: &Bound<'_, PyAny>) -> PyResult<(Option<Points>, Option<Vector3<f64>>)> {
    if let Ok(v) = obj.extract::<V3>() {
        if obj.extract::<Points>().is_err() {
            return Ok((None, Some(v.0)));
        }
    }
    Ok((Some(obj.extract::<Points>()?), None))
}

fn check_finite(v: &Vector3<f64>, what: &str) -> PyResult<()> {
    if v.iter().all(|c| c.is_finite()) {
        Ok(())
    } else {
        Err(stark_err(format!("{what} must be finite, got {v:?}")))
    }
}

fn prescribed_params(
    py: Python<'_>,
    p: Option<&Bound<'_, params::PrescribedParams>>,
) -> PyResult<stark::deformables::PrescribedParams> {
    match p {
        Some(p) => p.borrow().to_rust(py),
        None => Ok(Default::default()),
    }
}

/// Register the class.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Simulation>()?;
    Ok(())
}

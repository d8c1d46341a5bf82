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

use crate::convert::{
    floats_out, guarded, m3_out, points_out, pose, quat_out, stark_err, to_py_err, to_python, v3_out, Elements, Floats,
    Indices, Points, Rot, M3, V3,
};
use crate::handles::*;
use crate::params::{self, attachment_params_arg, Mirror};
use crate::rigid::MassProperties;
use nalgebra::{UnitQuaternion, Vector3};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use pyo3::PyTraverseError;
use pyo3::PyVisit;
use std::cell::RefCell;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::Mutex;

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

    // -----------------------------------------------------------------------------------------
    // Time stepping
    // -----------------------------------------------------------------------------------------

    /// Advance by one accepted time step; returns the step report as a dict (dt, Newton
    /// iterations, residual, criterion, contact statistics ...).
    fn step<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        let report = Self::drive(slf, |sim| sim.step())?;
        report_out(slf.py(), &report)
    }

    /// The same as `step()` (the original's name).
    fn run_one_step<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        Self::step(slf)
    }

    /// Simulate `duration` more seconds, calling `callback(sim)` before every step if given.
    /// The GIL is released while solving; Ctrl-C stops the run between steps. With
    /// `progress=True`, a progress bar (simulated time, steps, wall time) is drawn on
    /// `sys.stderr`. The last step is shortened to land on the end time. Returns the run
    /// summary as a dict.
    #[pyo3(signature = (duration, callback=None, progress=false))]
    fn run<'py>(
        slf: &Bound<'py, Self>,
        duration: f64,
        callback: Option<Py<PyAny>>,
        progress: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        if !(duration.is_finite() && duration >= 0.0) {
            return Err(stark_err(format!(
                "duration must be finite and non-negative, got {duration}"
            )));
        }
        if let Some(cb) = &callback {
            if !cb.bind(slf.py()).is_callable() {
                return Err(PyTypeError::new_err("callback must be callable"));
            }
        }
        let summary = Self::drive(slf, move |sim| {
            let mut bar = ProgressLine::new(sim.time(), duration);
            let result = sim.run_with(duration, |s| {
                let (t, steps) = (s.time(), s.summary().steps);
                Self::serve(s, |py, obj| {
                    py.check_signals()?;
                    if progress {
                        bar.draw(py, t, steps, false)?;
                    }
                    if let Some(cb) = &callback {
                        cb.call1(py, (obj,))?;
                    }
                    Ok(())
                })
            });
            if progress {
                let (t, steps) = (sim.time(), sim.summary().steps);
                // The final line is drawn whatever happened; a failure to draw is not the run's.
                let _ = Python::attach(|py| bar.draw(py, t, steps, true));
            }
            result
        })?;
        report_out(slf.py(), &summary)
    }

    /// Write a checkpoint of the whole state the next step depends on to `path`; a simulation
    /// rebuilt the same way (with its time events added again) continues from it bit for bit
    /// after `restore_checkpoint(path)`.
    fn save_checkpoint(&self, path: std::path::PathBuf) -> PyResult<()> {
        self.with(|s| s.save_checkpoint(&path))
    }

    /// Restore a checkpoint into this simulation, freshly built from the same scene (scene
    /// files rebuild their time events; closures added with `add_time_event` must be added
    /// again first) and not stepped yet. Another scene, a truncated file or another format
    /// version raise `StarkError` saying which.
    fn restore_checkpoint(slf: &Bound<'_, Self>, path: std::path::PathBuf) -> PyResult<()> {
        // Served like a step: the restore fires the spawns due by the checkpoint's time.
        Self::drive(slf, |s| s.restore_checkpoint(&path))
    }

    /// Add objects during the run: `action(sim)` runs once, when the simulated time first
    /// reaches `time_s` (before the first step when `time_s <= 0`, else right after the step that
    /// reaches it). It adds rigid bodies or deformables, their friction and initial state, as
    /// when building. What it adds must not intersect anything (the step raises `StarkError`
    /// naming the spawn). `restore_checkpoint` fires the spawns due by the checkpoint's time
    /// before restoring, so a resumed run must add the same spawns first, and the action must add
    /// the same objects whatever the state.
    fn add_spawn(&self, time_s: f64, label: &str, action: Py<PyAny>) -> PyResult<()> {
        Python::attach(|py| {
            if !action.bind(py).is_callable() {
                return Err(PyTypeError::new_err("the spawn action must be callable"));
            }
            Ok(())
        })?;
        let index = {
            let mut events = self.events.lock().unwrap_or_else(|e| e.into_inner());
            events.push(Some(action));
            events.len() - 1
        };
        self.with(|s| {
            s.add_spawn(time_s, label, move |sim| {
                Self::serve(sim, |py, obj| {
                    let action = obj.get().events.lock().unwrap_or_else(|e| e.into_inner())[index]
                        .as_ref()
                        .map(|a| a.clone_ref(py));
                    match action {
                        Some(a) => a.call1(py, (obj,)).map(|_| ()),
                        None => Err(stark_err("the spawn's action was cleared")),
                    }
                })
            })
        })
    }

    /// Spawns added with `add_spawn`, as `(time_s, label, fired)`.
    fn spawns(&self) -> PyResult<Vec<(f64, String, bool)>> {
        self.with(|s| Ok(s.spawns().into_iter().map(|(t, l, f)| (t, l.to_string(), f)).collect()))
    }

    /// Run `action(sim, t)` before every step whose end time `t` lies in `[t0, t1)`: move
    /// prescribed targets, change parameters or gravity. An exception stops the run.
    fn add_time_event(&self, t0: f64, t1: f64, action: Py<PyAny>) -> PyResult<()> {
        Python::attach(|py| {
            if !action.bind(py).is_callable() {
                return Err(PyTypeError::new_err("the time event action must be callable"));
            }
            Ok(())
        })?;
        if t0.is_nan() || t1.is_nan() {
            return Err(stark_err("time event bounds must not be NaN"));
        }
        let index = {
            let mut events = self.events.lock().unwrap_or_else(|e| e.into_inner());
            events.push(Some(action));
            events.len() - 1
        };
        self.get(|s| {
            s.add_time_event(t0, t1, move |sim, t| {
                Self::serve(sim, |py, obj| {
                    let action = obj.get().events.lock().unwrap_or_else(|e| e.into_inner())[index]
                        .as_ref()
                        .map(|a| a.clone_ref(py));
                    match action {
                        Some(a) => a.call1(py, (obj, t)).map(|_| ()),
                        None => Err(stark_err("the time event's action was cleared")),
                    }
                })
            })
        })
    }

    fn __traverse__(&self, visit: PyVisit<'_>) -> Result<(), PyTraverseError> {
        if let Ok(events) = self.events.try_lock() {
            for e in events.iter().flatten() {
                visit.call(e)?;
            }
        }
        Ok(())
    }

    fn __clear__(&self) {
        if let Ok(mut events) = self.events.try_lock() {
            for e in events.iter_mut() {
                *e = None;
            }
        }
    }

    /// Write one frame of every output mesh now (VTU, or legacy VTK if
    /// `settings.output.frame_format` says so); returns the file paths.
    fn write_frame(&self) -> PyResult<Vec<String>> {
        let files = self.with(|s| s.write_frame())?;
        Ok(files.iter().map(|p| p.display().to_string()).collect())
    }

    // -----------------------------------------------------------------------------------------
    // Nodes
    // -----------------------------------------------------------------------------------------

    /// Add bare nodes (no energy) at `positions` (n, 3) as a labelled object.
    fn add_nodes(&self, label: &str, positions: Points) -> PyResult<NodeSet> {
        let h = self.with(|s| s.add_nodes(label, &positions.0))?;
        Ok(NodeSet::new(self.id, h))
    }

    /// The node set labelled `label`, or None.
    fn node_set(&self, label: &str) -> PyResult<Option<NodeSet>> {
        Ok(self
            .get(|s| s.deformables.set_by_label(label))?
            .map(|h| NodeSet::new(self.id, h)))
    }

    /// Labels of all node sets (objects and collision meshes), in creation order.
    fn node_set_labels(&self) -> PyResult<Vec<String>> {
        self.get(|s| s.deformables.sets.iter().map(|(l, _)| l.clone()).collect())
    }

    /// Positions of an object's nodes, m: a new (n, 3) array.
    fn positions<'py>(&self, py: Python<'py>, nodes: NodesArg) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
        self.own(&nodes.0)?;
        let x = self.get(|s| s.positions(nodes.0.rust()).to_vec())?;
        Ok(points_out(py, &x))
    }

    /// Velocities of an object's nodes, m/s: a new (n, 3) array.
    fn velocities<'py>(&self, py: Python<'py>, nodes: NodesArg) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
        self.own(&nodes.0)?;
        let v = self.get(|s| s.velocities(nodes.0.rust()).to_vec())?;
        Ok(points_out(py, &v))
    }

    /// Rest positions of an object's nodes, m (body-frame positions for a rigid collision mesh).
    fn rest_positions<'py>(&self, py: Python<'py>, nodes: NodesArg) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
        self.own(&nodes.0)?;
        let r = nodes.0.rust().range();
        let x = self.get(|s| s.nodes.rest[r].to_vec())?;
        Ok(points_out(py, &x))
    }

    /// External forces on an object's nodes, N.
    fn forces<'py>(&self, py: Python<'py>, nodes: NodesArg) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
        self.own(&nodes.0)?;
        let r = nodes.0.rust().range();
        let f = self.get(|s| s.nodes.force[r].to_vec())?;
        Ok(points_out(py, &f))
    }

    /// Lumped masses of an object's nodes, kg: a new (n,) array.
    fn masses<'py>(&self, py: Python<'py>, nodes: NodesArg) -> PyResult<Bound<'py, numpy::PyArray1<f64>>> {
        self.own(&nodes.0)?;
        let r = nodes.0.rust().range();
        let m = self.get(|s| s.deformables.inertia.node_masses(s.nodes.len())[r].to_vec())?;
        Ok(floats_out(py, m))
    }

    /// Move an object's nodes to `positions` (n, 3), m (deformable objects only).
    fn set_positions(&self, nodes: NodesArg, positions: Points) -> PyResult<()> {
        self.set_node_field(nodes, Some(positions), None, |s| &mut s.nodes.x, "positions")
    }

    /// Set the velocities of an object's nodes, m/s: an (n, 3) array or one (3,) vector for all.
    fn set_velocities(&self, nodes: NodesArg, velocities: &Bound<'_, PyAny>) -> PyResult<()> {
        let (many, one) = points_or_vector(velocities)?;
        self.set_node_field(nodes, many, one, |s| &mut s.nodes.v, "velocities")
    }

    /// Set the velocity of every node of an object, m/s (the Rust `set_velocity`).
    fn set_velocity(&self, nodes: NodesArg, velocity: V3) -> PyResult<()> {
        self.set_node_field(nodes, None, Some(velocity.0), |s| &mut s.nodes.v, "velocities")
    }

    /// Set the external forces on an object's nodes, N (persist until changed): (n, 3) or (3,).
    fn set_forces(&self, nodes: NodesArg, forces: &Bound<'_, PyAny>) -> PyResult<()> {
        let (many, one) = points_or_vector(forces)?;
        self.set_node_field(nodes, many, one, |s| &mut s.nodes.force, "forces")
    }

    /// Set the external accelerations of an object's nodes (added to gravity), m/s²: (n, 3) or (3,).
    fn set_accelerations(&self, nodes: NodesArg, accelerations: &Bound<'_, PyAny>) -> PyResult<()> {
        let (many, one) = points_or_vector(accelerations)?;
        self.set_node_field(nodes, many, one, |s| &mut s.nodes.acceleration, "accelerations")
    }

    // -----------------------------------------------------------------------------------------
    // Deformable objects
    // -----------------------------------------------------------------------------------------

    /// A shell or cloth from vertices (n, 3) and triangles (m, 3).
    fn add_surface(
        &self,
        py: Python<'_>,
        label: &str,
        vertices: Points,
        triangles: Elements<3>,
        material: &Bound<'_, params::SurfaceMaterial>,
    ) -> PyResult<Surface> {
        let m = material.borrow().to_rust(py)?;
        let h = self.with(|s| s.add_surface(label, &vertices.0, &triangles.0, &m))?;
        Surface::new(py, self.id, label, &h)
    }

    /// A rectangular cloth of `size` (m) in the XY plane centred at the origin, `quads` per side.
    fn add_surface_grid(
        &self,
        py: Python<'_>,
        label: &str,
        size: [f64; 2],
        quads: [usize; 2],
        material: &Bound<'_, params::SurfaceMaterial>,
    ) -> PyResult<Surface> {
        let m = material.borrow().to_rust(py)?;
        let h = self.with(|s| s.add_surface_grid(label, size, quads, &m))?;
        Surface::new(py, self.id, label, &h)
    }

    /// A solid from vertices (n, 3) and tets (m, 4).
    fn add_volume(
        &self,
        py: Python<'_>,
        label: &str,
        vertices: Points,
        tets: Elements<4>,
        material: &Bound<'_, params::VolumeMaterial>,
    ) -> PyResult<Volume> {
        let m = material.borrow().to_rust(py)?;
        let h = self.with(|s| s.add_volume(label, &vertices.0, &tets.0, &m))?;
        Ok(Volume::new(self.id, label, &h))
    }

    /// A box of `size` (m) centred at the origin, `hexes` cells per side, 12 tets per cell.
    fn add_volume_grid(
        &self,
        py: Python<'_>,
        label: &str,
        size: [f64; 3],
        hexes: [usize; 3],
        material: &Bound<'_, params::VolumeMaterial>,
    ) -> PyResult<Volume> {
        let m = material.borrow().to_rust(py)?;
        let h = self.with(|s| s.add_volume_grid(label, size, hexes, &m))?;
        Ok(Volume::new(self.id, label, &h))
    }

    /// A rod or cable from vertices (n, 3) and segments (m, 2).
    fn add_line(
        &self,
        py: Python<'_>,
        label: &str,
        vertices: Points,
        segments: Elements<2>,
        material: &Bound<'_, params::LineMaterial>,
    ) -> PyResult<Line> {
        let m = material.borrow().to_rust(py)?;
        let h = self.with(|s| s.add_line(label, &vertices.0, &segments.0, &m))?;
        Ok(Line::new(self.id, label, &h))
    }

    /// A straight line of `n_segments` from `begin` to `end`.
    fn add_line_segments(
        &self,
        py: Python<'_>,
        label: &str,
        begin: V3,
        end: V3,
        n_segments: usize,
        material: &Bound<'_, params::LineMaterial>,
    ) -> PyResult<Line> {
        let m = material.borrow().to_rust(py)?;
        let h = self.with(|s| s.add_line_segments(label, begin.0, end.0, n_segments, &m))?;
        Ok(Line::new(self.id, label, &h))
    }

    /// A kinematic obstacle: a triangle surface whose nodes all follow prescribed targets
    /// (springs of `stiffness` N/m). Move it with `set_transform(obstacle, ...)`.
    #[pyo3(signature = (label, vertices, triangles, thickness_m, stiffness=1e6))]
    fn add_prescribed_surface(
        &self,
        label: &str,
        vertices: Points,
        triangles: Elements<3>,
        thickness_m: f64,
        stiffness: f64,
    ) -> PyResult<Obstacle> {
        let h = self.with(|s| s.add_prescribed_surface(label, &vertices.0, &triangles.0, thickness_m, stiffness))?;
        Ok(Obstacle::new(self.id, label, &h))
    }

    /// Prescribe the nodes of an object inside the axis-aligned box of `center` and full `size`
    /// (m); selecting no node is an error.
    #[pyo3(signature = (nodes, center, size, params=None))]
    fn prescribe_in_box(
        &self,
        py: Python<'_>,
        nodes: NodesArg,
        center: V3,
        size: V3,
        params: Option<&Bound<'_, params::PrescribedParams>>,
    ) -> PyResult<PrescribedHandle> {
        self.own(&nodes.0)?;
        let p = prescribed_params(py, params)?;
        let h = self.with(|s| s.prescribe_in_box(nodes.0.rust(), center.0, size.0, p))?;
        Ok(PrescribedHandle::new(self.id, h))
    }

    /// Prescribe the nodes of an object outside the axis-aligned box of `center` and `size` (m).
    #[pyo3(signature = (nodes, center, size, params=None))]
    fn prescribe_outside_box(
        &self,
        py: Python<'_>,
        nodes: NodesArg,
        center: V3,
        size: V3,
        params: Option<&Bound<'_, params::PrescribedParams>>,
    ) -> PyResult<PrescribedHandle> {
        self.own(&nodes.0)?;
        let p = prescribed_params(py, params)?;
        let set = nodes.0.rust();
        let h = self.with(|s| {
            let label = s.deformables.sets[set.index as usize].0.clone();
            let (h, n) = s
                .deformables
                .prescribed
                .add_in_box(&s.nodes, set, &label, center.0, size.0, false, p)?;
            if n == 0 {
                return Err(stark::StarkError::InvalidInput(format!(
                    "every node of '{label}' lies inside the box: nothing to prescribe"
                )));
            }
            Ok(h)
        })?;
        Ok(PrescribedHandle::new(self.id, h))
    }

    /// Prescribe the nodes `indices` (local to the object); targets start at their positions.
    #[pyo3(signature = (nodes, indices, params=None))]
    fn prescribe_nodes(
        &self,
        py: Python<'_>,
        nodes: NodesArg,
        indices: Indices,
        params: Option<&Bound<'_, params::PrescribedParams>>,
    ) -> PyResult<PrescribedHandle> {
        self.own(&nodes.0)?;
        let p = prescribed_params(py, params)?;
        let set = nodes.0.rust();
        let h = self.with(|s| {
            let label = s.deformables.sets[set.index as usize].0.clone();
            s.deformables.prescribed.add(&s.nodes, set, &label, &indices.0, p)
        })?;
        Ok(PrescribedHandle::new(self.id, h))
    }

    /// Targets become `R·p + translation` for the reference positions `p` (positions when the
    /// group was added); `rotation` is a quaternion (w, x, y, z) or a (3, 3) matrix.
    #[pyo3(signature = (prescribed, translation, rotation=None))]
    fn set_transform(&self, prescribed: PrescribedArg, translation: V3, rotation: Option<Rot>) -> PyResult<()> {
        self.own(&prescribed.0)?;
        let r = rotation.map(|r| r.0).unwrap_or_else(UnitQuaternion::identity);
        check_finite(&translation.0, "translation")?;
        self.with(|s| {
            s.deformables
                .prescribed
                .set_transform(prescribed.0.rust(), translation.0, r.to_rotation_matrix())
        })
    }

    /// `set_transform` with a rotation by `angle_deg` about `axis` through the origin.
    fn set_transform_deg(&self, prescribed: PrescribedArg, translation: V3, angle_deg: f64, axis: V3) -> PyResult<()> {
        self.own(&prescribed.0)?;
        check_finite(&translation.0, "translation")?;
        if !angle_deg.is_finite() || axis.0.norm() == 0.0 || !axis.0.iter().all(|c| c.is_finite()) {
            return Err(stark_err(format!(
                "angle {angle_deg} and axis {:?} must be finite and the axis non-zero",
                axis.0
            )));
        }
        self.with(|s| {
            s.deformables
                .prescribed
                .set_transform_deg(prescribed.0.rust(), translation.0, angle_deg, axis.0)
        })
    }

    /// Set the target of the `i`-th node of a prescribed group, m.
    fn set_target(&self, prescribed: PrescribedArg, i: usize, target: V3) -> PyResult<()> {
        self.own(&prescribed.0)?;
        check_finite(&target.0, "target")?;
        self.with(|s| s.deformables.prescribed.set_target(prescribed.0.rust(), i, target.0))
    }

    /// Targets of a prescribed group, m: a new (n, 3) array.
    fn targets<'py>(&self, py: Python<'py>, prescribed: PrescribedArg) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
        self.own(&prescribed.0)?;
        let t = self.with(|s| {
            s.deformables
                .prescribed
                .targets(prescribed.0.rust())
                .map(|t| t.to_vec())
        })?;
        Ok(points_out(py, &t))
    }

    /// Global node indices of a prescribed group.
    fn prescribed_nodes(&self, prescribed: PrescribedArg) -> PyResult<Vec<u32>> {
        self.own(&prescribed.0)?;
        self.with(|s| {
            s.deformables
                .prescribed
                .nodes_of(prescribed.0.rust())
                .map(|n| n.to_vec())
        })
    }

    /// Largest distance of a prescribed group's nodes to their targets, m.
    fn max_violation(&self, prescribed: PrescribedArg) -> PyResult<f64> {
        self.own(&prescribed.0)?;
        self.with(|s| {
            s.deformables
                .prescribed
                .max_violation_m(prescribed.0.rust(), &s.nodes.x)
        })
    }

    /// Total mass of an object's inertia group, kg.
    fn mass(&self, inertia: &Bound<'_, PyAny>) -> PyResult<f64> {
        let h = if let Ok(h) = inertia.cast::<InertiaHandle>() {
            *h.get()
        } else {
            inertia
                .getattr("inertia")
                .ok()
                .and_then(|a| a.cast::<InertiaHandle>().ok().map(|h| *h.get()))
                .ok_or_else(|| PyTypeError::new_err("expected an InertiaHandle or an object with inertia"))?
        };
        self.own(&h)?;
        self.with(|s| s.deformables.inertia.mass(h.rust()))
    }

    /// Number of inverted tets at the current positions.
    fn count_inverted_tets(&self) -> PyResult<usize> {
        self.get(|s| s.deformables.tets.count_inverted(&s.nodes.x))
    }

    // -----------------------------------------------------------------------------------------
    // Attachments
    // -----------------------------------------------------------------------------------------

    /// Glue node `points_a[i]` of `a` to node `points_b[i]` of `b`.
    #[pyo3(signature = (label, a, points_a, b, points_b, params=None))]
    fn add_attachment_point_point(
        &self,
        py: Python<'_>,
        label: &str,
        a: NodesArg,
        points_a: Indices,
        b: NodesArg,
        points_b: Indices,
        params: Option<&Bound<'_, params::AttachmentParams>>,
    ) -> PyResult<AttachmentHandle> {
        self.own(&a.0)?;
        self.own(&b.0)?;
        check_label(label)?;
        let p = attachment_params_arg(py, params)?;
        let h = self.with(|s| {
            s.deformables
                .attachments
                .add_point_point(label, a.0.rust(), &points_a.0, b.0.rust(), &points_b.0, p)
        })?;
        Ok(AttachmentHandle {
            handle: h,
            sim: self.id,
        })
    }

    /// Glue node `points[i]` of `a` to the point `(1 − t) e0 + t e1` of edge `edges[i]` of `b`
    /// with `t = edge_parameters[i]`.
    #[pyo3(signature = (label, a, points, b, edges, edge_parameters, params=None))]
    fn add_attachment_point_edge(
        &self,
        py: Python<'_>,
        label: &str,
        a: NodesArg,
        points: Indices,
        b: NodesArg,
        edges: Elements<2>,
        edge_parameters: Floats,
        params: Option<&Bound<'_, params::AttachmentParams>>,
    ) -> PyResult<AttachmentHandle> {
        self.own(&a.0)?;
        self.own(&b.0)?;
        check_label(label)?;
        let p = attachment_params_arg(py, params)?;
        let h = self.with(|s| {
            s.deformables.attachments.add_point_edge(
                label,
                a.0.rust(),
                &points.0,
                b.0.rust(),
                &edges.0,
                &edge_parameters.0,
                p,
            )
        })?;
        Ok(AttachmentHandle {
            handle: h,
            sim: self.id,
        })
    }

    /// Glue node `points[i]` of `a` to the point with barycentric coordinates `barycentric[i]`
    /// (summing to 1) of triangle `triangles[i]` of `b`.
    #[pyo3(signature = (label, a, points, b, triangles, barycentric, params=None))]
    fn add_attachment_point_triangle(
        &self,
        py: Python<'_>,
        label: &str,
        a: NodesArg,
        points: Indices,
        b: NodesArg,
        triangles: Elements<3>,
        barycentric: Points,
        params: Option<&Bound<'_, params::AttachmentParams>>,
    ) -> PyResult<AttachmentHandle> {
        self.own(&a.0)?;
        self.own(&b.0)?;
        check_label(label)?;
        let p = attachment_params_arg(py, params)?;
        let w: Vec<[f64; 3]> = barycentric.0.iter().map(|v| [v.x, v.y, v.z]).collect();
        let h = self.with(|s| {
            s.deformables
                .attachments
                .add_point_triangle(label, a.0.rust(), &points.0, b.0.rust(), &triangles.0, &w, p)
        })?;
        Ok(AttachmentHandle {
            handle: h,
            sim: self.id,
        })
    }

    /// Largest gap of an attachment group at the current positions, m.
    fn attachment_gap(&self, attachment: AttachmentHandle) -> PyResult<f64> {
        self.own(&attachment)?;
        self.with(|s| s.deformables.attachments.max_gap_m(attachment.handle, &s.nodes.x))
    }

    // -----------------------------------------------------------------------------------------
    // Contact
    // -----------------------------------------------------------------------------------------

    /// All contact objects, in creation order.
    fn contact_objects(&self) -> PyResult<Vec<ContactHandle>> {
        let n = self.get(|s| s.contact.objects().len())?;
        Ok((0..n as u32)
            .map(|i| ContactHandle::new(self.id, stark::contact::ContactHandle(i)))
            .collect())
    }

    /// The contact object labelled `label`, or None.
    fn contact_object(&self, label: &str) -> PyResult<Option<ContactHandle>> {
        Ok(self
            .get(|s| s.contact.object_by_label(label))?
            .map(|h| ContactHandle::new(self.id, h)))
    }

    /// Label of a contact object.
    fn contact_label(&self, contact: ContactArg) -> PyResult<String> {
        self.own(&contact.0)?;
        self.with(|s| {
            s.contact
                .objects()
                .get(contact.0.index as usize)
                .map(|o| o.label.clone())
                .ok_or_else(|| stark::StarkError::InvalidInput("no such contact object".into()))
        })
    }

    /// Contact thickness of an object, m.
    fn contact_thickness(&self, contact: ContactArg) -> PyResult<f64> {
        self.own(&contact.0)?;
        self.with(|s| {
            s.contact
                .objects()
                .get(contact.0.index as usize)
                .map(|o| o.thickness_m)
                .ok_or_else(|| stark::StarkError::InvalidInput("no such contact object".into()))
        })
    }

    /// Change an object's contact thickness, m (a pair activates within the sum of thicknesses).
    fn set_contact_thickness(&self, contact: ContactArg, thickness_m: f64) -> PyResult<()> {
        self.own(&contact.0)?;
        self.with(|s| s.contact.set_thickness(contact.0.rust(), thickness_m))
    }

    /// Friction coefficient μ between two objects (`a` = `b`: self-friction); unset pairs have 0.
    fn set_friction(&self, a: ContactArg, b: ContactArg, mu: f64) -> PyResult<()> {
        self.own(&a.0)?;
        self.own(&b.0)?;
        self.with(|s| s.contact.set_friction(a.0.rust(), b.0.rust(), mu))
    }

    /// Friction coefficient between two objects.
    fn friction(&self, a: ContactArg, b: ContactArg) -> PyResult<f64> {
        self.own(&a.0)?;
        self.own(&b.0)?;
        self.with(|s| s.contact.friction(a.0.rust(), b.0.rust()))
    }

    /// Switch collisions between two objects (`a` = `b`: self-collision) on or off.
    fn set_collision(&self, a: ContactArg, b: ContactArg, enabled: bool) -> PyResult<()> {
        self.own(&a.0)?;
        self.own(&b.0)?;
        self.with(|s| s.contact.set_collision(a.0.rust(), b.0.rust(), enabled))
    }

    /// Switch collisions between two objects off (the original's disable_collision).
    fn disable_collision(&self, a: ContactArg, b: ContactArg) -> PyResult<()> {
        self.set_collision(a, b, false)
    }

    /// Current barrier stiffness κ, N/m (0 before the first step).
    #[getter]
    fn contact_stiffness(&self) -> PyResult<f64> {
        self.get(|s| s.contact.stiffness())
    }

    /// Contact statistics of the last step (active pairs, smallest distance, κ, CCD) as a dict.
    fn contact_stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let stats = self.get(|s| s.contact.stats)?;
        report_out(py, &stats)
    }

    /// Descriptions of all intersecting edge–triangle pairs of the contact surfaces now (exact test).
    fn find_intersections(&self) -> PyResult<Vec<String>> {
        self.get(|s| s.contact.find_intersections(&s.nodes.x))
    }

    // -----------------------------------------------------------------------------------------
    // Rigid bodies
    // -----------------------------------------------------------------------------------------

    /// Add a rigid body of `mass_kg` and body-frame inertia tensor `inertia_kg_m2` (3, 3) about
    /// its centre of mass, placed at `position_m` with `orientation` (quaternion (w, x, y, z) or
    /// (3, 3) matrix). It starts at rest.
    #[pyo3(signature = (label, mass_kg, inertia_kg_m2, position_m=None, orientation=None))]
    fn add_rigid_body(
        &self,
        label: &str,
        mass_kg: f64,
        inertia_kg_m2: M3,
        position_m: Option<V3>,
        orientation: Option<Rot>,
    ) -> PyResult<RigidBody> {
        let (p, q) = pose(position_m, orientation);
        let h = self.with(|s| s.add_rigid_body(label, mass_kg, inertia_kg_m2.0, p, q))?;
        Ok(RigidBody::new(self.id, h, label))
    }

    /// Add a rigid body from its mass properties; its centre of mass goes to `position_m`.
    #[pyo3(signature = (label, mass_properties, position_m=None, orientation=None))]
    fn add_rigid_body_with(
        &self,
        label: &str,
        mass_properties: &MassProperties,
        position_m: Option<V3>,
        orientation: Option<Rot>,
    ) -> PyResult<RigidBody> {
        let (p, q) = pose(position_m, orientation);
        let props = mass_properties.rust();
        let h = self.with(|s| s.add_rigid_body_with(label, &props, p, q))?;
        Ok(RigidBody::new(self.id, h, label))
    }

    /// Give a body a collision mesh: vertices (n, 3) in the body frame (relative to its centre of
    /// mass) and triangles (m, 3), with contact thickness `thickness_m` (or the default).
    #[pyo3(signature = (body, local_vertices_m, triangles, thickness_m=None))]
    fn add_rigid_collision_mesh(
        &self,
        body: BodyArg,
        local_vertices_m: Points,
        triangles: Elements<3>,
        thickness_m: Option<f64>,
    ) -> PyResult<RigidMesh> {
        self.own(&body.0)?;
        let h =
            self.with(|s| s.add_rigid_collision_mesh(body.0.rust(), &local_vertices_m.0, &triangles.0, thickness_m))?;
        Ok(RigidMesh {
            body: body.0,
            nodes: NodeSet::new(self.id, h.nodes),
            contact: ContactHandle::new(self.id, h.contact),
        })
    }

    /// The rigid body labelled `label`, or None.
    fn rigid_body(&self, label: &str) -> PyResult<Option<RigidBody>> {
        Ok(self
            .get(|s| s.rigid_bodies.by_label(label))?
            .map(|h| RigidBody::new(self.id, h, label)))
    }

    /// All rigid bodies, in creation order.
    fn rigid_bodies(&self) -> PyResult<Vec<RigidBody>> {
        let labels = self.get(|s| s.rigid_bodies.labels.clone())?;
        Ok(labels
            .into_iter()
            .enumerate()
            .map(|(i, label)| RigidBody {
                index: i as u32,
                label,
                sim: self.id,
            })
            .collect())
    }

    /// Centre of mass of a body, m.
    fn body_position<'py>(&self, py: Python<'py>, body: BodyArg) -> PyResult<Bound<'py, numpy::PyArray1<f64>>> {
        let b = self.body(&body)?;
        Ok(v3_out(py, &self.get(|s| s.body_position(b))?))
    }

    /// Orientation of a body (body → world) as a quaternion (w, x, y, z).
    fn body_orientation<'py>(&self, py: Python<'py>, body: BodyArg) -> PyResult<Bound<'py, numpy::PyArray1<f64>>> {
        let b = self.body(&body)?;
        Ok(quat_out(py, &self.get(|s| s.body_orientation(b))?))
    }

    /// Rotation matrix of a body (body → world), (3, 3).
    fn body_rotation<'py>(&self, py: Python<'py>, body: BodyArg) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
        let b = self.body(&body)?;
        let r = self.get(|s| s.body_orientation(b).to_rotation_matrix().into_inner())?;
        Ok(m3_out(py, &r))
    }

    /// Linear velocity of a body's centre of mass, m/s.
    fn body_velocity<'py>(&self, py: Python<'py>, body: BodyArg) -> PyResult<Bound<'py, numpy::PyArray1<f64>>> {
        let b = self.body(&body)?;
        Ok(v3_out(py, &self.get(|s| s.body_velocity(b))?))
    }

    /// Angular velocity of a body (world frame), rad/s.
    fn body_angular_velocity<'py>(&self, py: Python<'py>, body: BodyArg) -> PyResult<Bound<'py, numpy::PyArray1<f64>>> {
        let b = self.body(&body)?;
        Ok(v3_out(py, &self.get(|s| s.body_angular_velocity(b))?))
    }

    /// Angular momentum of a body about its centre of mass (world), kg·m²/s.
    fn body_angular_momentum<'py>(&self, py: Python<'py>, body: BodyArg) -> PyResult<Bound<'py, numpy::PyArray1<f64>>> {
        let b = self.body(&body)?;
        Ok(v3_out(py, &self.get(|s| s.body_angular_momentum(b))?))
    }

    /// Mass of a body, kg.
    fn body_mass(&self, body: BodyArg) -> PyResult<f64> {
        let b = self.body(&body)?;
        self.get(|s| s.bodies.mass[b.i()])
    }

    /// Body-frame inertia tensor of a body about its centre of mass, kg·m², (3, 3).
    fn body_inertia<'py>(&self, py: Python<'py>, body: BodyArg) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
        let b = self.body(&body)?;
        Ok(m3_out(py, &self.get(|s| s.bodies.inertia_local[b.i()])?))
    }

    /// External force on a body's centre of mass, N.
    fn body_force<'py>(&self, py: Python<'py>, body: BodyArg) -> PyResult<Bound<'py, numpy::PyArray1<f64>>> {
        let b = self.body(&body)?;
        Ok(v3_out(py, &self.get(|s| s.bodies.force[b.i()])?))
    }

    /// External torque on a body, N·m.
    fn body_torque<'py>(&self, py: Python<'py>, body: BodyArg) -> PyResult<Bound<'py, numpy::PyArray1<f64>>> {
        let b = self.body(&body)?;
        Ok(v3_out(py, &self.get(|s| s.bodies.torque[b.i()])?))
    }

    /// World positions of body-frame points: (3,) → (3,), (n, 3) → (n, 3).
    fn body_point_to_world<'py>(
        &self,
        py: Python<'py>,
        body: BodyArg,
        points_m: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let b = self.body(&body)?;
        self.map_points(py, points_m, |s, p| s.body_point_to_world(b, p))
    }

    /// Body-frame coordinates of world points: (3,) → (3,), (n, 3) → (n, 3).
    fn body_point_to_local<'py>(
        &self,
        py: Python<'py>,
        body: BodyArg,
        points_m: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let b = self.body(&body)?;
        self.map_points(py, points_m, |s, p| s.body_point_to_local(b, p))
    }

    /// World directions of body-frame directions: (3,) → (3,), (n, 3) → (n, 3).
    fn body_direction_to_world<'py>(
        &self,
        py: Python<'py>,
        body: BodyArg,
        directions: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let b = self.body(&body)?;
        self.map_points(py, directions, |s, p| s.body_direction_to_world(b, p))
    }

    /// Body-frame directions of world directions: (3,) → (3,), (n, 3) → (n, 3).
    fn body_direction_to_local<'py>(
        &self,
        py: Python<'py>,
        body: BodyArg,
        directions: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let b = self.body(&body)?;
        self.map_points(py, directions, |s, p| s.body_direction_to_local(b, p))
    }

    /// Velocities of world points moving with the body, m/s: (3,) → (3,), (n, 3) → (n, 3).
    fn body_velocity_at<'py>(
        &self,
        py: Python<'py>,
        body: BodyArg,
        points_m: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let b = self.body(&body)?;
        self.map_points(py, points_m, |s, p| s.body_velocity_at(b, p))
    }

    /// Move a body: centre of mass to `position_m`, orientation to `orientation` (default:
    /// unchanged); its meshes follow.
    #[pyo3(signature = (body, position_m, orientation=None))]
    fn set_body_pose(&self, body: BodyArg, position_m: V3, orientation: Option<Rot>) -> PyResult<()> {
        let b = self.body(&body)?;
        self.with(|s| {
            let q = orientation.map(|q| q.0).unwrap_or_else(|| s.body_orientation(b));
            s.set_body_pose(b, position_m.0, q)
        })
    }

    /// Set the linear velocity of a body's centre of mass, m/s.
    fn set_body_velocity(&self, body: BodyArg, velocity_m_s: V3) -> PyResult<()> {
        let b = self.body(&body)?;
        self.with(|s| s.set_body_velocity(b, velocity_m_s.0))
    }

    /// Set the angular velocity of a body (world frame), rad/s.
    fn set_body_angular_velocity(&self, body: BodyArg, angular_velocity_rad_s: V3) -> PyResult<()> {
        let b = self.body(&body)?;
        self.with(|s| s.set_body_angular_velocity(b, angular_velocity_rad_s.0))
    }

    /// Set the external force at a body's centre of mass (persists until changed), N.
    fn set_body_force(&self, body: BodyArg, force_n: V3) -> PyResult<()> {
        let b = self.body(&body)?;
        self.with(|s| s.set_body_force(b, force_n.0))
    }

    /// Set the external torque on a body (persists until changed), N·m.
    fn set_body_torque(&self, body: BodyArg, torque_n_m: V3) -> PyResult<()> {
        let b = self.body(&body)?;
        self.with(|s| s.set_body_torque(b, torque_n_m.0))
    }

    /// Add a force `force_n` applied at the world point `at_m`: a force at the centre of mass
    /// plus the torque (at − c) × f (persists until changed).
    fn add_body_force_at(&self, body: BodyArg, force_n: V3, at_m: V3) -> PyResult<()> {
        let b = self.body(&body)?;
        self.with(|s| s.add_body_force_at(b, force_n.0, at_m.0))
    }

    /// Set the external acceleration of a body (added to gravity; persists), m/s².
    fn set_body_acceleration(&self, body: BodyArg, acceleration_m_s2: V3) -> PyResult<()> {
        let b = self.body(&body)?;
        self.with(|s| s.set_body_acceleration(b, acceleration_m_s2.0))
    }

    /// Set the external angular acceleration of a body (persists), rad/s².
    fn set_body_angular_acceleration(&self, body: BodyArg, angular_acceleration_rad_s2: V3) -> PyResult<()> {
        let b = self.body(&body)?;
        self.with(|s| s.set_body_angular_acceleration(b, angular_acceleration_rad_s2.0))
    }

    /// Every body's pose and velocity by label: dicts with `position_m`, `orientation_wxyz`,
    /// `velocity_m_s` and `angular_velocity_rad_s` (world frame), as in the body log.
    fn body_states<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let states = self.get(|s| s.body_states())?;
        let d = PyDict::new(py);
        for (label, state) in states {
            d.set_item(label, to_python(py, &state)?)?;
        }
        Ok(d)
    }

    /// The contact objects of a body's collision meshes, in the order they were added.
    fn body_collision_meshes(&self, body: BodyArg) -> PyResult<Vec<ContactHandle>> {
        let b = self.body(&body)?;
        let hs = self.with(|s| s.body_collision_meshes(b).map(|c| c.to_vec()))?;
        Ok(hs.into_iter().map(|c| ContactHandle::new(self.id, c)).collect())
    }

    /// Change the mass (kg) and body-frame inertia tensor (kg·m², (3, 3)) of a body.
    fn set_body_mass(&self, body: BodyArg, mass_kg: f64, inertia_kg_m2: M3) -> PyResult<()> {
        let b = self.body(&body)?;
        self.with(|s| s.set_body_mass(b, mass_kg, inertia_kg_m2.0))
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

/// The progress bar of `run(..., progress=True)`, written to `sys.stderr` (so notebooks and
/// pytest's capture see it), redrawn at most five times a second.
struct ProgressLine {
    start_s: f64,
    duration_s: f64,
    wall: std::time::Instant,
    last_draw: Option<std::time::Instant>,
}

impl ProgressLine {
    fn new(start_s: f64, duration_s: f64) -> Self {
        ProgressLine {
            start_s,
            duration_s,
            wall: std::time::Instant::now(),
            last_draw: None,
        }
    }

    fn draw(&mut self, py: Python<'_>, time_s: f64, steps: u64, last: bool) -> PyResult<()> {
        if !last && self.last_draw.is_some_and(|d| d.elapsed().as_secs_f64() < 0.2) {
            return Ok(());
        }
        self.last_draw = Some(std::time::Instant::now());
        const WIDTH: usize = 30;
        let done = if self.duration_s > 0.0 {
            ((time_s - self.start_s) / self.duration_s).clamp(0.0, 1.0)
        } else {
            1.0
        };
        let filled = (done * WIDTH as f64).round() as usize;
        let line = format!(
            "\r[{}{}] {:3.0}%  {:.3}/{:.3} s simulated  step {}  {:.1} s{}",
            "#".repeat(filled),
            "-".repeat(WIDTH - filled),
            100.0 * done,
            time_s - self.start_s,
            self.duration_s,
            steps,
            self.wall.elapsed().as_secs_f64(),
            if last { "\n" } else { "" }
        );
        let stderr = py.import("sys")?.getattr("stderr")?;
        stderr.call_method1("write", (line,))?;
        stderr.call_method0("flush")?;
        Ok(())
    }
}

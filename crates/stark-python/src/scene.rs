//! Scene files and built-in scenes.

use crate::convert::{guarded, stark_err};
use crate::handles::{
    AttachmentHandle, FixedSurface, Line, Obstacle, PrescribedHandle, SceneRigidBody, Surface, Volume,
};
use crate::joints::Joint;
use crate::params;
use crate::simulation::Simulation;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use stark::rigidbodies::joints::JointHandle;
use std::path::PathBuf;

/// A simulation built from a scene file or a built-in scene, ready to `run(duration_s)`.
#[pyclass(module = "starkrs", frozen, get_all)]
pub struct Scene {
    /// The simulation with every object, boundary condition and event of the scene.
    pub simulation: Py<Simulation>,
    /// Simulated time the scene asks for, s.
    pub duration_s: f64,
    /// Scene name.
    pub name: String,
    /// The objects by name: Surface, Volume, Line, Obstacle, FixedSurface or SceneRigidBody
    /// handles (scene files only).
    pub objects: Py<PyDict>,
    /// The `[[prescribed]]` entries in file order: dicts with `object`, `handle` and `nodes`.
    pub prescribed: Py<PyList>,
    /// The `[[attachment]]` entries by label.
    pub attachments: Py<PyDict>,
    /// The joints by label: the `[[joint]]` entries and the fix joints of fixed bodies (`<body>.fixed`).
    pub joints: Py<PyDict>,
}

#[pymethods]
impl Scene {
    /// Run the scene for `duration` seconds (default: its own duration); returns the run summary.
    #[pyo3(signature = (duration=None, callback=None, progress=false))]
    fn run<'py>(
        &self,
        py: Python<'py>,
        duration: Option<f64>,
        callback: Option<Py<PyAny>>,
        progress: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        self.simulation
            .bind(py)
            .call_method1("run", (duration.unwrap_or(self.duration_s), callback, progress))
    }

    fn __repr__(&self) -> String {
        format!("Scene('{}', duration_s={})", self.name, self.duration_s)
    }
}

fn configure(
    s: &mut stark::Settings,
    output_directory: Option<PathBuf>,
    threads: Option<usize>,
    frames: Option<bool>,
    step_log: Option<bool>,
) {
    if let Some(d) = output_directory {
        s.output.directory = d;
    }
    if let Some(t) = threads {
        s.threads = t;
    }
    if let Some(f) = frames {
        s.output.frames = f;
    }
    if let Some(l) = step_log {
        s.output.step_log = l;
    }
}

/// The joints of simulation `sim` as a dict by label.
fn joints_by_label(py: Python<'_>, sim: u64, joints: Vec<JointHandle>) -> PyResult<Bound<'_, PyDict>> {
    let d = PyDict::new(py);
    for h in joints {
        d.set_item(h.label.clone(), Joint::new(sim, h))?;
    }
    Ok(d)
}

fn wrap(py: Python<'_>, scene: stark::io::LoadedScene) -> PyResult<Scene> {
    let sim = Simulation::wrap(scene.simulation);
    let id = sim.id();
    let objects = PyDict::new(py);
    for (name, obj) in &scene.objects {
        use stark::io::scene::SceneObject as O;
        let handle: Bound<'_, PyAny> = match obj {
            O::Surface(h) => Bound::new(py, Surface::new(py, id, name, h)?)?.into_any(),
            O::Volume(h) => Bound::new(py, Volume::new(id, name, h))?.into_any(),
            O::Line(h) => Bound::new(py, Line::new(id, name, h))?.into_any(),
            O::Obstacle(h) => Bound::new(py, Obstacle::new(id, name, h))?.into_any(),
            O::FixedObstacle(h) => Bound::new(py, FixedSurface::new(id, name, h))?.into_any(),
            O::RigidBody(b) => Bound::new(py, SceneRigidBody::new(id, name, b))?.into_any(),
        };
        objects.set_item(name, handle)?;
    }
    let prescribed = PyList::empty(py);
    for p in &scene.prescribed {
        let d = PyDict::new(py);
        d.set_item("object", &p.object)?;
        d.set_item("handle", PrescribedHandle::new(id, p.handle))?;
        d.set_item("nodes", p.nodes)?;
        prescribed.append(d)?;
    }
    let attachments = PyDict::new(py);
    for (label, h) in &scene.attachments {
        attachments.set_item(label, AttachmentHandle { handle: *h, sim: id })?;
    }
    let joints = joints_by_label(py, id, scene.joints)?;
    Ok(Scene {
        simulation: Py::new(py, sim)?,
        duration_s: scene.duration_s,
        name: scene.name,
        objects: objects.unbind(),
        prescribed: prescribed.unbind(),
        attachments: attachments.unbind(),
        joints: joints.unbind(),
    })
}

/// Load a scene file (TOML, or JSON if the name ends in `.json`). The optional arguments
/// override the file's output directory, thread count, frames and step log; `overrides` is a
/// list of `key.path=value` strings applied to the file first (as `stark run --set`).
#[pyfunction]
#[pyo3(signature = (path, output_directory=None, threads=None, frames=None, step_log=None, overrides=None))]
fn load_scene(
    py: Python<'_>,
    path: PathBuf,
    output_directory: Option<PathBuf>,
    threads: Option<usize>,
    frames: Option<bool>,
    step_log: Option<bool>,
    overrides: Option<Vec<String>>,
) -> PyResult<Scene> {
    let overrides = overrides.unwrap_or_default();
    let scene = py.detach(|| {
        guarded(|| {
            stark::io::load_scene_with_overrides(&path, &overrides, |s| {
                configure(s, output_directory, threads, frames, step_log)
            })
        })
    })?;
    wrap(py, scene)
}

/// Build a scene from its text; `file_name` names it in errors and picks the format (JSON if it
/// ends in `.json`); relative mesh paths are resolved against `base_dir`.
#[pyfunction]
#[pyo3(signature = (text, file_name="scene.toml", base_dir=PathBuf::from("."), output_directory=None, threads=None, frames=None, step_log=None))]
fn parse_scene(
    py: Python<'_>,
    text: &str,
    file_name: &str,
    base_dir: PathBuf,
    output_directory: Option<PathBuf>,
    threads: Option<usize>,
    frames: Option<bool>,
    step_log: Option<bool>,
) -> PyResult<Scene> {
    let scene = guarded(|| {
        stark::io::parse_scene_with(text, file_name, &base_dir, |s| {
            configure(s, output_directory, threads, frames, step_log)
        })
    })?;
    wrap(py, scene)
}

/// The built-in scenes: a list of dicts with `name`, `description` and `duration_s`.
#[pyfunction]
fn builtin_scenes(py: Python<'_>) -> PyResult<Bound<'_, PyList>> {
    let list = PyList::empty(py);
    for s in stark::scenes::builtin_scenes() {
        let d = PyDict::new(py);
        d.set_item("name", s.name)?;
        d.set_item("description", s.description)?;
        d.set_item("duration_s", s.duration_s)?;
        list.append(d)?;
    }
    Ok(list)
}

/// Build the built-in scene `name` (see `builtin_scenes()`); `settings` provides the base
/// settings (output directory, threads, ...), which the scene then adjusts.
#[pyfunction]
#[pyo3(signature = (name, settings=None))]
fn builtin_scene(py: Python<'_>, name: &str, settings: Option<&Bound<'_, params::Settings>>) -> PyResult<Scene> {
    let settings = params::settings_from(py, settings)?;
    let scene = guarded(|| stark::scenes::find_scene(name))?;
    let sim = guarded(|| (scene.build)(settings))?;
    if sim.settings.name.is_empty() {
        return Err(stark_err("scene without a name"));
    }
    let name = sim.settings.name.clone();
    let named_joints = sim.rigid_bodies.named_joints.clone();
    let simulation = Simulation::wrap(sim);
    let joints = joints_by_label(py, simulation.id(), named_joints)?;
    Ok(Scene {
        simulation: Py::new(py, simulation)?,
        duration_s: scene.duration_s,
        name,
        objects: PyDict::new(py).unbind(),
        prescribed: PyList::empty(py).unbind(),
        attachments: PyDict::new(py).unbind(),
        joints: joints.unbind(),
    })
}

/// Classify a robot–towel run from its probe log (`<out>/<scene>.robot_towel.jsonl`): a dict
/// with `outcome` ("P", "O" or "S"), `reason`, `robot_advance_m`, `towel_advance_m` and
/// `mean_torque_fraction`, as `stark run` and `stark sweep` report it.
#[pyfunction]
fn classify_robot_towel(py: Python<'_>, log: PathBuf) -> PyResult<Bound<'_, PyAny>> {
    let c = guarded(|| stark::scenes::kobuki_towel::classify_log(&log))?;
    let text = serde_json::to_string(&c).map_err(|e| stark_err(e.to_string()))?;
    py.import("json")?.call_method1("loads", (text,))
}

/// The grasp's break and slip from a `franka_cup` (or `franka_rigid_box`) probe log
/// (`<out>/<scene>.grasp.jsonl`), as `stark run` reports them: a dict with `reference_time_s`,
/// `break_time_s` and `at_break` (when static grasping broke: the cup slid faster than 1 mm/s
/// with the jaws' friction at μ·ΣN; None: it never did), `slip_time_s` (the 1 mm slip; None: it
/// held), `at` (the readouts at the slip, or at the end), `load_over_capacity`, `max_held_ratio`
/// and `final_drop_m`.
#[pyfunction]
#[pyo3(signature = (log, pour_start_s=1.2))]
fn grasp_outcome(py: Python<'_>, log: PathBuf, pour_start_s: f64) -> PyResult<Bound<'_, PyAny>> {
    let o = guarded(|| stark::scenes::franka_cup::grasp_outcome(&log, pour_start_s))?;
    let text = serde_json::to_string(&o).map_err(|e| stark_err(e.to_string()))?;
    py.import("json")?.call_method1("loads", (text,))
}

/// The lab's outcome (Table I) of a built-in robot–towel scene, or None for other names.
#[pyfunction]
fn robot_towel_lab_outcome(name: &str) -> Option<String> {
    stark::scenes::kobuki_towel::Case::from_name(name).map(|c| c.lab_outcome().to_string())
}

/// Register the functions and classes.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(classify_robot_towel, m)?)?;
    m.add_function(wrap_pyfunction!(grasp_outcome, m)?)?;
    m.add_function(wrap_pyfunction!(robot_towel_lab_outcome, m)?)?;
    m.add_class::<Scene>()?;
    m.add_function(wrap_pyfunction!(load_scene, m)?)?;
    m.add_function(wrap_pyfunction!(parse_scene, m)?)?;
    m.add_function(wrap_pyfunction!(builtin_scenes, m)?)?;
    m.add_function(wrap_pyfunction!(builtin_scene, m)?)?;
    Ok(())
}

//! `starkrs`: Stark-rs from Python.
//!
//! The whole simulator (settings, deformables with their materials and presets, rigid bodies,
//! contact, time events, outputs, scene files and built-in scenes) and the contact geometry
//! toolkit, with NumPy arrays in and out. The Python package `starkrs` (in `python/`) re-exports
//! this extension module (`starkrs._starkrs`) and ships type stubs.
//!
//! Layout mirrors the library: `params.rs` (settings, parameters, materials), `handles.rs`,
//! `simulation.rs`, `rigid.rs`, `scene.rs`, `meshes.rs` and `geometry.rs`; `convert.rs` holds
//! the NumPy and error conversions. Joints, when the library has them, get `add_*` methods on
//! `Simulation` returning handles (like `add_rigid_body`), with their parameters read and
//! written through `Simulation.params`/`set_params` like every other model.

mod convert;
mod geometry;
mod handles;
mod meshes;
mod params;
mod rigid;
mod scene;
mod simulation;

use pyo3::prelude::*;

/// The extension module.
#[pymodule]
fn _starkrs(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("StarkError", py.get_type::<convert::StarkError>())?;
    m.add("SceneError", py.get_type::<convert::SceneError>())?;
    m.add("StepFailedError", py.get_type::<convert::StepFailedError>())?;
    m.add("InvalidHandleError", py.get_type::<convert::InvalidHandleError>())?;
    params::register(m)?;
    handles::register(m)?;
    rigid::register(m)?;
    simulation::register(m)?;
    scene::register(m)?;
    m.add_submodule(&geometry::module(py)?)?;
    m.add_submodule(&meshes::module(py)?)?;
    Ok(())
}

//! `starkrs`: Stark-rs from Python.
//!
//! The whole simulator (settings, deformables with their materials and presets, rigid bodies,
//! contact, time events, outputs, scene files and built-in scenes) and the contact geometry
//! toolkit, with NumPy arrays in and out. The Python package `starkrs` (in `python/`) re-exports
//! this extension module (`starkrs._starkrs`) and ships type stubs.
//!
//! Layout mirrors the library: `params.rs` (settings, parameters, materials; the parameter
//! classes listed in `param_list.rs`, which stark-codegen's `gen_stubs` renders into the stubs),
//! `handles.rs`, `handle_params.rs` (`params`/`set_params` of every handle kind),
//! `simulation.rs`, `rigid.rs`, `scene.rs`, `meshes.rs` and `geometry.rs`; `convert.rs` holds
//! the NumPy and error conversions. `joints.rs` adds the joint methods to `Simulation`
//! (`add_hinge_joint`, ..., returning `Joint`), `rigid_objects.rs` the rigid presets and the
//! deformable–rigid attachments (`add_box`, `attach_to_body`, ..., returning `RigidObject` and
//! `RigidAttachmentHandle`).

mod convert;
mod geometry;
mod handle_params;
mod handles;
mod joints;
mod meshes;
mod param_list;
mod params;
mod rigid;
mod rigid_objects;
mod robots;
mod scene;
mod simulation;
mod sym;

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
    joints::register(m)?;
    rigid_objects::register(m)?;
    robots::register(m)?;
    scene::register(m)?;
    m.add_submodule(&geometry::module(py)?)?;
    m.add_submodule(&meshes::module(py)?)?;
    m.add_submodule(&sym::module(py)?)?;
    Ok(())
}

//! Tests of the scene loader, by theme: `objects` (deformables, obstacles, materials, motions,
//! attachments), `rigid` (bodies, joints, spawns), `errors` (every error names its place) and
//! `same_as_rust` (scene files against the same scenes built through the API, bit for bit).

mod errors;
mod objects;
mod rigid;
mod same_as_rust;

use super::rigid_bodies::{keyframe_pose, Poses};
use super::*;
use crate::deformables::PrescribedHandle;
use crate::energy::{EnergyTerm, Node};
use crate::error::StarkError;
use crate::io::output::OutputCells;
use crate::presets::meshes;
use crate::presets::objects::BendingHandle;
use crate::presets::{SurfaceMaterial, VolumeMaterial};
use crate::rigidbodies::joints::{JointParams, Primitive, DEFAULT_CONTROLLER_DELAY};
use crate::rigidbodies::{MassProperties, RigidBodyHandle};
use nalgebra::{Unit, UnitQuaternion, Vector3};
use std::f64::consts::PI;
use std::path::PathBuf;

fn repo_scene(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes").join(name)
}

/// No files written, one thread (deterministic and quiet).
fn quiet(s: &mut Settings) {
    s.output.frames = false;
    s.output.step_log = false;
    s.threads = 1;
}

fn scene_error(e: StarkError) -> SceneError {
    match e {
        StarkError::SceneFile(e) => e,
        other => panic!("not a scene error: {other}"),
    }
}

fn parse(text: &str) -> LoadedScene {
    parse_scene_with(text, "test.toml", Path::new("."), quiet).unwrap_or_else(|e| panic!("{e}"))
}

fn parse_err(text: &str) -> SceneError {
    match parse_scene_with(text, "test.toml", Path::new("."), quiet) {
        Ok(_) => panic!("the scene parsed:\n{text}"),
        Err(e) => scene_error(e),
    }
}

fn bits(x: &[Vector3<f64>]) -> Vec<[u64; 3]> {
    x.iter()
        .map(|p| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
        .collect()
}

fn surface(scene: &LoadedScene, name: &str) -> SurfaceHandle {
    match scene.object(name) {
        Some(SceneObject::Surface(h)) => *h,
        other => panic!("{name} is {other:?}"),
    }
}

/// Positions, orientations and velocities of every body, as bits.
fn body_bits(sim: &Simulation) -> Vec<u64> {
    let b = &sim.bodies;
    (0..b.len())
        .flat_map(|i| {
            let q = b.orientation[i].coords;
            b.position[i]
                .iter()
                .chain(q.iter())
                .chain(b.velocity[i].iter())
                .chain(b.angular_velocity[i].iter())
                .map(|c| c.to_bits())
                .collect::<Vec<_>>()
        })
        .collect()
}

fn close(a: &Vector3<f64>, b: &Vector3<f64>, tol: f64) -> bool {
    (a - b).norm() <= tol
}

//! Robots from URDF files: `Simulation.add_robot`, mirroring the library's `robots` module and
//! the scene files' `[[robot]]`.

use crate::convert::{pose, stark_err, Rot, V3};
use crate::handles::RigidBody;
use crate::joints::Joint;
use crate::simulation::Simulation;
use pyo3::prelude::*;
use std::collections::BTreeMap;
use std::path::PathBuf;

/// A robot in a simulation: its bodies and joints by URDF name.
#[pyclass(module = "starkrs", frozen, get_all)]
pub struct Robot {
    /// Its name (its bodies and joints are labelled `<name>/<link>` and `<name>/<joint>`).
    name: String,
    /// The body of every link (links merged by fixed joints share one; None for links merged
    /// into the world by a fixed base).
    links: BTreeMap<String, Option<RigidBody>>,
    /// The main joint of every URDF joint that became one (hinge, prismatic, actuator, ...).
    joints: BTreeMap<String, Joint>,
    /// The other joints it made: limits, mimic couplings, damping, springs, fix joints.
    extra_joints: Vec<Joint>,
}

#[pymethods]
impl Robot {
    fn __repr__(&self) -> String {
        format!(
            "Robot(name={:?}, links={}, joints={})",
            self.name,
            self.links.len(),
            self.joints.len()
        )
    }
}

/// A table of overrides (`links=` or `joints=`) given as a dict: through JSON into the
/// library's override type, so that a misspelt field is named.
fn overrides<T: serde::de::DeserializeOwned>(
    py: Python<'_>,
    table: Option<&Bound<'_, PyAny>>,
    what: &str,
) -> PyResult<BTreeMap<String, T>> {
    let Some(table) = table else {
        return Ok(BTreeMap::new());
    };
    let json: String = py.import("json")?.call_method1("dumps", (table,))?.extract()?;
    serde_json::from_str(&json).map_err(|e| stark_err(format!("add_robot: {what}: {e}")))
}

#[pymethods]
impl Simulation {
    /// Load a robot from a URDF file (see the README's "Robots"): links become rigid bodies
    /// (massless ones merge into their parent, links joined by fixed joints merge unless
    /// `merge_fixed_joints=False`), joints become hinges, sliders and couplings, `<collision>`
    /// geometry collision meshes. `package_paths` resolve `package://` URIs (the environment
    /// variable `ROS_PACKAGE_PATH` is also read). `links` and `joints` are dicts of overrides by
    /// URDF name, with the fields of the scene files' `[robot.links.<link>]` and
    /// `[robot.joints.<joint>]` tables (docs/scene-format.md), e.g.
    /// `joints={"panda_finger_joint1": {"actuator": {"type": "press", "target_m_s": -0.02, "max_force_n": 20}}}`.
    #[pyo3(signature = (name, urdf, package_paths=None, position_m=None, orientation=None, fixed_base=false,
        merge_fixed_joints=true, visual_meshes=false, contact_thickness_m=None, adjacent_links_collide=false,
        self_collision=true, links=None, joints=None))]
    #[allow(clippy::too_many_arguments)]
    fn add_robot(
        &self,
        py: Python<'_>,
        name: &str,
        urdf: PathBuf,
        package_paths: Option<Vec<PathBuf>>,
        position_m: Option<V3>,
        orientation: Option<Rot>,
        fixed_base: bool,
        merge_fixed_joints: bool,
        visual_meshes: bool,
        contact_thickness_m: Option<f64>,
        adjacent_links_collide: bool,
        self_collision: bool,
        links: Option<&Bound<'_, PyAny>>,
        joints: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Robot> {
        let (position_m, orientation) = pose(position_m, orientation);
        let options = stark::robots::RobotOptions {
            package_paths: package_paths.unwrap_or_default(),
            position_m,
            orientation,
            fixed_base,
            merge_fixed_joints,
            visual_meshes,
            contact_thickness_m,
            adjacent_links_collide,
            self_collision,
            links: overrides(py, links, "links")?,
            joints: overrides(py, joints, "joints")?,
            ..Default::default()
        };
        let robot = self.with(|s| s.add_robot(name, &urdf, &options))?;
        let id = self.id();
        // A body is labelled after the first link it was made for.
        let label_of = |h: stark::rigidbodies::RigidBodyHandle| {
            let link = robot.bodies.iter().find(|(_, b)| *b == h).map(|(l, _)| l.as_str());
            format!("{name}/{}", link.unwrap_or("?"))
        };
        Ok(Robot {
            name: robot.name.clone(),
            links: robot
                .links
                .iter()
                .map(|(l, b)| (l.clone(), b.map(|h| RigidBody::new(id, h, &label_of(h)))))
                .collect(),
            joints: robot
                .joints
                .iter()
                .map(|(j, h)| (j.clone(), Joint::new(id, h.clone())))
                .collect(),
            extra_joints: robot.extra_joints.iter().map(|h| Joint::new(id, h.clone())).collect(),
        })
    }
}

/// Register the classes.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Robot>()
}

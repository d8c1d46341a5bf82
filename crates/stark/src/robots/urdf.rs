//! URDF import: [`Simulation::add_robot`].
//!
//! The XML is read twice: by roxmltree, for well-formedness (malformed XML is an error with its
//! line and column), the line of every `<link>`, `<joint>`, `<collision>` and `<visual>` (every
//! later error names the file, the line and the element) and a check of every number (a
//! non-finite or unreadable value is an error naming its attribute); then by urdf-rs into its
//! typed description. The robot is then built:
//!
//! - **Links → bodies.** Mass, centre of mass and the full inertia tensor of `<inertial>` (its
//!   origin's rotation applied). An inertia that is not positive definite or whose principal
//!   moments break the triangle inequality (`I₁ + I₂ ≥ I₃`) is an error naming the link. Links
//!   joined by `fixed` joints merge into one body (masses, centres and inertias combined by the
//!   parallel-axis theorem) unless [`RobotOptions::merge_fixed_joints`] is off; massless links
//!   (frames such as `base_footprint`, sensor links) always merge into their neighbour over a
//!   fixed joint. A body is labelled `<robot>/<link>` after its first link with mass; its frame
//!   is that group's top link's frame, moved to the centre of mass.
//! - **`<collision>` → one collision mesh per body**: every primitive (box, cylinder, capsule,
//!   sphere) and mesh (STL, OBJ, COLLADA; welded; `scale` applied), at its origin. `<visual>` →
//!   output meshes when [`RobotOptions::visual_meshes`] is on.
//! - **Joints**: `revolute` → hinge with its limits (`<robot>/<joint>.limits`), `continuous` →
//!   hinge, `prismatic` → prismatic joint with limits, `fixed` → merged (or a fix joint),
//!   `floating` → nothing (free), `planar` → planar joint, `spherical` → ball joint; `<mimic>` →
//!   the coupling `q = multiplier·q_mimicked + offset` (`<robot>/<joint>.mimic`), `<dynamics
//!   damping>` → joint damping (`<robot>/<joint>.damping`), `<limit effort velocity>` → the caps of
//!   an [`Actuator`] on that joint. Joint coordinates are URDF's (zero at the URDF's zero
//!   configuration), also when a joint starts elsewhere ([`JointOverride::position`]).
//! - **Mesh URIs**: `package://pkg/path` is looked up in the package roots (a root is a folder
//!   holding `pkg/`, or `pkg` itself): [`RobotOptions::package_paths`], then the folders of the
//!   environment variables [`PACKAGE_PATH_ENV`] and `ROS_PACKAGE_PATH` (`:`-separated), then the
//!   folders above the URDF file named `pkg`. `file://` URIs and plain paths are taken relative to
//!   the URDF file's folder.
//! - **Contact**: a link touching a parent or child through a joint does not collide with it;
//!   every other pair does ([`RobotOptions::adjacent_links_collide`], [`RobotOptions::self_collision`]).
//!
//! The options, the [`Robot`] handle and the file reading are here; building the robot
//! ([`Simulation::add_robot`]) is in `urdf/build.rs`.

mod build;

use crate::error::{Result, StarkError};
use crate::rigidbodies::joints::{JointHandle, JointParams};
use crate::rigidbodies::{RigidBodyHandle, RigidMeshHandle, Shape};
use crate::simulation::Simulation;
use nalgebra::{Isometry3, Matrix3, Translation3, UnitQuaternion, Vector3};
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

/// Environment variable with extra package roots (`:`-separated, like `ROS_PACKAGE_PATH`, which
/// is searched after it).
pub const PACKAGE_PATH_ENV: &str = "STARK_PACKAGE_PATH";

/// An actuator on a robot joint. Its caps default to the joint's `<limit effort velocity>`
/// (a target speed above the velocity limit is clamped to it); effort in N·m for hinges and N
/// for sliders.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum Actuator {
    /// A velocity motor on a hinge ([`Simulation::add_motor`]): drives the joint rate to
    /// `target_rad_s` with a smooth torque cap.
    Motor {
        /// Target rate, rad/s.
        target_rad_s: f64,
        /// Torque cap, N·m (default: the URDF effort).
        max_torque_n_m: Option<f64>,
        /// Width of the smooth transition to the cap: the rate error at which the torque
        /// reaches it, rad/s (default 0.01).
        #[serde(default)]
        delay_rad_s: Option<f64>,
        /// Drive only: no braking torque when the joint turns faster than the target
        /// ([`Simulation::set_motor_drive_only`]; default false).
        #[serde(default)]
        drive_only: bool,
    },
    /// A force-limited press or gripper on a slider ([`Simulation::add_prismatic_press`]):
    /// drives the joint rate to `target_m_s`, pushing with at most `max_force_n`, and stalls
    /// against a load at that force.
    Press {
        /// Target rate, m/s.
        target_m_s: f64,
        /// Force cap, N (default: the URDF effort).
        max_force_n: Option<f64>,
    },
    /// A position servo ([`Simulation::add_hinge_servo`], [`Simulation::add_prismatic_servo`]):
    /// drives the joint to `target` (rad or m, URDF coordinate) within `response_time_s`.
    Servo {
        /// Target coordinate: rad for hinges, m for sliders.
        target: f64,
        /// Effort cap: N·m or N (default: the URDF effort).
        max_effort: Option<f64>,
        /// Time constant of the approach, s (default 0.1).
        #[serde(default = "default_response_time_s")]
        response_time_s: f64,
    },
    /// A passive spring–damper on the joint coordinate: `−stiffness·(q − rest) − damping·q̇`.
    SpringDamper {
        /// N·m/rad or N/m.
        stiffness: f64,
        /// Rest coordinate: rad or m (URDF coordinate; default 0).
        #[serde(default)]
        rest: f64,
        /// N·m·s/rad or N·s/m (added to the URDF damping; default 0).
        #[serde(default)]
        damping: f64,
    },
}

fn default_response_time_s() -> f64 {
    0.1
}

/// Changes to one link.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinkOverride {
    /// Mass, kg (the URDF inertia is scaled with it unless `inertia_kg_m2` is given).
    pub mass_kg: Option<f64>,
    /// Inertia tensor about the link's centre of mass in the link frame, kg·m².
    pub inertia_kg_m2: Option<[[f64; 3]; 3]>,
    /// A mesh file replacing the link's `<collision>` elements (in the link frame; relative
    /// paths as mesh URIs).
    pub collision_mesh: Option<PathBuf>,
    /// A shape replacing the link's `<collision>` elements (in the link frame), from code: e.g.
    /// an inline mesh compiled into a program. Takes precedence over `collision_mesh`.
    #[serde(skip)]
    pub collision_shape: Option<Shape>,
    /// Contact thickness of the link's collision mesh, m.
    pub contact_thickness_m: Option<f64>,
}

/// Changes to one joint.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointOverride {
    /// Initial coordinate: rad or m (default 0, the URDF's zero configuration).
    pub position: Option<f64>,
    /// Damping, N·m·s/rad or N·s/m (replaces `<dynamics damping>`).
    pub damping: Option<f64>,
    /// An actuator on the joint.
    pub actuator: Option<Actuator>,
}

/// How to import a robot.
#[derive(Clone, Debug, PartialEq)]
pub struct RobotOptions {
    /// Package roots for `package://` URIs (see the module doc).
    pub package_paths: Vec<PathBuf>,
    /// Where the root link's frame goes, m (default: the origin).
    pub position_m: Vector3<f64>,
    /// Its orientation (default: identity).
    pub orientation: UnitQuaternion<f64>,
    /// Fix the root body to the world (default: false).
    pub fixed_base: bool,
    /// Merge links joined by fixed joints into one body (default: true); off, a fix joint
    /// holds them together.
    pub merge_fixed_joints: bool,
    /// Give each link its `<visual>` meshes as output meshes (default: false).
    pub visual_meshes: bool,
    /// Contact thickness of the collision meshes, m (default: `settings.contact.default_thickness_m`;
    /// with neither, collision geometry is only drawn).
    pub contact_thickness_m: Option<f64>,
    /// Whether links joined by a joint collide (default: false).
    pub adjacent_links_collide: bool,
    /// Whether the robot's links collide with each other at all (default: true).
    pub self_collision: bool,
    /// Segments around cylinders and capsules (default: 24).
    pub cylinder_slices: usize,
    /// Parameters of the joints, limits and fixed-base joint (default: [`JointParams::default`]).
    pub joint_params: JointParams,
    /// Parameters of mimic couplings (default: stiffness 1e6, tolerances 1e-6 m and 1e-4°, so
    /// mimicking fingers stay symmetric to a micrometre).
    pub mimic_params: JointParams,
    /// Overrides per link name.
    pub links: BTreeMap<String, LinkOverride>,
    /// Overrides and actuators per joint name.
    pub joints: BTreeMap<String, JointOverride>,
}

impl Default for RobotOptions {
    fn default() -> Self {
        RobotOptions {
            package_paths: Vec::new(),
            position_m: Vector3::zeros(),
            orientation: UnitQuaternion::identity(),
            fixed_base: false,
            merge_fixed_joints: true,
            visual_meshes: false,
            contact_thickness_m: None,
            adjacent_links_collide: false,
            self_collision: true,
            cylinder_slices: 24,
            joint_params: JointParams::default(),
            mimic_params: JointParams {
                stiffness: 1e6,
                tolerance_m: 1e-6,
                tolerance_deg: 1e-4,
            },
            links: BTreeMap::new(),
            joints: BTreeMap::new(),
        }
    }
}

/// A robot in a simulation: its bodies and joints by URDF name.
#[derive(Clone, Debug, PartialEq)]
pub struct Robot {
    /// Its name (the label prefix of its bodies and joints).
    pub name: String,
    /// The body of every link (merged links share one; `None` for links merged into the world
    /// by a fixed base).
    pub links: BTreeMap<String, Option<RigidBodyHandle>>,
    /// The main joint of every URDF joint that became one (hinge, prismatic, motor, press,
    /// servo, ...), by URDF name, labelled `<robot>/<joint>`.
    pub joints: BTreeMap<String, JointHandle>,
    /// The other joints it made: limits, mimic couplings, damping, springs, fix joints.
    pub extra_joints: Vec<JointHandle>,
    /// The bodies in creation order, with the link they are named after.
    pub bodies: Vec<(String, RigidBodyHandle)>,
    /// Initial coordinate of each joint (the URDF coordinate is this plus the joint state's).
    pub initial_positions: BTreeMap<String, f64>,
    /// The collision mesh of each body that has one (a body's `<collision>` elements are one
    /// mesh).
    pub collision_meshes: Vec<RigidMeshHandle>,
}

impl Robot {
    /// The body of link `link` (merged links share one).
    pub fn body(&self, link: &str) -> Option<RigidBodyHandle> {
        self.links.get(link).copied().flatten()
    }

    /// The main joint made from URDF joint `joint`.
    pub fn joint(&self, joint: &str) -> Option<&JointHandle> {
        self.joints.get(joint)
    }

    /// The URDF coordinate of joint `joint` at the last step (rad or m).
    pub fn joint_position(&self, sim: &Simulation, joint: &str) -> Option<f64> {
        let h = self.joints.get(joint)?;
        let q = sim.joint_state(h).coordinate?;
        Some(q + self.initial_positions.get(joint).copied().unwrap_or(0.0))
    }
}

// ------------------------------------------------------------------------------------------
// Reading the file
// ------------------------------------------------------------------------------------------

/// Lines of the elements, for error messages.
#[derive(Default)]
struct Lines {
    links: HashMap<String, Vec<usize>>,
    joints: HashMap<String, usize>,
    collisions: HashMap<String, Vec<usize>>,
    visuals: HashMap<String, Vec<usize>>,
}

const JOINT_TYPES: [&str; 7] = [
    "revolute",
    "continuous",
    "prismatic",
    "fixed",
    "floating",
    "planar",
    "spherical",
];

const NUMERIC_ATTRIBUTES: [&str; 22] = [
    "xyz",
    "rpy",
    "value",
    "ixx",
    "ixy",
    "ixz",
    "iyy",
    "iyz",
    "izz",
    "size",
    "radius",
    "length",
    "lower",
    "upper",
    "effort",
    "velocity",
    "damping",
    "friction",
    "multiplier",
    "offset",
    "scale",
    "rgba",
];

struct Source<'a> {
    file: &'a str,
}

impl Source<'_> {
    fn err(&self, line: Option<usize>, what: &str, message: impl std::fmt::Display) -> StarkError {
        match line {
            Some(l) => StarkError::InvalidInput(format!("{}:{l}: {what}: {message}", self.file)),
            None => StarkError::InvalidInput(format!("{}: {what}: {message}", self.file)),
        }
    }
}

/// Well-formedness, element lines, joint types and numbers, from the raw XML.
fn scan(src: &Source, text: &str) -> Result<Lines> {
    let doc = roxmltree::Document::parse(text).map_err(|e| {
        let pos = e.pos();
        StarkError::InvalidInput(format!("{}:{}:{}: malformed XML: {e}", src.file, pos.row, pos.col))
    })?;
    let line = |n: roxmltree::Node| doc.text_pos_at(n.range().start).row as usize;
    let root = doc.root_element();
    if root.tag_name().name() != "robot" {
        return Err(src.err(
            Some(line(root)),
            &format!("<{}>", root.tag_name().name()),
            "the root element of a URDF file must be <robot>",
        ));
    }
    let mut lines = Lines::default();
    for node in root.descendants().filter(|n| n.is_element()) {
        let tag = node.tag_name().name();
        let name = node.attribute("name").unwrap_or("");
        let at = line(node);
        // Only the robot's own links and joints (not <gazebo> or <transmission> children).
        let top = node.parent() == Some(root);
        match tag {
            "link" if top => lines.links.entry(name.to_string()).or_default().push(at),
            "joint" if top => {
                lines.joints.insert(name.to_string(), at);
                let kind = node.attribute("type").unwrap_or("");
                if !JOINT_TYPES.contains(&kind) {
                    return Err(src.err(
                        Some(at),
                        &format!("joint '{name}'"),
                        format!(
                            "unknown joint type '{kind}' (expected one of {})",
                            JOINT_TYPES.join(", ")
                        ),
                    ));
                }
            }
            "collision" | "visual" => {
                if let Some(link) = node
                    .parent()
                    .filter(|p| p.tag_name().name() == "link" && p.parent() == Some(root))
                {
                    let map = if tag == "collision" {
                        &mut lines.collisions
                    } else {
                        &mut lines.visuals
                    };
                    map.entry(link.attribute("name").unwrap_or("").to_string())
                        .or_default()
                        .push(at);
                }
            }
            _ => {}
        }
        // Numbers of the URDF elements (plugins under <gazebo> may hold anything).
        if !node
            .ancestors()
            .any(|a| matches!(a.tag_name().name(), "gazebo" | "transmission"))
        {
            for attr in node.attributes() {
                if !NUMERIC_ATTRIBUTES.contains(&attr.name()) || tag == "material" {
                    continue;
                }
                for word in attr.value().split_whitespace() {
                    match word.parse::<f64>() {
                        Ok(v) if v.is_finite() => {}
                        _ => {
                            let owner = node
                                .ancestors()
                                .find(|a| matches!(a.tag_name().name(), "link" | "joint"))
                                .map(|a| format!("{} '{}' ", a.tag_name().name(), a.attribute("name").unwrap_or("")))
                                .unwrap_or_default();
                            return Err(src.err(
                                Some(at),
                                &format!("{owner}<{tag} {}>", attr.name()),
                                format!("`{word}` is not a finite number"),
                            ));
                        }
                    }
                }
            }
        }
    }
    Ok(lines)
}

fn pose(p: &urdf_rs::Pose) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(p.xyz[0], p.xyz[1], p.xyz[2]),
        // URDF rpy: roll about x, then pitch about y, then yaw about z, all fixed axes.
        UnitQuaternion::from_euler_angles(p.rpy[0], p.rpy[1], p.rpy[2]),
    )
}

/// Where a mesh URI points.
fn resolve_uri(uri: &str, urdf_dir: &Path, roots: &[PathBuf]) -> std::result::Result<PathBuf, String> {
    if let Some(rest) = uri.strip_prefix("package://") {
        let (package, inner) = rest.split_once('/').unwrap_or((rest, ""));
        let mut env_roots: Vec<PathBuf> = Vec::new();
        for var in [PACKAGE_PATH_ENV, "ROS_PACKAGE_PATH"] {
            if let Ok(v) = std::env::var(var) {
                env_roots.extend(v.split(':').filter(|s| !s.is_empty()).map(PathBuf::from));
            }
        }
        let ancestors = urdf_dir
            .ancestors()
            .filter(|a| a.file_name().is_some_and(|n| n == package))
            .map(Path::to_path_buf);
        let mut searched = Vec::new();
        for root in roots.iter().cloned().chain(env_roots).chain(ancestors) {
            let dirs = [root.join(package), root.clone()];
            for (k, dir) in dirs.iter().enumerate() {
                let is_package = if k == 0 {
                    dir.is_dir()
                } else {
                    root.file_name().is_some_and(|n| n == package) && dir.is_dir()
                };
                if is_package {
                    return Ok(dir.join(inner));
                }
            }
            searched.push(root.display().to_string());
        }
        return Err(format!(
            "unknown package '{package}' in '{uri}' (searched the package roots [{}]; give package_paths or set {PACKAGE_PATH_ENV})",
            searched.join(", ")
        ));
    }
    let path = uri.strip_prefix("file://").unwrap_or(uri);
    Ok(urdf_dir.join(path))
}

/// The inertia tensor of `<inertia>` as a matrix, checked: positive definite and the principal
/// moments satisfy the triangle inequality (a physical mass distribution).
fn check_inertia(j: &Matrix3<f64>) -> std::result::Result<(), String> {
    let eig = j.symmetric_eigenvalues();
    let mut m = [eig[0], eig[1], eig[2]];
    m.sort_by(f64::total_cmp);
    if !(m[0] > 0.0) {
        return Err(format!(
            "the inertia tensor is not positive definite (principal moments {:.3e}, {:.3e}, {:.3e} kg·m²)",
            m[0], m[1], m[2]
        ));
    }
    if m[0] + m[1] < m[2] * (1.0 - 1e-9) {
        return Err(format!(
            "the principal moments {:.3e}, {:.3e}, {:.3e} kg·m² break the triangle inequality I₁ + I₂ ≥ I₃ (no mass \
             distribution has them)",
            m[0], m[1], m[2]
        ));
    }
    Ok(())
}

/// A mesh in a body's frame: vertices, triangles and its contact thickness, if overridden.
type BodyMesh = (Vec<Vector3<f64>>, Vec<[usize; 3]>, Option<f64>);

/// A link's mass, centre of mass and inertia about it, in the link frame.
#[derive(Clone, Copy)]
struct LinkMass {
    mass_kg: f64,
    com: Vector3<f64>,
    inertia: Matrix3<f64>,
}

fn geometry_shape(
    g: &urdf_rs::Geometry,
    urdf_dir: &Path,
    roots: &[PathBuf],
    slices: usize,
) -> std::result::Result<Shape, String> {
    Ok(match g {
        urdf_rs::Geometry::Box { size } => Shape::Box {
            size_m: Vector3::new(size[0], size[1], size[2]),
        },
        urdf_rs::Geometry::Cylinder { radius, length } => Shape::Cylinder {
            radius_m: *radius,
            height_m: *length,
            slices,
            stacks: 1,
        },
        urdf_rs::Geometry::Capsule { radius, length } => Shape::Capsule {
            radius_m: *radius,
            height_m: *length,
            slices,
            cap_rings: 6,
        },
        urdf_rs::Geometry::Sphere { radius } => Shape::Sphere {
            radius_m: *radius,
            subdivisions: 2,
        },
        urdf_rs::Geometry::Mesh { filename, scale } => Shape::MeshFile {
            path: resolve_uri(filename, urdf_dir, roots)?,
            scale: scale.map_or(Vector3::repeat(1.0), |s| Vector3::new(s[0], s[1], s[2])),
        },
    })
}

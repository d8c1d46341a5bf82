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

use crate::error::{Result, StarkError};
use crate::rigidbodies::joints::{JointHandle, JointKind, JointParams, DEFAULT_CONTROLLER_DELAY};
use crate::rigidbodies::{RigidBodyHandle, RigidMeshHandle, Shape};
use crate::simulation::Simulation;
use nalgebra::{Isometry3, Matrix3, Translation3, Unit, UnitQuaternion, Vector3};
use std::collections::{BTreeMap, HashMap, VecDeque};
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

impl Simulation {
    /// Import the robot of the URDF file `urdf` as `name` (its bodies are labelled
    /// `<name>/<link>`, its joints `<name>/<joint>`; see [`crate::robots::urdf`] for what becomes
    /// what). Every error names the file, the line and the element; nothing is added to the
    /// simulation when the file is rejected before building (bad XML, numbers, structure,
    /// inertias, meshes).
    pub fn add_robot(&mut self, name: &str, urdf: impl AsRef<Path>, options: &RobotOptions) -> Result<Robot> {
        let path = urdf.as_ref();
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path)
            .map_err(|e| StarkError::InvalidInput(format!("cannot read the URDF file '{file}': {e}")))?;
        let dir = path.parent().unwrap_or(Path::new("."));
        self.add_robot_from_str(name, &text, &file, dir, options)
    }

    /// [`Simulation::add_robot`] from the text of a URDF file; `file` names it in errors and
    /// relative mesh paths are resolved against `dir`.
    pub fn add_robot_from_str(
        &mut self,
        name: &str,
        text: &str,
        file: &str,
        dir: &Path,
        options: &RobotOptions,
    ) -> Result<Robot> {
        let src = Source { file };
        if name.is_empty() || name.contains('/') {
            return Err(StarkError::InvalidInput(format!(
                "robot name '{name}' must be non-empty and contain no '/'"
            )));
        }
        let lines = scan(&src, text)?;
        let robot = urdf_rs::read_from_string(text).map_err(|e| src.err(None, "robot", e))?;
        let link_line = |l: &str| lines.links.get(l).and_then(|v| v.first().copied());
        let joint_line = |j: &str| lines.joints.get(j).copied();

        // ---- Structure: unique names, a tree with one root ----
        let mut link_index: HashMap<&str, usize> = HashMap::new();
        for (i, l) in robot.links.iter().enumerate() {
            if link_index.insert(l.name.as_str(), i).is_some() {
                let at = lines.links.get(&l.name).and_then(|v| v.get(1).copied());
                return Err(src.err(at, &format!("link '{}'", l.name), "duplicate link name"));
            }
        }
        if robot.links.is_empty() {
            return Err(src.err(None, "robot", "the robot has no links"));
        }
        let mut joint_names: HashMap<&str, usize> = HashMap::new();
        let mut parent_of: Vec<Option<usize>> = vec![None; robot.links.len()]; // joint index
        for (k, j) in robot.joints.iter().enumerate() {
            let what = format!("joint '{}'", j.name);
            if joint_names.insert(j.name.as_str(), k).is_some() {
                return Err(src.err(joint_line(&j.name), &what, "duplicate joint name"));
            }
            for (role, l) in [("parent", &j.parent.link), ("child", &j.child.link)] {
                if !link_index.contains_key(l.as_str()) {
                    return Err(src.err(
                        joint_line(&j.name),
                        &what,
                        format!("its {role} link '{l}' does not exist"),
                    ));
                }
            }
            let c = link_index[j.child.link.as_str()];
            if let Some(other) = parent_of[c] {
                return Err(src.err(
                    joint_line(&j.name),
                    &what,
                    format!(
                        "link '{}' already has the parent joint '{}' (a URDF is a tree)",
                        j.child.link, robot.joints[other].name
                    ),
                ));
            }
            if j.parent.link == j.child.link {
                return Err(src.err(joint_line(&j.name), &what, "joins a link to itself"));
            }
            parent_of[c] = Some(k);
        }
        let roots: Vec<usize> = (0..robot.links.len()).filter(|&i| parent_of[i].is_none()).collect();
        let root = match roots.as_slice() {
            [r] => *r,
            [] => return Err(src.err(None, "robot", "every link has a parent joint: the joints form a cycle")),
            many => {
                let names: Vec<&str> = many.iter().map(|&i| robot.links[i].name.as_str()).collect();
                return Err(src.err(
                    link_line(names[1]),
                    "robot",
                    format!(
                        "{} root links ({}): a URDF has exactly one",
                        many.len(),
                        names.join(", ")
                    ),
                ));
            }
        };
        // Breadth-first order from the root; links not reached lie on a cycle.
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); robot.links.len()];
        for (k, j) in robot.joints.iter().enumerate() {
            children[link_index[j.parent.link.as_str()]].push(k);
        }
        let mut order = vec![root];
        let mut queue = VecDeque::from([root]);
        while let Some(l) = queue.pop_front() {
            for &k in &children[l] {
                let c = link_index[robot.joints[k].child.link.as_str()];
                order.push(c);
                queue.push_back(c);
            }
        }
        if order.len() < robot.links.len() {
            let lost = (0..robot.links.len())
                .find(|i| !order.contains(i))
                .expect("unreached link");
            let name = &robot.links[lost].name;
            return Err(src.err(link_line(name), &format!("link '{name}'"), "lies on a cycle of joints"));
        }
        for l in options.links.keys() {
            if !link_index.contains_key(l.as_str()) {
                return Err(StarkError::InvalidInput(format!(
                    "robot '{name}': an override names the link '{l}', which {file} does not have"
                )));
            }
        }
        for j in options.joints.keys() {
            if !joint_names.contains_key(j.as_str()) {
                return Err(StarkError::InvalidInput(format!(
                    "robot '{name}': an override names the joint '{j}', which {file} does not have"
                )));
            }
        }

        // ---- Link masses ----
        let mut masses: Vec<Option<LinkMass>> = Vec::with_capacity(robot.links.len());
        for l in &robot.links {
            let what = format!("link '{}'", l.name);
            let o = options.links.get(&l.name);
            let i = &l.inertial;
            let urdf_inertia = Matrix3::new(
                i.inertia.ixx,
                i.inertia.ixy,
                i.inertia.ixz,
                i.inertia.ixy,
                i.inertia.iyy,
                i.inertia.iyz,
                i.inertia.ixz,
                i.inertia.iyz,
                i.inertia.izz,
            );
            let mut mass = i.mass.value;
            if mass < 0.0 {
                return Err(src.err(link_line(&l.name), &what, format!("negative mass {mass} kg")));
            }
            let frame = pose(&i.origin);
            let r = frame.rotation.to_rotation_matrix().into_inner();
            let mut inertia = r * urdf_inertia * r.transpose();
            if let Some(m) = o.and_then(|o| o.mass_kg) {
                if !(m > 0.0 && m.is_finite()) {
                    return Err(StarkError::InvalidInput(format!(
                        "robot '{name}' link '{}': the mass_kg override {m} must be positive",
                        l.name
                    )));
                }
                if mass > 0.0 {
                    inertia *= m / mass;
                }
                mass = m;
            }
            if let Some(j) = o.and_then(|o| o.inertia_kg_m2) {
                inertia = Matrix3::from_row_slice(&j.concat());
                if (inertia - inertia.transpose()).norm() > 1e-9 * inertia.norm()
                    || !inertia.iter().all(|c| c.is_finite())
                {
                    return Err(StarkError::InvalidInput(format!(
                        "robot '{name}' link '{}': the inertia_kg_m2 override must be finite and symmetric",
                        l.name
                    )));
                }
            }
            if mass == 0.0 {
                masses.push(None);
                continue;
            }
            check_inertia(&inertia).map_err(|m| src.err(link_line(&l.name), &what, m))?;
            masses.push(Some(LinkMass {
                mass_kg: mass,
                com: frame.translation.vector,
                inertia,
            }));
        }

        // ---- Poses at the initial configuration ----
        let base = Isometry3::from_parts(Translation3::from(options.position_m), options.orientation);
        let initial = |j: &urdf_rs::Joint| options.joints.get(&j.name).and_then(|o| o.position).unwrap_or(0.0);
        let mut link_pose = vec![Isometry3::identity(); robot.links.len()];
        link_pose[root] = base;
        for &l in order.iter().skip(1) {
            let j = &robot.joints[parent_of[l].expect("non-root")];
            let p = link_pose[link_index[j.parent.link.as_str()]];
            let axis = Vector3::new(j.axis.xyz[0], j.axis.xyz[1], j.axis.xyz[2]);
            let q = initial(j);
            let motion = match j.joint_type {
                urdf_rs::JointType::Revolute | urdf_rs::JointType::Continuous if q != 0.0 => Isometry3::from_parts(
                    Translation3::identity(),
                    UnitQuaternion::from_axis_angle(&Unit::new_normalize(axis), q),
                ),
                urdf_rs::JointType::Prismatic if q != 0.0 => {
                    Isometry3::from_parts(Translation3::from(axis.normalize() * q), UnitQuaternion::identity())
                }
                _ => Isometry3::identity(),
            };
            link_pose[l] = p * pose(&j.origin) * motion;
        }

        // ---- Groups of links that form one body ----
        let mut group = (0..robot.links.len()).collect::<Vec<usize>>(); // link → group's top link
        for &l in order.iter().skip(1) {
            let j = &robot.joints[parent_of[l].expect("non-root")];
            let parent = link_index[j.parent.link.as_str()];
            let fixed = j.joint_type == urdf_rs::JointType::Fixed;
            let massless = masses[l].is_none();
            if fixed && (options.merge_fixed_joints || massless || masses[parent].is_none()) {
                group[l] = group[parent];
            } else if massless {
                return Err(src.err(
                    link_line(&robot.links[l].name),
                    &format!("link '{}'", robot.links[l].name),
                    format!(
                        "has no mass but moves on the {:?} joint '{}': give it an <inertial> (or a mass_kg override)",
                        j.joint_type, j.name
                    ),
                ));
            }
        }
        let tops: Vec<usize> = order.iter().copied().filter(|&l| group[l] == l).collect();

        // Mass properties of each group in world coordinates.
        struct Group {
            label_link: usize,
            mass_kg: f64,
            com: Vector3<f64>,
            orientation: UnitQuaternion<f64>,
            inertia_world: Matrix3<f64>,
        }
        let mut groups: HashMap<usize, Group> = HashMap::new();
        for &top in &tops {
            let members: Vec<usize> = order.iter().copied().filter(|&l| group[l] == top).collect();
            let mut mass = 0.0;
            let mut first = Vector3::zeros();
            for &l in &members {
                if let Some(m) = masses[l] {
                    mass += m.mass_kg;
                    first += (link_pose[l] * nalgebra::Point3::from(m.com)).coords * m.mass_kg;
                }
            }
            if mass == 0.0 {
                if top == root && options.fixed_base {
                    continue; // the world
                }
                return Err(src.err(
                    link_line(&robot.links[top].name),
                    &format!("link '{}'", robot.links[top].name),
                    "neither it nor any link fixed to it has a mass (give an <inertial>, a mass_kg override, or fixed_base)",
                ));
            }
            let com = first / mass;
            let mut inertia = Matrix3::zeros();
            for &l in &members {
                if let Some(m) = masses[l] {
                    let r = link_pose[l].rotation.to_rotation_matrix().into_inner();
                    let d = (link_pose[l] * nalgebra::Point3::from(m.com)).coords - com;
                    inertia += r * m.inertia * r.transpose()
                        + (Matrix3::identity() * d.norm_squared() - d * d.transpose()) * m.mass_kg;
                }
            }
            let label_link = members.iter().copied().find(|&l| masses[l].is_some()).unwrap_or(top);
            groups.insert(
                top,
                Group {
                    label_link,
                    mass_kg: mass,
                    com,
                    orientation: link_pose[top].rotation,
                    inertia_world: inertia,
                },
            );
        }

        // ---- Collision and visual geometry (loaded before anything is added) ----
        let roots_paths = &options.package_paths;
        // Per group: body-frame vertices, triangles and a contact thickness override.
        let mut collision: HashMap<usize, BodyMesh> = HashMap::new();
        let mut visuals: Vec<(usize, BodyMesh)> = Vec::new();
        let to_body = |top: usize, p: Vector3<f64>| -> Vector3<f64> {
            match groups.get(&top) {
                Some(g) => g.orientation.inverse() * (p - g.com),
                None => p,
            }
        };
        for &l in &order {
            let link = &robot.links[l];
            let top = group[l];
            let o = options.links.get(&link.name);
            let mut elements: Vec<(Shape, Isometry3<f64>, Option<usize>)> = Vec::new();
            if let Some(shape) = o.and_then(|o| o.collision_shape.as_ref()) {
                elements.push((shape.clone(), Isometry3::identity(), link_line(&link.name)));
            } else if let Some(mesh) = o.and_then(|o| o.collision_mesh.as_ref()) {
                let uri = mesh.to_string_lossy();
                let path = resolve_uri(&uri, dir, roots_paths).map_err(|m| {
                    src.err(
                        link_line(&link.name),
                        &format!("link '{}' collision_mesh", link.name),
                        m,
                    )
                })?;
                elements.push((Shape::mesh_file(path), Isometry3::identity(), link_line(&link.name)));
            } else {
                for (k, c) in link.collision.iter().enumerate() {
                    let at = lines.collisions.get(&link.name).and_then(|v| v.get(k).copied());
                    let shape = geometry_shape(&c.geometry, dir, roots_paths, options.cylinder_slices)
                        .map_err(|m| src.err(at, &format!("link '{}' <collision>", link.name), m))?;
                    elements.push((shape, pose(&c.origin), at));
                }
            }
            for (shape, origin, at) in elements {
                let mesh = shape
                    .surface_mesh()
                    .map_err(|e| src.err(at, &format!("link '{}' <collision> {}", link.name, shape.kind()), e))?;
                let entry = collision.entry(top).or_insert_with(|| (Vec::new(), Vec::new(), None));
                let offset = entry.0.len();
                let frame = link_pose[l] * origin;
                entry.0.extend(
                    mesh.vertices
                        .iter()
                        .map(|v| to_body(top, (frame * nalgebra::Point3::from(*v)).coords)),
                );
                entry.1.extend(mesh.elements.iter().map(|t| t.map(|i| i + offset)));
                if let Some(t) = o.and_then(|o| o.contact_thickness_m) {
                    entry.2 = Some(t);
                }
            }
            if options.visual_meshes && groups.contains_key(&top) {
                for (k, v) in link.visual.iter().enumerate() {
                    let at = lines.visuals.get(&link.name).and_then(|v| v.get(k).copied());
                    let shape = geometry_shape(&v.geometry, dir, roots_paths, options.cylinder_slices)
                        .map_err(|m| src.err(at, &format!("link '{}' <visual>", link.name), m))?;
                    let mesh = shape
                        .surface_mesh()
                        .map_err(|e| src.err(at, &format!("link '{}' <visual> {}", link.name, shape.kind()), e))?;
                    let frame = link_pose[l] * pose(&v.origin);
                    let local = mesh
                        .vertices
                        .iter()
                        .map(|p| to_body(top, (frame * nalgebra::Point3::from(*p)).coords))
                        .collect();
                    visuals.push((top, (local, mesh.elements, None)));
                }
            }
        }
        // Joint checks that need no simulation: axes, actuators fit their joints.
        for j in &robot.joints {
            let what = format!("joint '{}'", j.name);
            let axis = Vector3::new(j.axis.xyz[0], j.axis.xyz[1], j.axis.xyz[2]);
            let moving = !matches!(j.joint_type, urdf_rs::JointType::Fixed | urdf_rs::JointType::Floating);
            if moving && axis.norm() < 1e-12 {
                return Err(src.err(joint_line(&j.name), &what, "the axis is zero"));
            }
            if let Some(m) = &j.mimic {
                if !joint_names.contains_key(m.joint.as_str()) {
                    return Err(src.err(
                        joint_line(&j.name),
                        &what,
                        format!("<mimic> names the joint '{}', which does not exist", m.joint),
                    ));
                }
            }
            if let Some(a) = options.joints.get(&j.name).and_then(|o| o.actuator.as_ref()) {
                let hinge = matches!(
                    j.joint_type,
                    urdf_rs::JointType::Revolute | urdf_rs::JointType::Continuous
                );
                let slider = j.joint_type == urdf_rs::JointType::Prismatic;
                let fits = match a {
                    Actuator::Motor { .. } => hinge,
                    Actuator::Press { .. } => slider,
                    Actuator::Servo { .. } | Actuator::SpringDamper { .. } => hinge || slider,
                };
                if !fits {
                    return Err(StarkError::InvalidInput(format!(
                        "robot '{name}': the actuator {a:?} does not fit the {:?} joint '{}' (motors go on revolute and \
                         continuous joints, presses on prismatic ones)",
                        j.joint_type, j.name
                    )));
                }
            }
        }

        // ---- Build ----
        let mut body_of_top: HashMap<usize, RigidBodyHandle> = HashMap::new();
        let mut bodies = Vec::new();
        for &top in &tops {
            let Some(g) = groups.get(&top) else { continue };
            let r = g.orientation.to_rotation_matrix().into_inner();
            let local = r.transpose() * g.inertia_world * r;
            let local = 0.5 * (local + local.transpose());
            let link = &robot.links[g.label_link].name;
            let label = format!("{name}/{link}");
            let body = self.add_rigid_body(&label, g.mass_kg, local, g.com, g.orientation)?;
            body_of_top.insert(top, body);
            bodies.push((link.clone(), body));
        }
        let body_of_link = |l: usize| body_of_top.get(&group[l]).copied();
        let mut collision_meshes = Vec::new();
        for &top in &tops {
            let (Some(body), Some((vertices, triangles, thickness))) = (body_of_top.get(&top), collision.remove(&top))
            else {
                continue;
            };
            match thickness
                .or(options.contact_thickness_m)
                .or(self.settings.contact.default_thickness_m)
            {
                Some(t) => {
                    collision_meshes.push(self.add_rigid_collision_mesh(*body, &vertices, &triangles, Some(t))?);
                }
                None => {
                    self.add_rigid_output_mesh(*body, &vertices, &triangles)?;
                }
            }
        }
        for (top, (vertices, triangles, _)) in visuals {
            if let Some(body) = body_of_top.get(&top) {
                self.add_rigid_output_mesh(*body, &vertices, &triangles)?;
            }
        }

        let params = options.joint_params;
        let mut joints: BTreeMap<String, JointHandle> = BTreeMap::new();
        let mut extra = Vec::new();
        let mut initial_positions = BTreeMap::new();
        let mut adjacent = Vec::new();
        for &l in order.iter().skip(1) {
            let j = &robot.joints[parent_of[l].expect("non-root")];
            let parent = link_index[j.parent.link.as_str()];
            let (a, b) = (body_of_link(parent), body_of_link(l));
            if group[parent] == group[l] {
                continue;
            }
            let Some(b) = b else { continue };
            let label = format!("{name}/{}", j.name);
            let located = |e: StarkError| src.err(joint_line(&j.name), &format!("joint '{}'", j.name), e);
            let frame = link_pose[parent] * pose(&j.origin);
            let point = frame.translation.vector;
            let axis_local = Vector3::new(j.axis.xyz[0], j.axis.xyz[1], j.axis.xyz[2]);
            let axis = if axis_local.norm() > 0.0 {
                frame.rotation * axis_local.normalize()
            } else {
                Vector3::z()
            };
            let o = options.joints.get(&j.name);
            let q0 = initial(j);
            initial_positions.insert(j.name.clone(), q0);
            let effort = |given: Option<f64>| -> Result<f64> {
                let e = given.unwrap_or(j.limit.effort);
                if e > 0.0 && e.is_finite() {
                    Ok(e)
                } else {
                    Err(located(StarkError::InvalidInput(
                        "the actuator needs an effort cap: the URDF <limit effort> is 0 or missing; give one".into(),
                    )))
                }
            };
            let speed = |target: f64| {
                let v = j.limit.velocity;
                if v > 0.0 && v.is_finite() {
                    target.clamp(-v, v)
                } else {
                    target
                }
            };
            let use_hinge = matches!(
                j.joint_type,
                urdf_rs::JointType::Revolute | urdf_rs::JointType::Continuous
            );
            let main = match j.joint_type {
                urdf_rs::JointType::Revolute | urdf_rs::JointType::Continuous | urdf_rs::JointType::Prismatic => {
                    let actuator = o.and_then(|o| o.actuator.clone());
                    let (point_m, axis_dir) = (point.into(), axis.into());
                    let kind = match (&actuator, use_hinge) {
                        (
                            Some(Actuator::Motor {
                                target_rad_s,
                                max_torque_n_m,
                                delay_rad_s,
                                ..
                            }),
                            _,
                        ) => JointKind::Motor {
                            point_m,
                            axis: axis_dir,
                            target_velocity_deg_s: speed(*target_rad_s).to_degrees(),
                            max_torque_n_m: effort(*max_torque_n_m)?,
                            delay_deg_s: delay_rad_s.map(f64::to_degrees),
                        },
                        (
                            Some(Actuator::Press {
                                target_m_s,
                                max_force_n,
                            }),
                            _,
                        ) => JointKind::PrismaticPress {
                            point_m,
                            axis: axis_dir,
                            target_velocity_m_s: speed(*target_m_s),
                            max_force_n: effort(*max_force_n)?,
                            delay_m_s: DEFAULT_CONTROLLER_DELAY,
                        },
                        (
                            Some(Actuator::Servo {
                                target,
                                max_effort,
                                response_time_s,
                            }),
                            true,
                        ) => JointKind::HingeServo {
                            point_m,
                            axis: axis_dir,
                            target_deg: (target - q0).to_degrees(),
                            max_torque_n_m: effort(*max_effort)?,
                            response_time_s: *response_time_s,
                        },
                        (
                            Some(Actuator::Servo {
                                target,
                                max_effort,
                                response_time_s,
                            }),
                            false,
                        ) => JointKind::PrismaticServo {
                            point_m,
                            axis: axis_dir,
                            target_m: target - q0,
                            max_force_n: effort(*max_effort)?,
                            response_time_s: *response_time_s,
                        },
                        (_, true) => JointKind::Hinge {
                            point_m,
                            axis: axis_dir,
                        },
                        (_, false) => JointKind::Prismatic {
                            point_m,
                            axis: axis_dir,
                        },
                    };
                    let h = self.add_joint(&label, a, Some(b), kind, params).map_err(located)?;
                    if let Some(Actuator::Motor { drive_only: true, .. }) = &actuator {
                        self.set_motor_drive_only(&h, true).map_err(located)?;
                    }
                    let limited = j.joint_type != urdf_rs::JointType::Continuous && j.limit.lower < j.limit.upper;
                    if limited {
                        let (lo, hi) = (j.limit.lower - q0, j.limit.upper - q0);
                        let limit_label = format!("{label}.limits");
                        let range = if !use_hinge {
                            Some(JointKind::SliderRange {
                                point_m,
                                axis: axis_dir,
                                limits_m: [lo, hi],
                            })
                        } else if hi - lo <= std::f64::consts::TAU {
                            Some(JointKind::HingeRange {
                                point_m,
                                axis: axis_dir,
                                limits_deg: [lo.to_degrees(), hi.to_degrees()],
                            })
                        } else {
                            None
                        };
                        if let Some(range) = range {
                            extra.push(
                                self.add_joint(&limit_label, a, Some(b), range, params)
                                    .map_err(located)?,
                            );
                        }
                    }
                    let urdf_damping = j.dynamics.as_ref().map_or(0.0, |d| d.damping);
                    let damping = o.and_then(|o| o.damping).unwrap_or(urdf_damping);
                    let spring = match &actuator {
                        Some(Actuator::SpringDamper {
                            stiffness,
                            rest,
                            damping: d,
                        }) => Some(("spring", *stiffness, rest - q0, d + damping)),
                        _ if damping > 0.0 => Some(("damping", 0.0, 0.0, damping)),
                        _ => None,
                    };
                    if let Some((what, spring_stiffness, rest, damping)) = spring {
                        let kind = JointKind::JointSpring {
                            joint: h.label.clone(),
                            spring_stiffness,
                            rest,
                            damping,
                        };
                        let spring_label = format!("{label}.{what}");
                        let params = JointParams::default();
                        extra.push(
                            self.add_joint(&spring_label, None, None, kind, params)
                                .map_err(located)?,
                        );
                    }
                    Some(h)
                }
                urdf_rs::JointType::Fixed => {
                    // Not merged (merge_fixed_joints off): glue the two bodies.
                    let kind = match a {
                        Some(_) => JointKind::Attachment {},
                        None => JointKind::Fix {},
                    };
                    Some(self.add_joint(&label, a, Some(b), kind, params).map_err(located)?)
                }
                urdf_rs::JointType::Floating => None,
                urdf_rs::JointType::Planar => {
                    let kind = JointKind::Planar {
                        point_m: point.into(),
                        normal: axis.into(),
                    };
                    Some(self.add_joint(&label, a, Some(b), kind, params).map_err(located)?)
                }
                urdf_rs::JointType::Spherical => {
                    let kind = JointKind::Ball { point_m: point.into() };
                    Some(self.add_joint(&label, a, Some(b), kind, params).map_err(located)?)
                }
            };
            if let Some(h) = main {
                joints.insert(j.name.clone(), h);
            }
            if let Some(a) = a {
                adjacent.push((a, b));
            }
        }
        // Mimic couplings, once every joint exists.
        for j in &robot.joints {
            let Some(m) = &j.mimic else { continue };
            let located = |e: StarkError| src.err(joint_line(&j.name), &format!("joint '{}' <mimic>", j.name), e);
            let (Some(hb), Some(ha)) = (joints.get(&j.name), joints.get(&m.joint)) else {
                return Err(located(StarkError::InvalidInput(format!(
                    "both '{}' and '{}' must be moving joints",
                    j.name, m.joint
                ))));
            };
            let multiplier = m.multiplier.unwrap_or(1.0);
            let q0a = initial_positions.get(&m.joint).copied().unwrap_or(0.0);
            let q0b = initial_positions.get(&j.name).copied().unwrap_or(0.0);
            // URDF: q_b = m·q_a + c in URDF coordinates; the joints measure from their start.
            let offset = m.offset.unwrap_or(0.0) + multiplier * q0a - q0b;
            let kind = JointKind::JointCoupling {
                joint_a: ha.label.clone(),
                joint_b: hb.label.clone(),
                multiplier,
                offset,
            };
            let mimic_label = format!("{name}/{}.mimic", j.name);
            let h = self
                .add_joint(&mimic_label, None, None, kind, options.mimic_params)
                .map_err(located)?;
            extra.push(h);
        }
        if options.fixed_base {
            if let Some(body) = body_of_link(root) {
                let label = format!("{name}/fixed_base");
                extra.push(self.add_joint(&label, None, Some(body), JointKind::Fix {}, params)?);
            }
        }
        // Contact between the robot's own links.
        if !options.self_collision {
            for (i, (_, a)) in bodies.iter().enumerate() {
                for (_, b) in &bodies[i + 1..] {
                    self.set_bodies_collision(*a, *b, false)?;
                }
            }
        } else if !options.adjacent_links_collide {
            for (a, b) in adjacent {
                self.set_bodies_collision(a, b, false)?;
            }
        }
        let links = robot
            .links
            .iter()
            .enumerate()
            .map(|(i, l)| (l.name.clone(), body_of_link(i)))
            .collect();
        Ok(Robot {
            name: name.to_string(),
            links,
            joints,
            extra_joints: extra,
            bodies,
            initial_positions,
            collision_meshes,
        })
    }
}

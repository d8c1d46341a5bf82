//! Declarative scene files: a TOML document (or JSON, for files ending in `.json`) that builds a
//! [`Simulation`] through the same calls a Rust program would make.
//!
//! The format mirrors the API, so names, units and defaults are those of the Rust structs:
//!
//! - `[settings]` is deserialised straight into [`Settings`] (every setting, same names);
//!   `duration_s` is the simulated time.
//! - `[[surface]]`, `[[volume]]` and `[[line]]` call [`Simulation::add_surface`],
//!   [`Simulation::add_volume`] and [`Simulation::add_line`]. Each has a unique `name` and one
//!   geometry: a generator (`grid` or `segments`), a `mesh` file (relative paths are resolved
//!   against the scene file's directory) or inline `vertices_m` + `elements`; an optional placement
//!   (`scale`, then `rotate_deg`, then `translate_m`); and a `material`: a preset name or a table
//!   `{ preset = "...", strain = { ... }, ... }` whose sub-tables override single fields of the
//!   preset. The override is merged into the serialised preset and the result deserialised, so
//!   field names and checks are exactly those of [`SurfaceMaterial`], [`VolumeMaterial`] and
//!   [`LineMaterial`].
//! - `[[prescribed]]` selects nodes of an object (`inside_box`, `outside_box`, `nodes` or
//!   `all`) and pulls them to targets ([`PrescribedParams`]); an optional [`Motion`] moves the
//!   targets through [`Simulation::add_time_event`].
//! - `[[attachment]]` glues nodes of one object to nodes or triangles of another
//!   ([`Attachments`](crate::deformables::Attachments)).
//! - `[[gravity_ramp]]` changes gravity linearly over a time interval.
//! - Contact: `[settings.contact]` is [`ContactSettings`](crate::contact::ContactSettings), and an
//!   object takes part in contact when its material sets `contact_thickness_m` or
//!   `settings.contact.default_thickness_m` is set (as in the API).
//!   `[[obstacle]]` calls [`Simulation::add_prescribed_surface`]: a kinematic triangle surface
//!   (generator `sphere`, `box`, `cylinder` or `grid`, a `mesh` file or inline `vertices_m` +
//!   `triangles`, placed like the objects) whose nodes follow prescribed targets, optionally moved
//!   by a [`Motion`]. `[[friction]]` calls [`Contact::set_friction`](crate::contact::Contact::set_friction)
//!   and `[[disable_collision]]` [`Contact::disable_collision`](crate::contact::Contact::disable_collision)
//!   for a pair of object names (the same name twice for the object with itself).
//! - `[[rigid_body]]` calls [`Simulation::add_rigid_body`] with the mass properties of its shape
//!   (`box`, `sphere`, `cylinder`, `torus`, a `mesh` file or inline `vertices_m` + `triangles`;
//!   `mass_kg` or `density_kg_m3`) and gives it its mesh
//!   ([`Simulation::add_rigid_collision_mesh`] when it has a contact thickness, else
//!   [`Simulation::add_rigid_output_mesh`]); `fixed = true` adds a fix joint, which a `motion`
//!   or `keyframes` drive. `[[joint]]` calls the joint constructor of its `type` between body
//!   `a` (or `"world"`) and body `b` ([`JointKind`](crate::rigidbodies::joints::JointKind)). Rigid bodies count as objects: friction,
//!   disabled collisions and attachments (to the vertices of their meshes) may name them.
//!
//! Every error is a [`SceneError`] naming the file, the line and column where they are known
//! (always for TOML; for JSON only for syntax, type and unknown-field errors of the file's
//! structure) and the entry and field, e.g.
//!
//! ```text
//! hanging.toml:14:3: unknown field `youngs_modulu` in surface 'cloth' material.strain, expected one of ...
//! ```
//!
//! `docs/scene-format.md` documents every table and field.
//!
//! ```
//! let text = r#"
//! duration_s = 1.0
//! [[surface]]
//! name = "cloth"
//! grid = { size_m = [1.0, 1.0], quads = [4, 4] }
//! material = "cotton_fabric"
//! [[prescribed]]
//! object = "cloth"
//! inside_box = { center_m = [0.5, 0.5, 0.0], size_m = [0.01, 0.01, 0.01] }
//! stiffness = 1e6
//! "#;
//! let scene = stark::io::scene::parse_scene(text, "doc.toml", std::path::Path::new(".")).unwrap();
//! assert_eq!(scene.simulation.nodes.len(), 25);
//! assert_eq!(scene.name, "doc");
//! ```

mod rigid;
mod robot;

pub use rigid::SceneRigidBody;

use crate::contact::ContactHandle;
use crate::deformables::{AttachmentHandle, AttachmentParams, PrescribedHandle, PrescribedParams};
use crate::error::{Result, StarkError};
use crate::geometry::mesh;
use crate::io::mesh_files::{load_tet_mesh, load_triangle_mesh};
use crate::presets::meshes;
use crate::presets::{
    LineHandle, LineMaterial, ObstacleHandle, SurfaceHandle, SurfaceMaterial, VolumeHandle, VolumeMaterial,
};
use crate::rigidbodies::joints::{JointHandle, JointKind};
use crate::rigidbodies::{Shape, ShapeError};
use crate::simulation::Simulation;
use crate::solver::Settings;
use nalgebra::{Rotation3, Unit, Vector3};
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use std::fmt;
use std::fmt::Write as _;
use std::ops::Range;
use std::path::Path;
use toml::de::{DeTable, DeValue};

// ------------------------------------------------------------------------------------------
// Public API
// ------------------------------------------------------------------------------------------

/// A simulation built from a scene file, ready to run for `duration_s`.
pub struct LoadedScene {
    /// The simulation with every object, boundary condition and event of the file.
    pub simulation: Simulation,
    /// Simulated time the scene asks for, s.
    pub duration_s: f64,
    /// Scene name: `settings.name` if the file sets it, else the file name without extension.
    pub name: String,
    /// The objects in creation order (surfaces, then volumes, then lines, then obstacles, each in
    /// file order).
    pub objects: Vec<(String, SceneObject)>,
    /// The `[[prescribed]]` entries in file order.
    pub prescribed: Vec<ScenePrescribed>,
    /// The `[[attachment]]` entries in file order, with their labels.
    pub attachments: Vec<(String, AttachmentHandle)>,
    /// The joints in creation order: the fix joints of fixed rigid bodies (`<body>.fixed`), in
    /// the order of the bodies, then the `[[joint]]` entries in file order, then the joints of
    /// the robots.
    pub joints: Vec<JointHandle>,
    /// The `[[robot]]` entries in file order (their links with a collision mesh are also
    /// rigid-body objects, named `<robot>/<link>`).
    pub robots: Vec<crate::robots::Robot>,
}

impl LoadedScene {
    /// The object called `name`.
    pub fn object(&self, name: &str) -> Option<&SceneObject> {
        self.objects.iter().find(|(n, _)| n == name).map(|(_, o)| o)
    }

    /// The rigid body called `name`.
    pub fn rigid_body(&self, name: &str) -> Option<SceneRigidBody> {
        match self.object(name) {
            Some(SceneObject::RigidBody(b)) => Some(*b),
            _ => None,
        }
    }

    /// The joint called `name`.
    pub fn joint(&self, name: &str) -> Option<&JointHandle> {
        self.joints.iter().find(|j| j.label == name)
    }
}

/// Handles of one object of a scene.
#[derive(Clone, Copy, Debug)]
pub enum SceneObject {
    /// A `[[surface]]`.
    Surface(SurfaceHandle),
    /// A `[[volume]]`.
    Volume(VolumeHandle),
    /// A `[[line]]`.
    Line(LineHandle),
    /// An `[[obstacle]]`.
    Obstacle(ObstacleHandle),
    /// A `[[rigid_body]]`.
    RigidBody(SceneRigidBody),
}

impl SceneObject {
    /// Its node set.
    pub fn nodes(&self) -> crate::deformables::NodeSetHandle {
        match self {
            SceneObject::Surface(h) => h.nodes,
            SceneObject::Volume(h) => h.nodes,
            SceneObject::Line(h) => h.nodes,
            SceneObject::Obstacle(h) => h.nodes,
            SceneObject::RigidBody(h) => h.nodes,
        }
    }

    /// What kind of entry it is (`"surface"`, ..., `"rigid body"`).
    pub fn kind(&self) -> &'static str {
        match self {
            SceneObject::Surface(_) => "surface",
            SceneObject::Volume(_) => "volume",
            SceneObject::Line(_) => "line",
            SceneObject::Obstacle(_) => "obstacle",
            SceneObject::RigidBody(_) => "rigid body",
        }
    }

    /// Its contact object, if it takes part in contact (obstacles always do).
    pub fn contact(&self) -> Option<ContactHandle> {
        match self {
            SceneObject::Surface(h) => h.contact,
            SceneObject::Volume(h) => h.contact,
            SceneObject::Line(h) => h.contact,
            SceneObject::Obstacle(h) => Some(h.contact),
            SceneObject::RigidBody(h) => h.contact,
        }
    }
}

/// One `[[prescribed]]` entry of a scene.
#[derive(Clone, Debug)]
pub struct ScenePrescribed {
    /// Name of the object whose nodes are prescribed.
    pub object: String,
    /// Handle of the group.
    pub handle: PrescribedHandle,
    /// Number of nodes selected.
    pub nodes: usize,
    /// Scripted motion of the targets, if any.
    pub motion: Option<Motion>,
}

/// Scripted rigid motion of prescribed targets: at time `t` the targets are the reference
/// positions (the nodes' positions when prescribed) rotated by `ω·τ` about `axis` through
/// `center_m` and then translated by `v·τ`, with `τ = min(t, end_s) − start_s` (no motion
/// before `start_s`; the pose at `end_s` is held afterwards).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Motion {
    /// Time the motion starts, s (default: 0).
    pub start_s: f64,
    /// Time the motion stops, s (default: ∞, never; TOML `inf`).
    pub end_s: f64,
    /// Linear velocity `v`, m/s (default: 0).
    pub velocity_m_s: [f64; 3],
    /// Angular velocity `ω`, degrees/s, right-handed about `axis` (default: 0).
    pub angular_velocity_deg_s: f64,
    /// Rotation axis (normalised here); required when `angular_velocity_deg_s` ≠ 0
    /// (default: none).
    pub axis: Option<[f64; 3]>,
    /// A point on the rotation axis, m (default: the origin).
    pub center_m: [f64; 3],
}

impl Default for Motion {
    fn default() -> Self {
        Motion {
            start_s: 0.0,
            end_s: f64::INFINITY,
            velocity_m_s: [0.0; 3],
            angular_velocity_deg_s: 0.0,
            axis: None,
            center_m: [0.0; 3],
        }
    }
}

impl Motion {
    /// Check the values; the error names the field.
    pub fn validate(&self) -> std::result::Result<(), (&'static str, String)> {
        if !self.start_s.is_finite() {
            return Err(("start_s", format!("start_s = {} must be finite", self.start_s)));
        }
        if self.end_s.is_nan() || self.end_s <= self.start_s {
            return Err((
                "end_s",
                format!("end_s = {} must be greater than start_s = {}", self.end_s, self.start_s),
            ));
        }
        if !self.velocity_m_s.iter().all(|v| v.is_finite()) {
            return Err(("velocity_m_s", "velocity_m_s must be finite".into()));
        }
        if !self.center_m.iter().all(|v| v.is_finite()) {
            return Err(("center_m", "center_m must be finite".into()));
        }
        if !self.angular_velocity_deg_s.is_finite() {
            return Err(("angular_velocity_deg_s", "angular_velocity_deg_s must be finite".into()));
        }
        match self.axis {
            Some(a) if !a.iter().all(|v| v.is_finite()) || Vector3::from(a).norm() == 0.0 => {
                Err(("axis", format!("axis {a:?} must be finite and non-zero")))
            }
            None if self.angular_velocity_deg_s != 0.0 => {
                Err(("angular_velocity_deg_s", "a rotating motion needs an `axis`".into()))
            }
            _ => Ok(()),
        }
    }

    /// The target transform at time `t`: targets are `R·p + translation` for the reference
    /// positions `p`.
    pub fn transform_at(&self, t: f64) -> (Vector3<f64>, Rotation3<f64>) {
        let tau = (t.min(self.end_s) - self.start_s).max(0.0);
        let angle = (self.angular_velocity_deg_s * tau).to_radians();
        let rotation = match self.axis {
            Some(a) if angle != 0.0 => Rotation3::from_axis_angle(&Unit::new_normalize(Vector3::from(a)), angle),
            _ => Rotation3::identity(),
        };
        let c = Vector3::from(self.center_m);
        let translation = c - rotation * c + Vector3::from(self.velocity_m_s) * tau;
        (translation, rotation)
    }

    /// Move the targets of group `h` to their pose at time `t`.
    pub fn apply(&self, sim: &mut Simulation, h: PrescribedHandle, t: f64) -> Result<()> {
        let (translation, rotation) = self.transform_at(t);
        sim.deformables.prescribed.set_transform(h, translation, rotation)
    }
}

/// An invalid scene file: where the problem is and what it is.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneError {
    /// The file as given to the loader.
    pub file: String,
    /// 1-based line, where known.
    pub line: Option<usize>,
    /// 1-based column in characters, where known.
    pub column: Option<usize>,
    /// The entry and field, e.g. `surface 'cloth' material.strain` (empty for the whole file).
    pub path: String,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file)?;
        if let Some(line) = self.line {
            write!(f, ":{line}")?;
            if let Some(column) = self.column {
                write!(f, ":{column}")?;
            }
        }
        write!(f, ": ")?;
        if self.path.is_empty() {
            write!(f, "{}", self.message)
        } else if let Some((head, tail)) = self.message.split_once(", expected") {
            write!(f, "{head} in {}, expected{tail}", self.path)
        } else {
            write!(f, "{} in {}", self.message, self.path)
        }
    }
}

impl std::error::Error for SceneError {}

/// Load a scene file (TOML, or JSON if the name ends in `.json`). Relative mesh paths are
/// resolved against the file's directory.
pub fn load_scene(path: &Path) -> Result<LoadedScene> {
    load_scene_with(path, |_| {})
}

/// [`load_scene`], letting `configure` change the settings (output directory, threads, ...)
/// after they are read and before the simulation is built.
pub fn load_scene_with(path: &Path, configure: impl FnOnce(&mut Settings)) -> Result<LoadedScene> {
    let file = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| SceneError {
        file: file.clone(),
        line: None,
        column: None,
        path: String::new(),
        message: format!("cannot read the scene file: {e}"),
    })?;
    let base_dir = path.parent().unwrap_or(Path::new("."));
    let mut loaded = parse_scene_with(&text, &file, base_dir, configure)?;
    loaded.simulation.set_scene_origin(crate::io::SceneOrigin::File {
        path: std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf()),
        overrides: Vec::new(),
    });
    Ok(loaded)
}

/// [`load_scene_with`] after applying `overrides`, each `key.path=value`, to the file's document
/// before it is read: `settings.time_step_s=0.01`, `surface.cloth.material.strain.youngs_modulus=1e5`
/// (an entry of an array of tables is chosen by its `name` or its index), `duration_s=2`. The
/// value is TOML (`1e5`, `true`, `[0, 0, -9.81]`, `"text"`; a bare word is taken as a string).
/// Tables missing on the way are created, so any field can be set, and a misspelt key is
/// reported as the unknown field it is; an index or name that selects no entry, or a key below a
/// value that is not a table, is an error naming the override.
pub fn load_scene_with_overrides(
    path: &Path,
    overrides: &[String],
    configure: impl FnOnce(&mut Settings),
) -> Result<LoadedScene> {
    let origin = crate::io::SceneOrigin::File {
        path: std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf()),
        overrides: overrides.to_vec(),
    };
    let mut loaded = if overrides.is_empty() {
        load_scene_with(path, configure)?
    } else {
        let file = path.display().to_string();
        let scene_err = |message: String| SceneError {
            file: file.clone(),
            line: None,
            column: None,
            path: String::new(),
            message,
        };
        let text = std::fs::read_to_string(path).map_err(|e| scene_err(format!("cannot read the scene file: {e}")))?;
        let mut doc: toml::Table = if file.to_ascii_lowercase().ends_with(".json") {
            serde_json::from_str(&text).map_err(|e| json_error(&file, &e))?
        } else {
            toml::from_str(&text).map_err(|e| scene_err(e.message().trim_end().to_string()))?
        };
        for o in overrides {
            apply_override(&mut doc, o).map_err(|m| scene_err(format!("--set {o}: {m}")))?;
        }
        // The name defaults to the file's stem; the rewritten document has no file of its own.
        let stem = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        if let toml::Value::Table(settings) = doc
            .entry("settings")
            .or_insert_with(|| toml::Value::Table(toml::Table::new()))
        {
            settings.entry("name").or_insert(toml::Value::String(stem));
        }
        let text = toml::to_string(&doc).map_err(|e| scene_err(format!("cannot write the overridden scene: {e}")))?;
        let base_dir = path.parent().unwrap_or(Path::new("."));
        parse_scene_with(&text, &format!("{file} (with --set overrides)"), base_dir, configure)?
    };
    loaded.simulation.set_scene_origin(origin);
    Ok(loaded)
}

/// Apply one `key.path=value` override to a scene document (see [`load_scene_with_overrides`]).
pub fn apply_override(doc: &mut toml::Table, spec: &str) -> std::result::Result<(), String> {
    let (key, raw) = spec
        .split_once('=')
        .ok_or_else(|| "expected key.path=value".to_string())?;
    let keys: Vec<&str> = key.trim().split('.').collect();
    if keys.iter().any(|k| k.is_empty()) {
        return Err(format!("`{key}` has an empty key"));
    }
    let raw = raw.trim();
    let value = match toml::from_str::<toml::Table>(&format!("v = {raw}")) {
        Ok(mut t) => t.remove("v").expect("parsed key"),
        Err(_) => toml::Value::String(raw.to_string()),
    };
    let mut current = doc;
    let mut walked = String::new();
    let (last, parents) = keys.split_last().expect("at least one key");
    for (i, k) in parents.iter().enumerate() {
        let next_is_index = keys[i + 1].parse::<usize>().is_ok();
        let entry = current.entry(k.to_string()).or_insert_with(|| {
            if next_is_index {
                toml::Value::Array(Vec::new())
            } else {
                toml::Value::Table(toml::Table::new())
            }
        });
        walked = if walked.is_empty() {
            k.to_string()
        } else {
            format!("{walked}.{k}")
        };
        current = match entry {
            toml::Value::Table(t) => t,
            toml::Value::Array(entries) => {
                // An array of tables: the next key names an entry (by `name` or index).
                return set_in_array(entries, &walked, &keys[i + 1..], value);
            }
            other => {
                return Err(format!(
                    "`{walked}` is a {}, not a table, so it has no `{}`",
                    other.type_str(),
                    keys[i + 1]
                ))
            }
        };
    }
    current.insert(last.to_string(), value);
    Ok(())
}

fn set_in_array(
    entries: &mut [toml::Value],
    walked: &str,
    keys: &[&str],
    value: toml::Value,
) -> std::result::Result<(), String> {
    let sel = keys[0];
    let names: Vec<String> = entries
        .iter()
        .enumerate()
        .map(|(i, e)| {
            e.get("name")
                .and_then(|n| n.as_str())
                .map(str::to_string)
                .unwrap_or_else(|| i.to_string())
        })
        .collect();
    let index = match sel.parse::<usize>() {
        Ok(i) if i < entries.len() => i,
        Ok(i) => {
            return Err(format!(
                "`{walked}` has {} entries, there is no entry {i}",
                entries.len()
            ))
        }
        Err(_) => names.iter().position(|n| n == sel).ok_or_else(|| {
            format!(
                "`{walked}` has no entry named '{sel}' (its entries: {})",
                if names.is_empty() {
                    "none".to_string()
                } else {
                    names.join(", ")
                }
            )
        })?,
    };
    let walked = format!("{walked}.{sel}");
    if keys.len() == 1 {
        entries[index] = value;
        return Ok(());
    }
    match &mut entries[index] {
        toml::Value::Table(t) => {
            let rest = keys[1..].join(".");
            apply_override(t, &format!("{rest}={}", toml_value_text(&value))).map_err(|m| format!("in `{walked}`: {m}"))
        }
        other => Err(format!(
            "`{walked}` is a {}, not a table, so it has no `{}`",
            other.type_str(),
            keys[1]
        )),
    }
}

/// A value written back as TOML (for a recursive [`apply_override`]).
fn toml_value_text(v: &toml::Value) -> String {
    match v {
        toml::Value::String(s) => toml::Value::String(s.clone()).to_string(),
        other => other.to_string(),
    }
}

/// Build a scene from its text. `file_name` names the file in errors and chooses the format
/// (JSON if it ends in `.json`, TOML otherwise); relative mesh paths are resolved against
/// `base_dir`.
pub fn parse_scene(text: &str, file_name: &str, base_dir: &Path) -> Result<LoadedScene> {
    parse_scene_with(text, file_name, base_dir, |_| {})
}

/// [`parse_scene`], letting `configure` change the settings (output directory, threads, ...)
/// after they are read and before the simulation is built.
pub fn parse_scene_with(
    text: &str,
    file_name: &str,
    base_dir: &Path,
    configure: impl FnOnce(&mut Settings),
) -> Result<LoadedScene> {
    if file_name.to_ascii_lowercase().ends_with(".json") {
        let value: serde_json::Value = serde_json::from_str(text).map_err(|e| json_error(file_name, &e))?;
        let file: SceneFile = serde_json::from_str(text).map_err(|e| json_error(file_name, &e))?;
        let ctx = Ctx {
            file: file_name,
            text,
            tree: Tree::Json(&value),
            root_span: None,
        };
        Ok(build(file, &ctx, base_dir, configure)?)
    } else {
        let doc = DeTable::parse(text).map_err(|e| {
            let (line, column) = e.span().map(|s| line_col(text, s.start)).unzip();
            SceneError {
                file: file_name.to_string(),
                line,
                column,
                path: String::new(),
                message: e.message().trim_end().to_string(),
            }
        })?;
        let ctx = Ctx {
            file: file_name,
            text,
            tree: Tree::Toml(doc.get_ref()),
            root_span: Some(doc.span()),
        };
        let file: SceneFile = toml::from_str(text).map_err(|e| ctx.toml_error(&e))?;
        Ok(build(file, &ctx, base_dir, configure)?)
    }
}

// ------------------------------------------------------------------------------------------
// The file's structure
// ------------------------------------------------------------------------------------------

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    #[serde(default)]
    settings: Settings,
    duration_s: f64,
    #[serde(default)]
    surface: Vec<SurfaceEntry>,
    #[serde(default)]
    volume: Vec<VolumeEntry>,
    #[serde(default)]
    line: Vec<LineEntry>,
    #[serde(default)]
    prescribed: Vec<PrescribedEntry>,
    #[serde(default)]
    attachment: Vec<AttachmentEntry>,
    #[serde(default)]
    gravity_ramp: Vec<GravityRampEntry>,
    #[serde(default)]
    obstacle: Vec<ObstacleEntry>,
    #[serde(default)]
    friction: Vec<FrictionEntry>,
    #[serde(default)]
    disable_collision: Vec<DisableCollisionEntry>,
    #[serde(default)]
    rigid_body: Vec<rigid::RigidBodyEntry>,
    #[serde(default)]
    joint: Vec<rigid::JointEntry>,
    #[serde(default)]
    robot: Vec<robot::RobotEntry>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SurfaceGrid {
    size_m: [f64; 2],
    quads: [usize; 2],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct VolumeGrid {
    size_m: [f64; 3],
    cells: [usize; 3],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LineSegments {
    begin_m: [f64; 3],
    end_m: [f64; 3],
    count: usize,
}

#[derive(Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct Rotate {
    angle: f64,
    axis: [f64; 3],
}

/// `cup = { ... }`: a thin cup shell ([`meshes::cup_mesh`]); unset fields keep
/// [`meshes::CupShape::default`]'s values.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CupGenerator {
    height_m: Option<f64>,
    rim_radius_m: Option<f64>,
    bottom_radius_m: Option<f64>,
    lip_radius_m: Option<f64>,
    lip_angle_deg: Option<f64>,
    segments: Option<usize>,
    lip_max_row_angle_deg: Option<f64>,
}

impl CupGenerator {
    fn shape(&self) -> meshes::CupShape {
        let d = meshes::CupShape::default();
        meshes::CupShape {
            height_m: self.height_m.unwrap_or(d.height_m),
            rim_radius_m: self.rim_radius_m.unwrap_or(d.rim_radius_m),
            bottom_radius_m: self.bottom_radius_m.unwrap_or(d.bottom_radius_m),
            lip_radius_m: self.lip_radius_m.unwrap_or(d.lip_radius_m),
            lip_angle_deg: self.lip_angle_deg.unwrap_or(d.lip_angle_deg),
            segments: self.segments.unwrap_or(d.segments),
            lip_max_row_angle_deg: self.lip_max_row_angle_deg.unwrap_or(d.lip_max_row_angle_deg),
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SurfaceEntry {
    name: String,
    grid: Option<SurfaceGrid>,
    cup: Option<CupGenerator>,
    mesh: Option<String>,
    vertices_m: Option<Vec<[f64; 3]>>,
    elements: Option<Vec<[usize; 3]>>,
    translate_m: Option<[f64; 3]>,
    rotate_deg: Option<Rotate>,
    scale: Option<f64>,
    material: toml::Value,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct VolumeEntry {
    name: String,
    grid: Option<VolumeGrid>,
    mesh: Option<String>,
    vertices_m: Option<Vec<[f64; 3]>>,
    elements: Option<Vec<[usize; 4]>>,
    translate_m: Option<[f64; 3]>,
    rotate_deg: Option<Rotate>,
    scale: Option<f64>,
    material: toml::Value,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LineEntry {
    name: String,
    segments: Option<LineSegments>,
    vertices_m: Option<Vec<[f64; 3]>>,
    elements: Option<Vec<[usize; 2]>>,
    translate_m: Option<[f64; 3]>,
    rotate_deg: Option<Rotate>,
    scale: Option<f64>,
    material: toml::Value,
}

fn default_sphere_subdivisions() -> usize {
    2
}

fn default_cylinder_slices() -> usize {
    16
}

fn default_cylinder_stacks() -> usize {
    1
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SphereGenerator {
    radius_m: f64,
    #[serde(default = "default_sphere_subdivisions")]
    subdivisions: usize,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BoxGenerator {
    size_m: [f64; 3],
}

fn default_capsule_slices() -> usize {
    16
}

fn default_capsule_rings() -> usize {
    4
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CapsuleGenerator {
    radius_m: f64,
    height_m: f64,
    #[serde(default = "default_capsule_slices")]
    slices: usize,
    #[serde(default = "default_capsule_rings")]
    cap_rings: usize,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CylinderGenerator {
    radius_m: f64,
    height_m: f64,
    #[serde(default = "default_cylinder_slices")]
    slices: usize,
    #[serde(default = "default_cylinder_stacks")]
    stacks: usize,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ObstacleEntry {
    name: String,
    sphere: Option<SphereGenerator>,
    #[serde(rename = "box")]
    box_: Option<BoxGenerator>,
    cylinder: Option<CylinderGenerator>,
    grid: Option<SurfaceGrid>,
    mesh: Option<String>,
    vertices_m: Option<Vec<[f64; 3]>>,
    triangles: Option<Vec<[usize; 3]>>,
    translate_m: Option<[f64; 3]>,
    rotate_deg: Option<Rotate>,
    scale: Option<f64>,
    contact_thickness_m: Option<f64>,
    stiffness: Option<f64>,
    motion: Option<Motion>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FrictionEntry {
    objects: [String; 2],
    mu: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct DisableCollisionEntry {
    objects: [String; 2],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BoxSelection {
    center_m: [f64; 3],
    size_m: [f64; 3],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PrescribedEntry {
    object: String,
    inside_box: Option<BoxSelection>,
    outside_box: Option<BoxSelection>,
    nodes: Option<Vec<usize>>,
    all: Option<bool>,
    stiffness: Option<f64>,
    tolerance_m: Option<f64>,
    motion: Option<Motion>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct AttachmentEntry {
    name: Option<String>,
    a: String,
    b: String,
    nodes_a: Option<Vec<usize>>,
    nodes_b: Option<Vec<usize>>,
    triangles_b: Option<Vec<[usize; 3]>>,
    barycentric_b: Option<Vec<[f64; 3]>>,
    within_m: Option<f64>,
    stiffness: Option<f64>,
    tolerance_m: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct GravityRampEntry {
    start_s: f64,
    end_s: f64,
    from_m_s2: Option<[f64; 3]>,
    to_m_s2: [f64; 3],
}

// ------------------------------------------------------------------------------------------
// Locating errors
// ------------------------------------------------------------------------------------------

/// One step of a path into the document.
#[derive(Clone, Debug, PartialEq)]
enum Seg {
    Key(String),
    Index(usize),
}

/// A path into the document.
#[derive(Clone, Debug, Default, PartialEq)]
struct At(Vec<Seg>);

impl At {
    fn entry(kind: &str, index: usize) -> At {
        At(vec![Seg::Key(kind.into()), Seg::Index(index)])
    }
    fn key(&self, key: &str) -> At {
        let mut p = self.clone();
        p.0.push(Seg::Key(key.into()));
        p
    }
    fn index(&self, index: usize) -> At {
        let mut p = self.clone();
        p.0.push(Seg::Index(index));
        p
    }
    fn keys<S: AsRef<str>>(&self, keys: &[S]) -> At {
        let mut p = self.clone();
        p.0.extend(keys.iter().map(|k| Seg::Key(k.as_ref().into())));
        p
    }
}

/// Entry arrays whose items are described by name rather than by index.
const ENTRY_KINDS: [&str; 12] = [
    "robot",
    "surface",
    "volume",
    "line",
    "obstacle",
    "prescribed",
    "attachment",
    "gravity_ramp",
    "friction",
    "disable_collision",
    "rigid_body",
    "joint",
];

/// The untyped document, for spans (TOML only) and entry labels.
enum Tree<'a> {
    Toml(&'a DeTable<'a>),
    Json(&'a serde_json::Value),
}

impl Tree<'_> {
    fn item_str(&self, kind: &str, index: usize, key: &str) -> Option<String> {
        match self {
            Tree::Toml(doc) => doc
                .get(kind)?
                .get_ref()
                .as_array()?
                .get(index)?
                .get_ref()
                .as_table()?
                .get(key)?
                .get_ref()
                .as_str()
                .map(str::to_string),
            Tree::Json(v) => v.get(kind)?.get(index)?.get(key)?.as_str().map(str::to_string),
        }
    }

    /// Whether entry `index` of `kind` gives the field `key`.
    fn item_has(&self, kind: &str, index: usize, key: &str) -> bool {
        match self {
            Tree::Toml(doc) => (|| {
                doc.get(kind)?
                    .get_ref()
                    .as_array()?
                    .get(index)?
                    .get_ref()
                    .as_table()?
                    .get(key)
            })()
            .is_some(),
            Tree::Json(v) => v
                .get(kind)
                .and_then(|k| k.get(index))
                .and_then(|e| e.get(key))
                .is_some(),
        }
    }

    /// The strings of an array field of an entry (`None` unless every item is a string).
    fn item_strs(&self, kind: &str, index: usize, key: &str) -> Option<Vec<String>> {
        match self {
            Tree::Toml(doc) => doc
                .get(kind)?
                .get_ref()
                .as_array()?
                .get(index)?
                .get_ref()
                .as_table()?
                .get(key)?
                .get_ref()
                .as_array()?
                .iter()
                .map(|v| v.get_ref().as_str().map(str::to_string))
                .collect(),
            Tree::Json(v) => v
                .get(kind)?
                .get(index)?
                .get(key)?
                .as_array()?
                .iter()
                .map(|v| v.as_str().map(str::to_string))
                .collect(),
        }
    }
}

struct Ctx<'a> {
    file: &'a str,
    text: &'a str,
    tree: Tree<'a>,
    /// Span of the whole TOML document (errors there, such as a missing top-level field, have no
    /// path).
    root_span: Option<Range<usize>>,
}

/// 1-based line and column (in characters) of a byte offset.
fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(text.len());
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    (line, before[line_start..].chars().count() + 1)
}

/// The deepest path whose key or value span contains `pos`.
fn locate_in_table(table: &DeTable, pos: usize, path: &mut Vec<Seg>) -> bool {
    for (key, value) in table.iter() {
        path.push(Seg::Key(key.get_ref().to_string()));
        if key.span().contains(&pos) || locate_in_value(value.get_ref(), pos, path) {
            return true;
        }
        if value.span().contains(&pos) {
            return true;
        }
        path.pop();
    }
    false
}

fn locate_in_value(value: &DeValue, pos: usize, path: &mut Vec<Seg>) -> bool {
    match value {
        DeValue::Table(t) => locate_in_table(t, pos, path),
        DeValue::Array(a) => {
            for (i, item) in a.iter().enumerate() {
                path.push(Seg::Index(i));
                if locate_in_value(item.get_ref(), pos, path) || item.span().contains(&pos) {
                    return true;
                }
                path.pop();
            }
            false
        }
        _ => false,
    }
}

impl Ctx<'_> {
    /// Span of the deepest element of `at` that exists in the document (a key's span for keys).
    fn span_of(&self, at: &At) -> Option<Range<usize>> {
        let Tree::Toml(doc) = self.tree else {
            return None;
        };
        let mut span = None;
        let mut table: Option<&DeTable> = Some(doc);
        let mut array: Option<&[toml::Spanned<DeValue>]> = None;
        for seg in &at.0 {
            let value = match seg {
                Seg::Key(k) => {
                    let Some((key, value)) = table.and_then(|t| t.get_key_value(k.as_str())) else {
                        break;
                    };
                    span = Some(key.span());
                    value
                }
                Seg::Index(i) => {
                    let Some(item) = array.and_then(|a| a.get(*i)) else {
                        break;
                    };
                    span = Some(item.span());
                    item
                }
            };
            table = value.get_ref().as_table();
            array = value.get_ref().as_array().map(|a| &a[..]);
        }
        span
    }

    /// Span of the value at `at` (an entry's field).
    fn value_span(&self, at: &At) -> Option<Range<usize>> {
        let (Tree::Toml(doc), [Seg::Key(kind), Seg::Index(i), Seg::Key(key)]) = (&self.tree, &at.0[..]) else {
            return None;
        };
        let entry = doc
            .get(kind.as_str())?
            .get_ref()
            .as_array()?
            .get(*i)?
            .get_ref()
            .as_table()?;
        entry.get(key.as_str()).map(|v| v.span())
    }

    fn entry_label(&self, kind: &str, index: usize) -> String {
        let field = |k: &str| self.tree.item_str(kind, index, k);
        let n = index + 1;
        if kind == "joint" && field("name").is_none() {
            let a = field("a").unwrap_or_else(|| "world".into());
            return match (field("type"), field("b")) {
                (Some(t), Some(b)) => format!("joint #{n} ({t} '{a}' to '{b}')"),
                _ => format!("joint #{n}"),
            };
        }
        match (field("name"), field("object"), field("a"), field("b")) {
            (Some(name), ..) => format!("{kind} '{name}'"),
            (None, Some(object), ..) => format!("{kind} #{n} (object '{object}')"),
            (None, None, Some(a), Some(b)) => format!("{kind} #{n} ('{a}' to '{b}')"),
            _ => match self.tree.item_strs(kind, index, "objects").as_deref() {
                Some([a, b]) => format!("{kind} #{n} ('{a}' and '{b}')"),
                _ => format!("{kind} #{n}"),
            },
        }
    }

    fn describe(&self, at: &At) -> String {
        let mut out = String::new();
        let mut rest = &at.0[..];
        if let [Seg::Key(kind), Seg::Index(i), tail @ ..] = &at.0[..] {
            if ENTRY_KINDS.contains(&kind.as_str()) {
                out = self.entry_label(kind, *i);
                rest = tail;
                if !rest.is_empty() {
                    out.push(' ');
                }
            }
        }
        for (j, seg) in rest.iter().enumerate() {
            match seg {
                Seg::Key(k) => {
                    if j > 0 {
                        out.push('.');
                    }
                    out.push_str(k);
                }
                Seg::Index(i) => {
                    let _ = write!(out, "[{i}]");
                }
            }
        }
        out
    }

    /// Whether the entry at `at` (`[kind, index]`) gives the field `key`.
    fn gives(&self, at: &At, key: &str) -> bool {
        match &at.0[..] {
            [Seg::Key(kind), Seg::Index(i), ..] => self.tree.item_has(kind, *i, key),
            _ => false,
        }
    }

    /// An error at `at`; for "unknown field `x`" the path names the table holding `x`.
    fn err(&self, at: &At, message: impl Into<String>) -> SceneError {
        let message = message.into();
        let (line, column) = self.span_of(at).map(|s| line_col(self.text, s.start)).unzip();
        let mut shown = at.clone();
        if let (Some(Seg::Key(last)), Some(unknown)) = (
            shown.0.last(),
            message
                .strip_prefix("unknown field `")
                .and_then(|m| m.split('`').next()),
        ) {
            if last == unknown {
                shown.0.pop();
            }
        }
        SceneError {
            file: self.file.to_string(),
            line,
            column,
            path: self.describe(&shown),
            message,
        }
    }

    /// A deserialisation error of the TOML document, located through its span.
    fn toml_error(&self, e: &toml::de::Error) -> SceneError {
        let mut path = Vec::new();
        let mut line_column = None;
        if let Some(span) = e.span() {
            line_column = Some(line_col(self.text, span.start));
            if let (Tree::Toml(doc), false) = (&self.tree, self.root_span == Some(span.clone())) {
                if !locate_in_table(doc, span.start, &mut path) {
                    path.clear();
                }
            }
        }
        let mut message = e.message().trim_end().to_string();
        if let [Seg::Key(kind), Seg::Index(i)] = &path[..] {
            if kind == "joint" {
                if let Some((key, m)) = self.joint_culprit(*i, &message) {
                    // At the key, or at the value of an unknown `type`.
                    let at = At(vec![Seg::Key("joint".into()), Seg::Index(*i), Seg::Key(key.clone())]);
                    let span = match key.as_str() {
                        "type" if m.starts_with("unknown variant") => self.value_span(&at),
                        _ => self.span_of(&at),
                    };
                    line_column = span.map(|s| line_col(self.text, s.start));
                    path.push(Seg::Key(key));
                    message = m;
                }
            }
        }
        let at = At(path);
        let mut err = self.err(&at, message);
        if let Some((line, column)) = line_column {
            err.line = Some(line);
            err.column = Some(column);
        }
        err
    }

    /// The field of `[[joint]]` `index` that a deserialisation error is about, and a message
    /// naming it. A joint's type and fields are a flattened, internally tagged `JointKind`,
    /// deserialised from a buffer that has lost the fields' places: unknown and missing fields
    /// are named in the message; any other error is traced to the field whose removal changes
    /// it (the entry is deserialised again without each field in turn).
    fn joint_culprit(&self, index: usize, message: &str) -> Option<(String, String)> {
        let type_name = self.tree.item_str("joint", index, "type");
        let ticked =
            |m: &str, prefix: &str| -> Option<String> { m.strip_prefix(prefix)?.split('`').next().map(str::to_string) };
        let fields = |t: &str| JointKind::fields_of(t).unwrap_or_default();
        let list = |v: &[String]| v.iter().map(|f| format!("`{f}`")).collect::<Vec<_>>().join(", ");
        if let Some(field) = ticked(message, "unknown field `") {
            let t = type_name.unwrap_or_default();
            let mut takes = fields(&t);
            let driven = takes.iter().any(|f| f.starts_with("target_"));
            takes.extend(["stiffness", "tolerance_m", "tolerance_deg"].map(String::from));
            if driven {
                takes.push("target_schedule".into());
            }
            let elsewhere = JointKind::type_names().iter().any(|o| fields(o).contains(&field));
            let m = if elsewhere {
                format!("`{field}` does not apply to a {t} joint, which takes {}", list(&takes))
            } else {
                format!("unknown field `{field}`, expected one of {}", list(&takes))
            };
            return Some((field, m));
        }
        if message.starts_with("unknown variant `") {
            return Some(("type".into(), message.to_string()));
        }
        if let Some(field) = ticked(message, "missing field `") {
            if field == "type" {
                return None;
            }
            let t = type_name.unwrap_or_default();
            let m = format!("a {t} joint needs `{field}` (it takes {})", list(&fields(&t)));
            return Some(("type".into(), m));
        }
        // Deserialise the entry again without each of its fields.
        let doc: toml::Table = toml::from_str(self.text).ok()?;
        let entry = doc.get("joint")?.as_array()?.get(index)?.as_table()?.clone();
        let fails_alike = |t: toml::Table| match toml::Value::Table(t).try_into::<rigid::JointEntry>() {
            Ok(_) => false,
            Err(e) => e.message().trim_end() == message,
        };
        let key = entry.keys().find(|k| {
            let mut without = entry.clone();
            without.remove(*k);
            !fails_alike(without)
        })?;
        Some((key.clone(), format!("`{key}`: {message}")))
    }

    /// A library error raised while building the entry at `at`.
    fn stark(&self, at: &At, e: StarkError) -> SceneError {
        self.err(at, e.to_string())
    }
}

fn json_error(file: &str, e: &serde_json::Error) -> SceneError {
    let text = e.to_string();
    let message = text
        .rsplit_once(" at line ")
        .map_or(text.as_str(), |(m, _)| m)
        .to_string();
    SceneError {
        file: file.to_string(),
        line: Some(e.line()),
        column: Some(e.column()),
        path: String::new(),
        message,
    }
}

// ------------------------------------------------------------------------------------------
// Materials: a preset plus overrides merged in TOML-value space
// ------------------------------------------------------------------------------------------

trait MaterialPresets: Serialize + DeserializeOwned {
    const KIND: &'static str;
    fn presets() -> Vec<(&'static str, Self)>;
}

impl MaterialPresets for SurfaceMaterial {
    const KIND: &'static str = "surface";
    fn presets() -> Vec<(&'static str, Self)> {
        vec![
            ("cotton_fabric", SurfaceMaterial::cotton_fabric()),
            ("default", SurfaceMaterial::default()),
        ]
    }
}

impl MaterialPresets for VolumeMaterial {
    const KIND: &'static str = "volume";
    fn presets() -> Vec<(&'static str, Self)> {
        vec![
            ("soft_rubber", VolumeMaterial::soft_rubber()),
            ("default", VolumeMaterial::default()),
        ]
    }
}

impl MaterialPresets for LineMaterial {
    const KIND: &'static str = "line";
    fn presets() -> Vec<(&'static str, Self)> {
        vec![
            ("elastic_rubber_band", LineMaterial::elastic_rubber_band()),
            ("default", LineMaterial::default()),
        ]
    }
}

/// A preset value that is a one-key table (an externally tagged enum such as `bending`) is
/// replaced, not merged, by a one-key override naming another variant.
fn is_variant_switch(base: &toml::Table, over: &toml::Table) -> bool {
    base.len() == 1 && over.len() == 1 && base.keys().next() != over.keys().next()
}

/// Merge `over` into `base`: tables key by key, anything else replaced.
fn merge(base: &mut toml::Value, over: &toml::Value) {
    match (base, over) {
        (toml::Value::Table(b), toml::Value::Table(o)) if !is_variant_switch(b, o) => {
            for (k, v) in o {
                match b.get_mut(k) {
                    Some(bv) => merge(bv, v),
                    None => {
                        b.insert(k.clone(), v.clone());
                    }
                }
            }
        }
        (b, o) => *b = o.clone(),
    }
}

/// `value` nested under `path`.
fn nest(path: &[String], value: &toml::Value) -> toml::Value {
    path.iter().rev().fold(value.clone(), |v, k| {
        let mut t = toml::Table::new();
        t.insert(k.clone(), v);
        toml::Value::Table(t)
    })
}

fn value_at<'v>(base: &'v toml::Value, path: &[String]) -> Option<&'v toml::Value> {
    path.iter().try_fold(base, |v, k| v.as_table()?.get(k))
}

/// The first override key that fails on its own (the innermost one where possible), with the
/// deserialisation error it causes.
fn find_culprit<M: DeserializeOwned>(
    base: &toml::Value,
    over: &toml::Table,
    prefix: &mut Vec<String>,
) -> Option<(Vec<String>, String)> {
    for (k, v) in over {
        prefix.push(k.clone());
        let mut merged = base.clone();
        merge(&mut merged, &nest(prefix, v));
        if let Err(e) = merged.try_into::<M>() {
            if let (toml::Value::Table(t), Some(toml::Value::Table(b))) = (v, value_at(base, prefix)) {
                if !is_variant_switch(b, t) {
                    if let Some(found) = find_culprit::<M>(base, t, prefix) {
                        return Some(found);
                    }
                }
            }
            return Some((prefix.clone(), e.message().trim_end().to_string()));
        }
        prefix.pop();
    }
    None
}

/// The path of the first key called `key` in `over`.
fn find_key(over: &toml::Table, key: &str) -> Option<Vec<String>> {
    for (k, v) in over {
        if k == key {
            return Some(vec![k.clone()]);
        }
        if let toml::Value::Table(t) = v {
            if let Some(mut p) = find_key(t, key) {
                p.insert(0, k.clone());
                return Some(p);
            }
        }
    }
    None
}

/// The material of the entry at `at` from its `material` value.
fn resolve_material<M: MaterialPresets>(ctx: &Ctx, at: &At, value: &toml::Value) -> std::result::Result<M, SceneError> {
    let at = at.key("material");
    let (preset_name, preset_at, overrides) = match value {
        toml::Value::String(s) => (s.as_str(), at.clone(), None),
        toml::Value::Table(t) => {
            let mut overrides = t.clone();
            let name = match overrides.remove("preset") {
                None => "default",
                Some(toml::Value::String(_)) => t["preset"].as_str().unwrap_or("default"),
                Some(other) => {
                    return Err(ctx.err(
                        &at.key("preset"),
                        format!("invalid type: {}, expected a preset name", other.type_str()),
                    ))
                }
            };
            (name, at.key("preset"), Some(overrides))
        }
        other => {
            return Err(ctx.err(
                &at,
                format!(
                    "invalid type: {}, expected a preset name or a table {{ preset = \"...\", ... }}",
                    other.type_str()
                ),
            ))
        }
    };
    let presets = M::presets();
    let Some((_, preset)) = presets.into_iter().find(|(n, _)| *n == preset_name) else {
        let names: Vec<_> = M::presets().iter().map(|(n, _)| *n).collect();
        return Err(ctx.err(
            &preset_at,
            format!(
                "unknown {} material preset '{preset_name}', expected one of {}",
                M::KIND,
                names.join(", ")
            ),
        ));
    };
    let Some(overrides) = overrides else {
        return Ok(preset);
    };
    let base = toml::Value::try_from(&preset).map_err(|e| ctx.err(&at, format!("cannot serialise the preset: {e}")))?;
    let mut merged = base.clone();
    merge(&mut merged, &toml::Value::Table(overrides.clone()));
    merged
        .try_into::<M>()
        .map_err(|e| match find_culprit::<M>(&base, &overrides, &mut Vec::new()) {
            Some((path, message)) => ctx.err(&at.keys(&path), message),
            None => ctx.err(&at, e.message().trim_end()),
        })
}

/// Locate a library error raised by `add_surface`/`add_volume`/`add_line`: a parameter in the
/// material, anything else in the geometry.
fn object_error(ctx: &Ctx, at: &At, material: &toml::Value, geometry_key: &str, e: StarkError) -> SceneError {
    match &e {
        StarkError::InvalidParameter { field, .. } => {
            let path = material.as_table().and_then(|t| find_key(t, field)).unwrap_or_default();
            ctx.stark(&at.key("material").keys(&path), e)
        }
        _ => ctx.stark(&at.key(geometry_key), e),
    }
}

// ------------------------------------------------------------------------------------------
// Geometry
// ------------------------------------------------------------------------------------------

/// Which geometry an entry gives, checking that it gives exactly one. `generators` are the
/// entry's generator keys and whether each is given, `mesh` whether a mesh file is given (`None`
/// if the entry takes none), and `elements` the key of the inline element list and whether it is
/// given.
fn geometry_key(
    ctx: &Ctx,
    at: &At,
    generators: &[(&'static str, bool)],
    mesh: Option<bool>,
    vertices: bool,
    elements: (&'static str, bool),
) -> std::result::Result<&'static str, SceneError> {
    let mut given: Vec<&'static str> = generators.iter().filter(|g| g.1).map(|g| g.0).collect();
    if mesh == Some(true) {
        given.push("mesh");
    }
    if vertices {
        given.push("vertices_m");
    }
    let (elements_key, elements) = elements;
    if vertices != elements {
        let (has, missing) = if vertices {
            ("vertices_m", elements_key)
        } else {
            (elements_key, "vertices_m")
        };
        return Err(ctx.err(
            &at.key(has),
            format!("`{has}` needs `{missing}` (inline geometry gives both)"),
        ));
    }
    let mut keys: Vec<String> = generators.iter().map(|g| format!("`{}`", g.0)).collect();
    if mesh.is_some() {
        keys.push("`mesh`".into());
    }
    let last = format!("`vertices_m` + `{elements_key}`");
    let options = format!("{} or {last}", keys.join(", "));
    match given[..] {
        [one] => Ok(one),
        [] => Err(ctx.err(at, format!("no geometry: give one of {options}"))),
        _ => Err(ctx.err(
            &at.key(given[1]),
            format!("more than one geometry ({}): give one of {options}", given.join(", ")),
        )),
    }
}

/// Apply `scale`, then `rotate_deg`, then `translate_m`.
fn place(
    ctx: &Ctx,
    at: &At,
    vertices: &mut [Vector3<f64>],
    scale: Option<f64>,
    rotate: Option<&Rotate>,
    translate: Option<[f64; 3]>,
) -> std::result::Result<(), SceneError> {
    if let Some(s) = scale {
        if !(s > 0.0 && s.is_finite()) {
            return Err(ctx.err(&at.key("scale"), format!("scale = {s} must be positive and finite")));
        }
        mesh::scale(vertices, s);
    }
    if let Some(r) = rotate {
        let axis = Vector3::from(r.axis);
        if !(r.angle.is_finite() && axis.iter().all(|a| a.is_finite()) && axis.norm() > 0.0) {
            return Err(ctx.err(
                &at.key("rotate_deg"),
                format!(
                    "rotation by {} deg about {:?} needs a finite angle and a non-zero axis",
                    r.angle, r.axis
                ),
            ));
        }
        mesh::rotate_deg(vertices, r.angle, &axis);
    }
    if let Some(t) = translate {
        if !t.iter().all(|c| c.is_finite()) {
            return Err(ctx.err(&at.key("translate_m"), "translate_m must be finite"));
        }
        mesh::translate(vertices, &Vector3::from(t));
    }
    Ok(())
}

fn check_grid(
    ctx: &Ctx,
    at: &At,
    size: &[f64],
    counts: &[usize],
    counts_key: &str,
) -> std::result::Result<(), SceneError> {
    if !size.iter().all(|s| *s > 0.0 && s.is_finite()) {
        return Err(ctx.err(
            &at.key("size_m"),
            format!("size_m = {size:?} must be positive and finite"),
        ));
    }
    if counts.contains(&0) {
        return Err(ctx.err(
            &at.key(counts_key),
            format!("{counts_key} = {counts:?} must be positive"),
        ));
    }
    Ok(())
}

fn mesh_path(base_dir: &Path, file: &str) -> std::path::PathBuf {
    base_dir.join(file)
}

/// The shape of an entry's inline mesh (`vertices_m` and `triangles`, checked present).
fn inline_mesh(vertices_m: &Option<Vec<[f64; 3]>>, triangles: &Option<Vec<[usize; 3]>>, scale: Vector3<f64>) -> Shape {
    Shape::Mesh {
        vertices_m: vertices_m
            .as_ref()
            .expect("checked")
            .iter()
            .map(|v| Vector3::from(*v))
            .collect(),
        triangles: triangles.clone().expect("checked"),
        scale,
    }
}

fn build_surface(
    sim: &mut Simulation,
    ctx: &Ctx,
    base_dir: &Path,
    at: &At,
    e: &SurfaceEntry,
) -> std::result::Result<SurfaceHandle, SceneError> {
    let material: SurfaceMaterial = resolve_material(ctx, at, &e.material)?;
    let key = geometry_key(
        ctx,
        at,
        &[("grid", e.grid.is_some()), ("cup", e.cup.is_some())],
        Some(e.mesh.is_some()),
        e.vertices_m.is_some(),
        ("elements", e.elements.is_some()),
    )?;
    let (mut vertices, triangles) = match key {
        "cup" => {
            let m = meshes::cup_mesh(&e.cup.as_ref().expect("checked").shape()).map_err(|err| match &err {
                StarkError::InvalidParameter { field, .. } => {
                    let field = field.to_string();
                    ctx.stark(&at.keys(&["cup", &field]), err)
                }
                _ => ctx.stark(&at.key("cup"), err),
            })?;
            (m.vertices, m.elements)
        }
        "grid" => {
            let g = e.grid.as_ref().expect("checked");
            check_grid(ctx, &at.key("grid"), &g.size_m, &g.quads, "quads")?;
            let m = meshes::triangle_grid([0.0, 0.0], g.size_m, g.quads, 0.0);
            (m.vertices, m.elements)
        }
        "mesh" => {
            let path = mesh_path(base_dir, e.mesh.as_deref().expect("checked"));
            let m = load_triangle_mesh(&path).map_err(|err| ctx.err(&at.key("mesh"), err.to_string()))?;
            (m.vertices, m.elements)
        }
        _ => (
            e.vertices_m
                .as_ref()
                .expect("checked")
                .iter()
                .map(|v| Vector3::from(*v))
                .collect(),
            e.elements.clone().expect("checked"),
        ),
    };
    place(ctx, at, &mut vertices, e.scale, e.rotate_deg.as_ref(), e.translate_m)?;
    sim.add_surface(&e.name, &vertices, &triangles, &material)
        .map_err(|err| object_error(ctx, at, &e.material, key, err))
}

fn build_volume(
    sim: &mut Simulation,
    ctx: &Ctx,
    base_dir: &Path,
    at: &At,
    e: &VolumeEntry,
) -> std::result::Result<VolumeHandle, SceneError> {
    let material: VolumeMaterial = resolve_material(ctx, at, &e.material)?;
    let key = geometry_key(
        ctx,
        at,
        &[("grid", e.grid.is_some())],
        Some(e.mesh.is_some()),
        e.vertices_m.is_some(),
        ("elements", e.elements.is_some()),
    )?;
    let (mut vertices, tets) = match key {
        "grid" => {
            let g = e.grid.as_ref().expect("checked");
            check_grid(ctx, &at.key("grid"), &g.size_m, &g.cells, "cells")?;
            let m = meshes::tet_grid(Vector3::zeros(), Vector3::from(g.size_m), g.cells);
            (m.vertices, m.elements)
        }
        "mesh" => {
            let path = mesh_path(base_dir, e.mesh.as_deref().expect("checked"));
            let m = load_tet_mesh(&path).map_err(|err| {
                ctx.err(
                    &at.key("mesh"),
                    format!("{err} (a volume needs a tetrahedral mesh: .vtk or .msh)"),
                )
            })?;
            (m.vertices, m.elements)
        }
        _ => (
            e.vertices_m
                .as_ref()
                .expect("checked")
                .iter()
                .map(|v| Vector3::from(*v))
                .collect(),
            e.elements.clone().expect("checked"),
        ),
    };
    place(ctx, at, &mut vertices, e.scale, e.rotate_deg.as_ref(), e.translate_m)?;
    sim.add_volume(&e.name, &vertices, &tets, &material)
        .map_err(|err| object_error(ctx, at, &e.material, key, err))
}

fn build_line(sim: &mut Simulation, ctx: &Ctx, at: &At, e: &LineEntry) -> std::result::Result<LineHandle, SceneError> {
    let material: LineMaterial = resolve_material(ctx, at, &e.material)?;
    let key = geometry_key(
        ctx,
        at,
        &[("segments", e.segments.is_some())],
        None,
        e.vertices_m.is_some(),
        ("elements", e.elements.is_some()),
    )?;
    let (mut vertices, segments) = match key {
        "segments" => {
            let s = e.segments.as_ref().expect("checked");
            let ends = s.begin_m.iter().chain(&s.end_m);
            if !ends.clone().all(|c| c.is_finite()) {
                return Err(ctx.err(&at.key("segments"), "begin_m and end_m must be finite"));
            }
            if s.count == 0 {
                return Err(ctx.err(&at.keys(&["segments", "count"]), "count = 0 must be positive"));
            }
            let m = meshes::segment_line(Vector3::from(s.begin_m), Vector3::from(s.end_m), s.count);
            (m.vertices, m.elements)
        }
        _ => (
            e.vertices_m
                .as_ref()
                .expect("checked")
                .iter()
                .map(|v| Vector3::from(*v))
                .collect(),
            e.elements.clone().expect("checked"),
        ),
    };
    place(ctx, at, &mut vertices, e.scale, e.rotate_deg.as_ref(), e.translate_m)?;
    sim.add_line(&e.name, &vertices, &segments, &material)
        .map_err(|err| object_error(ctx, at, &e.material, key, err))
}

/// Prescribed-position stiffness of an obstacle that gives none, N/m.
const DEFAULT_OBSTACLE_STIFFNESS: f64 = 1e6;

/// A [`ShapeError`] of the geometry given under `key` (`box`, `sphere`, ..., `mesh`,
/// `vertices_m`) located at its field: `box.size_m`, `sphere.radius_m`, `mesh`,
/// `triangles[i]`, ...
fn shape_error(ctx: &Ctx, at: &At, key: &str, e: ShapeError) -> SceneError {
    let field = e.field.split('.').next().unwrap_or(e.field);
    let at = match field {
        "mass_kg" | "density_kg_m3" | "scale" | "vertices_m" => at.key(field),
        "triangles" => match e.index {
            Some(i) => at.key("triangles").index(i),
            None => at.key("triangles"),
        },
        "path" => at.key("mesh"),
        "surface" => at.key(key),
        _ => at.keys(&[key, field]),
    };
    ctx.err(&at, e.message)
}

fn check_positive(ctx: &Ctx, at: &At, key: &str, value: f64, unit: &str) -> std::result::Result<(), SceneError> {
    if value > 0.0 && value.is_finite() {
        Ok(())
    } else {
        Err(ctx.err(
            &at.key(key),
            format!("{key} = {value} must be positive and finite ({unit})"),
        ))
    }
}

fn build_obstacle(
    sim: &mut Simulation,
    ctx: &Ctx,
    base_dir: &Path,
    at: &At,
    e: &ObstacleEntry,
) -> std::result::Result<ObstacleHandle, SceneError> {
    let key = geometry_key(
        ctx,
        at,
        &[
            ("sphere", e.sphere.is_some()),
            ("box", e.box_.is_some()),
            ("cylinder", e.cylinder.is_some()),
            ("grid", e.grid.is_some()),
        ],
        Some(e.mesh.is_some()),
        e.vertices_m.is_some(),
        ("triangles", e.triangles.is_some()),
    )?;
    let shape = match key {
        "sphere" => {
            let g = e.sphere.as_ref().expect("checked");
            Some(Shape::Sphere {
                radius_m: g.radius_m,
                subdivisions: g.subdivisions,
            })
        }
        "box" => Some(Shape::Box {
            size_m: Vector3::from(e.box_.as_ref().expect("checked").size_m),
        }),
        "cylinder" => {
            let g = e.cylinder.as_ref().expect("checked");
            Some(Shape::Cylinder {
                radius_m: g.radius_m,
                height_m: g.height_m,
                slices: g.slices,
                stacks: g.stacks,
            })
        }
        "mesh" => Some(Shape::mesh_file(mesh_path(
            base_dir,
            e.mesh.as_deref().expect("checked"),
        ))),
        "vertices_m" => Some(inline_mesh(&e.vertices_m, &e.triangles, Vector3::repeat(1.0))),
        _ => None,
    };
    let (mut vertices, triangles) = match shape {
        Some(shape) => {
            let m = shape.surface_mesh().map_err(|err| shape_error(ctx, at, key, err))?;
            (m.vertices, m.elements)
        }
        None => {
            let g = e.grid.as_ref().expect("checked");
            check_grid(ctx, &at.key("grid"), &g.size_m, &g.quads, "quads")?;
            let m = meshes::triangle_grid([0.0, 0.0], g.size_m, g.quads, 0.0);
            (m.vertices, m.elements)
        }
    };
    place(ctx, at, &mut vertices, e.scale, e.rotate_deg.as_ref(), e.translate_m)?;
    let Some(thickness) = e.contact_thickness_m.or(sim.settings.contact.default_thickness_m) else {
        return Err(ctx.err(
            at,
            format!(
                "obstacle '{}' has no contact thickness: give `contact_thickness_m` or set \
                 `settings.contact.default_thickness_m`",
                e.name
            ),
        ));
    };
    check_positive(ctx, at, "contact_thickness_m", thickness, "m")?;
    let stiffness = e.stiffness.unwrap_or(DEFAULT_OBSTACLE_STIFFNESS);
    check_positive(ctx, at, "stiffness", stiffness, "N/m")?;
    if let Some(motion) = &e.motion {
        motion
            .validate()
            .map_err(|(field, message)| ctx.err(&at.keys(&["motion", field]), message))?;
    }
    let handle = sim
        .add_prescribed_surface(&e.name, &vertices, &triangles, thickness, stiffness)
        .map_err(|err| ctx.stark(&at.key(key), err))?;
    if let Some(motion) = &e.motion {
        let m = motion.clone();
        sim.add_time_event(motion.start_s, f64::INFINITY, move |sim, t| {
            m.apply(sim, handle.prescribed, t)
        });
    }
    Ok(handle)
}

// ------------------------------------------------------------------------------------------
// Boundary conditions, attachments, events
// ------------------------------------------------------------------------------------------

fn find_object<'o>(
    ctx: &Ctx,
    at: &At,
    objects: &'o [(String, SceneObject)],
    name: &str,
) -> std::result::Result<&'o SceneObject, SceneError> {
    objects.iter().find(|(n, _)| n == name).map(|(_, o)| o).ok_or_else(|| {
        let names: Vec<_> = objects.iter().map(|(n, _)| n.as_str()).collect();
        ctx.err(
            at,
            format!(
                "unknown object '{name}', expected one of {}",
                if names.is_empty() {
                    "(no objects defined)".to_string()
                } else {
                    names.join(", ")
                }
            ),
        )
    })
}

/// Locate an error of a parameter group: a named parameter at its key, anything else at
/// `fallback`.
fn param_error(ctx: &Ctx, at: &At, fallback: &str, e: StarkError) -> SceneError {
    match &e {
        StarkError::InvalidParameter { field, .. } => ctx.stark(&at.key(field), e),
        _ => ctx.stark(&at.key(fallback), e),
    }
}

fn check_box(ctx: &Ctx, at: &At, b: &BoxSelection) -> std::result::Result<(), SceneError> {
    if !b.center_m.iter().all(|c| c.is_finite()) {
        return Err(ctx.err(&at.key("center_m"), "center_m must be finite"));
    }
    if !b.size_m.iter().all(|s| *s >= 0.0 && s.is_finite()) {
        return Err(ctx.err(
            &at.key("size_m"),
            format!("size_m = {:?} must be non-negative and finite", b.size_m),
        ));
    }
    Ok(())
}

fn build_prescribed(
    sim: &mut Simulation,
    ctx: &Ctx,
    at: &At,
    objects: &[(String, SceneObject)],
    e: &PrescribedEntry,
) -> std::result::Result<ScenePrescribed, SceneError> {
    let object = find_object(ctx, &at.key("object"), objects, &e.object)?;
    if let SceneObject::Obstacle(_) = object {
        return Err(ctx.err(
            &at.key("object"),
            format!(
                "'{}' is an obstacle, whose nodes are prescribed already (move it with the obstacle's `motion`)",
                e.object
            ),
        ));
    }
    if let SceneObject::RigidBody(_) = object {
        return Err(ctx.err(
            &at.key("object"),
            format!(
                "'{}' is a rigid body: hold it with `fixed = true` in its entry (and move it with `motion` or `keyframes`)",
                e.object
            ),
        ));
    }
    let set = object.nodes();
    let defaults = PrescribedParams::default();
    let params = PrescribedParams {
        stiffness: e.stiffness.unwrap_or(defaults.stiffness),
        tolerance_m: e.tolerance_m.unwrap_or(defaults.tolerance_m),
    };
    params
        .validate(&e.object)
        .map_err(|err| param_error(ctx, at, "object", err))?;
    let mut given = Vec::new();
    if e.inside_box.is_some() {
        given.push("inside_box");
    }
    if e.outside_box.is_some() {
        given.push("outside_box");
    }
    if e.nodes.is_some() {
        given.push("nodes");
    }
    if e.all.is_some() {
        given.push("all");
    }
    let options = "`inside_box`, `outside_box`, `nodes` or `all = true`";
    let key = match given[..] {
        [one] => one,
        [] => return Err(ctx.err(at, format!("no node selection: give one of {options}"))),
        _ => {
            return Err(ctx.err(
                &at.key(given[1]),
                format!(
                    "more than one node selection ({}): give one of {options}",
                    given.join(", ")
                ),
            ))
        }
    };
    let label = e.object.as_str();
    let located = |err: StarkError| ctx.stark(&at.key(key), err);
    let (handle, n) = match key {
        "inside_box" | "outside_box" => {
            let b = e.inside_box.as_ref().or(e.outside_box.as_ref()).expect("checked");
            check_box(ctx, &at.key(key), b)?;
            let (center, size) = (Vector3::from(b.center_m), Vector3::from(b.size_m));
            let (h, n) = sim
                .deformables
                .prescribed
                .add_in_box(&sim.nodes, set, label, center, size, key == "inside_box", params)
                .map_err(located)?;
            if n == 0 {
                let where_ = if key == "inside_box" { "inside" } else { "outside" };
                return Err(ctx.err(
                    &at.key(key),
                    format!(
                        "no node of '{label}' lies {where_} the box at {:?} of size {:?}",
                        b.center_m, b.size_m
                    ),
                ));
            }
            (h, n)
        }
        "nodes" => {
            let nodes = e.nodes.as_ref().expect("checked");
            if nodes.is_empty() {
                return Err(ctx.err(&at.key("nodes"), "the node list is empty"));
            }
            let h = sim
                .deformables
                .prescribed
                .add(&sim.nodes, set, label, nodes, params)
                .map_err(located)?;
            (h, nodes.len())
        }
        _ => {
            if e.all != Some(true) {
                return Err(ctx.err(
                    &at.key("all"),
                    "`all = false` selects nothing: give one of `inside_box`, `outside_box`, `nodes` or `all = true`",
                ));
            }
            let nodes: Vec<usize> = (0..set.len as usize).collect();
            let h = sim
                .deformables
                .prescribed
                .add(&sim.nodes, set, label, &nodes, params)
                .map_err(located)?;
            (h, nodes.len())
        }
    };
    if let Some(motion) = &e.motion {
        motion
            .validate()
            .map_err(|(field, message)| ctx.err(&at.keys(&["motion", field]), message))?;
        let m = motion.clone();
        sim.add_time_event(motion.start_s, f64::INFINITY, move |sim, t| m.apply(sim, handle, t));
    }
    Ok(ScenePrescribed {
        object: e.object.clone(),
        handle,
        nodes: n,
        motion: e.motion.clone(),
    })
}

fn build_attachment(
    sim: &mut Simulation,
    ctx: &Ctx,
    at: &At,
    objects: &[(String, SceneObject)],
    e: &AttachmentEntry,
) -> std::result::Result<(String, AttachmentHandle), SceneError> {
    let a = find_object(ctx, &at.key("a"), objects, &e.a)?.nodes();
    let b = find_object(ctx, &at.key("b"), objects, &e.b)?.nodes();
    let label = e.name.clone().unwrap_or_else(|| format!("{}-{}", e.a, e.b));
    let defaults = AttachmentParams::default();
    let params = AttachmentParams {
        stiffness: e.stiffness.unwrap_or(defaults.stiffness),
        tolerance_m: e.tolerance_m.unwrap_or(defaults.tolerance_m),
    };
    params.validate(&label).map_err(|err| param_error(ctx, at, "a", err))?;
    let attachments = &mut sim.deformables.attachments;
    let handle = match (&e.nodes_a, &e.nodes_b, &e.triangles_b, &e.barycentric_b, e.within_m) {
        (Some(pa), Some(pb), None, None, None) => attachments
            .add_point_point(&label, a, pa, b, pb, params)
            .map_err(|err| ctx.stark(&at.key("nodes_b"), err))?,
        (Some(pa), None, Some(tb), Some(wb), None) => attachments
            .add_point_triangle(&label, a, pa, b, tb, wb, params)
            .map_err(|err| ctx.stark(&at.key("triangles_b"), err))?,
        (None, None, None, None, Some(d)) => {
            if !(d >= 0.0 && d.is_finite()) || e.a == e.b {
                return Err(ctx.err(
                    &at.key("within_m"),
                    format!("within_m = {d} needs a non-negative distance and two different objects"),
                ));
            }
            let xa = &sim.nodes.x[a.range()];
            let xb = &sim.nodes.x[b.range()];
            let mut pa = Vec::new();
            let mut pb = Vec::new();
            for (i, p) in xa.iter().enumerate() {
                let nearest = xb
                    .iter()
                    .enumerate()
                    .map(|(j, q)| (j, (p - q).norm()))
                    .min_by(|x, y| x.1.total_cmp(&y.1));
                if let Some((j, dist)) = nearest {
                    if dist <= d {
                        pa.push(i);
                        pb.push(j);
                    }
                }
            }
            if pa.is_empty() {
                return Err(ctx.err(
                    &at.key("within_m"),
                    format!("no node of '{}' lies within {d} m of a node of '{}'", e.a, e.b),
                ));
            }
            attachments
                .add_point_point(&label, a, &pa, b, &pb, params)
                .map_err(|err| ctx.stark(&at.key("within_m"), err))?
        }
        _ => {
            return Err(ctx.err(
                at,
                "give the attached nodes as `nodes_a` + `nodes_b` (point–point), `nodes_a` + \
                 `triangles_b` + `barycentric_b` (point–triangle) or `within_m` (every node of `a` \
                 near a node of `b`)",
            ))
        }
    };
    Ok((label, handle))
}

/// The contact objects of the two names of a `[[friction]]` or `[[disable_collision]]` entry.
fn contact_pair(
    ctx: &Ctx,
    at: &At,
    objects: &[(String, SceneObject)],
    names: &[String; 2],
) -> std::result::Result<[ContactHandle; 2], SceneError> {
    Ok([
        contact_of(ctx, &at.key("objects").index(0), objects, &names[0])?,
        contact_of(ctx, &at.key("objects").index(1), objects, &names[1])?,
    ])
}

/// The contact object of the object `name` (located at `at` in errors).
fn contact_of(
    ctx: &Ctx,
    at: &At,
    objects: &[(String, SceneObject)],
    name: &str,
) -> std::result::Result<ContactHandle, SceneError> {
    let object = find_object(ctx, at, objects, name)?;
    object.contact().ok_or_else(|| {
        let with: Vec<_> = objects
            .iter()
            .filter(|(_, o)| o.contact().is_some())
            .map(|(n, _)| n.as_str())
            .collect();
        let why = if let SceneObject::RigidBody(_) = object {
            "rigid body '{name}' takes no part in contact: it has no contact thickness or `contact = false` \
             (give it `contact_thickness_m` or set `settings.contact.default_thickness_m`)"
        } else {
            "object '{name}' takes no part in contact: it has no contact thickness (set `contact_thickness_m` \
             in its material or `settings.contact.default_thickness_m`)"
        };
        ctx.err(
            at,
            format!(
                "{}; objects with contact: {}",
                why.replace("{name}", name),
                if with.is_empty() {
                    "none".to_string()
                } else {
                    with.join(", ")
                }
            ),
        )
    })
}

fn add_friction(
    sim: &mut Simulation,
    ctx: &Ctx,
    at: &At,
    objects: &[(String, SceneObject)],
    e: &FrictionEntry,
) -> std::result::Result<(), SceneError> {
    let [a, b] = contact_pair(ctx, at, objects, &e.objects)?;
    if !(e.mu >= 0.0 && e.mu.is_finite()) {
        return Err(ctx.err(&at.key("mu"), format!("mu = {} must be non-negative and finite", e.mu)));
    }
    sim.contact
        .set_friction(a, b, e.mu)
        .map_err(|err| ctx.stark(&at.key("mu"), err))
}

fn add_disable_collision(
    sim: &mut Simulation,
    ctx: &Ctx,
    at: &At,
    objects: &[(String, SceneObject)],
    e: &DisableCollisionEntry,
) -> std::result::Result<(), SceneError> {
    let [a, b] = contact_pair(ctx, at, objects, &e.objects)?;
    sim.contact
        .disable_collision(a, b)
        .map_err(|err| ctx.stark(&at.key("objects"), err))
}

fn add_gravity_ramps(
    sim: &mut Simulation,
    ctx: &Ctx,
    ramps: &[GravityRampEntry],
) -> std::result::Result<(), SceneError> {
    let mut order: Vec<usize> = (0..ramps.len()).collect();
    order.sort_by(|&i, &j| ramps[i].start_s.total_cmp(&ramps[j].start_s));
    for i in order {
        let r = &ramps[i];
        let at = At::entry("gravity_ramp", i);
        if !(r.start_s.is_finite() && r.end_s.is_finite() && r.end_s > r.start_s) {
            return Err(ctx.err(
                &at.key("end_s"),
                format!(
                    "the ramp from {} s to {} s needs finite times with end_s > start_s",
                    r.start_s, r.end_s
                ),
            ));
        }
        let from = Vector3::from(r.from_m_s2.unwrap_or(sim.settings.gravity_m_s2));
        let to = Vector3::from(r.to_m_s2);
        if !(from.iter().chain(to.iter()).all(|g| g.is_finite())) {
            return Err(ctx.err(&at.key("to_m_s2"), "gravity must be finite"));
        }
        let (start, end) = (r.start_s, r.end_s);
        sim.add_time_event(start, f64::INFINITY, move |sim, t| {
            let s = ((t - start) / (end - start)).clamp(0.0, 1.0);
            sim.set_gravity(from + (to - from) * s);
            Ok(())
        });
    }
    Ok(())
}

// ------------------------------------------------------------------------------------------
// Building the simulation
// ------------------------------------------------------------------------------------------

fn build(
    file: SceneFile,
    ctx: &Ctx,
    base_dir: &Path,
    configure: impl FnOnce(&mut Settings),
) -> std::result::Result<LoadedScene, SceneError> {
    if !(file.duration_s > 0.0 && file.duration_s.is_finite()) {
        return Err(ctx.err(
            &At::default().key("duration_s"),
            format!("duration_s = {} must be positive and finite", file.duration_s),
        ));
    }
    let mut settings = file.settings;
    if settings.name == Settings::default().name {
        let stem = Path::new(ctx.file)
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        if !stem.is_empty() {
            settings.name = stem;
        }
    }
    configure(&mut settings);
    let name = settings.name.clone();
    // `Settings::validate` does not check the contact settings; the scene does.
    let settings_error = |e: StarkError| {
        let at = At::default().key("settings");
        match &e {
            StarkError::InvalidParameter { object, field, .. } => {
                // `object` is "settings" or a sub-table such as "settings.contact".
                let keys: Vec<&str> = object
                    .strip_prefix("settings")
                    .unwrap_or("")
                    .split('.')
                    .chain(field.split('.'))
                    .filter(|k| !k.is_empty())
                    .collect();
                ctx.stark(&at.keys(&keys), e)
            }
            _ => ctx.stark(&at, e),
        }
    };
    settings.contact.validate().map_err(settings_error)?;
    let mut sim = Simulation::new(settings).map_err(settings_error)?;

    // Names are unique across surfaces, volumes and lines.
    let names = file
        .surface
        .iter()
        .map(|e| ("surface", &e.name))
        .chain(file.volume.iter().map(|e| ("volume", &e.name)))
        .chain(file.line.iter().map(|e| ("line", &e.name)))
        .chain(file.obstacle.iter().map(|e| ("obstacle", &e.name)))
        .chain(file.rigid_body.iter().map(|e| ("rigid_body", &e.name)));
    let mut seen: Vec<(&str, usize, &String)> = Vec::new();
    let mut counters = std::collections::HashMap::new();
    for (kind, name) in names {
        let i = counters.entry(kind).or_insert(0usize);
        let at = At::entry(kind, *i).key("name");
        if name.is_empty() {
            return Err(ctx.err(&at, "the object name is empty"));
        }
        if kind == "rigid_body" && name == "world" {
            return Err(ctx.err(&at, "'world' names the fixed world in joints: choose another name"));
        }
        if let Some((k, j, _)) = seen.iter().find(|(_, _, n)| *n == name) {
            return Err(ctx.err(
                &at,
                format!("duplicate object name '{name}' (already used by {k} #{})", j + 1),
            ));
        }
        seen.push((kind, *i, name));
        *i += 1;
    }

    let mut objects = Vec::new();
    for (i, e) in file.surface.iter().enumerate() {
        let h = build_surface(&mut sim, ctx, base_dir, &At::entry("surface", i), e)?;
        objects.push((e.name.clone(), SceneObject::Surface(h)));
    }
    for (i, e) in file.volume.iter().enumerate() {
        let h = build_volume(&mut sim, ctx, base_dir, &At::entry("volume", i), e)?;
        objects.push((e.name.clone(), SceneObject::Volume(h)));
    }
    for (i, e) in file.line.iter().enumerate() {
        let h = build_line(&mut sim, ctx, &At::entry("line", i), e)?;
        objects.push((e.name.clone(), SceneObject::Line(h)));
    }
    for (i, e) in file.obstacle.iter().enumerate() {
        let h = build_obstacle(&mut sim, ctx, base_dir, &At::entry("obstacle", i), e)?;
        objects.push((e.name.clone(), SceneObject::Obstacle(h)));
    }
    let mut joints = Vec::new();
    // Bodies with `spawn` are added during the run (after the friction entries are known).
    let spawned: Vec<(usize, &rigid::RigidBodyEntry)> = file
        .rigid_body
        .iter()
        .enumerate()
        .filter(|(_, e)| e.spawn.is_some())
        .collect();
    for &(i, e) in &spawned {
        let count = e.spawn.as_ref().map_or(0, |s| s.count);
        if let Some((_, j, name)) = seen
            .iter()
            .find(|(_, _, n)| (1..=count).any(|k| **n == rigid::spawned_name(&e.name, k)))
        {
            return Err(ctx.err(
                &At::entry("rigid_body", i).key("name"),
                format!(
                    "the copies of spawned '{}' would take the name '{name}' of object #{}",
                    e.name,
                    j + 1
                ),
            ));
        }
    }
    for (i, e) in file.rigid_body.iter().enumerate().filter(|(_, e)| e.spawn.is_none()) {
        let (h, fix) = rigid::build_rigid_body(&mut sim, ctx, base_dir, &At::entry("rigid_body", i), e)?;
        objects.push((e.name.clone(), SceneObject::RigidBody(h)));
        joints.extend(fix);
    }
    let mut robots = Vec::new();
    for (i, e) in file.robot.iter().enumerate() {
        let at = At::entry("robot", i);
        if e.name.is_empty() || objects.iter().any(|(n, _)| n == &e.name) {
            return Err(ctx.err(
                &at.key("name"),
                format!("robot name '{}' is empty or already used", e.name),
            ));
        }
        let r = robot::build_robot(&mut sim, ctx, base_dir, &at, e)?;
        for mesh in &r.collision_meshes {
            let label = sim.rigid_bodies.labels[mesh.body.i()].clone();
            objects.push((
                label,
                SceneObject::RigidBody(SceneRigidBody {
                    body: mesh.body,
                    nodes: mesh.nodes,
                    contact: Some(mesh.contact),
                }),
            ));
        }
        robots.push(r);
    }
    let spawned_count = |name: &str| {
        spawned
            .iter()
            .find(|(_, e)| e.name == name)
            .and_then(|(_, e)| e.spawn.as_ref())
            .map(|s| s.count)
    };
    // Friction with spawned bodies is set when each copy is added.
    let mut spawned_friction: Vec<Vec<(rigid::FrictionPartner, f64)>> = vec![Vec::new(); spawned.len()];
    for (i, e) in file.friction.iter().enumerate() {
        let at = At::entry("friction", i);
        let sides = [spawned_count(&e.objects[0]), spawned_count(&e.objects[1])];
        if sides == [None, None] {
            add_friction(&mut sim, ctx, &at, &objects, e)?;
            continue;
        }
        if !(e.mu >= 0.0 && e.mu.is_finite()) {
            return Err(ctx.err(&at.key("mu"), format!("mu = {} must be non-negative and finite", e.mu)));
        }
        for side in 0..2 {
            let Some(k) = spawned.iter().position(|(_, s)| s.name == e.objects[side]) else {
                continue;
            };
            let other = &e.objects[1 - side];
            let partner = match sides[1 - side] {
                Some(count) => rigid::FrictionPartner::Spawned {
                    name: other.clone(),
                    count,
                },
                None => rigid::FrictionPartner::Present(contact_of(
                    ctx,
                    &at.key("objects").index(1 - side),
                    &objects,
                    other,
                )?),
            };
            spawned_friction[k].push((partner, e.mu));
            if e.objects[0] == e.objects[1] {
                break;
            }
        }
    }
    for (i, e) in file.disable_collision.iter().enumerate() {
        let at = At::entry("disable_collision", i);
        if let Some(name) = e.objects.iter().find(|n| spawned_count(n).is_some()) {
            return Err(ctx.err(
                &at.key("objects"),
                format!("'{name}' is spawned during the run: spawned bodies take `[[friction]]` entries but not `[[disable_collision]]`"),
            ));
        }
        add_disable_collision(&mut sim, ctx, &at, &objects, e)?;
    }
    for (k, &(i, e)) in spawned.iter().enumerate() {
        let friction = std::mem::take(&mut spawned_friction[k]);
        rigid::spawn_rigid_body(&mut sim, ctx, base_dir, &At::entry("rigid_body", i), e, friction)?;
    }
    let mut prescribed = Vec::new();
    for (i, e) in file.prescribed.iter().enumerate() {
        let at = At::entry("prescribed", i);
        prescribed.push(build_prescribed(&mut sim, ctx, &at, &objects, e)?);
    }
    let mut attachments = Vec::new();
    for (i, e) in file.attachment.iter().enumerate() {
        let at = At::entry("attachment", i);
        attachments.push(build_attachment(&mut sim, ctx, &at, &objects, e)?);
    }
    for (i, e) in file.joint.iter().enumerate() {
        let at = At::entry("joint", i);
        let name = match &e.name {
            Some(name) => {
                if name.is_empty() {
                    return Err(ctx.err(&at.key("name"), "the joint name is empty"));
                }
                if joints.iter().any(|j: &JointHandle| &j.label == name) {
                    return Err(ctx.err(&at.key("name"), format!("duplicate joint name '{name}'")));
                }
                name.clone()
            }
            None => {
                // `<type> <a>-<b>`, numbered from the second of the same name.
                let base = e.default_name();
                let mut name = base.clone();
                let mut k = 1;
                while joints.iter().any(|j| j.label == name) {
                    k += 1;
                    name = format!("{base} #{k}");
                }
                name
            }
        };
        joints.push(rigid::build_joint(&mut sim, ctx, &at, &objects, e, &name)?);
    }
    for r in &robots {
        joints.extend(r.joints.values().cloned());
        joints.extend(r.extra_joints.iter().cloned());
    }
    add_gravity_ramps(&mut sim, ctx, &file.gravity_ramp)?;
    Ok(LoadedScene {
        robots,
        simulation: sim,
        duration_s: file.duration_s,
        name,
        objects,
        prescribed,
        attachments,
        joints,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energy::Potential;
    use crate::io::output::OutputCells;
    use crate::presets::objects::BendingHandle;
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

    #[test]
    fn default_scene_parses_with_the_right_counts() {
        let scene = load_scene_with(&repo_scene("default.toml"), quiet).unwrap();
        assert_eq!(scene.name, "default");
        assert_eq!(scene.duration_s, 3.0);
        let sim = &scene.simulation;
        assert_eq!(sim.nodes.len(), 33 * 33);
        assert_eq!(sim.deformables.triangles.num_elements(), 2 * 32 * 32);
        match &sim.output.meshes[0].cells {
            OutputCells::Triangles(t) => assert_eq!(t.len(), 2 * 32 * 32),
            _ => panic!("the cloth is not a triangle mesh"),
        }
        // Default settings: residual 1e-6 N, dt = 1/30 s.
        assert_eq!(sim.settings.newton.residual_tolerance_n, 1e-6);
        assert_eq!(sim.settings.newton.step_tolerance_m_s, 0.0);
        assert_eq!(sim.settings.time_step_s, 1.0 / 30.0);
        // Two pinned corners at y = +0.5, k = 1e6 N/m.
        assert_eq!(scene.prescribed.len(), 2);
        for (p, x) in scene.prescribed.iter().zip([0.5, -0.5]) {
            assert_eq!(p.nodes, 1);
            let pp = &sim.deformables.prescribed;
            assert_eq!(pp.params(p.handle).unwrap().stiffness, 1e6);
            assert_eq!(pp.targets(p.handle).unwrap()[0], Vector3::new(x, 0.5, 0.0));
        }
    }

    #[test]
    fn default_scene_matches_the_builtin_hanging_cloth_bit_for_bit() {
        let mut from_file = load_scene_with(&repo_scene("default.toml"), |s| {
            quiet(s);
            crate::scenes::stark_tolerances(s);
        })
        .unwrap()
        .simulation;
        let mut settings = Settings::default();
        quiet(&mut settings);
        let mut builtin = crate::scenes::hanging_cloth(settings).unwrap();
        assert_eq!(from_file.settings.newton, builtin.settings.newton);
        assert_eq!(bits(&from_file.nodes.x), bits(&builtin.nodes.x));
        for _ in 0..3 {
            from_file.step().unwrap();
            builtin.step().unwrap();
        }
        assert!(builtin.nodes.x.iter().any(|p| p.z < -0.01), "nothing moved");
        assert_eq!(bits(&from_file.nodes.x), bits(&builtin.nodes.x));
    }

    #[test]
    fn box_scene_matches_the_builtin_hanging_deformable_box() {
        let scene = load_scene_with(&repo_scene("hanging_deformable_box.toml"), quiet).unwrap();
        let mut from_file = scene.simulation;
        let mut settings = Settings::default();
        quiet(&mut settings);
        let mut builtin = crate::scenes::hanging_deformable_box(settings).unwrap();
        // The file writes the tolerances as decimals: equal to the built-in's within rounding.
        let (f, b) = (&from_file.settings, &builtin.settings);
        assert_eq!(f.time_step_s, b.time_step_s);
        assert_eq!(f.newton.step_tolerance_m_s, b.newton.step_tolerance_m_s);
        let rel = (f.newton.residual_tolerance_n / b.newton.residual_tolerance_n - 1.0).abs();
        assert!(rel < 1e-15, "{rel}");
        assert_eq!((scene.duration_s * 30.0).round(), 151.0);
        assert_eq!(from_file.nodes.len(), 2331);
        assert_eq!(from_file.deformables.tets.num_elements(), 12000);
        assert_eq!(bits(&from_file.nodes.x), bits(&builtin.nodes.x));
        from_file.settings.newton = builtin.settings.newton.clone();
        from_file.step().unwrap();
        builtin.step().unwrap();
        assert_eq!(bits(&from_file.nodes.x), bits(&builtin.nodes.x));
    }

    #[test]
    fn every_repository_scene_loads() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
        let mut n = 0;
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == "toml" || e == "json") {
                load_scene_with(&path, quiet).unwrap_or_else(|e| panic!("{e}"));
                n += 1;
            }
        }
        assert!(n >= 3);
    }

    #[test]
    fn the_documented_example_loads() {
        let doc =
            std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/scene-format.md")).unwrap();
        let example = doc
            .rsplit("```toml\n")
            .next()
            .and_then(|s| s.split("```").next())
            .unwrap();
        let scene = parse_scene_with(example, "example.toml", Path::new("."), quiet).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(scene.name, "cloth_on_a_block");
        assert_eq!(scene.objects.len(), 3);
        assert_eq!(scene.prescribed[0].nodes, 25);
        assert_eq!(scene.attachments.len(), 1);
    }

    #[test]
    fn material_overrides_change_single_fields_of_the_preset() {
        let scene = parse(
            r#"
duration_s = 1.0
[[surface]]
name = "a"
grid = { size_m = [1.0, 1.0], quads = [2, 2] }
material = { preset = "cotton_fabric", strain = { youngs_modulus = 1e4 }, inertia = { density = 0.3 }, bending = { flat = { stiffness = 2e-6 } } }
[[surface]]
name = "b"
grid = { size_m = [1.0, 1.0], quads = [2, 2] }
material = { preset = "cotton_fabric", bending = "none" }
[[surface]]
name = "c"
grid = { size_m = [1.0, 1.0], quads = [2, 2] }
material.preset = "cotton_fabric"
material.bending.dihedral = { stiffness = 1e-5 }
[[volume]]
name = "v"
grid = { size_m = [1.0, 1.0, 1.0], cells = [1, 1, 1] }
material = { preset = "soft_rubber", strain = { poissons_ratio = 0.45, strain_limit = inf } }
[[line]]
name = "l"
segments = { begin_m = [0.0, 0.0, 0.0], end_m = [1.0, 0.0, 0.0], count = 4 }
material = { preset = "elastic_rubber_band", strain = { section_radius_m = 0.003 } }
"#,
        );
        let d = &scene.simulation.deformables;
        let cotton = SurfaceMaterial::cotton_fabric();
        let a = surface(&scene, "a");
        let strain = d.triangles.params(a.strain).unwrap();
        assert_eq!(strain.youngs_modulus, 1e4);
        let expected = crate::deformables::TriangleStrainParams {
            youngs_modulus: 1e4,
            ..cotton.strain.clone()
        };
        assert_eq!(strain, &expected);
        let inertia = d.inertia.params(a.inertia).unwrap();
        assert_eq!((inertia.density, inertia.damping), (0.3, 0.1));
        let Some(BendingHandle::Flat(fb)) = a.bending else {
            panic!("a has no flat bending")
        };
        let fb = d.flat_bending.params(fb).unwrap();
        assert_eq!((fb.stiffness, fb.damping), (2e-6, 1e-7));
        assert!(surface(&scene, "b").bending.is_none());
        let Some(BendingHandle::Dihedral(db)) = surface(&scene, "c").bending else {
            panic!("c has no dihedral bending")
        };
        let db = d.dihedral_bending.params(db).unwrap();
        assert_eq!(db.stiffness, 1e-5);
        let Some(SceneObject::Volume(v)) = scene.object("v") else {
            panic!()
        };
        let tet = d.tets.params(v.strain).unwrap();
        assert_eq!(tet.poissons_ratio, 0.45);
        assert_eq!(tet.strain_limit, f64::INFINITY);
        assert_eq!(tet.youngs_modulus, VolumeMaterial::soft_rubber().strain.youngs_modulus);
        let Some(SceneObject::Line(l)) = scene.object("l") else {
            panic!()
        };
        let seg = d.segments.params(l.strain).unwrap();
        assert_eq!(seg.section_radius_m, 0.003);
        assert_eq!(seg.youngs_modulus, 1e4);
        assert_eq!(scene.simulation.nodes.len(), 3 * 9 + 9 + 5);
    }

    const CLOTH: &str = "duration_s = 1.0\n[[surface]]\nname = \"cloth\"\n\
                         grid = { size_m = [1.0, 1.0], quads = [2, 2] }\n";

    /// A cloth with contact (lines 2–5), a rope without (6–9) and an obstacle (10–14).
    const CONTACT: &str = "duration_s = 1.0\n[[surface]]\nname = \"cloth\"\n\
                           grid = { size_m = [1.0, 1.0], quads = [2, 2] }\n\
                           material = { preset = \"cotton_fabric\", contact_thickness_m = 0.002 }\n\
                           [[line]]\nname = \"rope\"\n\
                           segments = { begin_m = [0.0, 0.0, 1.0], end_m = [0.0, 0.0, 2.0], count = 2 }\n\
                           material = \"elastic_rubber_band\"\n\
                           [[obstacle]]\nname = \"ball\"\nsphere = { radius_m = 0.1, subdivisions = 1 }\n\
                           translate_m = [0.0, 0.0, -0.5]\ncontact_thickness_m = 0.002\n";

    /// The start of an obstacle entry; its geometry goes on line 4.
    const OBSTACLE: &str = "duration_s = 1.0\n[[obstacle]]\nname = \"ball\"\n";

    /// Each error names the file, the line (and column) and the offending field.
    #[test]
    fn errors_name_file_line_and_field() {
        let cases: Vec<(&str, String, Vec<&str>)> = vec![
            (
                "syntax",
                "duration_s = 1.0\n[[surface]\n".into(),
                vec!["test.toml:2:"],
            ),
            (
                "missing field",
                "[settings]\nthreads = 1\n".into(),
                vec!["=test.toml:1:1: missing field `duration_s`"],
            ),
            (
                "unknown field in an override",
                format!("{CLOTH}[surface.material]\npreset = \"cotton_fabric\"\nstrain = {{ youngs_modulu = 1e4 }}\n"),
                vec![
                    "test.toml:7:12: unknown field `youngs_modulu` in surface 'cloth' material.strain, expected one of",
                    "`youngs_modulus`",
                ],
            ),
            (
                "unknown field in an object",
                format!("{CLOTH}material = \"cotton_fabric\"\ncolour = \"red\"\n"),
                vec!["test.toml:6:1: unknown field `colour` in surface 'cloth', expected one of"],
            ),
            (
                "unknown top-level table",
                format!("{CLOTH}material = \"cotton_fabric\"\n[[surfaces]]\nname = \"x\"\n"),
                vec!["test.toml:6:", "unknown field `surfaces`"],
            ),
            (
                "unknown setting",
                "duration_s = 1.0\n[settings.newton]\nresidual_tolerance = 1e-6\n".into(),
                vec!["test.toml:3:1: unknown field `residual_tolerance` in settings.newton"],
            ),
            (
                "type error in a generator",
                "duration_s = 1.0\n[[surface]]\nname = \"cloth\"\ngrid = { size_m = [1.0, 1.0], quads = [2, \"x\"] }\nmaterial = \"cotton_fabric\"\n".into(),
                vec!["test.toml:4:", "in surface 'cloth' grid.quads[1]", "invalid type"],
            ),
            (
                "type error in an override",
                format!("{CLOTH}material = {{ preset = \"cotton_fabric\", strain = {{ youngs_modulus = \"soft\" }} }}\n"),
                vec!["test.toml:5:", "invalid type: string \"soft\" in surface 'cloth' material.strain.youngs_modulus"],
            ),
            (
                "unknown variant",
                format!("{CLOTH}material = {{ preset = \"cotton_fabric\", bending = \"flatt\" }}\n"),
                vec!["test.toml:5:", "unknown variant `flatt`", "material.bending"],
            ),
            (
                "unknown preset",
                format!("{CLOTH}material = \"soft_rubber\"\n"),
                vec!["test.toml:5:", "unknown surface material preset 'soft_rubber'", "cotton_fabric", "surface 'cloth' material"],
            ),
            (
                "bad parameter value in an override",
                format!("{CLOTH}material = {{ preset = \"cotton_fabric\", strain = {{ youngs_modulus = -1.0 }} }}\n"),
                vec!["test.toml:5:", "`youngs_modulus` = -1", "surface 'cloth' material.strain.youngs_modulus"],
            ),
            (
                "bad setting value",
                "duration_s = 1.0\n[settings]\ntime_step_s = -1.0\n".into(),
                vec!["test.toml:3:1:", "`time_step_s` = -1", "settings.time_step_s"],
            ),
            (
                "bad duration",
                "duration_s = 0.0\n".into(),
                vec!["test.toml:1:1:", "duration_s"],
            ),
            (
                "duplicate names",
                format!("{CLOTH}material = \"cotton_fabric\"\n[[volume]]\nname = \"cloth\"\ngrid = {{ size_m = [1.0, 1.0, 1.0], cells = [1, 1, 1] }}\nmaterial = \"soft_rubber\"\n"),
                vec!["test.toml:7:1: duplicate object name 'cloth' (already used by surface #1) in volume 'cloth' name"],
            ),
            (
                "no geometry",
                "duration_s = 1.0\n[[surface]]\nname = \"cloth\"\nmaterial = \"cotton_fabric\"\n".into(),
                vec!["test.toml:2:", "no geometry", "surface 'cloth'"],
            ),
            (
                "two geometries",
                format!("{CLOTH}mesh = \"cloth.obj\"\nmaterial = \"cotton_fabric\"\n"),
                vec!["test.toml:5:1:", "more than one geometry (grid, mesh)", "surface 'cloth' mesh"],
            ),
            (
                "bad grid",
                "duration_s = 1.0\n[[surface]]\nname = \"cloth\"\ngrid = { size_m = [1.0, 1.0], quads = [0, 2] }\nmaterial = \"cotton_fabric\"\n".into(),
                vec!["test.toml:4:31:", "quads = [0, 2] must be positive", "surface 'cloth' grid.quads"],
            ),
            (
                "missing mesh file",
                "duration_s = 1.0\n[[surface]]\nname = \"cloth\"\nmesh = \"no/such/cloth.obj\"\nmaterial = \"cotton_fabric\"\n".into(),
                vec!["test.toml:4:1:", "cloth.obj' not found", "surface 'cloth' mesh"],
            ),
            (
                "unknown object",
                format!("{CLOTH}material = \"cotton_fabric\"\n[[prescribed]]\nobject = \"clth\"\nall = true\n"),
                vec!["test.toml:7:1: unknown object 'clth' in prescribed #1 (object 'clth') object, expected one of cloth"],
            ),
            (
                "empty box",
                format!("{CLOTH}material = \"cotton_fabric\"\n[[prescribed]]\nobject = \"cloth\"\ninside_box = {{ center_m = [5.0, 0.0, 0.0], size_m = [0.1, 0.1, 0.1] }}\n"),
                vec!["test.toml:8:1:", "no node of 'cloth' lies inside the box", "prescribed #1 (object 'cloth') inside_box"],
            ),
            (
                "no selection",
                format!("{CLOTH}material = \"cotton_fabric\"\n[[prescribed]]\nobject = \"cloth\"\n"),
                vec!["test.toml:6:", "no node selection", "prescribed #1"],
            ),
            (
                "node out of range",
                format!("{CLOTH}material = \"cotton_fabric\"\n[[prescribed]]\nobject = \"cloth\"\nnodes = [0, 99]\n"),
                vec!["test.toml:8:1:", "node 99 does not exist", "prescribed #1 (object 'cloth') nodes"],
            ),
            (
                "bad stiffness",
                format!("{CLOTH}material = \"cotton_fabric\"\n[[prescribed]]\nobject = \"cloth\"\nall = true\nstiffness = -5.0\n"),
                vec!["test.toml:9:1:", "`stiffness` = -5", "prescribed #1 (object 'cloth') stiffness"],
            ),
            (
                "motion without axis",
                format!("{CLOTH}material = \"cotton_fabric\"\n[[prescribed]]\nobject = \"cloth\"\nall = true\nmotion = {{ angular_velocity_deg_s = 90.0 }}\n"),
                vec!["test.toml:9:12:", "needs an `axis`", "prescribed #1 (object 'cloth') motion.angular_velocity_deg_s"],
            ),
            (
                "unknown motion field",
                format!("{CLOTH}material = \"cotton_fabric\"\n[[prescribed]]\nobject = \"cloth\"\nall = true\nmotion = {{ velocity = [1.0, 0.0, 0.0] }}\n"),
                vec!["test.toml:9:12:", "unknown field `velocity` in prescribed #1 (object 'cloth') motion, expected"],
            ),
            (
                "attachment to an unknown object",
                format!("{CLOTH}material = \"cotton_fabric\"\n[[attachment]]\na = \"cloth\"\nb = \"box\"\nnodes_a = [0]\nnodes_b = [0]\n"),
                vec!["test.toml:8:1:", "unknown object 'box'", "attachment #1 ('cloth' to 'box') b"],
            ),
            (
                "bad contact setting",
                "duration_s = 1.0\n[settings.contact]\nfriction_iterations = 0\n".into(),
                vec!["=test.toml:3:1: `friction_iterations` = 0 on 'settings.contact' must be at least 1 in settings.contact.friction_iterations"],
            ),
            (
                "unknown contact setting",
                "duration_s = 1.0\n[settings]\ncontact = { thickness_m = 0.001 }\n".into(),
                vec!["test.toml:3:13: unknown field `thickness_m` in settings.contact, expected"],
            ),
            (
                "friction with an unknown object",
                format!("{CONTACT}[[friction]]\nobjects = [\"cloth\", \"bal\"]\nmu = 0.5\n"),
                vec!["=test.toml:16:21: unknown object 'bal' in friction #1 ('cloth' and 'bal') objects[1], expected one of cloth, rope, ball"],
            ),
            (
                "friction with an object without contact",
                format!("{CONTACT}[[friction]]\nobjects = [\"rope\", \"ball\"]\nmu = 0.5\n"),
                vec![
                    "test.toml:16:12: object 'rope' takes no part in contact: it has no contact thickness",
                    "objects with contact: cloth, ball in friction #1 ('rope' and 'ball') objects[0]",
                ],
            ),
            (
                "disabled collision of an object without contact",
                format!("{CONTACT}[[disable_collision]]\nobjects = [\"cloth\", \"rope\"]\n"),
                vec!["test.toml:16:21: object 'rope' takes no part in contact", "in disable_collision #1 ('cloth' and 'rope') objects[1]"],
            ),
            (
                "disabled collision with an unknown object",
                format!("{CONTACT}[[disable_collision]]\nobjects = [\"clth\", \"cloth\"]\n"),
                vec!["test.toml:16:12: unknown object 'clth' in disable_collision #1 ('clth' and 'cloth') objects[0]"],
            ),
            (
                "negative friction",
                format!("{CONTACT}[[friction]]\nobjects = [\"cloth\", \"ball\"]\nmu = -0.5\n"),
                vec!["=test.toml:17:1: mu = -0.5 must be non-negative and finite in friction #1 ('cloth' and 'ball') mu"],
            ),
            (
                "unknown field in a friction entry",
                format!("{CONTACT}[[friction]]\nobjects = [\"cloth\", \"ball\"]\nmu = 0.5\nstatic_mu = 0.6\n"),
                vec!["test.toml:18:1: unknown field `static_mu` in friction #1 ('cloth' and 'ball'), expected"],
            ),
            (
                "one object in a friction entry",
                format!("{CONTACT}[[friction]]\nobjects = [\"cloth\"]\nmu = 0.5\n"),
                vec!["test.toml:16:", "invalid length 1", "friction #1 objects"],
            ),
            (
                "unknown field in a disable_collision entry",
                format!("{CONTACT}[[disable_collision]]\nobjects = [\"cloth\", \"ball\"]\nmu = 0.5\n"),
                vec!["test.toml:17:1: unknown field `mu` in disable_collision #1 ('cloth' and 'ball'), expected `objects`"],
            ),
            (
                "prescribed obstacle",
                format!("{CONTACT}[[prescribed]]\nobject = \"ball\"\nall = true\n"),
                vec!["test.toml:16:1: 'ball' is an obstacle, whose nodes are prescribed already", "in prescribed #1 (object 'ball') object"],
            ),
            (
                "duplicate obstacle name",
                format!("{CLOTH}material = \"cotton_fabric\"\n[[obstacle]]\nname = \"cloth\"\nsphere = {{ radius_m = 0.1 }}\n"),
                vec!["=test.toml:7:1: duplicate object name 'cloth' (already used by surface #1) in obstacle 'cloth' name"],
            ),
            (
                "unknown field in an obstacle",
                format!("{CONTACT}colour = \"red\"\n"),
                vec!["test.toml:15:1: unknown field `colour` in obstacle 'ball', expected"],
            ),
            (
                "unknown field in an obstacle generator",
                format!("{OBSTACLE}sphere = {{ radius = 0.1 }}\ncontact_thickness_m = 0.002\n"),
                vec!["test.toml:4:12: unknown field `radius` in obstacle 'ball' sphere, expected"],
            ),
            (
                "obstacle without geometry",
                format!("{OBSTACLE}contact_thickness_m = 0.002\n"),
                vec!["test.toml:2:", "no geometry: give one of `sphere`, `box`, `cylinder`, `grid`, `mesh` or `vertices_m` + `triangles` in obstacle 'ball'"],
            ),
            (
                "obstacle with two geometries",
                format!("{OBSTACLE}sphere = {{ radius_m = 0.1 }}\nbox = {{ size_m = [1.0, 1.0, 1.0] }}\ncontact_thickness_m = 0.002\n"),
                vec!["test.toml:5:1: more than one geometry (sphere, box)", "in obstacle 'ball' box"],
            ),
            (
                "obstacle without contact thickness",
                format!("{OBSTACLE}sphere = {{ radius_m = 0.1 }}\n"),
                vec!["test.toml:2:", "obstacle 'ball' has no contact thickness: give `contact_thickness_m`", "in obstacle 'ball'"],
            ),
            (
                "negative obstacle contact thickness",
                format!("{OBSTACLE}sphere = {{ radius_m = 0.1 }}\ncontact_thickness_m = -0.002\n"),
                vec!["=test.toml:5:1: contact_thickness_m = -0.002 must be positive and finite (m) in obstacle 'ball' contact_thickness_m"],
            ),
            (
                "bad obstacle stiffness",
                format!("{OBSTACLE}sphere = {{ radius_m = 0.1 }}\ncontact_thickness_m = 0.002\nstiffness = 0.0\n"),
                vec!["=test.toml:6:1: stiffness = 0 must be positive and finite (N/m) in obstacle 'ball' stiffness"],
            ),
            (
                "bad sphere radius",
                format!("{OBSTACLE}sphere = {{ radius_m = -0.1 }}\ncontact_thickness_m = 0.002\n"),
                vec!["=test.toml:4:12: radius_m = -0.1 must be positive and finite (m) in obstacle 'ball' sphere.radius_m"],
            ),
            (
                "too many sphere subdivisions",
                format!("{OBSTACLE}sphere = {{ radius_m = 0.1, subdivisions = 12 }}\ncontact_thickness_m = 0.002\n"),
                vec!["test.toml:4:28: subdivisions = 12 is too many (at most 7", "in obstacle 'ball' sphere.subdivisions"],
            ),
            (
                "bad box",
                format!("{OBSTACLE}box = {{ size_m = [1.0, 0.0, 1.0] }}\ncontact_thickness_m = 0.002\n"),
                vec!["test.toml:4:9: size_m.y = 0 must be positive and finite (m) in obstacle 'ball' box.size_m"],
            ),
            (
                "bad cylinder",
                format!("{OBSTACLE}cylinder = {{ radius_m = 0.1, height_m = 0.2, slices = 2 }}\ncontact_thickness_m = 0.002\n"),
                vec!["test.toml:4:", "slices = 2 must be at least 3 in obstacle 'ball' cylinder.slices"],
            ),
            (
                "inline obstacle triangle out of range",
                format!("{OBSTACLE}vertices_m = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]\ntriangles = [[0, 1, 2], [0, 1, 3]]\ncontact_thickness_m = 0.002\n"),
                vec!["=test.toml:5:25: triangle 1 refers to vertex 3, but there are 3 vertices in obstacle 'ball' triangles[1]"],
            ),
            (
                "inline obstacle without triangles",
                format!("{OBSTACLE}vertices_m = [[0.0, 0.0, 0.0]]\ncontact_thickness_m = 0.002\n"),
                vec!["test.toml:4:1: `vertices_m` needs `triangles` (inline geometry gives both) in obstacle 'ball' vertices_m"],
            ),
            (
                "missing obstacle mesh",
                format!("{OBSTACLE}mesh = \"no/such/ball.obj\"\ncontact_thickness_m = 0.002\n"),
                vec!["test.toml:4:1:", "ball.obj' not found", "obstacle 'ball' mesh"],
            ),
            (
                "obstacle motion without axis",
                format!("{CONTACT}motion = {{ angular_velocity_deg_s = 90.0 }}\n"),
                vec!["test.toml:15:12:", "needs an `axis`", "obstacle 'ball' motion.angular_velocity_deg_s"],
            ),
        ];
        let mut failures = Vec::new();
        for (what, text, expected) in cases {
            let e = parse_err(&text);
            let shown = e.to_string();
            for s in expected {
                // A leading `=` asks for the whole message.
                let ok = match s.strip_prefix('=') {
                    Some(whole) => shown == whole,
                    None => shown.contains(s),
                };
                if !ok {
                    failures.push(format!("{what}: `{shown}` does not contain `{s}`"));
                }
            }
            if e.file != "test.toml" || e.line.is_none() {
                failures.push(format!("{what}: no file or line in {e:?}"));
            }
        }
        assert!(failures.is_empty(), "{}", failures.join("\n"));
    }

    #[test]
    fn json_scenes_parse_and_errors_have_lines() {
        let json = r#"{
  "duration_s": 1.0,
  "settings": { "gravity_m_s2": [0.0, -9.81, 0.0] },
  "surface": [
    { "name": "cloth", "grid": { "size_m": [1.0, 1.0], "quads": [4, 4] },
      "material": { "preset": "cotton_fabric", "strain": { "youngs_modulus": 1e4 } } }
  ],
  "prescribed": [ { "object": "cloth", "nodes": [0, 4], "stiffness": 1e6 } ]
}"#;
        let scene = parse_scene_with(json, "scene.json", Path::new("."), quiet).unwrap();
        assert_eq!(scene.simulation.nodes.len(), 25);
        assert_eq!(scene.simulation.settings.gravity_m_s2, [0.0, -9.81, 0.0]);
        assert_eq!(scene.prescribed[0].nodes, 2);
        let h = surface(&scene, "cloth");
        let strain = scene.simulation.deformables.triangles.params(h.strain).unwrap();
        assert_eq!(strain.youngs_modulus, 1e4);

        let bad = json.replace("\"quads\": [4, 4]", "\"quads\": [4, 4], \"colour\": 1");
        let e = scene_error(parse_scene(&bad, "scene.json", Path::new(".")).err().unwrap());
        assert_eq!(e.line, Some(5), "{e}");
        assert!(e.to_string().starts_with("scene.json:5:"), "{e}");
        assert!(e.to_string().contains("unknown field `colour`"), "{e}");
        let bad = json.replace("\"youngs_modulus\": 1e4", "\"youngs_modulu\": 1e4");
        let e = scene_error(parse_scene(&bad, "scene.json", Path::new(".")).err().unwrap());
        assert!(
            e.to_string()
                .contains("unknown field `youngs_modulu` in surface 'cloth' material.strain"),
            "{e}"
        );
        let e = scene_error(
            parse_scene("{ \"duration_s\": 1.0,\n ]", "scene.json", Path::new("."))
                .err()
                .unwrap(),
        );
        assert_eq!(e.line, Some(2), "{e}");
    }

    #[test]
    fn motions_move_the_targets() {
        let mut scene = parse(
            r#"
duration_s = 2.0
[settings]
gravity_m_s2 = [0.0, 0.0, 0.0]
[[surface]]
name = "cloth"
grid = { size_m = [0.5, 0.5], quads = [4, 4] }
rotate_deg = { angle = 90.0, axis = [1.0, 0.0, 0.0] }
material = "cotton_fabric"
[[prescribed]]
object = "cloth"
inside_box = { center_m = [0.25, 0.0, 0.0], size_m = [0.001, 1.0, 1.0] }
stiffness = 1e6
motion = { start_s = 0.5, end_s = 1.5, angular_velocity_deg_s = 90.0, axis = [2.0, 0.0, 0.0], center_m = [0.0, 0.0, 0.1], velocity_m_s = [0.0, 0.0, 0.2] }
[[prescribed]]
object = "cloth"
inside_box = { center_m = [-0.25, 0.0, 0.0], size_m = [0.001, 1.0, 1.0] }
stiffness = 1e6
motion = { velocity_m_s = [0.0, 0.3, 0.0] }
"#,
        );
        let twist = scene.prescribed[0].clone();
        let slide = scene.prescribed[1].clone();
        assert_eq!((twist.nodes, slide.nodes), (5, 5));
        let sim = &mut scene.simulation;
        let reference: Vec<_> = sim.deformables.prescribed.targets(twist.handle).unwrap().to_vec();
        // The grid was turned into the XZ plane.
        assert!(reference.iter().all(|p| p.x == 0.25 && p.y.abs() < 1e-15));
        let motion = twist.motion.clone().unwrap();
        for (t, tau) in [(0.0, 0.0), (0.5, 0.0), (1.0, 0.5), (1.25, 0.75), (1.5, 1.0), (3.0, 1.0)] {
            motion.apply(sim, twist.handle, t).unwrap();
            let (s, c) = (90.0f64 * tau).to_radians().sin_cos();
            let targets = sim.deformables.prescribed.targets(twist.handle).unwrap();
            for (p, q) in reference.iter().zip(targets) {
                let (y, z) = (p.y, p.z - 0.1);
                let expected = Vector3::new(p.x, c * y - s * z, s * y + c * z + 0.1 + 0.2 * tau);
                assert!((q - expected).norm() < 1e-12, "t = {t}: {q} vs {expected}");
            }
        }
        // Through the event: after one step the sliding edge's targets are at t = dt.
        let slide_ref: Vec<_> = sim.deformables.prescribed.targets(slide.handle).unwrap().to_vec();
        sim.step().unwrap();
        let t = sim.time();
        assert!(t > 0.0);
        let targets = sim.deformables.prescribed.targets(slide.handle).unwrap();
        for (p, q) in slide_ref.iter().zip(targets) {
            assert!((q - (p + Vector3::new(0.0, 0.3 * t, 0.0))).norm() < 1e-14);
        }
    }

    #[test]
    fn twisting_cloth_scene_follows_its_motions() {
        let mut scene = load_scene_with(&repo_scene("twisting_cloth_no_contact.toml"), quiet).unwrap();
        assert_eq!(scene.simulation.gravity(), Vector3::zeros());
        assert_eq!(scene.duration_s, 2.0);
        let edges: Vec<_> = scene.prescribed.iter().map(|p| (p.handle, p.nodes)).collect();
        assert_eq!(edges.iter().map(|e| e.1).collect::<Vec<_>>(), vec![33, 33]);
        let sim = &mut scene.simulation;
        for _ in 0..3 {
            sim.step().unwrap();
        }
        let t = sim.time();
        for ((h, _), sign) in edges.iter().zip([1.0, -1.0]) {
            let pp = &sim.deformables.prescribed;
            assert!(pp.max_violation_m(*h, &sim.nodes.x).unwrap() <= 1e-3);
            // The edge node at the top (z = +0.25 before the motion) turned by ±90°/s · t.
            let (s, c) = (sign * 90.0f64 * t).to_radians().sin_cos();
            let top = pp
                .targets(*h)
                .unwrap()
                .iter()
                .map(|p| (p - Vector3::new(p.x, -0.25 * s, 0.25 * c)).norm())
                .fold(f64::INFINITY, f64::min);
            assert!(top < 1e-12, "{top}");
        }
    }

    #[test]
    fn mesh_paths_are_relative_to_the_scene_file() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir_all(dir.path().join("meshes")).unwrap();
        std::fs::create_dir_all(dir.path().join("scenes")).unwrap();
        std::fs::write(
            dir.path().join("meshes/square.obj"),
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n",
        )
        .unwrap();
        std::fs::write(
            dir.path().join("meshes/tet.vtk"),
            "# vtk DataFile Version 2.0\ntet\nASCII\nDATASET UNSTRUCTURED_GRID\n\
             POINTS 4 double\n0 0 0\n1 0 0\n0 1 0\n0 0 1\nCELLS 1 5\n4 0 1 2 3\n\
             CELL_TYPES 1\n10\n",
        )
        .unwrap();
        let scene_path = dir.path().join("scenes/meshes.toml");
        std::fs::write(
            &scene_path,
            r#"duration_s = 1.0
[[surface]]
name = "square"
mesh = "../meshes/square.obj"
scale = 2.0
translate_m = [0.0, 0.0, 1.0]
material = "cotton_fabric"
[[volume]]
name = "tet"
mesh = "../meshes/tet.vtk"
material = "soft_rubber"
[[obstacle]]
name = "plate"
mesh = "../meshes/square.obj"
translate_m = [0.0, 0.0, -1.0]
contact_thickness_m = 0.001
"#,
        )
        .unwrap();
        let scene = load_scene_with(&scene_path, quiet).unwrap();
        let sim = &scene.simulation;
        let square = surface(&scene, "square");
        let x = sim.positions(square.nodes);
        assert_eq!(x.len(), 4);
        assert_eq!(x[2], Vector3::new(2.0, 2.0, 1.0));
        assert_eq!(sim.deformables.triangles.num_elements(), 2);
        assert_eq!(sim.deformables.tets.num_elements(), 1);
        assert_eq!(scene.name, "meshes");
        let Some(SceneObject::Obstacle(plate)) = scene.object("plate") else {
            panic!("no obstacle 'plate'")
        };
        assert_eq!(sim.positions(plate.nodes)[2], Vector3::new(1.0, 1.0, -1.0));
        assert_eq!(sim.contact.objects().len(), 1);

        // A volume needs tets; a missing file names the resolved path and the line.
        let text = std::fs::read_to_string(&scene_path)
            .unwrap()
            .replace("../meshes/tet.vtk", "../meshes/square.obj");
        std::fs::write(&scene_path, text).unwrap();
        let e = scene_error(load_scene(&scene_path).err().unwrap()).to_string();
        assert!(e.contains("meshes.toml:10:1:"), "{e}");
        assert!(e.contains("contains no tetrahedra"), "{e}");
        assert!(e.contains("volume 'tet' mesh"), "{e}");
        let text = std::fs::read_to_string(&scene_path)
            .unwrap()
            .replace("../meshes/square.obj\"\nscale", "square.obj\"\nscale");
        std::fs::write(&scene_path, text).unwrap();
        let e = scene_error(load_scene(&scene_path).err().unwrap()).to_string();
        assert!(e.contains("meshes.toml:4:1:"), "{e}");
        assert!(e.contains("scenes/square.obj' not found"), "{e}");
    }

    #[test]
    fn attachments_and_gravity_ramps() {
        let mut scene = parse(
            r#"
duration_s = 1.0
[[surface]]
name = "a"
grid = { size_m = [1.0, 1.0], quads = [2, 2] }
material = "cotton_fabric"
[[surface]]
name = "b"
grid = { size_m = [1.0, 1.0], quads = [2, 2] }
translate_m = [0.0, 0.0, 0.5]
material = "cotton_fabric"
[[line]]
name = "rope"
vertices_m = [[0.5, 0.5, 0.0], [0.5, 0.5, -0.5]]
elements = [[0, 1]]
material = "elastic_rubber_band"
[[attachment]]
a = "a"
b = "b"
nodes_a = [0, 8]
nodes_b = [0, 8]
stiffness = 1e5
[[attachment]]
name = "knot"
a = "rope"
b = "a"
within_m = 1e-9
[[attachment]]
a = "rope"
b = "b"
nodes_a = [1]
triangles_b = [[0, 1, 2]]
barycentric_b = [[0.2, 0.3, 0.5]]
[[gravity_ramp]]
start_s = 0.0
end_s = 1.0
to_m_s2 = [0.0, 0.0, -1.0]
"#,
        );
        let labels: Vec<_> = scene.attachments.iter().map(|(l, _)| l.as_str()).collect();
        assert_eq!(labels, ["a-b", "knot", "rope-b"]);
        let sim = &mut scene.simulation;
        let knot = scene.attachments[1].1;
        // The rope's top node coincides with the cloth's corner (0.5, 0.5, 0).
        let gap = sim.deformables.attachments.max_gap_m(knot, &sim.nodes.x).unwrap();
        assert_eq!(gap, 0.0);
        sim.step().unwrap();
        let t = sim.time();
        let expected = -9.81 + (9.81 - 1.0) * t;
        assert!((sim.gravity().z - expected).abs() < 1e-12);
    }

    #[test]
    fn franka_cup_scene_matches_the_builtin() {
        let scene = load_scene_with(&repo_scene("franka_cup.toml"), quiet).unwrap();
        let mut from_file = scene.simulation;
        let mut settings = Settings::default();
        quiet(&mut settings);
        let mut builtin = crate::scenes::franka_cup_scene(settings).unwrap();
        from_file.settings.name = builtin.settings.name.clone();
        assert_eq!(from_file.settings, builtin.settings);
        assert_eq!(from_file.nodes.len(), builtin.nodes.len());
        let close = |a: &[Vector3<f64>], b: &[Vector3<f64>]| a.iter().zip(b).all(|(p, q)| (p - q).norm() < 1e-12);
        assert!(close(&from_file.nodes.x, &builtin.nodes.x));
        assert!(close(&from_file.nodes.rest, &builtin.nodes.rest));
        let labels = |s: &Simulation| -> Vec<(String, f64)> {
            s.contact
                .objects()
                .iter()
                .map(|o| (o.label.clone(), o.thickness_m))
                .collect()
        };
        assert_eq!(labels(&from_file), labels(&builtin));
        let n = from_file.contact.objects().len();
        for a in 0..n {
            for b in 0..n {
                let (ha, hb) = (ContactHandle(a as u32), ContactHandle(b as u32));
                let (cf, cb) = (&from_file.contact, &builtin.contact);
                assert_eq!(cf.friction(ha, hb).unwrap(), cb.friction(ha, hb).unwrap(), "{a} {b}");
                assert_eq!(
                    cf.collision_enabled(ha, hb).unwrap(),
                    cb.collision_enabled(ha, hb).unwrap()
                );
            }
        }
        let spawns = |s: &Simulation| -> Vec<(f64, String)> {
            s.spawns().into_iter().map(|(t, l, _)| (t, l.to_string())).collect()
        };
        assert_eq!(spawns(&from_file), spawns(&builtin));
        // A few steps of the closing jaws agree (the hand's height is written out in the file).
        for _ in 0..3 {
            from_file.step().unwrap();
            builtin.step().unwrap();
        }
        assert!(from_file
            .nodes
            .x
            .iter()
            .zip(&builtin.nodes.x)
            .all(|(p, q)| (p - q).norm() < 1e-9));
    }

    #[test]
    fn cloth_on_sphere_scene_matches_the_builtin() {
        let scene = load_scene_with(&repo_scene("cloth_on_sphere.toml"), quiet).unwrap();
        assert_eq!((scene.name.as_str(), scene.duration_s), ("cloth_on_sphere", 3.0));
        let Some(SceneObject::Obstacle(sphere)) = scene.object("sphere").copied() else {
            panic!("no obstacle 'sphere'")
        };
        let mut from_file = scene.simulation;
        let mut settings = Settings::default();
        quiet(&mut settings);
        let mut builtin = crate::scenes::cloth_on_sphere(settings).unwrap();
        assert_eq!(from_file.settings, builtin.settings);
        // Same nodes (the cloth's 33², then the sphere's 642) at the same positions.
        assert_eq!(from_file.nodes.len(), 33 * 33 + 642);
        assert_eq!(from_file.nodes.len(), builtin.nodes.len());
        assert_eq!(bits(&from_file.nodes.x), bits(&builtin.nodes.x));
        let d = (&from_file.deformables, &builtin.deformables);
        assert_eq!(d.0.triangles.num_elements(), d.1.triangles.num_elements());
        assert_eq!(d.0.flat_bending.num_elements(), d.1.flat_bending.num_elements());
        // Same contact objects, thicknesses and friction coefficients.
        let (fc, bc) = (&from_file.contact, &builtin.contact);
        let describe = |c: &crate::contact::Contact| -> Vec<(String, f64, u32, u32)> {
            c.objects()
                .iter()
                .map(|o| (o.label.clone(), o.thickness_m, o.nodes.first, o.nodes.len))
                .collect()
        };
        assert_eq!(describe(fc), describe(bc));
        assert_eq!(
            describe(fc),
            [("cloth".into(), 0.002, 0, 1089), ("sphere".into(), 0.002, 1089, 642)]
        );
        for a in 0..2 {
            for b in 0..2 {
                let (ha, hb) = (ContactHandle(a), ContactHandle(b));
                assert_eq!(fc.friction(ha, hb).unwrap(), bc.friction(ha, hb).unwrap());
            }
        }
        assert_eq!(fc.friction(ContactHandle(0), sphere.contact).unwrap(), 0.5);
        // The sphere is held as in the built-in scene.
        let pp = (&d.0.prescribed, &d.1.prescribed);
        assert_eq!(
            pp.0.params(sphere.prescribed).unwrap(),
            pp.1.params(PrescribedHandle(0)).unwrap()
        );
        assert_eq!(pp.0.params(sphere.prescribed).unwrap().stiffness, 1e6);
        assert_eq!(from_file.output.meshes.len(), builtin.output.meshes.len());
        // One step (the cloth is still 5 cm above the sphere) gives the same positions.
        from_file.step().unwrap();
        builtin.step().unwrap();
        assert!(builtin.nodes.x.iter().any(|p| p.z < -1e-3), "nothing moved");
        assert_eq!(bits(&from_file.nodes.x), bits(&builtin.nodes.x));
    }

    /// A sheet pierced by a blade (an obstacle), three more obstacles, friction and a disabled
    /// collision.
    const OBSTACLES: &str = r#"
duration_s = 1.0
[settings]
contact.default_thickness_m = 0.001
[[surface]]
name = "sheet"
vertices_m = [[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [0.0, 1.0, 0.0]]
elements = [[0, 1, 2]]
material = "cotton_fabric"
[[obstacle]]
name = "blade"
vertices_m = [[0.0, 0.0, -1.0], [0.5, 0.0, 1.0], [-0.5, 0.0, 1.0]]
triangles = [[0, 1, 2]]
[[obstacle]]
name = "crate"
box = { size_m = [0.2, 0.4, 0.6] }
translate_m = [5.0, 0.0, 0.0]
contact_thickness_m = 0.003
stiffness = 1e5
[[obstacle]]
name = "drum"
cylinder = { radius_m = 0.1, height_m = 0.3 }
rotate_deg = { angle = 90.0, axis = [1.0, 0.0, 0.0] }
translate_m = [-5.0, 0.0, 0.0]
[[obstacle]]
name = "floor"
grid = { size_m = [2.0, 2.0], quads = [2, 2] }
scale = 2.0
translate_m = [0.0, 0.0, -3.0]
[[friction]]
objects = ["sheet", "sheet"]
mu = 0.3
[[friction]]
objects = ["sheet", "floor"]
mu = 0.5
[[disable_collision]]
objects = ["sheet", "blade"]
"#;

    #[test]
    fn obstacles_friction_and_disabled_collisions() {
        let scene = parse(OBSTACLES);
        let sim = &scene.simulation;
        let names: Vec<_> = scene.objects.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["sheet", "blade", "crate", "drum", "floor"]);
        let obstacle = |name: &str| match scene.object(name) {
            Some(SceneObject::Obstacle(h)) => *h,
            other => panic!("{name} is {other:?}"),
        };
        // Geometry counts: a closed box (8, 12), a capped cylinder (16·2 + 2, 64), a 2×2 grid.
        let contact = &sim.contact;
        let count = |name: &str| obstacle(name).nodes.len;
        assert_eq!(
            [count("blade"), count("crate"), count("drum"), count("floor")],
            [3, 8, 34, 9]
        );
        let floor = sim.positions(obstacle("floor").nodes);
        assert!(floor
            .iter()
            .all(|p| p.z == -3.0 && p.x.abs() <= 2.0 && p.y.abs() <= 2.0));
        assert!(floor.iter().any(|p| p.x == 2.0));
        let drum = sim.positions(obstacle("drum").nodes);
        // Turned about X: the axis is along Y.
        assert!(drum
            .iter()
            .all(|p| ((p.x + 5.0).powi(2) + p.z.powi(2)).sqrt() <= 0.1 + 1e-12));
        // Thickness: given, else the default; stiffness: given, else 1e6; all self-collision off.
        let thickness: Vec<_> = contact.objects().iter().map(|o| o.thickness_m).collect();
        assert_eq!(thickness, [0.001, 0.001, 0.003, 0.001, 0.001]);
        let pp = &sim.deformables.prescribed;
        assert_eq!(pp.params(obstacle("crate").prescribed).unwrap().stiffness, 1e5);
        assert_eq!(pp.params(obstacle("drum").prescribed).unwrap().stiffness, 1e6);
        assert_eq!(
            pp.params(obstacle("crate").prescribed).unwrap().tolerance_m,
            1e-4 * 0.003
        );
        // Friction, including self-friction.
        let sheet = scene.object("sheet").unwrap().contact().unwrap();
        let mu = |h: ContactHandle| contact.friction(sheet, h).unwrap();
        assert_eq!(mu(sheet), 0.3);
        assert_eq!(mu(obstacle("floor").contact), 0.5);
        assert_eq!(mu(obstacle("blade").contact), 0.0);
        assert_eq!(contact.friction(obstacle("floor").contact, sheet).unwrap(), 0.5);
        // The blade pierces the sheet: only with the collision on is that an intersection.
        assert!(contact.find_intersections(&sim.nodes.x).is_empty());
        let on = parse(&OBSTACLES.replace("[[disable_collision]]\nobjects = [\"sheet\", \"blade\"]\n", ""));
        let found = on.simulation.contact.find_intersections(&on.simulation.nodes.x);
        assert!(!found.is_empty());
    }

    #[test]
    fn obstacle_motions_move_the_obstacle() {
        let mut scene = parse(
            r#"
duration_s = 1.0
[settings]
gravity_m_s2 = [0.0, 0.0, 0.0]
[[obstacle]]
name = "crate"
box = { size_m = [0.2, 0.2, 0.2] }
contact_thickness_m = 0.001
motion = { velocity_m_s = [0.0, 0.0, 0.3], angular_velocity_deg_s = 90.0, axis = [0.0, 0.0, 1.0], center_m = [0.1, 0.0, 0.0] }
"#,
        );
        let Some(SceneObject::Obstacle(crate_)) = scene.object("crate").copied() else {
            panic!()
        };
        let sim = &mut scene.simulation;
        let reference = sim.positions(crate_.nodes).to_vec();
        sim.step().unwrap();
        let t = sim.time();
        assert!(t > 0.0);
        let (s, c) = (90.0f64 * t).to_radians().sin_cos();
        let targets = sim.deformables.prescribed.targets(crate_.prescribed).unwrap().to_vec();
        for (p, q) in reference.iter().zip(&targets) {
            let (x, y) = (p.x - 0.1, p.y);
            let expected = Vector3::new(c * x - s * y + 0.1, s * x + c * y, p.z + 0.3 * t);
            assert!((q - expected).norm() < 1e-12, "{q} vs {expected}");
        }
        // The nodes follow within the hardening tolerance (1e-4 of the thickness).
        let gap = sim
            .deformables
            .prescribed
            .max_violation_m(crate_.prescribed, &sim.nodes.x)
            .unwrap();
        assert!(gap <= 1e-7 * (1.0 + 1e-9), "{gap}");
    }

    #[test]
    fn json_contact_entries_are_labelled() {
        let json = r#"{
  "duration_s": 1.0,
  "settings": { "contact": { "default_thickness_m": 0.001 } },
  "surface": [ { "name": "cloth", "grid": { "size_m": [1.0, 1.0], "quads": [2, 2] }, "material": "cotton_fabric" } ],
  "obstacle": [ { "name": "ball", "sphere": { "radius_m": 0.1 }, "translate_m": [0.0, 0.0, -0.5] } ],
  "friction": [ { "objects": ["cloth", "ball"], "mu": 0.2 } ]
}"#;
        let scene = parse_scene_with(json, "scene.json", Path::new("."), quiet).unwrap();
        let c = &scene.simulation.contact;
        assert_eq!(c.objects().len(), 2);
        assert_eq!(c.friction(ContactHandle(0), ContactHandle(1)).unwrap(), 0.2);
        assert_eq!(scene.simulation.nodes.len(), 9 + 162);
        let bad = json.replace("[\"cloth\", \"ball\"]", "[\"cloth\", \"bal\"]");
        let e = scene_error(parse_scene(&bad, "scene.json", Path::new(".")).err().unwrap());
        assert!(
            e.to_string()
                .contains("unknown object 'bal' in friction #1 ('cloth' and 'bal') objects[1]"),
            "{e}"
        );
    }

    #[test]
    fn every_documented_scene_loads() {
        let doc =
            std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/scene-format.md")).unwrap();
        let blocks: Vec<_> = doc
            .split("```toml\n")
            .skip(1)
            .filter_map(|s| s.split("```").next())
            .filter(|b| b.contains("duration_s"))
            .collect();
        assert!(blocks.len() >= 2, "{}", blocks.len());
        for b in blocks {
            parse_scene_with(b, "doc.toml", Path::new("."), quiet).unwrap_or_else(|e| panic!("{e}\n{b}"));
        }
    }
}

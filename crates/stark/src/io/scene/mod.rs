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
//!
//! The loader's stages, one file each: `errors` (locating errors in the document), `build` (the
//! file's tables and the order they are built in), `materials`, `geometry` (what entries with a
//! geometry share), `deformables`, `obstacles`, `prescribed`, `attachments`, `contact`, `events`,
//! `rigid_bodies`, `spawn`, `joints`, `robot`, and `overrides` (`--set key=value`).

mod attachments;
mod build;
mod contact;
mod deformables;
mod errors;
mod events;
mod geometry;
mod joints;
mod materials;
mod obstacles;
mod overrides;
mod prescribed;
mod rigid_bodies;
mod robot;
mod spawn;
#[cfg(test)]
mod tests;

pub use errors::SceneError;
pub use events::Motion;
pub use overrides::{apply_override, load_scene_with_overrides};
pub use prescribed::ScenePrescribed;
pub use rigid_bodies::SceneRigidBody;

use crate::contact::ContactHandle;
use crate::deformables::{AttachmentHandle, NodeSetHandle};
use crate::error::Result;
use crate::presets::{FixedSurfaceHandle, LineHandle, ObstacleHandle, SurfaceHandle, VolumeHandle};
use crate::rigidbodies::joints::JointHandle;
use crate::settings::Settings;
use crate::simulation::Simulation;
use errors::{json_error, line_col, At, Ctx, Res, Tree};
use std::path::Path;
use toml::de::DeTable;

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
    /// An `[[obstacle]]` with `fixed = true`.
    FixedObstacle(FixedSurfaceHandle),
    /// A `[[rigid_body]]`.
    RigidBody(SceneRigidBody),
}

impl SceneObject {
    /// Its node set.
    pub fn nodes(&self) -> NodeSetHandle {
        match self {
            SceneObject::Surface(h) => h.nodes,
            SceneObject::Volume(h) => h.nodes,
            SceneObject::Line(h) => h.nodes,
            SceneObject::Obstacle(h) => h.nodes,
            SceneObject::FixedObstacle(h) => h.nodes,
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
            SceneObject::FixedObstacle(_) => "fixed obstacle",
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
            SceneObject::FixedObstacle(h) => Some(h.contact),
            SceneObject::RigidBody(h) => h.contact,
        }
    }
}

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
        let file: build::SceneFile = serde_json::from_str(text).map_err(|e| json_error(file_name, &e))?;
        let ctx = Ctx {
            file: file_name,
            text,
            tree: Tree::Json(&value),
            root_span: None,
        };
        Ok(build::build(file, &ctx, base_dir, configure)?)
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
        let file: build::SceneFile = toml::from_str(text).map_err(|e| ctx.toml_error(&e, joints::joint_culprit))?;
        Ok(build::build(file, &ctx, base_dir, configure)?)
    }
}

/// The object called `name` (located at `at` in errors).
fn find_object<'o>(ctx: &Ctx, at: &At, objects: &'o [(String, SceneObject)], name: &str) -> Res<&'o SceneObject> {
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

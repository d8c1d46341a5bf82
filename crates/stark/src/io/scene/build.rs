//! The scene file's top-level tables and the order in which they are built: settings, the
//! objects (surfaces, volumes, lines, obstacles, rigid bodies, robots), friction and disabled
//! collisions, spawned bodies, prescribed nodes, attachments, joints and gravity ramps.

use super::attachments::{build_attachment, AttachmentEntry};
use super::contact::{add_disable_collision_entries, add_friction_entries, DisableCollisionEntry, FrictionEntry};
use super::deformables::{build_line, build_surface, build_volume, LineEntry, SurfaceEntry, VolumeEntry};
use super::errors::{At, Ctx, Res};
use super::events::{add_gravity_ramps, GravityRampEntry};
use super::joints::{build_joint, joint_name, JointEntry};
use super::obstacles::{build_obstacle, ObstacleEntry};
use super::prescribed::{build_prescribed, PrescribedEntry};
use super::rigid_bodies::{build_rigid_body, RigidBodyEntry, SceneRigidBody};
use super::robot::{build_robot, RobotEntry};
use super::spawn::{spawn_rigid_body, spawned_name};
use super::{LoadedScene, SceneObject};
use crate::error::StarkError;
use crate::settings::Settings;
use crate::simulation::Simulation;
use serde::Deserialize;
use std::path::Path;

/// A scene file: `[settings]`, `duration_s` and the arrays of entries.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SceneFile {
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
    rigid_body: Vec<RigidBodyEntry>,
    #[serde(default)]
    joint: Vec<JointEntry>,
    #[serde(default)]
    robot: Vec<RobotEntry>,
}

/// The simulation of the file's settings (after `configure`) and its name, which defaults to the
/// file's.
fn new_simulation(
    ctx: &Ctx,
    mut settings: Settings,
    configure: impl FnOnce(&mut Settings),
) -> Res<(Simulation, String)> {
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
    Ok((Simulation::new(settings).map_err(settings_error)?, name))
}

/// Check that object names are non-empty and unique across surfaces, volumes, lines, obstacles
/// and rigid bodies; returns each name with its kind and index among its kind.
fn object_names<'f>(ctx: &Ctx, file: &'f SceneFile) -> Res<Vec<(&'static str, usize, &'f String)>> {
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
    Ok(seen)
}

/// Build the scene of `file`.
pub(super) fn build(
    mut file: SceneFile,
    ctx: &Ctx,
    base_dir: &Path,
    configure: impl FnOnce(&mut Settings),
) -> Res<LoadedScene> {
    if !(file.duration_s > 0.0 && file.duration_s.is_finite()) {
        return Err(ctx.err(
            &At::default().key("duration_s"),
            format!("duration_s = {} must be positive and finite", file.duration_s),
        ));
    }
    let (mut sim, name) = new_simulation(ctx, std::mem::take(&mut file.settings), configure)?;
    let seen = object_names(ctx, &file)?;

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
        let object = build_obstacle(&mut sim, ctx, base_dir, &At::entry("obstacle", i), e)?;
        objects.push((e.name.clone(), object));
    }
    let mut joints = Vec::new();
    // Bodies with `spawn` are added during the run (after the friction entries are known).
    let spawned: Vec<(usize, &RigidBodyEntry)> = file
        .rigid_body
        .iter()
        .enumerate()
        .filter(|(_, e)| e.spawn.is_some())
        .collect();
    for &(i, e) in &spawned {
        let count = e.spawn.as_ref().map_or(0, |s| s.count);
        if let Some((_, j, name)) = seen
            .iter()
            .find(|(_, _, n)| (1..=count).any(|k| **n == spawned_name(&e.name, k)))
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
        let (h, fix) = build_rigid_body(&mut sim, ctx, base_dir, &At::entry("rigid_body", i), e)?;
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
        let r = build_robot(&mut sim, ctx, base_dir, &at, e)?;
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
    let mut spawned_friction = add_friction_entries(&mut sim, ctx, &objects, &file.friction, &spawned)?;
    add_disable_collision_entries(&mut sim, ctx, &objects, &file.disable_collision, &spawned)?;
    for (k, &(i, e)) in spawned.iter().enumerate() {
        let friction = std::mem::take(&mut spawned_friction[k]);
        spawn_rigid_body(&mut sim, ctx, base_dir, &At::entry("rigid_body", i), e, friction)?;
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
        let name = joint_name(ctx, &at, e, &joints)?;
        joints.push(build_joint(&mut sim, ctx, &at, &objects, e, &name)?);
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

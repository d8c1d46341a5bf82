//! `[[joint]]` entries: a [`JointKind`] (its `type` and fields) plus the fields every joint
//! takes, between body `a` (or `"world"`) and body `b`, built by [`Simulation::add_joint`]; a
//! `target_schedule` drives the joint's target over time.

use super::errors::{At, Ctx, Res, SceneError};
use super::SceneObject;
use crate::error::StarkError;
use crate::rigidbodies::joints::{JointHandle, JointKind, JointParams};
use crate::rigidbodies::RigidBodyHandle;
use crate::simulation::Simulation;
use serde::Deserialize;

/// A `[[joint]]`: the fields every joint takes, and its [`JointKind`] (`type` and the type's
/// fields) flattened into the same table. Unknown fields are rejected by `JointKind`.
#[derive(Deserialize)]
pub(super) struct JointEntry {
    pub(super) name: Option<String>,
    pub(super) a: Option<String>,
    pub(super) b: Option<String>,
    enabled: Option<bool>,
    target_schedule: Option<Vec<[f64; 2]>>,
    stiffness: Option<f64>,
    tolerance_m: Option<f64>,
    tolerance_deg: Option<f64>,
    #[serde(flatten)]
    pub(super) kind: JointKind,
}

impl JointEntry {
    /// The default name: `<type> <a>-<b>` (`<type>` for the couplings, which name joints).
    pub(super) fn default_name(&self) -> String {
        let kind = self.kind.type_name();
        match &self.b {
            Some(b) => format!("{kind} {}-{b}", self.a.as_deref().unwrap_or("world")),
            None => kind,
        }
    }
}

/// The body a joint side names: `None` for "world".
fn joint_body(ctx: &Ctx, at: &At, objects: &[(String, SceneObject)], name: &str) -> Res<Option<RigidBodyHandle>> {
    if name == "world" {
        return Ok(None);
    }
    let bodies = || {
        let names: Vec<_> = objects
            .iter()
            .filter(|(_, o)| matches!(o, SceneObject::RigidBody(_)))
            .map(|(n, _)| n.as_str())
            .collect();
        if names.is_empty() {
            "world (no rigid bodies defined)".to_string()
        } else {
            format!("world, {}", names.join(", "))
        }
    };
    match objects.iter().find(|(n, _)| n == name).map(|(_, o)| o) {
        Some(SceneObject::RigidBody(b)) => Ok(Some(b.body)),
        Some(other) => Err(ctx.err(
            at,
            format!(
                "'{name}' is a {}, not a rigid body, expected one of {}",
                other.kind(),
                bodies()
            ),
        )),
        None => Err(ctx.err(at, format!("unknown rigid body '{name}', expected one of {}", bodies()))),
    }
}

/// The value of a piecewise-linear schedule `[[t, value], ...]` at `t` (held outside).
fn schedule_value(points: &[[f64; 2]], t: f64) -> f64 {
    let i = points.partition_point(|p| p[0] <= t);
    if i == 0 {
        return points[0][1];
    }
    if i == points.len() {
        return points[i - 1][1];
    }
    let (a, b) = (points[i - 1], points[i]);
    a[1] + (b[1] - a[1]) * (t - a[0]) / (b[0] - a[0])
}

/// Build a `[[joint]]` labelled `name` through [`Simulation::add_joint`].
pub(super) fn build_joint(
    sim: &mut Simulation,
    ctx: &Ctx,
    at: &At,
    objects: &[(String, SceneObject)],
    e: &JointEntry,
    name: &str,
) -> Res<JointHandle> {
    let mut kind = e.kind.clone();
    let type_name = kind.type_name();
    let target = kind.target_field();
    // The target: given, or the schedule's value at t = 0.
    match (target, &e.target_schedule) {
        (None, Some(_)) => {
            return Err(ctx.err(
                &at.key("target_schedule"),
                format!("a {type_name} joint has no target to schedule"),
            ))
        }
        (Some((key, _)), None) if !ctx.gives(at, key) => {
            return Err(ctx.err(
                &at.key("type"),
                format!("a {type_name} joint needs `{key}` or a `target_schedule`"),
            ))
        }
        (Some((key, _)), Some(_)) if ctx.gives(at, key) => {
            return Err(ctx.err(
                &at.key("target_schedule"),
                format!("give the target once: `{key}` or `target_schedule`"),
            ))
        }
        _ => {}
    }
    if let Some(points) = &e.target_schedule {
        let at = at.key("target_schedule");
        if points.is_empty() {
            return Err(ctx.err(&at, "the schedule is empty: give `[[time_s, target], ...]`"));
        }
        for (i, p) in points.iter().enumerate() {
            let after = i == 0 || p[0] > points[i - 1][0];
            if !(p[0].is_finite() && p[1].is_finite() && after) {
                return Err(ctx.err(
                    &at.index(i),
                    format!("[{}, {}] needs finite values and times that increase", p[0], p[1]),
                ));
            }
        }
        if let Some((_, value, _)) = kind.target() {
            *value = schedule_value(points, 0.0);
        }
    }

    let a_name = e.a.as_deref().unwrap_or("world");
    let a = joint_body(ctx, &at.key("a"), objects, a_name)?;
    let b = match &e.b {
        Some(b) => joint_body(ctx, &at.key("b"), objects, b)?,
        None => None,
    };
    let defaults = JointParams::default();
    let params = JointParams {
        stiffness: e.stiffness.unwrap_or(defaults.stiffness),
        tolerance_m: e.tolerance_m.unwrap_or(defaults.tolerance_m),
        tolerance_deg: e.tolerance_deg.unwrap_or(defaults.tolerance_deg),
    };
    let handle = sim
        .add_joint(name, a, b, kind, params)
        .map_err(|err| joint_error(ctx, at, err))?;

    if e.enabled == Some(false) {
        sim.set_joint_enabled(&handle, false)
            .map_err(|err| ctx.stark(&at.key("enabled"), err))?;
    }
    if let (Some(points), Some((_, target))) = (&e.target_schedule, target) {
        let (points, h) = (points.clone(), handle.clone());
        sim.add_time_event(0.0, f64::INFINITY, move |sim, t| {
            target.set(sim, &h, schedule_value(&points, t))
        });
    }
    Ok(handle)
}

/// Locate an error of [`Simulation::add_joint`] at the field it names (a parameter's field, or
/// the first `field` in backticks that the entry gives), else at the entry's `type`.
fn joint_error(ctx: &Ctx, at: &At, err: StarkError) -> SceneError {
    let message = err.to_string();
    let named = match &err {
        StarkError::InvalidParameter { field, .. } => vec![field.to_string()],
        _ => message.split('`').skip(1).step_by(2).map(str::to_string).collect(),
    };
    let key = named
        .into_iter()
        .find(|k| ctx.gives(at, k))
        .unwrap_or_else(|| "type".to_string());
    ctx.err(&at.key(&key), message)
}

/// The label of `[[joint]]` entry `e`: its `name`, checked non-empty and unique among `joints`,
/// or `<type> <a>-<b>`, numbered from the second of the same name.
pub(super) fn joint_name(ctx: &Ctx, at: &At, e: &JointEntry, joints: &[JointHandle]) -> Res<String> {
    match &e.name {
        Some(name) => {
            if name.is_empty() {
                return Err(ctx.err(&at.key("name"), "the joint name is empty"));
            }
            if joints.iter().any(|j| &j.label == name) {
                return Err(ctx.err(&at.key("name"), format!("duplicate joint name '{name}'")));
            }
            Ok(name.clone())
        }
        None => {
            let base = e.default_name();
            let mut name = base.clone();
            let mut k = 1;
            while joints.iter().any(|j| j.label == name) {
                k += 1;
                name = format!("{base} #{k}");
            }
            Ok(name)
        }
    }
}

/// The field of `[[joint]]` `index` that a deserialisation error is about, and a message
/// naming it. A joint's type and fields are a flattened, internally tagged `JointKind`,
/// deserialised from a buffer that has lost the fields' places: unknown and missing fields
/// are named in the message; any other error is traced to the field whose removal changes
/// it (the entry is deserialised again without each field in turn).
pub(super) fn joint_culprit(ctx: &Ctx, index: usize, message: &str) -> Option<(String, String)> {
    let type_name = ctx.tree.item_str("joint", index, "type");
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
    let doc: toml::Table = toml::from_str(ctx.text).ok()?;
    let entry = doc.get("joint")?.as_array()?.get(index)?.as_table()?.clone();
    let fails_alike = |t: toml::Table| match toml::Value::Table(t).try_into::<JointEntry>() {
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

//! `[[prescribed]]` entries: a selection of an object's nodes (`inside_box`, `outside_box`,
//! `nodes` or `all`) pulled to targets ([`PrescribedParams`]), which an optional [`Motion`] moves.

use super::errors::{param_error, At, Ctx, Res};
use super::events::Motion;
use super::{find_object, SceneObject};
use crate::deformables::{PrescribedHandle, PrescribedParams};
use crate::error::StarkError;
use crate::simulation::Simulation;
use nalgebra::Vector3;
use serde::Deserialize;

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

/// `inside_box`/`outside_box = { center_m, size_m }`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BoxSelection {
    center_m: [f64; 3],
    size_m: [f64; 3],
}

/// A `[[prescribed]]`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct PrescribedEntry {
    object: String,
    inside_box: Option<BoxSelection>,
    outside_box: Option<BoxSelection>,
    nodes: Option<Vec<usize>>,
    all: Option<bool>,
    stiffness: Option<f64>,
    tolerance_m: Option<f64>,
    motion: Option<Motion>,
}

/// The one node selection an entry gives.
enum Selection<'e> {
    InBox { inside: bool, b: &'e BoxSelection },
    Nodes(&'e [usize]),
    All(bool),
}

impl PrescribedEntry {
    /// Its node selection and key, checking that it gives exactly one.
    fn selection(&self, ctx: &Ctx, at: &At) -> Res<(&'static str, Selection<'_>)> {
        let mut given: Vec<(&'static str, Selection)> = [
            (
                "inside_box",
                self.inside_box.as_ref().map(|b| Selection::InBox { inside: true, b }),
            ),
            (
                "outside_box",
                self.outside_box.as_ref().map(|b| Selection::InBox { inside: false, b }),
            ),
            ("nodes", self.nodes.as_deref().map(Selection::Nodes)),
            ("all", self.all.map(Selection::All)),
        ]
        .into_iter()
        .filter_map(|(key, s)| Some((key, s?)))
        .collect();
        let options = "`inside_box`, `outside_box`, `nodes` or `all = true`";
        match given.len() {
            1 => Ok(given.remove(0)),
            0 => Err(ctx.err(at, format!("no node selection: give one of {options}"))),
            _ => {
                let keys: Vec<&str> = given.iter().map(|g| g.0).collect();
                Err(ctx.err(
                    &at.key(keys[1]),
                    format!(
                        "more than one node selection ({}): give one of {options}",
                        keys.join(", ")
                    ),
                ))
            }
        }
    }
}

fn check_box(ctx: &Ctx, at: &At, b: &BoxSelection) -> Res<()> {
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

pub(super) fn build_prescribed(
    sim: &mut Simulation,
    ctx: &Ctx,
    at: &At,
    objects: &[(String, SceneObject)],
    e: &PrescribedEntry,
) -> Res<ScenePrescribed> {
    let object = find_object(ctx, &at.key("object"), objects, &e.object)?;
    if let SceneObject::FixedObstacle(_) = object {
        return Err(ctx.err(
            &at.key("object"),
            format!("'{}' is a fixed obstacle: its nodes never move", e.object),
        ));
    }
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
    let (key, selection) = e.selection(ctx, at)?;
    let label = e.object.as_str();
    let located = |err: StarkError| ctx.stark(&at.key(key), err);
    let prescribed = &mut sim.deformables.prescribed;
    let (handle, n) = match selection {
        Selection::InBox { inside, b } => {
            check_box(ctx, &at.key(key), b)?;
            let (center, size) = (Vector3::from(b.center_m), Vector3::from(b.size_m));
            let (h, n) = prescribed
                .add_in_box(&sim.nodes, set, label, center, size, inside, params)
                .map_err(located)?;
            if n == 0 {
                let where_ = if inside { "inside" } else { "outside" };
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
        Selection::Nodes(nodes) => {
            if nodes.is_empty() {
                return Err(ctx.err(&at.key("nodes"), "the node list is empty"));
            }
            let h = prescribed.add(&sim.nodes, set, label, nodes, params).map_err(located)?;
            (h, nodes.len())
        }
        Selection::All(false) => {
            return Err(ctx.err(
                &at.key("all"),
                "`all = false` selects nothing: give one of `inside_box`, `outside_box`, `nodes` or `all = true`",
            ))
        }
        Selection::All(true) => {
            let nodes: Vec<usize> = (0..set.len as usize).collect();
            let h = prescribed
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

//! `[[attachment]]` entries: nodes of one object glued to nodes or triangles of another
//! ([`Attachments`](crate::deformables::Attachments)), given as node lists or found by distance.

use super::errors::{param_error, At, Ctx, Res};
use super::{find_object, SceneObject};
use crate::deformables::{AttachmentHandle, AttachmentParams};
use crate::simulation::Simulation;
use serde::Deserialize;

/// An `[[attachment]]`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct AttachmentEntry {
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

pub(super) fn build_attachment(
    sim: &mut Simulation,
    ctx: &Ctx,
    at: &At,
    objects: &[(String, SceneObject)],
    e: &AttachmentEntry,
) -> Res<(String, AttachmentHandle)> {
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

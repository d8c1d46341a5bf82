//! `[[obstacle]]` entries: kinematic triangle surfaces whose nodes follow prescribed targets
//! ([`Simulation::add_prescribed_surface`]), optionally moved by a [`Motion`], or with `fixed =
//! true` surfaces fixed in the world ([`Simulation::add_fixed_surface`]).

use super::errors::{At, Ctx, Res};
use super::events::Motion;
use super::geometry::{
    check_positive, inline_shape, mesh_path, one_geometry, place, shape_error, BoxGenerator, CylinderGenerator,
    Geometry, Rotate, SphereGenerator, SurfaceGrid,
};
use super::SceneObject;
use crate::rigidbodies::Shape;
use crate::simulation::Simulation;
use nalgebra::Vector3;
use serde::Deserialize;
use std::path::Path;

/// Prescribed-position stiffness of an obstacle that gives none, N/m.
const DEFAULT_OBSTACLE_STIFFNESS: f64 = 1e6;

/// An `[[obstacle]]`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct ObstacleEntry {
    pub(super) name: String,
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
    #[serde(default)]
    fixed: bool,
}

/// The geometry sources of an obstacle: a closed shape, a mesh file, or a flat grid.
enum ObstacleSource<'e> {
    Shape(Shape),
    Grid(&'e SurfaceGrid),
}

pub(super) fn build_obstacle(
    sim: &mut Simulation,
    ctx: &Ctx,
    base_dir: &Path,
    at: &At,
    e: &ObstacleEntry,
) -> Res<SceneObject> {
    let shape = |s: Option<Shape>| s.map(ObstacleSource::Shape);
    let geometry = one_geometry(
        ctx,
        at,
        [
            ("sphere", shape(e.sphere.as_ref().map(Shape::from))),
            ("box", shape(e.box_.as_ref().map(Shape::from))),
            ("cylinder", shape(e.cylinder.as_ref().map(Shape::from))),
            ("grid", e.grid.as_ref().map(ObstacleSource::Grid)),
            (
                "mesh",
                shape(e.mesh.as_deref().map(|f| Shape::mesh_file(mesh_path(base_dir, f)))),
            ),
        ],
        e.vertices_m.as_deref(),
        ("triangles", e.triangles.as_deref()),
    )?;
    let key = geometry.key();
    let source = match geometry {
        Geometry::Source { source, .. } => source,
        Geometry::Inline { vertices_m, elements } => {
            ObstacleSource::Shape(inline_shape(vertices_m, elements, Vector3::repeat(1.0)))
        }
    };
    let (mut vertices, triangles) = match source {
        ObstacleSource::Shape(shape) => {
            let m = shape.surface_mesh().map_err(|err| shape_error(ctx, at, key, err))?;
            (m.vertices, m.elements)
        }
        ObstacleSource::Grid(g) => g.mesh(ctx, at)?,
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
    if e.fixed {
        for (field, given) in [("stiffness", e.stiffness.is_some()), ("motion", e.motion.is_some())] {
            if given {
                return Err(ctx.err(
                    &at.key(field),
                    format!("obstacle '{}' is fixed (`fixed = true`): it has no `{field}`", e.name),
                ));
            }
        }
        let handle = sim
            .add_fixed_surface(&e.name, &vertices, &triangles, thickness)
            .map_err(|err| ctx.stark(&at.key(key), err))?;
        return Ok(SceneObject::FixedObstacle(handle));
    }
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
    Ok(SceneObject::Obstacle(handle))
}

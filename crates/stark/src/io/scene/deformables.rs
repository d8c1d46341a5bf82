//! `[[surface]]`, `[[volume]]` and `[[line]]` entries: a material, one geometry and a placement,
//! built through [`Simulation::add_surface`], [`Simulation::add_volume`] and
//! [`Simulation::add_line`]. The three differ only in their generators, the mesh files they read
//! and the elements they take.

use super::errors::{At, Ctx, Res};
use super::geometry::{check_grid, mesh_path, one_geometry, place, Rotate, SurfaceGrid};
use super::materials::{object_error, resolve_material};
use crate::error::StarkError;
use crate::io::mesh_files::{load_tet_mesh, load_triangle_mesh};
use crate::presets::meshes;
use crate::presets::{LineHandle, LineMaterial, SurfaceHandle, SurfaceMaterial, VolumeHandle, VolumeMaterial};
use crate::simulation::Simulation;
use nalgebra::Vector3;
use serde::Deserialize;
use std::path::Path;

/// `grid = { size_m, cells }` of a volume: a box of tetrahedra.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct VolumeGrid {
    size_m: [f64; 3],
    cells: [usize; 3],
}

/// `segments = { begin_m, end_m, count }` of a line: a straight polyline.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LineSegments {
    begin_m: [f64; 3],
    end_m: [f64; 3],
    count: usize,
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

/// A `[[surface]]`: a triangle mesh.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SurfaceEntry {
    pub(super) name: String,
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

/// A `[[volume]]`: a tetrahedral mesh.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct VolumeEntry {
    pub(super) name: String,
    grid: Option<VolumeGrid>,
    mesh: Option<String>,
    vertices_m: Option<Vec<[f64; 3]>>,
    elements: Option<Vec<[usize; 4]>>,
    translate_m: Option<[f64; 3]>,
    rotate_deg: Option<Rotate>,
    scale: Option<f64>,
    material: toml::Value,
}

/// A `[[line]]`: a polyline of segments.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct LineEntry {
    pub(super) name: String,
    segments: Option<LineSegments>,
    vertices_m: Option<Vec<[f64; 3]>>,
    elements: Option<Vec<[usize; 2]>>,
    translate_m: Option<[f64; 3]>,
    rotate_deg: Option<Rotate>,
    scale: Option<f64>,
    material: toml::Value,
}

/// The geometry sources of a surface.
enum SurfaceSource<'e> {
    Grid(&'e SurfaceGrid),
    Cup(&'e CupGenerator),
    Mesh(&'e str),
}

pub(super) fn build_surface(
    sim: &mut Simulation,
    ctx: &Ctx,
    base_dir: &Path,
    at: &At,
    e: &SurfaceEntry,
) -> Res<SurfaceHandle> {
    let material: SurfaceMaterial = resolve_material(ctx, at, &e.material)?;
    let geometry = one_geometry(
        ctx,
        at,
        [
            ("grid", e.grid.as_ref().map(SurfaceSource::Grid)),
            ("cup", e.cup.as_ref().map(SurfaceSource::Cup)),
            ("mesh", e.mesh.as_deref().map(SurfaceSource::Mesh)),
        ],
        e.vertices_m.as_deref(),
        ("elements", e.elements.as_deref()),
    )?;
    let key = geometry.key();
    let (mut vertices, triangles) = geometry.into_mesh(|source| match source {
        SurfaceSource::Cup(cup) => {
            let m = meshes::cup_mesh(&cup.shape()).map_err(|err| match &err {
                StarkError::InvalidParameter { field, .. } => {
                    let field = field.to_string();
                    ctx.stark(&at.keys(&["cup", &field]), err)
                }
                _ => ctx.stark(&at.key("cup"), err),
            })?;
            Ok((m.vertices, m.elements))
        }
        SurfaceSource::Grid(g) => g.mesh(ctx, at),
        SurfaceSource::Mesh(file) => {
            let m = load_triangle_mesh(mesh_path(base_dir, file))
                .map_err(|err| ctx.err(&at.key("mesh"), err.to_string()))?;
            Ok((m.vertices, m.elements))
        }
    })?;
    place(ctx, at, &mut vertices, e.scale, e.rotate_deg.as_ref(), e.translate_m)?;
    sim.add_surface(&e.name, &vertices, &triangles, &material)
        .map_err(|err| object_error(ctx, at, &e.material, key, err))
}

/// The geometry sources of a volume.
enum VolumeSource<'e> {
    Grid(&'e VolumeGrid),
    Mesh(&'e str),
}

pub(super) fn build_volume(
    sim: &mut Simulation,
    ctx: &Ctx,
    base_dir: &Path,
    at: &At,
    e: &VolumeEntry,
) -> Res<VolumeHandle> {
    let material: VolumeMaterial = resolve_material(ctx, at, &e.material)?;
    let geometry = one_geometry(
        ctx,
        at,
        [
            ("grid", e.grid.as_ref().map(VolumeSource::Grid)),
            ("mesh", e.mesh.as_deref().map(VolumeSource::Mesh)),
        ],
        e.vertices_m.as_deref(),
        ("elements", e.elements.as_deref()),
    )?;
    let key = geometry.key();
    let (mut vertices, tets) = geometry.into_mesh(|source| match source {
        VolumeSource::Grid(g) => {
            check_grid(ctx, &at.key("grid"), &g.size_m, &g.cells, "cells")?;
            let m = meshes::tet_grid(Vector3::zeros(), Vector3::from(g.size_m), g.cells);
            Ok((m.vertices, m.elements))
        }
        VolumeSource::Mesh(file) => {
            let m = load_tet_mesh(mesh_path(base_dir, file)).map_err(|err| {
                ctx.err(
                    &at.key("mesh"),
                    format!("{err} (a volume needs a tetrahedral mesh: .vtk or .msh)"),
                )
            })?;
            Ok((m.vertices, m.elements))
        }
    })?;
    place(ctx, at, &mut vertices, e.scale, e.rotate_deg.as_ref(), e.translate_m)?;
    sim.add_volume(&e.name, &vertices, &tets, &material)
        .map_err(|err| object_error(ctx, at, &e.material, key, err))
}

pub(super) fn build_line(sim: &mut Simulation, ctx: &Ctx, at: &At, e: &LineEntry) -> Res<LineHandle> {
    let material: LineMaterial = resolve_material(ctx, at, &e.material)?;
    let geometry = one_geometry(
        ctx,
        at,
        [("segments", e.segments.as_ref())],
        e.vertices_m.as_deref(),
        ("elements", e.elements.as_deref()),
    )?;
    let key = geometry.key();
    let (mut vertices, segments) = geometry.into_mesh(|s| {
        let ends = s.begin_m.iter().chain(&s.end_m);
        if !ends.clone().all(|c| c.is_finite()) {
            return Err(ctx.err(&at.key("segments"), "begin_m and end_m must be finite"));
        }
        if s.count == 0 {
            return Err(ctx.err(&at.keys(&["segments", "count"]), "count = 0 must be positive"));
        }
        let m = meshes::segment_line(Vector3::from(s.begin_m), Vector3::from(s.end_m), s.count);
        Ok((m.vertices, m.elements))
    })?;
    place(ctx, at, &mut vertices, e.scale, e.rotate_deg.as_ref(), e.translate_m)?;
    sim.add_line(&e.name, &vertices, &segments, &material)
        .map_err(|err| object_error(ctx, at, &e.material, key, err))
}

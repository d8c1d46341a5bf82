//! What the entries with a geometry share: the check that an entry gives exactly one geometry
//! (a generator table, a mesh file or an inline mesh) and the [`Geometry`] it returns, the
//! generator tables of the closed shapes, the placement (`scale`, `rotate_deg`, `translate_m`) and
//! the small checks of vectors and orientations.

use super::errors::{At, Ctx, Res};
use crate::geometry::mesh;
use crate::rigidbodies::{Shape, ShapeError};
use nalgebra::{Quaternion, Unit, UnitQuaternion, Vector3};
use serde::Deserialize;
use std::path::Path;

/// Vertices and elements of a mesh.
pub(super) type MeshData<E> = (Vec<Vector3<f64>>, Vec<E>);

/// The one geometry an entry gives.
pub(super) enum Geometry<'e, S, E> {
    /// A generator table or a mesh file, under the entry's `key`; `S` is the entry's own enum of
    /// these sources.
    Source { key: &'static str, source: S },
    /// Inline `vertices_m` with their elements (`elements` or `triangles`).
    Inline {
        vertices_m: &'e [[f64; 3]],
        elements: &'e [E],
    },
}

impl<S, E: Clone> Geometry<'_, S, E> {
    /// The entry's key of this geometry, where errors about it are located (`vertices_m` for an
    /// inline mesh).
    pub(super) fn key(&self) -> &'static str {
        match self {
            Geometry::Source { key, .. } => key,
            Geometry::Inline { .. } => "vertices_m",
        }
    }

    /// The vertices and elements: an inline mesh as given, a source through `mesh_of`.
    pub(super) fn into_mesh(self, mesh_of: impl FnOnce(S) -> Res<MeshData<E>>) -> Res<MeshData<E>> {
        match self {
            Geometry::Source { source, .. } => mesh_of(source),
            Geometry::Inline { vertices_m, elements } => Ok((vectors(vertices_m), elements.to_vec())),
        }
    }
}

/// Check that an entry gives exactly one geometry and return it. `sources` are the entry's
/// generator keys and, where it takes one, `mesh` (last), each with its value if given;
/// `vertices_m` and `elements` (under its key) are the inline mesh, which gives both or neither.
pub(super) fn one_geometry<'e, S, E>(
    ctx: &Ctx,
    at: &At,
    sources: impl IntoIterator<Item = (&'static str, Option<S>)>,
    vertices_m: Option<&'e [[f64; 3]]>,
    elements: (&'static str, Option<&'e [E]>),
) -> Res<Geometry<'e, S, E>> {
    let mut keys = Vec::new();
    let mut given = Vec::new();
    let mut chosen = None;
    for (key, source) in sources {
        keys.push(format!("`{key}`"));
        if let Some(source) = source {
            given.push(key);
            chosen.get_or_insert(Geometry::Source { key, source });
        }
    }
    let (elements_key, elements) = elements;
    match (vertices_m, elements) {
        (Some(vertices_m), Some(elements)) => {
            given.push("vertices_m");
            chosen.get_or_insert(Geometry::Inline { vertices_m, elements });
        }
        (None, None) => {}
        (v, _) => {
            let (has, missing) = if v.is_some() {
                ("vertices_m", elements_key)
            } else {
                (elements_key, "vertices_m")
            };
            return Err(ctx.err(
                &at.key(has),
                format!("`{has}` needs `{missing}` (inline geometry gives both)"),
            ));
        }
    }
    let options = format!("{} or `vertices_m` + `{elements_key}`", keys.join(", "));
    match (given.len(), chosen) {
        (1, Some(one)) => Ok(one),
        (0, _) => Err(ctx.err(at, format!("no geometry: give one of {options}"))),
        _ => Err(ctx.err(
            &at.key(given[1]),
            format!("more than one geometry ({}): give one of {options}", given.join(", ")),
        )),
    }
}

/// Points as vectors.
pub(super) fn vectors(points: &[[f64; 3]]) -> Vec<Vector3<f64>> {
    points.iter().map(|v| Vector3::from(*v)).collect()
}

/// The path of a mesh file given in the scene: relative to the scene file's directory.
pub(super) fn mesh_path(base_dir: &Path, file: &str) -> std::path::PathBuf {
    base_dir.join(file)
}

/// `rotate_deg = { angle, axis }`.
#[derive(Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct Rotate {
    pub(super) angle: f64,
    pub(super) axis: [f64; 3],
}

/// Apply `scale`, then `rotate_deg`, then `translate_m`.
pub(super) fn place(
    ctx: &Ctx,
    at: &At,
    vertices: &mut [Vector3<f64>],
    scale: Option<f64>,
    rotate: Option<&Rotate>,
    translate: Option<[f64; 3]>,
) -> Res<()> {
    if let Some(s) = scale {
        if !(s > 0.0 && s.is_finite()) {
            return Err(ctx.err(&at.key("scale"), format!("scale = {s} must be positive and finite")));
        }
        mesh::scale(vertices, s);
    }
    if let Some(r) = rotate {
        let axis = Vector3::from(r.axis);
        if !(r.angle.is_finite() && axis.iter().all(|a| a.is_finite()) && axis.norm() > 0.0) {
            return Err(rotation_error(ctx, at, r));
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

/// A `rotate_deg` with a non-finite angle or a zero axis.
fn rotation_error(ctx: &Ctx, at: &At, r: &Rotate) -> super::SceneError {
    ctx.err(
        &at.key("rotate_deg"),
        format!(
            "rotation by {} deg about {:?} needs a finite angle and a non-zero axis",
            r.angle, r.axis
        ),
    )
}

/// `grid = { size_m, quads }`: a flat rectangle of triangles in the xy plane.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SurfaceGrid {
    pub(super) size_m: [f64; 2],
    pub(super) quads: [usize; 2],
}

impl SurfaceGrid {
    /// Its vertices and triangles, the sizes checked (`at` is the entry).
    pub(super) fn mesh(&self, ctx: &Ctx, at: &At) -> Res<MeshData<[usize; 3]>> {
        check_grid(ctx, &at.key("grid"), &self.size_m, &self.quads, "quads")?;
        let m = crate::presets::meshes::triangle_grid([0.0, 0.0], self.size_m, self.quads, 0.0);
        Ok((m.vertices, m.elements))
    }
}

/// Check a grid generator's `size_m` and element counts (under `counts_key`).
pub(super) fn check_grid(ctx: &Ctx, at: &At, size: &[f64], counts: &[usize], counts_key: &str) -> Res<()> {
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

fn default_sphere_subdivisions() -> usize {
    2
}

fn default_cylinder_slices() -> usize {
    16
}

fn default_cylinder_stacks() -> usize {
    1
}

fn default_capsule_slices() -> usize {
    16
}

fn default_capsule_rings() -> usize {
    4
}

fn default_torus_major_segments() -> usize {
    32
}

fn default_torus_minor_segments() -> usize {
    16
}

/// `sphere = { radius_m, subdivisions }`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SphereGenerator {
    radius_m: f64,
    #[serde(default = "default_sphere_subdivisions")]
    subdivisions: usize,
}

/// `box = { size_m }`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct BoxGenerator {
    size_m: [f64; 3],
}

/// `capsule = { radius_m, height_m, slices, cap_rings }`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct CapsuleGenerator {
    radius_m: f64,
    height_m: f64,
    #[serde(default = "default_capsule_slices")]
    slices: usize,
    #[serde(default = "default_capsule_rings")]
    cap_rings: usize,
}

/// `cylinder = { radius_m, height_m, slices, stacks }`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct CylinderGenerator {
    radius_m: f64,
    height_m: f64,
    #[serde(default = "default_cylinder_slices")]
    slices: usize,
    #[serde(default = "default_cylinder_stacks")]
    stacks: usize,
}

/// `torus = { major_radius_m, minor_radius_m, major_segments, minor_segments }`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TorusGenerator {
    major_radius_m: f64,
    minor_radius_m: f64,
    #[serde(default = "default_torus_major_segments")]
    major_segments: usize,
    #[serde(default = "default_torus_minor_segments")]
    minor_segments: usize,
}

impl From<&SphereGenerator> for Shape {
    fn from(g: &SphereGenerator) -> Shape {
        Shape::Sphere {
            radius_m: g.radius_m,
            subdivisions: g.subdivisions,
        }
    }
}

impl From<&BoxGenerator> for Shape {
    fn from(g: &BoxGenerator) -> Shape {
        Shape::Box {
            size_m: Vector3::from(g.size_m),
        }
    }
}

impl From<&CapsuleGenerator> for Shape {
    fn from(g: &CapsuleGenerator) -> Shape {
        Shape::Capsule {
            radius_m: g.radius_m,
            height_m: g.height_m,
            slices: g.slices,
            cap_rings: g.cap_rings,
        }
    }
}

impl From<&CylinderGenerator> for Shape {
    fn from(g: &CylinderGenerator) -> Shape {
        Shape::Cylinder {
            radius_m: g.radius_m,
            height_m: g.height_m,
            slices: g.slices,
            stacks: g.stacks,
        }
    }
}

impl From<&TorusGenerator> for Shape {
    fn from(g: &TorusGenerator) -> Shape {
        Shape::Torus {
            major_radius_m: g.major_radius_m,
            minor_radius_m: g.minor_radius_m,
            major_segments: g.major_segments,
            minor_segments: g.minor_segments,
        }
    }
}

/// An inline triangle mesh as a [`Shape`].
pub(super) fn inline_shape(vertices_m: &[[f64; 3]], triangles: &[[usize; 3]], scale: Vector3<f64>) -> Shape {
    Shape::Mesh {
        vertices_m: vectors(vertices_m),
        triangles: triangles.to_vec(),
        scale,
    }
}

/// A [`ShapeError`] of the geometry given under `key` (`box`, `sphere`, ..., `mesh`,
/// `vertices_m`) located at its field: `box.size_m`, `sphere.radius_m`, `mesh`,
/// `triangles[i]`, ...
pub(super) fn shape_error(ctx: &Ctx, at: &At, key: &str, e: ShapeError) -> super::SceneError {
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

/// `key = value` must be positive and finite (in `unit`).
pub(super) fn check_positive(ctx: &Ctx, at: &At, key: &str, value: f64, unit: &str) -> Res<()> {
    if value > 0.0 && value.is_finite() {
        Ok(())
    } else {
        Err(ctx.err(
            &at.key(key),
            format!("{key} = {value} must be positive and finite ({unit})"),
        ))
    }
}

/// The vector `key = v`, checked finite.
pub(super) fn finite(ctx: &Ctx, at: &At, key: &str, v: [f64; 3]) -> Res<Vector3<f64>> {
    if v.iter().all(|c| c.is_finite()) {
        Ok(Vector3::from(v))
    } else {
        Err(ctx.err(&at.key(key), format!("{key} = {v:?} must be finite")))
    }
}

/// An orientation from `rotate_deg = { angle, axis }` or `quaternion_wxyz = [w, x, y, z]`
/// (normalised); `None` if neither is given.
pub(super) fn orientation(
    ctx: &Ctx,
    at: &At,
    rotate: Option<&Rotate>,
    quaternion: Option<[f64; 4]>,
) -> Res<Option<UnitQuaternion<f64>>> {
    match (rotate, quaternion) {
        (Some(_), Some(_)) => Err(ctx.err(
            &at.key("quaternion_wxyz"),
            "give the orientation once: `rotate_deg` or `quaternion_wxyz`",
        )),
        (Some(r), None) => {
            let axis = Vector3::from(r.axis);
            if !(r.angle.is_finite() && axis.iter().all(|a| a.is_finite()) && axis.norm() > 0.0) {
                return Err(rotation_error(ctx, at, r));
            }
            Ok(Some(UnitQuaternion::from_axis_angle(
                &Unit::new_normalize(axis),
                r.angle.to_radians(),
            )))
        }
        (None, Some(q)) => {
            let quat = Quaternion::new(q[0], q[1], q[2], q[3]);
            if !(q.iter().all(|c| c.is_finite()) && quat.norm() > 1e-12) {
                return Err(ctx.err(
                    &at.key("quaternion_wxyz"),
                    format!("quaternion_wxyz = {q:?} must be finite and non-zero"),
                ));
            }
            Ok(Some(UnitQuaternion::from_quaternion(quat)))
        }
        (None, None) => Ok(None),
    }
}

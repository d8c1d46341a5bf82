//! `[[rigid_body]]` and `[[joint]]` entries of scene files.
//!
//! A rigid body is built from a shape (a primitive, a mesh file or an inline mesh), its mass (or
//! density) and a pose, through [`Simulation::add_rigid_body`] and
//! [`Simulation::add_rigid_collision_mesh`] (or [`Simulation::add_rigid_output_mesh`] when it
//! takes no part in contact); `fixed = true` adds a fix joint, which a `motion` or `keyframes`
//! drive through [`Simulation::set_fixed_transform`]. A joint entry is a [`JointKind`] (its `type`
//! and fields) plus the fields every joint takes, built by [`Simulation::add_joint`].

use super::{
    check_positive, geometry_key, mesh_path, shape_error, At, BoxGenerator, CapsuleGenerator, Ctx, CylinderGenerator,
    Motion, Rotate, SceneError, SceneObject, SphereGenerator,
};
use crate::contact::ContactHandle;
use crate::deformables::NodeSetHandle;
use crate::error::StarkError;
use crate::rigidbodies::joints::{JointHandle, JointKind, JointParams};
use crate::rigidbodies::{Mass, MassProperties, RigidBodyHandle, RigidBodyParams, Shape, ShapeError};
use crate::simulation::Simulation;
use nalgebra::{Matrix3, Quaternion, Unit, UnitQuaternion, Vector3};
use serde::Deserialize;
use std::path::Path;

type Res<T> = std::result::Result<T, SceneError>;

/// The handles of a `[[rigid_body]]`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SceneRigidBody {
    /// The body.
    pub body: RigidBodyHandle,
    /// The vertices of its mesh (they move with the body; attachments may name them).
    pub nodes: NodeSetHandle,
    /// Its contact object, if it takes part in contact.
    pub contact: Option<ContactHandle>,
}

fn default_torus_major_segments() -> usize {
    32
}

fn default_torus_minor_segments() -> usize {
    16
}

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

/// A pose a fixed body passes through at `time_s`; a missing position or orientation keeps the
/// previous keyframe's.
#[derive(Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct Keyframe {
    time_s: f64,
    position_m: Option<[f64; 3]>,
    rotate_deg: Option<Rotate>,
    quaternion_wxyz: Option<[f64; 4]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RigidBodyEntry {
    pub(super) name: String,
    #[serde(rename = "box")]
    box_: Option<BoxGenerator>,
    sphere: Option<SphereGenerator>,
    cylinder: Option<CylinderGenerator>,
    capsule: Option<CapsuleGenerator>,
    torus: Option<TorusGenerator>,
    mesh: Option<String>,
    vertices_m: Option<Vec<[f64; 3]>>,
    triangles: Option<Vec<[usize; 3]>>,
    scale: Option<f64>,
    mass_kg: Option<f64>,
    density_kg_m3: Option<f64>,
    inertia_kg_m2: Option<[[f64; 3]; 3]>,
    position_m: Option<[f64; 3]>,
    rotate_deg: Option<Rotate>,
    quaternion_wxyz: Option<[f64; 4]>,
    velocity_m_s: Option<[f64; 3]>,
    angular_velocity_deg_s: Option<[f64; 3]>,
    linear_damping_1_s: Option<f64>,
    angular_damping_1_s: Option<f64>,
    force_n: Option<[f64; 3]>,
    torque_n_m: Option<[f64; 3]>,
    contact_thickness_m: Option<f64>,
    contact: Option<bool>,
    fixed: Option<bool>,
    motion: Option<Motion>,
    keyframes: Option<Vec<Keyframe>>,
    pub(super) spawn: Option<SpawnEntry>,
}

/// `spawn = { ... }` of a `[[rigid_body]]`: copies of the body added during the run
/// ([`Simulation::add_spawn`]), named `<name>_1`, `<name>_2`, ...
#[derive(Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SpawnEntry {
    /// Time of the first copy, s.
    start_s: f64,
    /// Time between copies, s (default: 0, all at once).
    #[serde(default)]
    every_s: f64,
    /// Number of copies.
    pub(super) count: usize,
    /// Where the copies' centres of mass go, in turn, m (default: the body's `position_m`).
    positions_m: Option<Vec<[f64; 3]>>,
    /// Lower each copy straight down until it is this far above what it would land on, m
    /// (default: place it where given).
    drop_to_gap_m: Option<f64>,
}

/// Whom a spawned body's copies have friction with (from `[[friction]]` entries).
#[derive(Clone)]
pub(super) enum FrictionPartner {
    /// An object present from the start.
    Present(ContactHandle),
    /// The copies of a spawned body (`<name>_1` .. `<name>_<count>`), those spawned so far.
    Spawned { name: String, count: usize },
}

/// The name of copy `k` (from 1) of spawned body `name`.
pub(super) fn spawned_name(name: &str, k: usize) -> String {
    format!("{name}_{k}")
}

/// Register the spawns of a `[[rigid_body]]` with `spawn`: everything is checked now (shape,
/// mass, pose, velocities, damping), the copies are added at their times with the friction of
/// `friction` (partner and μ).
pub(super) fn spawn_rigid_body(
    sim: &mut Simulation,
    ctx: &Ctx,
    base_dir: &Path,
    at: &At,
    e: &RigidBodyEntry,
    friction: Vec<(FrictionPartner, f64)>,
) -> Res<()> {
    let spawn = e.spawn.clone().expect("called for spawned bodies");
    let sat = at.key("spawn");
    for (key, given) in [
        ("fixed", e.fixed.is_some()),
        ("motion", e.motion.is_some()),
        ("keyframes", e.keyframes.is_some()),
    ] {
        if given {
            return Err(ctx.err(&at.key(key), format!("a spawned body cannot take `{key}`")));
        }
    }
    if !spawn.start_s.is_finite() {
        return Err(ctx.err(
            &sat.key("start_s"),
            format!("start_s = {} must be finite", spawn.start_s),
        ));
    }
    if !(spawn.every_s >= 0.0 && spawn.every_s.is_finite()) {
        return Err(ctx.err(
            &sat.key("every_s"),
            format!("every_s = {} must be non-negative (s)", spawn.every_s),
        ));
    }
    if spawn.count == 0 {
        return Err(ctx.err(&sat.key("count"), "count must be at least 1"));
    }
    if let Some(g) = spawn.drop_to_gap_m {
        check_positive(ctx, &sat, "drop_to_gap_m", g, "m")?;
    }
    let shape = shape(ctx, base_dir, at, e)?;
    let positions: Vec<Vector3<f64>> = match &spawn.positions_m {
        Some(p) if p.is_empty() => return Err(ctx.err(&sat.key("positions_m"), "positions_m is empty")),
        Some(p) => p
            .iter()
            .map(|&v| finite(ctx, &sat, "positions_m", v))
            .collect::<Res<_>>()?,
        None => vec![finite(ctx, at, "position_m", e.position_m.unwrap_or([0.0; 3]))?],
    };
    let q = orientation(ctx, at, e.rotate_deg.as_ref(), e.quaternion_wxyz)?.unwrap_or_else(UnitQuaternion::identity);
    let velocity = e.velocity_m_s.map(|v| finite(ctx, at, "velocity_m_s", v)).transpose()?;
    let angular = e
        .angular_velocity_deg_s
        .map(|w| finite(ctx, at, "angular_velocity_deg_s", w).map(|w| w.map(f64::to_radians)))
        .transpose()?;
    let thickness = e.contact_thickness_m.or(sim.settings.contact.default_thickness_m);
    if let Some(t) = thickness {
        check_positive(ctx, at, "contact_thickness_m", t, "m")?;
    }
    let contact = match (e.contact, thickness) {
        (Some(false), _) | (None, None) => None,
        (_, Some(t)) => Some(t),
        (Some(true), None) => return Err(no_thickness(ctx, at, &e.name)),
    };
    let params = RigidBodyParams {
        linear_damping_1_s: e.linear_damping_1_s.unwrap_or(0.0),
        angular_damping_1_s: e.angular_damping_1_s.unwrap_or(0.0),
    };
    params.validate(&e.name).map_err(|err| ctx.stark(at, err))?;
    for (key, v) in [("force_n", e.force_n), ("torque_n_m", e.torque_n_m)] {
        if let Some(v) = v {
            finite(ctx, at, key, v)?;
        }
    }
    let (force, torque) = (e.force_n.map(Vector3::from), e.torque_n_m.map(Vector3::from));
    let shape = std::sync::Arc::new(shape);
    for k in 1..=spawn.count {
        let label = spawned_name(&e.name, k);
        let time_s = spawn.start_s + (k - 1) as f64 * spawn.every_s;
        let at_m = positions[(k - 1) % positions.len()];
        let (shape, friction, gap) = (shape.clone(), friction.clone(), spawn.drop_to_gap_m);
        let name = e.name.clone();
        sim.add_spawn(time_s, &label.clone(), move |sim| {
            let mut position = at_m;
            if let (Some(gap), Some(_)) = (gap, contact) {
                let world: Vec<Vector3<f64>> = shape.vertices.iter().map(|v| q * v + at_m).collect();
                if let Some(c) = sim.contact.clearance_below(&sim.nodes.x, &world, &shape.triangles) {
                    position.z -= (c - gap).max(0.0);
                }
            }
            let body = sim.add_rigid_body(&label, shape.mass.mass_kg, shape.mass.inertia_kg_m2, position, q)?;
            let mine = match contact {
                Some(t) => Some(
                    sim.add_rigid_collision_mesh(body, &shape.vertices, &shape.triangles, Some(t))?
                        .contact,
                ),
                None => {
                    sim.add_rigid_output_mesh(body, &shape.vertices, &shape.triangles)?;
                    None
                }
            };
            if let Some(v) = velocity {
                sim.set_body_velocity(body, v)?;
            }
            if let Some(w) = angular {
                sim.set_body_angular_velocity(body, w)?;
            }
            if let Some(f) = force {
                sim.set_body_force(body, f)?;
            }
            if let Some(t) = torque {
                sim.set_body_torque(body, t)?;
            }
            sim.set_body_params(body, params)?;
            if let Some(mine) = mine {
                for (partner, mu) in &friction {
                    match partner {
                        FrictionPartner::Present(h) => sim.contact.set_friction(mine, *h, *mu)?,
                        FrictionPartner::Spawned { name: other, count } => {
                            for j in 1..=*count {
                                if other == &name && j == k {
                                    continue;
                                }
                                if let Some(h) = sim.contact.object_by_label(&spawned_name(other, j)) {
                                    sim.contact.set_friction(mine, h, *mu)?;
                                }
                            }
                        }
                    }
                }
            }
            Ok(())
        })
        .map_err(|err| ctx.stark(&sat, err))?;
    }
    Ok(())
}

// ------------------------------------------------------------------------------------------
// Small checks
// ------------------------------------------------------------------------------------------

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
                return Err(ctx.err(
                    &at.key("rotate_deg"),
                    format!(
                        "rotation by {} deg about {:?} needs a finite angle and a non-zero axis",
                        r.angle, r.axis
                    ),
                ));
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

// ------------------------------------------------------------------------------------------
// Rigid bodies
// ------------------------------------------------------------------------------------------

/// A body's shape in its body frame (centre of mass at the origin) and its mass properties.
struct BodyShape {
    vertices: Vec<Vector3<f64>>,
    triangles: Vec<[usize; 3]>,
    mass: MassProperties,
}

/// The [`Shape`] of an entry (its generator table, `mesh` file or inline mesh) and its mass
/// properties, all checks done by [`Shape`].
fn shape(ctx: &Ctx, base_dir: &Path, at: &At, e: &RigidBodyEntry) -> Res<BodyShape> {
    let key = geometry_key(
        ctx,
        at,
        &[
            ("box", e.box_.is_some()),
            ("sphere", e.sphere.is_some()),
            ("cylinder", e.cylinder.is_some()),
            ("capsule", e.capsule.is_some()),
            ("torus", e.torus.is_some()),
        ],
        Some(e.mesh.is_some()),
        e.vertices_m.is_some(),
        ("triangles", e.triangles.is_some()),
    )?;
    let mass = match (e.mass_kg, e.density_kg_m3) {
        (None, None) => {
            return Err(ctx.err(
                at,
                format!(
                    "rigid body '{}' needs a mass: give `mass_kg` or `density_kg_m3`",
                    e.name
                ),
            ))
        }
        (Some(_), Some(_)) => {
            return Err(ctx.err(
                &at.key("density_kg_m3"),
                "give the mass once: `mass_kg` or `density_kg_m3`",
            ))
        }
        (Some(m), None) => Mass::Kg(m),
        (None, Some(rho)) => Mass::DensityKgM3(rho),
    };
    if e.scale.is_some() && !matches!(key, "mesh" | "vertices_m") {
        return Err(ctx.err(
            &at.key("scale"),
            format!("`scale` applies to `mesh` and inline geometry; give the {key}'s size instead"),
        ));
    }
    if let Some(s) = e.scale {
        check_positive(ctx, at, "scale", s, "a factor")?;
    }
    let scale = Vector3::repeat(e.scale.unwrap_or(1.0));
    let shape = match key {
        "box" => Shape::Box {
            size_m: Vector3::from(e.box_.as_ref().expect("checked").size_m),
        },
        "sphere" => {
            let g = e.sphere.as_ref().expect("checked");
            Shape::Sphere {
                radius_m: g.radius_m,
                subdivisions: g.subdivisions,
            }
        }
        "cylinder" => {
            let g = e.cylinder.as_ref().expect("checked");
            Shape::Cylinder {
                radius_m: g.radius_m,
                height_m: g.height_m,
                slices: g.slices,
                stacks: g.stacks,
            }
        }
        "capsule" => {
            let g = e.capsule.as_ref().expect("checked");
            Shape::Capsule {
                radius_m: g.radius_m,
                height_m: g.height_m,
                slices: g.slices,
                cap_rings: g.cap_rings,
            }
        }
        "torus" => {
            let g = e.torus.as_ref().expect("checked");
            Shape::Torus {
                major_radius_m: g.major_radius_m,
                minor_radius_m: g.minor_radius_m,
                major_segments: g.major_segments,
                minor_segments: g.minor_segments,
            }
        }
        "mesh" => Shape::MeshFile {
            path: mesh_path(base_dir, e.mesh.as_deref().expect("checked")),
            scale,
        },
        _ => super::inline_mesh(&e.vertices_m, &e.triangles, scale),
    };
    let located = |err: ShapeError| {
        let hint = if err.field == "surface" {
            " (give `mass_kg` and `inertia_kg_m2` for an open mesh)"
        } else {
            ""
        };
        let message = format!("{}{hint}", err.message);
        shape_error(ctx, at, key, ShapeError { message, ..err })
    };
    let (mesh, mut mass) = match (e.mass_kg, e.inertia_kg_m2) {
        // Mass and inertia given: a mesh need not be closed; its frame is the body's.
        (Some(m), Some(_)) if shape.primitive_volume_m3().is_none() => {
            check_positive(ctx, at, "mass_kg", m, "kg")?;
            let mesh = shape.surface_mesh().map_err(located)?;
            let props = MassProperties {
                mass_kg: m,
                center_of_mass_m: Vector3::zeros(),
                inertia_kg_m2: Matrix3::identity(),
            };
            (mesh, props)
        }
        _ => {
            let solid = shape.solid(mass).map_err(located)?;
            (solid.mesh, solid.mass)
        }
    };
    let com = mass.center_of_mass_m;
    let vertices = mesh.vertices.iter().map(|v| v - com).collect();
    mass.center_of_mass_m = Vector3::zeros();
    if let Some(j) = e.inertia_kg_m2 {
        let inertia = Matrix3::from_row_slice(&j.concat());
        let symmetric = (inertia - inertia.transpose()).norm() <= 1e-9 * inertia.norm();
        if !(inertia.iter().all(|c| c.is_finite()) && symmetric && inertia.symmetric_eigenvalues().min() > 0.0) {
            return Err(ctx.err(
                &at.key("inertia_kg_m2"),
                format!("inertia_kg_m2 = {j:?} must be symmetric positive definite (kg·m²)"),
            ));
        }
        mass.inertia_kg_m2 = inertia;
    }
    Ok(BodyShape {
        vertices,
        triangles: mesh.elements,
        mass,
    })
}

/// `contact = true` without a contact thickness.
fn no_thickness(ctx: &Ctx, at: &At, name: &str) -> SceneError {
    ctx.err(
        &at.key("contact"),
        format!(
            "rigid body '{name}' takes part in contact but has no contact thickness: give `contact_thickness_m` \
             or set `settings.contact.default_thickness_m`"
        ),
    )
}

/// The poses of a keyframed body: its initial pose at t = 0, then each keyframe.
type Poses = Vec<(f64, Vector3<f64>, UnitQuaternion<f64>)>;

fn resolve_keyframes(
    ctx: &Ctx,
    at: &At,
    frames: &[Keyframe],
    start: (Vector3<f64>, UnitQuaternion<f64>),
) -> Res<Poses> {
    let at = at.key("keyframes");
    if frames.is_empty() {
        return Err(ctx.err(&at, "the keyframe list is empty"));
    }
    let mut poses = vec![(0.0, start.0, start.1)];
    for (i, k) in frames.iter().enumerate() {
        let at = at.index(i);
        let (t_prev, p_prev, q_prev) = *poses.last().expect("initial pose");
        if !(k.time_s.is_finite() && k.time_s > t_prev) {
            return Err(ctx.err(
                &at.key("time_s"),
                format!(
                    "time_s = {} must be finite and after the previous keyframe ({t_prev} s; the motion starts from the initial pose at 0 s)",
                    k.time_s
                ),
            ));
        }
        let p = match k.position_m {
            Some(p) => finite(ctx, &at, "position_m", p)?,
            None => p_prev,
        };
        let q = orientation(ctx, &at, k.rotate_deg.as_ref(), k.quaternion_wxyz)?.unwrap_or(q_prev);
        poses.push((k.time_s, p, q));
    }
    Ok(poses)
}

/// The pose at time `t`: linear in position, spherical-linear in orientation between
/// keyframes; the last keyframe is held.
fn keyframe_pose(poses: &Poses, t: f64) -> (Vector3<f64>, UnitQuaternion<f64>) {
    let i = poses.partition_point(|p| p.0 <= t);
    if i == 0 {
        return (poses[0].1, poses[0].2);
    }
    if i == poses.len() {
        let last = poses[i - 1];
        return (last.1, last.2);
    }
    let (a, b) = (&poses[i - 1], &poses[i]);
    let s = (t - a.0) / (b.0 - a.0);
    (a.1 + (b.1 - a.1) * s, a.2.try_slerp(&b.2, s, 1e-12).unwrap_or(b.2))
}

/// Build a `[[rigid_body]]`: the body, its mesh, its initial state and, if fixed, its fix joint
/// (labelled `<name>.fixed`) with the events that move it.
pub(super) fn build_rigid_body(
    sim: &mut Simulation,
    ctx: &Ctx,
    base_dir: &Path,
    at: &At,
    e: &RigidBodyEntry,
) -> Res<(SceneRigidBody, Option<JointHandle>)> {
    let shape = shape(ctx, base_dir, at, e)?;
    let position = finite(ctx, at, "position_m", e.position_m.unwrap_or([0.0; 3]))?;
    let q = orientation(ctx, at, e.rotate_deg.as_ref(), e.quaternion_wxyz)?.unwrap_or_else(UnitQuaternion::identity);
    let located = |key: &'static str| move |err: StarkError| ctx.stark(&at.key(key), err);
    let body = sim
        .add_rigid_body(&e.name, shape.mass.mass_kg, shape.mass.inertia_kg_m2, position, q)
        .map_err(located("name"))?;

    let thickness = e.contact_thickness_m.or(sim.settings.contact.default_thickness_m);
    let (nodes, contact) = match (e.contact, thickness) {
        (Some(false), _) | (None, None) => {
            let nodes = sim
                .add_rigid_output_mesh(body, &shape.vertices, &shape.triangles)
                .map_err(located("name"))?;
            (nodes, None)
        }
        (_, Some(t)) => {
            check_positive(ctx, at, "contact_thickness_m", t, "m")?;
            let mesh = sim
                .add_rigid_collision_mesh(body, &shape.vertices, &shape.triangles, Some(t))
                .map_err(located("name"))?;
            (mesh.nodes, Some(mesh.contact))
        }
        (Some(true), None) => return Err(no_thickness(ctx, at, &e.name)),
    };

    if let Some(v) = e.velocity_m_s {
        let v = finite(ctx, at, "velocity_m_s", v)?;
        sim.set_body_velocity(body, v).map_err(located("velocity_m_s"))?;
    }
    if let Some(w) = e.angular_velocity_deg_s {
        let w = finite(ctx, at, "angular_velocity_deg_s", w)?.map(f64::to_radians);
        sim.set_body_angular_velocity(body, w)
            .map_err(located("angular_velocity_deg_s"))?;
    }
    if let Some(f) = e.force_n {
        let f = finite(ctx, at, "force_n", f)?;
        sim.set_body_force(body, f).map_err(located("force_n"))?;
    }
    if let Some(t) = e.torque_n_m {
        let t = finite(ctx, at, "torque_n_m", t)?;
        sim.set_body_torque(body, t).map_err(located("torque_n_m"))?;
    }
    if e.linear_damping_1_s.is_some() || e.angular_damping_1_s.is_some() {
        let params = RigidBodyParams {
            linear_damping_1_s: e.linear_damping_1_s.unwrap_or(0.0),
            angular_damping_1_s: e.angular_damping_1_s.unwrap_or(0.0),
        };
        sim.set_body_params(body, params).map_err(|err| match &err {
            StarkError::InvalidParameter { field, .. } => ctx.stark(&at.key(field), err),
            _ => ctx.stark(at, err),
        })?;
    }

    let moving = match (&e.motion, &e.keyframes) {
        (Some(_), Some(_)) => {
            return Err(ctx.err(
                &at.key("keyframes"),
                "give one scripted motion: `motion` or `keyframes`",
            ))
        }
        (Some(_), None) => Some("motion"),
        (None, Some(_)) => Some("keyframes"),
        (None, None) => None,
    };
    if let (Some(false), Some(key)) = (e.fixed, moving) {
        return Err(ctx.err(
            &at.key(key),
            format!("a scripted `{key}` drives a fixed body: remove `fixed = false`"),
        ));
    }
    let fix = if e.fixed.unwrap_or(moving.is_some()) {
        let fix = sim
            .add_fix_joint(&format!("{}.fixed", e.name), body, JointParams::default())
            .map_err(located("fixed"))?;
        if let Some(motion) = &e.motion {
            motion
                .validate()
                .map_err(|(field, message)| ctx.err(&at.keys(&["motion", field]), message))?;
            // The motion moves the initial pose (centre of mass `position`, orientation `q`).
            let (m, h, q_start) = (motion.clone(), fix.clone(), q);
            sim.add_time_event(motion.start_s, f64::INFINITY, move |sim, t| {
                let (translation, rotation) = m.transform_at(t);
                let r = UnitQuaternion::from_rotation_matrix(&rotation);
                sim.set_fixed_transform(&h, rotation * position + translation, r * q_start)
            });
        }
        if let Some(frames) = &e.keyframes {
            let poses = resolve_keyframes(ctx, at, frames, (position, q))?;
            let h = fix.clone();
            sim.add_time_event(0.0, f64::INFINITY, move |sim, t| {
                let (p, q) = keyframe_pose(&poses, t);
                sim.set_fixed_transform(&h, p, q)
            });
        }
        Some(fix)
    } else {
        None
    };
    Ok((SceneRigidBody { body, nodes, contact }, fix))
}

// ------------------------------------------------------------------------------------------
// Joints
// ------------------------------------------------------------------------------------------

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

#[cfg(test)]
mod tests {
    use super::super::{load_scene_with, parse_scene, parse_scene_with, LoadedScene};
    use super::*;
    use crate::energy::Node;
    use crate::presets::meshes;
    use crate::rigidbodies::joints::{Primitive, DEFAULT_CONTROLLER_DELAY};
    use crate::solver::Settings;
    use std::f64::consts::PI;
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

    fn parse(text: &str) -> LoadedScene {
        parse_scene_with(text, "test.toml", Path::new("."), quiet).unwrap_or_else(|e| panic!("{e}"))
    }

    fn parse_err(text: &str) -> SceneError {
        match parse_scene_with(text, "test.toml", Path::new("."), quiet) {
            Ok(_) => panic!("the scene parsed:\n{text}"),
            Err(StarkError::SceneFile(e)) => e,
            Err(other) => panic!("not a scene error: {other}"),
        }
    }

    fn bits(x: &[Vector3<f64>]) -> Vec<[u64; 3]> {
        x.iter()
            .map(|p| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
            .collect()
    }

    /// Positions, orientations and velocities of every body, as bits.
    fn body_bits(sim: &Simulation) -> Vec<u64> {
        let b = &sim.bodies;
        (0..b.len())
            .flat_map(|i| {
                let q = b.orientation[i].coords;
                b.position[i]
                    .iter()
                    .chain(q.iter())
                    .chain(b.velocity[i].iter())
                    .chain(b.angular_velocity[i].iter())
                    .map(|c| c.to_bits())
                    .collect::<Vec<_>>()
            })
            .collect()
    }

    fn close(a: &Vector3<f64>, b: &Vector3<f64>, tol: f64) -> bool {
        (a - b).norm() <= tol
    }

    #[test]
    fn shapes_masses_poses_and_initial_state() {
        let scene = parse(
            r#"
duration_s = 1.0
[settings]
contact.default_thickness_m = 0.001
[[rigid_body]]
name = "crate"
box = { size_m = [0.1, 0.2, 0.3] }
density_kg_m3 = 500.0
position_m = [1.0, 2.0, 3.0]
rotate_deg = { angle = 90.0, axis = [0.0, 0.0, 2.0] }
velocity_m_s = [0.1, 0.0, 0.0]
angular_velocity_deg_s = [0.0, 0.0, 180.0]
linear_damping_1_s = 0.5
force_n = [0.0, 0.0, 1.0]
torque_n_m = [0.0, 0.1, 0.0]
[[rigid_body]]
name = "ball"
sphere = { radius_m = 0.1, subdivisions = 1 }
mass_kg = 2.0
position_m = [5.0, 0.0, 0.0]
quaternion_wxyz = [0.0, 2.0, 0.0, 0.0]
contact = false
[[rigid_body]]
name = "can"
cylinder = { radius_m = 0.05, height_m = 0.2, slices = 8 }
mass_kg = 0.3
position_m = [-5.0, 0.0, 0.0]
contact_thickness_m = 0.003
[[rigid_body]]
name = "ring"
torus = { major_radius_m = 0.2, minor_radius_m = 0.05, major_segments = 8, minor_segments = 6 }
density_kg_m3 = 1000.0
position_m = [0.0, 5.0, 0.0]
[[rigid_body]]
name = "tet"
vertices_m = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
triangles = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]
scale = 0.5
mass_kg = 6.0
position_m = [0.0, -5.0, 0.0]
"#,
        );
        let sim = &scene.simulation;
        assert_eq!(sim.num_rigid_bodies(), 5);
        let body = |n: &str| scene.rigid_body(n).unwrap_or_else(|| panic!("no body {n}"));
        // The box: mass from the density, pose, velocities, damping, force and torque.
        let c = body("crate");
        let size = Vector3::new(0.1, 0.2, 0.3);
        let mass = 500.0 * (0.1 * 0.2 * 0.3);
        assert_eq!(sim.bodies.mass[c.body.i()], mass);
        assert_eq!(
            sim.bodies.inertia_local[c.body.i()],
            MassProperties::cuboid(mass, size).inertia_kg_m2
        );
        assert_eq!(sim.body_position(c.body), Vector3::new(1.0, 2.0, 3.0));
        let q = sim.body_orientation(c.body);
        assert!((q.angle() - PI / 2.0).abs() < 1e-15 && close(&q.axis().unwrap(), &Vector3::z(), 1e-15));
        assert_eq!(sim.body_velocity(c.body), Vector3::new(0.1, 0.0, 0.0));
        assert_eq!(sim.body_angular_velocity(c.body), Vector3::new(0.0, 0.0, PI));
        assert_eq!(sim.body_params(c.body).unwrap().linear_damping_1_s, 0.5);
        assert_eq!(sim.body_params(c.body).unwrap().angular_damping_1_s, 0.0);
        assert_eq!(sim.bodies.force[0], Vector3::new(0.0, 0.0, 1.0));
        assert_eq!(sim.bodies.torque[0], Vector3::new(0.0, 0.1, 0.0));
        // Its mesh follows the pose: the corner (−x, −y, −z)/2 turned 90° about z.
        let corner = sim.positions(c.nodes)[0];
        assert!(close(&corner, &Vector3::new(1.1, 1.95, 2.85), 1e-15), "{corner}");
        // The sphere: a half turn about x, no contact.
        let b = body("ball");
        assert_eq!(
            sim.bodies.inertia_local[b.body.i()],
            MassProperties::sphere(2.0, 0.1).inertia_kg_m2
        );
        assert!((sim.body_orientation(b.body).angle() - PI).abs() < 1e-15);
        assert!(b.contact.is_none());
        assert_eq!(b.nodes.len, 42);
        // The cylinder's and torus's meshes and masses.
        assert_eq!(body("can").nodes.len, 2 * 8 + 2);
        let ring = body("ring");
        assert_eq!(ring.nodes.len, 48);
        let ring_mass = 1000.0 * (2.0 * PI * PI * 0.2 * 0.05 * 0.05);
        assert_eq!(sim.bodies.mass[ring.body.i()], ring_mass);
        // The inline tetrahedron: scaled, recentred at its centre of mass, mass scaled to 6 kg.
        let tet = body("tet");
        let x = sim.positions(tet.nodes);
        assert!(close(&x[0], &Vector3::new(-0.125, -5.125, -0.125), 1e-15), "{}", x[0]);
        assert!(close(&x[1], &Vector3::new(0.375, -5.125, -0.125), 1e-15), "{}", x[1]);
        let v: Vec<_> = [[0.0, 0.0, 0.0], [0.5, 0.0, 0.0], [0.0, 0.5, 0.0], [0.0, 0.0, 0.5]]
            .iter()
            .map(|p| Vector3::from(*p))
            .collect();
        let tris = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        let props = MassProperties::from_mesh(&v, &tris, 1.0).unwrap();
        let expected = props.inertia_kg_m2 * (6.0 / props.mass_kg);
        assert!((sim.bodies.inertia_local[tet.body.i()] - expected).norm() < 1e-15);
        // Contact: thickness given, else the default; the sphere has none.
        let thickness: Vec<_> = sim
            .contact
            .objects()
            .iter()
            .map(|o| (o.label.clone(), o.thickness_m))
            .collect();
        assert_eq!(
            thickness,
            [
                ("crate".to_string(), 0.001),
                ("can".to_string(), 0.003),
                ("ring".to_string(), 0.001),
                ("tet".to_string(), 0.001)
            ]
        );
        // Every body's mesh is in the frames.
        let meshes: Vec<_> = sim.output.meshes.iter().map(|m| m.label.as_str()).collect();
        assert_eq!(meshes, ["crate", "ball", "can", "ring", "tet"]);
        assert!(scene.joints.is_empty());
    }

    #[test]
    fn keyframes_interpolate_and_hold() {
        let q1 = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), PI / 2.0);
        let poses: Poses = vec![
            (0.0, Vector3::new(2.0, 0.0, 0.0), UnitQuaternion::identity()),
            (0.5, Vector3::new(2.0, 0.0, 1.0), q1),
            (1.0, Vector3::new(3.0, 0.0, 1.0), q1),
        ];
        let (p, q) = keyframe_pose(&poses, 0.25);
        assert!(close(&p, &Vector3::new(2.0, 0.0, 0.5), 1e-15));
        assert!((q.angle() - PI / 4.0).abs() < 1e-15);
        let (p, q) = keyframe_pose(&poses, 0.75);
        assert!(close(&p, &Vector3::new(2.5, 0.0, 1.0), 1e-15));
        assert!(q.angle_to(&q1) < 1e-15);
        assert_eq!(keyframe_pose(&poses, 7.0).0, Vector3::new(3.0, 0.0, 1.0));
        assert_eq!(keyframe_pose(&poses, 0.0).0, Vector3::new(2.0, 0.0, 0.0));
    }

    #[test]
    fn fixed_bodies_follow_their_motion_and_keyframes() {
        let mut scene = parse(
            r#"
duration_s = 1.0
[settings]
time_step_s = 0.05
[[rigid_body]]
name = "lift"
box = { size_m = [0.2, 0.2, 0.2] }
mass_kg = 1.0
position_m = [0.3, 0.0, 0.0]
motion = { velocity_m_s = [0.0, 0.0, 0.5], angular_velocity_deg_s = 90.0, axis = [0.0, 0.0, 1.0], center_m = [0.1, 0.0, 0.0] }
[[rigid_body]]
name = "arm"
box = { size_m = [0.2, 0.2, 0.2] }
mass_kg = 1.0
position_m = [2.0, 0.0, 0.0]
keyframes = [
  { time_s = 0.5, position_m = [2.0, 0.0, 1.0], rotate_deg = { angle = 90.0, axis = [1.0, 0.0, 0.0] } },
  { time_s = 1.0, position_m = [3.0, 0.0, 1.0] },
]
[[rigid_body]]
name = "post"
box = { size_m = [0.2, 0.2, 0.2] }
mass_kg = 1.0
position_m = [0.0, 3.0, 0.0]
fixed = true
"#,
        );
        let labels: Vec<_> = scene.joints.iter().map(|j| j.label.as_str()).collect();
        assert_eq!(labels, ["lift.fixed", "arm.fixed", "post.fixed"]);
        let lift = scene.rigid_body("lift").unwrap().body;
        let arm = scene.rigid_body("arm").unwrap().body;
        let post = scene.rigid_body("post").unwrap().body;
        let fix = scene.joint("lift.fixed").unwrap().clone();
        let sim = &mut scene.simulation;
        for _ in 0..10 {
            sim.step().unwrap();
            let t = sim.time();
            // The lift: turned by 90°·t about the vertical through (0.1, 0, 0), raised by 0.5·t.
            let (s, c) = (90.0f64 * t).to_radians().sin_cos();
            let expected = Vector3::new(0.1 + 0.2 * c, 0.2 * s, 0.5 * t);
            let target = &sim.rigid_bodies.joints.potential.elements[fix.elements[0] as usize].nodes[0];
            let Node::World(target) = *target else {
                panic!("{target:?}")
            };
            assert!(close(&Vector3::from(target), &expected, 1e-14), "t = {t}: {target:?}");
            assert!(close(&sim.body_position(lift), &expected, 1e-3), "t = {t}");
            let turn = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), (90.0f64 * t).to_radians());
            assert!(
                sim.body_orientation(lift).angle_to(&turn) < 1f64.to_radians(),
                "t = {t}"
            );
            // The arm: up by 2·t and turning about x until 0.5 s.
            let z = (2.0 * t).min(1.0);
            assert!(
                close(&sim.body_position(arm), &Vector3::new(2.0, 0.0, z), 1e-3),
                "t = {t}"
            );
            let turn = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), (180.0 * t).min(90.0).to_radians());
            assert!(sim.body_orientation(arm).angle_to(&turn) < 1f64.to_radians(), "t = {t}");
            assert!(close(&sim.body_position(post), &Vector3::new(0.0, 3.0, 0.0), 1e-3));
        }
        assert!((sim.time() - 0.5).abs() < 1e-12);
        let state = sim.joint_state(&fix);
        assert!(state.violation_m <= 1e-3, "{state:?}");
    }

    /// One body per joint type (or two), each joint to the world or to a second body.
    const ALL_JOINTS: &str = r#"
duration_s = 1.0
[settings]
gravity_m_s2 = [0.0, 0.0, 0.0]
"#;

    fn all_joints_scene() -> String {
        let types = [
            ("ball", "point_m = [P]"),
            ("ball_cone", "point_m = [P]\naxis = [0.0, 0.0, 1.0]\nlimit_deg = 30.0"),
            ("hinge", "point_m = [P]\naxis = [0.0, 1.0, 0.0]"),
            ("hinge_limit", "point_m = [P]\naxis = [0.0, 1.0, 0.0]\nlimit_deg = 45.0"),
            ("universal", "point_m = [P]\naxis_a = [1.0, 0.0, 0.0]\naxis_b = [0.0, 1.0, 0.0]"),
            ("slider", "point_m = [P]\naxis = [0.0, 0.0, 1.0]"),
            ("prismatic", "point_m = [P]\naxis = [0.0, 0.0, 1.0]"),
            ("prismatic_press", "point_m = [P]\naxis = [0.0, 0.0, 1.0]\ntarget_velocity_m_s = 0.1\nmax_force_n = 10.0"),
            ("motor", "point_m = [P]\naxis = [0.0, 1.0, 0.0]\nmax_torque_n_m = 1.0\ntarget_schedule = [[0.0, 0.0], [1.0, 90.0]]"),
            ("hinge_servo", "point_m = [P]\naxis = [0.0, 1.0, 0.0]\ntarget_deg = 30.0\nmax_torque_n_m = 1.0\nresponse_time_s = 0.1"),
            ("prismatic_servo", "point_m = [P]\naxis = [0.0, 0.0, 1.0]\ntarget_schedule = [[0.0, 0.0], [0.5, 0.1]]\nmax_force_n = 10.0"),
            ("fix", ""),
            ("attachment", "a = \"base\""),
            ("distance", "point_a_m = [P]\npoint_b_m = [Q]"),
            ("distance_limits", "point_a_m = [P]\npoint_b_m = [Q]\nmin_m = 0.05\nmax_m = 0.2"),
            ("spring", "point_a_m = [P]\npoint_b_m = [Q]\nspring_stiffness_n_m = 100.0\ndamping_n_s_m = 1.0\nlimits_m = [0.05, 0.2]"),
            ("direction", "axis = [0.0, 0.0, 1.0]"),
            ("angle_limit", "axis = [0.0, 0.0, 1.0]\nlimit_deg = 10.0"),
            ("point_on_axis", "point_m = [P]\naxis = [1.0, 0.0, 0.0]"),
            ("linear_velocity", "point_m = [P]\naxis = [1.0, 0.0, 0.0]\ntarget_velocity_m_s = 0.2\nmax_force_n = 5.0\ndelay_m_s = 0.02"),
            ("angular_velocity", "axis = [0.0, 0.0, 1.0]\ntarget_velocity_deg_s = 45.0\nmax_torque_n_m = 2.0\ndelay_deg_s = 1.0"),
        ];
        let mut s = ALL_JOINTS.to_string();
        s += "[[rigid_body]]\nname = \"base\"\nbox = { size_m = [0.1, 0.1, 0.1] }\nmass_kg = 1.0\nposition_m = [0.0, -2.0, 0.0]\n";
        for (i, (t, _)) in types.iter().enumerate() {
            s += &format!(
                "[[rigid_body]]\nname = \"{t}\"\nbox = {{ size_m = [0.1, 0.1, 0.1] }}\nmass_kg = 1.0\nposition_m = [{}.0, 0.0, 0.0]\n",
                i
            );
        }
        for (i, (t, fields)) in types.iter().enumerate() {
            let p = format!("{i}.0, 0.0, 0.05");
            let q = format!("{i}.0, 0.0, -0.05");
            s += &format!(
                "[[joint]]\ntype = \"{t}\"\nb = \"{t}\"\n{}\n",
                fields
                    .replace("[P]", &format!("[{p}]"))
                    .replace("[Q]", &format!("[{q}]"))
            );
        }
        s
    }

    #[test]
    fn every_joint_type_is_built_registered_and_runs() {
        let mut scene = parse(&all_joints_scene());
        let names: Vec<_> = scene.joints.iter().map(|j| j.label.clone()).collect();
        assert_eq!(names.len(), 21);
        assert_eq!(names[0], "ball world-ball");
        assert_eq!(names[12], "attachment base-attachment");
        // The simulation knows the same joints, with all their elements.
        let joints = scene.joints.clone();
        let sim = &mut scene.simulation;
        assert_eq!(sim.rigid_bodies.named_joints, joints);
        let counts: Vec<_> = joints.iter().map(|j| j.elements.len()).collect();
        assert_eq!(counts, [1, 2, 2, 3, 2, 2, 3, 4, 3, 3, 4, 3, 3, 1, 1, 2, 1, 1, 1, 1, 1]);
        let elements = sim.rigid_bodies.joints.potential.elements.len();
        assert_eq!(elements, counts.iter().sum::<usize>());
        // Parameters arrive in SI units.
        let driver = |sim: &Simulation, name: &str| {
            let h = joints.iter().find(|j| j.label == name).unwrap();
            sim.rigid_bodies.joints.potential.elements[h.driver.unwrap() as usize].clone()
        };
        match driver(sim, "angular_velocity world-angular_velocity").primitive {
            Primitive::AngularVelocity {
                target_rad_s,
                max_torque_n_m,
                delay_rad_s,
                ..
            } => {
                assert_eq!(target_rad_s, 45f64.to_radians());
                assert_eq!(max_torque_n_m, 2.0);
                assert_eq!(delay_rad_s, 1f64.to_radians());
            }
            other => panic!("{other:?}"),
        }
        let servo = driver(sim, "hinge_servo world-hinge_servo").servo.unwrap();
        assert_eq!((servo.target, servo.response_time_s), (30f64.to_radians(), 0.1));
        let spring = driver(sim, "spring world-spring");
        assert_eq!(spring.stiffness, 100.0);
        // Schedules set the targets before each step.
        for _ in 0..3 {
            sim.step().unwrap();
        }
        let t = sim.time();
        match driver(sim, "motor world-motor").primitive {
            Primitive::AngularVelocity { target_rad_s, .. } => {
                assert!((target_rad_s - (90.0 * t).to_radians()).abs() < 1e-12, "{target_rad_s}")
            }
            other => panic!("{other:?}"),
        }
        let servo = driver(sim, "prismatic_servo world-prismatic_servo").servo.unwrap();
        assert!((servo.target - 0.2 * t).abs() < 1e-12);
        // Every joint has a state; the hinge angle is measured.
        let states = sim.joint_states();
        assert_eq!(states.len(), 21);
        assert!(states[2].1.coordinate.is_some());
    }

    /// The scene's joints are what the loader built before `[[joint]]` deserialised into
    /// `JointKind` (issue 12): elements and registered joints, printed with `{:?}`, stored from
    /// the code before the change.
    #[test]
    fn every_joint_type_builds_what_it_built_before_joint_kind() {
        let scene = parse(&all_joints_scene());
        let mut now = String::new();
        for (i, e) in scene
            .simulation
            .rigid_bodies
            .joints
            .potential
            .elements
            .iter()
            .enumerate()
        {
            now += &format!("element {i}: {e:?}\n");
        }
        for h in &scene.simulation.rigid_bodies.named_joints {
            now += &format!("joint: {h:?}\n");
        }
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("src/rigidbodies/joints/testdata/scene_joints_built_before_joint_kind.txt");
        if std::env::var_os("STARK_WRITE_GOLDEN").is_some() {
            std::fs::write(&path, &now).unwrap();
        }
        let before = std::fs::read_to_string(&path).unwrap();
        let (now, before): (Vec<_>, Vec<_>) = (now.lines().collect(), before.lines().collect());
        assert_eq!(now.len(), before.len());
        for (n, b) in now.iter().zip(&before) {
            assert_eq!(n, b);
        }
    }

    #[test]
    fn couplings_name_the_joints_they_couple() {
        let text = "duration_s = 1.0\n\
                    [[rigid_body]]\nname = \"a\"\nbox = { size_m = [0.1, 0.1, 0.1] }\nmass_kg = 1.0\n\
                    [[rigid_body]]\nname = \"b\"\nbox = { size_m = [0.1, 0.1, 0.1] }\nmass_kg = 1.0\nposition_m = [1.0, 0.0, 0.0]\n\
                    [[joint]]\nname = \"h1\"\ntype = \"hinge\"\nb = \"a\"\npoint_m = [0.0, 0.0, 0.0]\naxis = [0.0, 1.0, 0.0]\n\
                    [[joint]]\nname = \"h2\"\ntype = \"hinge\"\nb = \"b\"\npoint_m = [1.0, 0.0, 0.0]\naxis = [0.0, 1.0, 0.0]\n\
                    [[joint]]\ntype = \"joint_coupling\"\njoint_a = \"h1\"\njoint_b = \"h2\"\nmultiplier = -1.0\n\
                    [[joint]]\ntype = \"joint_spring\"\njoint = \"h1\"\nspring_stiffness = 2.0\ndamping = 0.5\n";
        let scene = parse(text);
        let names: Vec<_> = scene.joints.iter().map(|j| j.label.as_str()).collect();
        assert_eq!(names, ["h1", "h2", "joint_coupling", "joint_spring"]);
        let elements = &scene.simulation.rigid_bodies.joints.potential.elements;
        let coupling = &elements[scene.joint("joint_coupling").unwrap().elements[0] as usize];
        match &coupling.primitive {
            Primitive::Coupling(c) => assert_eq!((c.multiplier, c.offset, c.hard), (-1.0, 0.0, true)),
            other => panic!("{other:?}"),
        }
        let spring = &elements[scene.joint("joint_spring").unwrap().elements[0] as usize];
        match &spring.primitive {
            Primitive::Coupling(c) => assert_eq!((c.damping, c.hard), (0.5, false)),
            other => panic!("{other:?}"),
        }
        assert_eq!(spring.stiffness, 2.0);
    }

    #[test]
    fn joint_names_default_and_must_be_unique() {
        let base = "duration_s = 1.0\n[[rigid_body]]\nname = \"a\"\nsphere = { radius_m = 0.1 }\nmass_kg = 1.0\n\
                    [[rigid_body]]\nname = \"b\"\nsphere = { radius_m = 0.1 }\nmass_kg = 1.0\nposition_m = [0.0, 0.0, -0.5]\n";
        let ball = "[[joint]]\ntype = \"ball\"\na = \"a\"\nb = \"b\"\npoint_m = [0.0, 0.0, 0.0]\n";
        let scene = parse(&format!("{base}{ball}{ball}"));
        let names: Vec<_> = scene.joints.iter().map(|j| j.label.as_str()).collect();
        assert_eq!(names, ["ball a-b", "ball a-b #2"]);
        // `enabled = false` creates it switched off.
        let off = parse(&format!("{base}{ball}enabled = false\n"));
        let h = &off.joints[0];
        let elements = &off.simulation.rigid_bodies.joints.potential.elements;
        assert!(h.elements.iter().all(|&e| !elements[e as usize].enabled));
        let named = format!("{base}{ball}name = \"j\"\n{ball}name = \"j\"\n");
        let e = parse_err(&named).to_string();
        assert!(
            e.contains("test.toml:22:1: duplicate joint name 'j' in joint 'j' name"),
            "{e}"
        );
    }

    #[test]
    fn rigid_bodies_take_part_in_friction_collisions_and_attachments() {
        let text = r#"
duration_s = 1.0
[settings]
contact.default_thickness_m = 0.001
[[surface]]
name = "flag"
vertices_m = [[0.05, 0.05, 0.6], [0.05, 1.05, 0.6], [0.05, 0.05, 1.6]]
elements = [[0, 1, 2]]
material = "cotton_fabric"
[[rigid_body]]
name = "pole"
box = { size_m = [0.1, 0.1, 0.2] }
mass_kg = 1.0
position_m = [0.0, 0.0, 0.5]
fixed = true
[[rigid_body]]
name = "ghost"
sphere = { radius_m = 0.1 }
mass_kg = 1.0
position_m = [3.0, 0.0, 0.0]
contact = false
[[friction]]
objects = ["flag", "pole"]
mu = 0.4
[[disable_collision]]
objects = ["flag", "pole"]
[[attachment]]
a = "flag"
b = "pole"
within_m = 1e-9
stiffness = 1e5
"#;
        let mut scene = parse(text);
        let pole = scene.rigid_body("pole").unwrap();
        let flag = scene.object("flag").unwrap().contact().unwrap();
        let sim = &mut scene.simulation;
        assert_eq!(sim.contact.friction(flag, pole.contact.unwrap()).unwrap(), 0.4);
        // The flag's corner touches the pole's top corner: only without the collision is that
        // a valid start.
        let (att_label, att) = scene.attachments[0].clone();
        assert_eq!(att_label, "flag-pole");
        for _ in 0..5 {
            sim.step().unwrap();
        }
        // The corner hangs on the pole while the rest of the flag falls.
        let gap = sim.deformables.attachments.max_gap_m(att, &sim.nodes.x).unwrap();
        assert!(gap < 1e-3, "{gap}");
        let flag_x = sim.positions(scene.objects[0].1.nodes()).to_vec();
        assert!(close(&flag_x[0], &Vector3::new(0.05, 0.05, 0.6), 1e-3), "{}", flag_x[0]);
        assert!(flag_x[1].z < 0.5, "{}", flag_x[1]);
        // A body without contact cannot have friction.
        let bad = text.replace(
            "objects = [\"flag\", \"pole\"]\nmu",
            "objects = [\"flag\", \"ghost\"]\nmu",
        );
        let e = parse_err(&bad).to_string();
        assert!(
            e.contains("test.toml:23:20: rigid body 'ghost' takes no part in contact: it has no contact thickness or `contact = false`"),
            "{e}"
        );
    }

    #[test]
    fn errors_name_file_line_and_field() {
        const BODY: &str =
            "duration_s = 1.0\n[[rigid_body]]\nname = \"link\"\nbox = { size_m = [0.1, 0.1, 0.1] }\nmass_kg = 1.0\n";
        const BODIES: &str = "duration_s = 1.0\n\
                              [[rigid_body]]\nname = \"a\"\nbox = { size_m = [0.1, 0.1, 0.1] }\nmass_kg = 1.0\n\
                              [[rigid_body]]\nname = \"b\"\nbox = { size_m = [0.1, 0.1, 0.1] }\nmass_kg = 1.0\nposition_m = [0.0, 0.0, -0.2]\n\
                              [[surface]]\nname = \"cloth\"\ngrid = { size_m = [1.0, 1.0], quads = [1, 1] }\nmaterial = \"cotton_fabric\"\n";
        // Line 15 is the `[[joint]]` header, line 16 its `type`, 17 `a`, 18 `b`, 19 `point_m`.
        let hinge = "[[joint]]\ntype = \"hinge\"\na = \"a\"\nb = \"b\"\npoint_m = [0.0, 0.0, -0.1]\n";
        let cases: Vec<(&str, String, Vec<&str>)> = vec![
            (
                "unknown field in a body",
                format!("{BODY}colour = \"red\"\n"),
                vec!["test.toml:6:1: unknown field `colour` in rigid_body 'link', expected one of"],
            ),
            (
                "no mass",
                "duration_s = 1.0\n[[rigid_body]]\nname = \"link\"\nbox = { size_m = [0.1, 0.1, 0.1] }\n".into(),
                vec!["test.toml:2:", "rigid body 'link' needs a mass: give `mass_kg` or `density_kg_m3` in rigid_body 'link'"],
            ),
            (
                "two masses",
                format!("{BODY}density_kg_m3 = 10.0\n"),
                vec!["=test.toml:6:1: give the mass once: `mass_kg` or `density_kg_m3` in rigid_body 'link' density_kg_m3"],
            ),
            (
                "negative mass",
                "duration_s = 1.0\n[[rigid_body]]\nname = \"link\"\nbox = { size_m = [0.1, 0.1, 0.1] }\nmass_kg = -1.0\n".into(),
                vec!["=test.toml:5:1: mass_kg = -1 must be positive and finite (kg) in rigid_body 'link' mass_kg"],
            ),
            (
                "no shape",
                "duration_s = 1.0\n[[rigid_body]]\nname = \"link\"\nmass_kg = 1.0\n".into(),
                vec!["test.toml:2:", "no geometry: give one of `box`, `sphere`, `cylinder`, `capsule`, `torus`, `mesh` or `vertices_m` + `triangles`"],
            ),
            (
                "scale of a primitive",
                format!("{BODY}scale = 2.0\n"),
                vec!["test.toml:6:1: `scale` applies to `mesh` and inline geometry; give the box's size instead"],
            ),
            (
                "two orientations",
                format!("{BODY}rotate_deg = {{ angle = 90.0, axis = [0.0, 0.0, 1.0] }}\nquaternion_wxyz = [1.0, 0.0, 0.0, 0.0]\n"),
                vec!["test.toml:7:1: give the orientation once", "rigid_body 'link' quaternion_wxyz"],
            ),
            (
                "zero quaternion",
                format!("{BODY}quaternion_wxyz = [0.0, 0.0, 0.0, 0.0]\n"),
                vec!["test.toml:6:1: quaternion_wxyz = [0.0, 0.0, 0.0, 0.0] must be finite and non-zero"],
            ),
            (
                "bad inertia",
                format!("{BODY}inertia_kg_m2 = [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]]\n"),
                vec!["test.toml:6:1:", "must be symmetric positive definite", "rigid_body 'link' inertia_kg_m2"],
            ),
            (
                "open mesh without inertia",
                "duration_s = 1.0\n[[rigid_body]]\nname = \"plate\"\nvertices_m = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]\ntriangles = [[0, 1, 2]]\nmass_kg = 1.0\n".into(),
                vec!["test.toml:4:1:", "the mesh is not closed", "(give `mass_kg` and `inertia_kg_m2` for an open mesh) in rigid_body 'plate' vertices_m"],
            ),
            (
                "bad torus",
                "duration_s = 1.0\n[[rigid_body]]\nname = \"ring\"\ntorus = { major_radius_m = 0.1, minor_radius_m = 0.2 }\nmass_kg = 1.0\n".into(),
                vec!["test.toml:4:", "minor_radius_m = 0.2 must be smaller than major_radius_m = 0.1", "rigid_body 'ring' torus.minor_radius_m"],
            ),
            (
                "contact without thickness",
                format!("{BODY}contact = true\n"),
                vec!["test.toml:6:1: rigid body 'link' takes part in contact but has no contact thickness"],
            ),
            (
                "motion of a body that is not fixed",
                format!("{BODY}fixed = false\nmotion = {{ velocity_m_s = [0.0, 0.0, 1.0] }}\n"),
                vec!["test.toml:7:1: a scripted `motion` drives a fixed body: remove `fixed = false` in rigid_body 'link' motion"],
            ),
            (
                "motion without axis",
                format!("{BODY}motion = {{ angular_velocity_deg_s = 90.0 }}\n"),
                vec!["test.toml:6:12:", "needs an `axis`", "rigid_body 'link' motion.angular_velocity_deg_s"],
            ),
            (
                "keyframes out of order",
                format!("{BODY}keyframes = [{{ time_s = 1.0 }}, {{ time_s = 0.5 }}]\n"),
                vec!["test.toml:6:", "time_s = 0.5 must be finite and after the previous keyframe (1 s", "rigid_body 'link' keyframes[1].time_s"],
            ),
            (
                "body called world",
                "duration_s = 1.0\n[[rigid_body]]\nname = \"world\"\nbox = { size_m = [0.1, 0.1, 0.1] }\nmass_kg = 1.0\n".into(),
                vec!["test.toml:3:1: 'world' names the fixed world in joints"],
            ),
            (
                "prescribed rigid body",
                format!("{BODY}[[prescribed]]\nobject = \"link\"\nall = true\n"),
                vec!["test.toml:7:1: 'link' is a rigid body: hold it with `fixed = true`", "prescribed #1 (object 'link') object"],
            ),
            (
                "bad joint type",
                format!("{BODIES}[[joint]]\ntype = \"hing\"\nb = \"b\"\n"),
                vec!["test.toml:16:8: unknown variant `hing` in joint #1 (hing 'world' to 'b') type, expected one of `ball`, `ball_cone`, `hinge`"],
            ),
            (
                "missing axis",
                format!("{BODIES}{hinge}"),
                vec!["=test.toml:16:1: a hinge joint needs `axis` (it takes `point_m`, `axis`) in joint #1 (hinge 'a' to 'b') type"],
            ),
            (
                "unknown body label",
                format!("{BODIES}{}axis = [0.0, 1.0, 0.0]\n", hinge.replace("a = \"a\"", "a = \"c\"")),
                vec!["=test.toml:17:1: unknown rigid body 'c' in joint #1 (hinge 'c' to 'b') a, expected one of world, a, b"],
            ),
            (
                "a deformable object in a joint",
                format!("{BODIES}{}axis = [0.0, 1.0, 0.0]\n", hinge.replace("b = \"b\"", "b = \"cloth\"")),
                vec!["test.toml:18:1: 'cloth' is a surface, not a rigid body", "in joint #1 (hinge 'a' to 'cloth') b, expected one of world, a, b"],
            ),
            (
                "the world as b",
                format!("{BODIES}{}axis = [0.0, 1.0, 0.0]\n", hinge.replace("b = \"b\"", "b = \"world\"")),
                vec!["test.toml:18:1: joint 'hinge a-world': `b` must be a rigid body"],
            ),
            (
                "a field of another joint type",
                format!("{BODIES}{hinge}axis = [0.0, 1.0, 0.0]\nlimit_deg = 30.0\n"),
                vec!["test.toml:21:1: `limit_deg` does not apply to a hinge joint, which takes `point_m`, `axis`, `stiffness`"],
            ),
            (
                "zero axis",
                format!("{BODIES}{hinge}axis = [0.0, 0.0, 0.0]\n"),
                vec!["=test.toml:20:1: joint 'hinge a-b': `axis` = [0.0, 0.0, 0.0] must be finite and non-zero in joint #1 (hinge 'a' to 'b') axis"],
            ),
            (
                "bad joint stiffness",
                format!("{BODIES}{hinge}axis = [0.0, 1.0, 0.0]\nstiffness = -1.0\n"),
                vec!["test.toml:21:1:", "`stiffness` = -1", "joint #1 (hinge 'a' to 'b') stiffness"],
            ),
            (
                "bad cone limit",
                format!("{BODIES}{}axis = [0.0, 0.0, 1.0]\nlimit_deg = 200.0\n", hinge.replace("hinge", "ball_cone")),
                vec!["test.toml:21:1:", "`limit_deg` = 200", "in joint #1 (ball_cone 'a' to 'b') limit_deg"],
            ),
            (
                "motor without target",
                format!("{BODIES}{}axis = [0.0, 1.0, 0.0]\nmax_torque_n_m = 1.0\n", hinge.replace("hinge", "motor")),
                vec!["test.toml:16:1: a motor joint needs `target_velocity_deg_s` or a `target_schedule`"],
            ),
            (
                "motor with negative torque",
                format!("{BODIES}{}axis = [0.0, 1.0, 0.0]\nmax_torque_n_m = -1.0\ntarget_velocity_deg_s = 10.0\n", hinge.replace("hinge", "motor")),
                vec!["test.toml:21:1:", "in joint #1 (motor 'a' to 'b') max_torque_n_m"],
            ),
            (
                "schedule out of order",
                format!("{BODIES}{}axis = [0.0, 1.0, 0.0]\nmax_torque_n_m = 1.0\ntarget_schedule = [[1.0, 0.0], [0.5, 1.0]]\n", hinge.replace("hinge", "motor")),
                vec!["test.toml:22:", "needs finite values and times that increase", "joint #1 (motor 'a' to 'b') target_schedule[1]"],
            ),
            (
                "universal axes not perpendicular",
                format!("{BODIES}{}axis_a = [1.0, 0.0, 0.0]\naxis_b = [1.0, 1.0, 0.0]\n", hinge.replace("hinge", "universal")),
                vec!["test.toml:21:1: joint 'universal a-b': `axis_b` = [1.0, 1.0, 0.0] must be perpendicular to `axis_a`"],
            ),
            (
                "fix joint with a body a",
                format!("{BODIES}[[joint]]\ntype = \"fix\"\na = \"a\"\nb = \"b\"\n"),
                vec!["test.toml:17:1: joint 'fix a-b': a fix joint holds body b in the world"],
            ),
            (
                "distance limits around the wrong distance",
                format!("{BODIES}[[joint]]\ntype = \"distance_limits\"\na = \"a\"\nb = \"b\"\npoint_a_m = [0.0, 0.0, 0.0]\npoint_b_m = [0.0, 0.0, -0.2]\nmin_m = 0.5\nmax_m = 1.0\n"),
                vec!["test.toml:21:1:", "current distance", "joint #1 (distance_limits 'a' to 'b') min_m"],
            ),
            (
                "a joint between a body and itself",
                format!("{BODIES}{}axis = [0.0, 1.0, 0.0]\n", hinge.replace("a = \"a\"", "a = \"b\"")),
                vec!["test.toml:18:1: joint 'hinge b-b' connects 'b' to itself"],
            ),
            (
                "misspelt field of a motor",
                format!("{BODIES}{}axis = [0.0, 1.0, 0.0]\nmax_torque_nm = 1.0\ntarget_velocity_deg_s = 10.0\n", hinge.replace("hinge", "motor")),
                vec!["=test.toml:21:1: unknown field `max_torque_nm` in joint #1 (motor 'a' to 'b'), expected one of `point_m`, `axis`, `target_velocity_deg_s`, `max_torque_n_m`, `delay_deg_s`, `stiffness`, `tolerance_m`, `tolerance_deg`, `target_schedule`"],
            ),
            (
                "a joint field of the wrong type",
                format!("{BODIES}{hinge}axis = \"up\"\n"),
                vec!["test.toml:20:1: `axis`: invalid type: string \"up\"", "in joint #1 (hinge 'a' to 'b') axis"],
            ),
            (
                "a typo in a joint type",
                format!("{BODIES}[[joint]]\ntype = \"ball_con\"\nb = \"b\"\n"),
                vec!["test.toml:16:8: unknown variant `ball_con` in joint #1 (ball_con 'world' to 'b') type, expected one of `ball`, `ball_cone`"],
            ),
            (
                "a schedule on a joint without a target",
                format!("{BODIES}{hinge}axis = [0.0, 1.0, 0.0]\ntarget_schedule = [[0.0, 1.0]]\n"),
                vec!["=test.toml:21:1: a hinge joint has no target to schedule in joint #1 (hinge 'a' to 'b') target_schedule"],
            ),
            (
                "a coupling of an unknown joint",
                format!("{BODIES}[[joint]]\ntype = \"joint_coupling\"\njoint_a = \"x\"\njoint_b = \"y\"\n"),
                vec!["test.toml:17:1: joint 'joint_coupling': `joint_a`: no joint is labelled 'x'; the joints are none yet"],
            ),
            (
                "unknown field in a joint",
                format!("{BODIES}{hinge}axis = [0.0, 1.0, 0.0]\nspeed = 1.0\n"),
                vec!["test.toml:21:1: unknown field `speed` in joint #1 (hinge 'a' to 'b'), expected one of"],
            ),
        ];
        let mut failures = Vec::new();
        for (what, text, expected) in cases {
            let e = parse_err(&text);
            let shown = e.to_string();
            for s in expected {
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
    fn json_rigid_scenes_parse() {
        let json = r#"{
  "duration_s": 1.0,
  "rigid_body": [
    { "name": "a", "box": { "size_m": [0.1, 0.1, 0.1] }, "mass_kg": 1.0, "fixed": true },
    { "name": "b", "sphere": { "radius_m": 0.05 }, "mass_kg": 0.5, "position_m": [0.0, 0.0, -0.3] }
  ],
  "joint": [ { "name": "rod", "type": "distance", "a": "a", "b": "b", "point_a_m": [0.0, 0.0, 0.0], "point_b_m": [0.0, 0.0, -0.3] } ]
}"#;
        let scene = parse_scene_with(json, "scene.json", Path::new("."), quiet).unwrap();
        assert_eq!(scene.simulation.num_rigid_bodies(), 2);
        let names: Vec<_> = scene.joints.iter().map(|j| j.label.as_str()).collect();
        assert_eq!(names, ["a.fixed", "rod"]);
        let bad = json.replace("\"distance\"", "\"distanc\"");
        let Err(StarkError::SceneFile(e)) = parse_scene(&bad, "scene.json", Path::new(".")) else {
            panic!("parsed")
        };
        assert_eq!(e.line, Some(7), "{e}");
        assert!(e.to_string().contains("unknown variant `distanc`"), "{e}");
    }

    /// `scenes/rb_pendulum_chain.toml` built with the Rust API.
    fn pendulum_chain_in_rust(settings: Settings) -> Simulation {
        let mut sim = Simulation::new(settings).unwrap();
        let size = Vector3::new(0.2, 0.03, 0.03);
        let link = meshes::box_mesh(size);
        let mut links = Vec::new();
        for i in 0..5 {
            let b = sim
                .add_rigid_body_with(
                    &format!("link{i}"),
                    &MassProperties::cuboid(0.2, size),
                    Vector3::new([0.1, 0.3, 0.5, 0.7, 0.9][i], 0.0, 0.0),
                    UnitQuaternion::identity(),
                )
                .unwrap();
            sim.add_rigid_output_mesh(b, &link.vertices, &link.elements).unwrap();
            links.push(b);
        }
        let (r, h) = (0.15, 0.02);
        let disc = meshes::cylinder_mesh(r, h, 24, 1);
        let q = UnitQuaternion::from_axis_angle(&Unit::new_normalize(Vector3::x()), 90f64.to_radians());
        let wheel = sim
            .add_rigid_body_with(
                "wheel",
                &MassProperties::cylinder(1000.0 * (PI * r * r * h), r, h),
                Vector3::new(0.0, 0.5, 0.0),
                q,
            )
            .unwrap();
        sim.add_rigid_output_mesh(wheel, &disc.vertices, &disc.elements)
            .unwrap();
        let p = JointParams::default();
        sim.add_hinge_joint("pivot", None, links[0], Vector3::zeros(), Vector3::y(), p)
            .unwrap();
        for i in 1..5 {
            let at = Vector3::new([0.2, 0.4, 0.6, 0.8][i - 1], 0.0, 0.0);
            sim.add_hinge_joint(&format!("hinge{i}"), Some(links[i - 1]), links[i], at, Vector3::y(), p)
                .unwrap();
        }
        sim.add_motor(
            "motor",
            None,
            wheel,
            Vector3::new(0.0, 0.5, 0.0),
            Vector3::y(),
            90f64.to_radians(),
            1.0,
            DEFAULT_CONTROLLER_DELAY,
            p,
        )
        .unwrap();
        sim
    }

    #[test]
    fn pendulum_chain_scene_matches_the_same_scene_built_in_rust() {
        let scene = load_scene_with(&repo_scene("rb_pendulum_chain.toml"), quiet).unwrap();
        assert_eq!((scene.name.as_str(), scene.duration_s), ("rb_pendulum_chain", 3.0));
        let mut from_file = scene.simulation;
        let mut settings = from_file.settings.clone();
        quiet(&mut settings);
        let mut in_rust = pendulum_chain_in_rust(settings);
        assert_eq!(from_file.bodies.mass, in_rust.bodies.mass);
        assert_eq!(from_file.bodies.inertia_local, in_rust.bodies.inertia_local);
        assert_eq!(body_bits(&from_file), body_bits(&in_rust));
        assert_eq!(bits(&from_file.nodes.x), bits(&in_rust.nodes.x));
        assert_eq!(from_file.rigid_bodies.named_joints, in_rust.rigid_bodies.named_joints);
        assert!(from_file.contact.objects().is_empty());
        for _ in 0..4 {
            from_file.step().unwrap();
            in_rust.step().unwrap();
        }
        assert!(
            in_rust.body_position(RigidBodyHandle { index: 4 }).z < -1e-3,
            "nothing moved"
        );
        assert_eq!(body_bits(&from_file), body_bits(&in_rust));
        assert_eq!(bits(&from_file.nodes.x), bits(&in_rust.nodes.x));
        assert_eq!(from_file.joint_states(), in_rust.joint_states());
    }

    /// `scenes/rb_box_on_cloth.toml` built with the Rust API.
    fn box_on_cloth_in_rust(settings: Settings) -> Simulation {
        use crate::deformables::PrescribedParams;
        use crate::presets::SurfaceMaterial;
        let mut sim = Simulation::new(settings).unwrap();
        let grid = meshes::triangle_grid([0.0, 0.0], [1.0, 1.0], [20, 20], 0.0);
        let material = SurfaceMaterial {
            contact_thickness_m: Some(0.002),
            ..SurfaceMaterial::cotton_fabric()
        };
        let cloth = sim
            .add_surface("cloth", &grid.vertices, &grid.elements, &material)
            .unwrap();
        let size = Vector3::repeat(0.15);
        let cube = meshes::box_mesh(size);
        let q = UnitQuaternion::from_axis_angle(&Unit::new_normalize(Vector3::new(1.0, 1.0, 0.0)), 30f64.to_radians());
        let body = sim
            .add_rigid_body_with(
                "box",
                &MassProperties::cuboid(0.5, size),
                Vector3::new(0.1, 0.0, 0.2),
                q,
            )
            .unwrap();
        let box_mesh = sim
            .add_rigid_collision_mesh(body, &cube.vertices, &cube.elements, Some(0.002))
            .unwrap();
        let paddle_size = Vector3::new(0.1, 0.4, 0.02);
        let plate = meshes::box_mesh(paddle_size);
        let start = Vector3::new(-0.3, 0.0, -0.15);
        let paddle = sim
            .add_rigid_body_with(
                "paddle",
                &MassProperties::cuboid(1.0, paddle_size),
                start,
                UnitQuaternion::identity(),
            )
            .unwrap();
        let paddle_mesh = sim
            .add_rigid_collision_mesh(paddle, &plate.vertices, &plate.elements, Some(0.002))
            .unwrap();
        let fix = sim
            .add_fix_joint("paddle.fixed", paddle, JointParams::default())
            .unwrap();
        let tilt = UnitQuaternion::from_axis_angle(&Unit::new_normalize(Vector3::y()), 20f64.to_radians());
        let poses: Poses = vec![
            (0.0, start, UnitQuaternion::identity()),
            (1.0, start, UnitQuaternion::identity()),
            (1.5, Vector3::new(-0.25, 0.0, -0.05), tilt),
            (2.0, Vector3::new(-0.2, 0.0, -0.1), tilt),
        ];
        sim.add_time_event(0.0, f64::INFINITY, move |sim, t| {
            let (p, q) = keyframe_pose(&poses, t);
            sim.set_fixed_transform(&fix, p, q)
        });
        let c = cloth.contact.unwrap();
        sim.contact.set_friction(c, box_mesh.contact, 0.5).unwrap();
        sim.contact.set_friction(c, paddle_mesh.contact, 0.3).unwrap();
        let pin = PrescribedParams {
            stiffness: 1e6,
            ..Default::default()
        };
        for x in [-0.5, 0.5] {
            for y in [-0.5, 0.5] {
                sim.deformables
                    .prescribed
                    .add_in_box(
                        &sim.nodes,
                        cloth.nodes,
                        "cloth",
                        Vector3::new(x, y, 0.0),
                        Vector3::repeat(0.001),
                        true,
                        pin.clone(),
                    )
                    .unwrap();
            }
        }
        sim
    }

    #[test]
    fn box_on_cloth_scene_matches_the_same_scene_built_in_rust() {
        let scene = load_scene_with(&repo_scene("rb_box_on_cloth.toml"), quiet).unwrap();
        let mut from_file = scene.simulation;
        let mut in_rust = box_on_cloth_in_rust(from_file.settings.clone());
        assert_eq!(from_file.settings, in_rust.settings);
        assert_eq!(body_bits(&from_file), body_bits(&in_rust));
        assert_eq!(bits(&from_file.nodes.x), bits(&in_rust.nodes.x));
        let describe = |c: &crate::contact::Contact| -> Vec<(String, f64, u32, u32)> {
            c.objects()
                .iter()
                .map(|o| (o.label.clone(), o.thickness_m, o.nodes.first, o.nodes.len))
                .collect()
        };
        assert_eq!(describe(&from_file.contact), describe(&in_rust.contact));
        for _ in 0..3 {
            from_file.step().unwrap();
            in_rust.step().unwrap();
        }
        assert!(
            in_rust.body_position(RigidBodyHandle { index: 0 }).z < 0.2 - 1e-3,
            "nothing moved"
        );
        assert_eq!(body_bits(&from_file), body_bits(&in_rust));
        assert_eq!(bits(&from_file.nodes.x), bits(&in_rust.nodes.x));
    }

    const SPAWN_SCENE: &str = r#"
duration_s = 0.4
[settings]
time_step_s = 0.01
contact.default_thickness_m = 0.0005
[[obstacle]]
name = "floor"
box = { size_m = [0.4, 0.4, 0.02] }
translate_m = [0.0, 0.0, -0.01]
[[rigid_body]]
name = "ball"
sphere = { radius_m = 0.01, subdivisions = 2 }
mass_kg = 0.01
spawn = { start_s = 0.05, every_s = 0.1, count = 3, drop_to_gap_m = 0.002, positions_m = [[0.0, 0.0, 0.2], [0.05, 0.0, 0.3]] }
[[friction]]
objects = ["ball", "floor"]
mu = 0.5
[[friction]]
objects = ["ball", "ball"]
mu = 0.2
"#;

    #[test]
    fn spawned_bodies_come_at_their_times_lowered_onto_the_floor_with_their_friction() {
        let mut sim = parse(SPAWN_SCENE).simulation;
        assert_eq!(sim.num_rigid_bodies(), 0);
        let spawns: Vec<(f64, String)> = sim.spawns().into_iter().map(|(t, l, _)| (t, l.to_string())).collect();
        assert_eq!(
            spawns,
            [
                (0.05, "ball_1".into()),
                (0.15000000000000002, "ball_2".into()),
                (0.25, "ball_3".into())
            ]
        );
        let mut first_z = Vec::new();
        while sim.time() < 0.4 - 1e-9 {
            let before = sim.num_rigid_bodies();
            sim.step().unwrap();
            if sim.num_rigid_bodies() > before {
                let b = sim.rigid_bodies.by_label(&format!("ball_{}", before + 1)).unwrap();
                let ball_1 = sim.rigid_bodies.by_label("ball_1").unwrap();
                first_z.push((sim.body_position(b), sim.body_position(ball_1).z));
            }
            assert!(sim.state_check().intersections.is_empty());
        }
        assert_eq!(sim.num_rigid_bodies(), 3);
        // Each was lowered from its place (0.2 m, 0.3 m, 0.2 m high) to 2 mm above the floor,
        // or for ball 3, 2 mm above ball 1 (its lowest vertex is within 5% of the radius of the
        // sphere's bottom).
        // (The floor's top is at 0 within the micrometres its springs give under the balls.)
        for (k, (z, ball_1_z)) in first_z.iter().enumerate() {
            let below = if k == 2 { ball_1_z + 0.01 } else { 0.0 };
            let gap = z.z - 0.01 - below;
            assert!((0.002 - 1e-6..0.0025).contains(&gap), "ball {}: gap {gap}", k + 1);
        }
        assert_eq!((first_z[0].0.x, first_z[1].0.x, first_z[2].0.x), (0.0, 0.05, 0.0));
        let c = &sim.contact;
        let h = |l: &str| c.object_by_label(l).unwrap();
        assert_eq!(c.friction(h("ball_3"), h("floor")).unwrap(), 0.5);
        assert_eq!(c.friction(h("ball_3"), h("ball_1")).unwrap(), 0.2);
        assert_eq!(c.friction(h("ball_2"), h("ball_1")).unwrap(), 0.2);
    }

    #[test]
    fn spawn_entries_with_bad_values_are_errors_naming_them() {
        for (change, expected) in [
            ("count = 3", "count = 0", "count must be at least 1"),
            ("every_s = 0.1", "every_s = -0.1", "every_s = -0.1 must be non-negative"),
            (
                "drop_to_gap_m = 0.002",
                "drop_to_gap_m = 0.0",
                "drop_to_gap_m = 0 must be positive",
            ),
            (
                "mass_kg = 0.01",
                "mass_kg = 0.01\nfixed = true",
                "a spawned body cannot take `fixed`",
            ),
        ]
        .map(|(a, b, e)| ((a, b), e))
        {
            let text = SPAWN_SCENE.replace(change.0, change.1);
            let e = parse_err(&text);
            assert!(e.to_string().contains(expected), "{}: {e}", change.1);
        }
        let clash = format!("{SPAWN_SCENE}[[obstacle]]\nname = \"ball_2\"\nbox = {{ size_m = [0.1, 0.1, 0.1] }}\n");
        let e = parse_err(&clash);
        assert!(e.to_string().contains("would take the name 'ball_2'"), "{e}");
        let disabled = format!("{SPAWN_SCENE}[[disable_collision]]\nobjects = [\"ball\", \"floor\"]\n");
        let e = parse_err(&disabled);
        assert!(e.to_string().contains("'ball' is spawned during the run"), "{e}");
    }
}

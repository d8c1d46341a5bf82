//! `[[rigid_body]]` entries: a body built from a shape (a primitive, a mesh file or an inline mesh),
//! its mass (or density) and a pose, through [`Simulation::add_rigid_body`] and
//! [`Simulation::add_rigid_collision_mesh`] (or [`Simulation::add_rigid_output_mesh`] when it
//! takes no part in contact); `fixed = true` adds a fix joint, which a `motion` or `keyframes`
//! drive through [`Simulation::set_fixed_transform`]. Bodies with `spawn` are added during the run
//! (`spawn.rs`).

use super::errors::{At, Ctx, Res, SceneError};
use super::events::Motion;
use super::geometry::{
    check_positive, finite, inline_shape, mesh_path, one_geometry, orientation, shape_error, BoxGenerator,
    CapsuleGenerator, CylinderGenerator, Geometry, Rotate, SphereGenerator, TorusGenerator,
};
use crate::contact::ContactHandle;
use crate::deformables::NodeSetHandle;
use crate::error::StarkError;
use crate::rigidbodies::joints::{JointHandle, JointParams};
use crate::rigidbodies::{Mass, MassProperties, RigidBodyHandle, RigidBodyParams, Shape, ShapeError};
use crate::simulation::Simulation;
use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use serde::Deserialize;
use std::path::Path;

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

/// A `[[rigid_body]]`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RigidBodyEntry {
    pub(super) name: String,
    #[serde(rename = "box")]
    pub(super) box_: Option<BoxGenerator>,
    pub(super) sphere: Option<SphereGenerator>,
    pub(super) cylinder: Option<CylinderGenerator>,
    pub(super) capsule: Option<CapsuleGenerator>,
    pub(super) torus: Option<TorusGenerator>,
    pub(super) mesh: Option<String>,
    pub(super) vertices_m: Option<Vec<[f64; 3]>>,
    pub(super) triangles: Option<Vec<[usize; 3]>>,
    pub(super) scale: Option<f64>,
    pub(super) mass_kg: Option<f64>,
    density_kg_m3: Option<f64>,
    inertia_kg_m2: Option<[[f64; 3]; 3]>,
    pub(super) position_m: Option<[f64; 3]>,
    pub(super) rotate_deg: Option<Rotate>,
    pub(super) quaternion_wxyz: Option<[f64; 4]>,
    pub(super) velocity_m_s: Option<[f64; 3]>,
    pub(super) angular_velocity_deg_s: Option<[f64; 3]>,
    pub(super) linear_damping_1_s: Option<f64>,
    pub(super) angular_damping_1_s: Option<f64>,
    pub(super) force_n: Option<[f64; 3]>,
    pub(super) torque_n_m: Option<[f64; 3]>,
    pub(super) contact_thickness_m: Option<f64>,
    pub(super) contact: Option<bool>,
    pub(super) fixed: Option<bool>,
    pub(super) motion: Option<Motion>,
    pub(super) keyframes: Option<Vec<Keyframe>>,
    pub(super) spawn: Option<SpawnEntry>,
}

/// `spawn = { ... }` of a `[[rigid_body]]`: copies added during the run (`spawn.rs`).
#[derive(Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SpawnEntry {
    /// Time of the first copy, s.
    pub(super) start_s: f64,
    /// Time between copies, s (default: 0, all at once).
    #[serde(default)]
    pub(super) every_s: f64,
    /// Number of copies.
    pub(super) count: usize,
    /// Where the copies' centres of mass go, in turn, m (default: the body's `position_m`).
    pub(super) positions_m: Option<Vec<[f64; 3]>>,
    /// Lower each copy straight down until it is this far above what it would land on, m
    /// (default: place it where given).
    pub(super) drop_to_gap_m: Option<f64>,
}

/// A body's shape in its body frame (centre of mass at the origin) and its mass properties.
pub(super) struct BodyShape {
    pub(super) vertices: Vec<Vector3<f64>>,
    pub(super) triangles: Vec<[usize; 3]>,
    pub(super) mass: MassProperties,
}

/// The [`Shape`] of an entry (its generator table, `mesh` file or inline mesh) and its mass
/// properties, all checks done by [`Shape`].
pub(super) fn shape(ctx: &Ctx, base_dir: &Path, at: &At, e: &RigidBodyEntry) -> Res<BodyShape> {
    // A mesh file's scale is set below, once it is checked.
    let geometry = one_geometry(
        ctx,
        at,
        [
            ("box", e.box_.as_ref().map(Shape::from)),
            ("sphere", e.sphere.as_ref().map(Shape::from)),
            ("cylinder", e.cylinder.as_ref().map(Shape::from)),
            ("capsule", e.capsule.as_ref().map(Shape::from)),
            ("torus", e.torus.as_ref().map(Shape::from)),
            (
                "mesh",
                e.mesh.as_deref().map(|f| Shape::mesh_file(mesh_path(base_dir, f))),
            ),
        ],
        e.vertices_m.as_deref(),
        ("triangles", e.triangles.as_deref()),
    )?;
    let key = geometry.key();
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
    let scalable = matches!(
        geometry,
        Geometry::Inline { .. }
            | Geometry::Source {
                source: Shape::MeshFile { .. },
                ..
            }
    );
    if e.scale.is_some() && !scalable {
        return Err(ctx.err(
            &at.key("scale"),
            format!("`scale` applies to `mesh` and inline geometry; give the {key}'s size instead"),
        ));
    }
    if let Some(s) = e.scale {
        check_positive(ctx, at, "scale", s, "a factor")?;
    }
    let scale = Vector3::repeat(e.scale.unwrap_or(1.0));
    let shape = match geometry {
        Geometry::Source {
            source: Shape::MeshFile { path, .. },
            ..
        } => Shape::MeshFile { path, scale },
        Geometry::Source { source, .. } => source,
        Geometry::Inline { vertices_m, elements } => inline_shape(vertices_m, elements, scale),
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
pub(super) fn no_thickness(ctx: &Ctx, at: &At, name: &str) -> SceneError {
    ctx.err(
        &at.key("contact"),
        format!(
            "rigid body '{name}' takes part in contact but has no contact thickness: give `contact_thickness_m` \
             or set `settings.contact.default_thickness_m`"
        ),
    )
}

/// The poses of a keyframed body: its initial pose at t = 0, then each keyframe.
pub(super) type Poses = Vec<(f64, Vector3<f64>, UnitQuaternion<f64>)>;

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
pub(super) fn keyframe_pose(poses: &Poses, t: f64) -> (Vector3<f64>, UnitQuaternion<f64>) {
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

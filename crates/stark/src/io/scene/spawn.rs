//! `spawn = { ... }` of a `[[rigid_body]]`: copies of the body added during the run
//! ([`Simulation::add_spawn`]), named `<name>_1`, `<name>_2`, ..., with the friction of the
//! `[[friction]]` entries that name them.

use super::errors::{At, Ctx, Res};
use super::geometry::{check_positive, finite, orientation};
use super::rigid_bodies::{no_thickness, shape, RigidBodyEntry};
use crate::contact::ContactHandle;
use crate::rigidbodies::RigidBodyParams;
use crate::simulation::Simulation;
use nalgebra::{UnitQuaternion, Vector3};
use std::path::Path;

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

/// The number of copies of `name` if it is one of the `spawned` bodies.
pub(super) fn spawned_count(spawned: &[(usize, &RigidBodyEntry)], name: &str) -> Option<usize> {
    spawned
        .iter()
        .find(|(_, e)| e.name == name)
        .and_then(|(_, e)| e.spawn.as_ref())
        .map(|s| s.count)
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

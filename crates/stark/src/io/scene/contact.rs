//! `[[friction]]` and `[[disable_collision]]` entries: calls of
//! [`Contact::set_friction`](crate::contact::Contact::set_friction) and
//! [`Contact::disable_collision`](crate::contact::Contact::disable_collision) for a pair of object
//! names.

use super::errors::{At, Ctx, Res};
use super::rigid_bodies::RigidBodyEntry;
use super::spawn::{spawned_count, FrictionPartner};
use super::{find_object, SceneObject};
use crate::contact::ContactHandle;
use crate::simulation::Simulation;
use serde::Deserialize;

/// A `[[friction]]`: the friction coefficient between two objects.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct FrictionEntry {
    objects: [String; 2],
    mu: f64,
}

/// A `[[disable_collision]]`: two objects (or one, twice) that do not collide.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct DisableCollisionEntry {
    objects: [String; 2],
}

/// The contact objects of the two names of a `[[friction]]` or `[[disable_collision]]` entry.
fn contact_pair(ctx: &Ctx, at: &At, objects: &[(String, SceneObject)], names: &[String; 2]) -> Res<[ContactHandle; 2]> {
    Ok([
        contact_of(ctx, &at.key("objects").index(0), objects, &names[0])?,
        contact_of(ctx, &at.key("objects").index(1), objects, &names[1])?,
    ])
}

/// The contact object of the object `name` (located at `at` in errors).
fn contact_of(ctx: &Ctx, at: &At, objects: &[(String, SceneObject)], name: &str) -> Res<ContactHandle> {
    let object = find_object(ctx, at, objects, name)?;
    object.contact().ok_or_else(|| {
        let with: Vec<_> = objects
            .iter()
            .filter(|(_, o)| o.contact().is_some())
            .map(|(n, _)| n.as_str())
            .collect();
        let why = if let SceneObject::RigidBody(_) = object {
            "rigid body '{name}' takes no part in contact: it has no contact thickness or `contact = false` \
             (give it `contact_thickness_m` or set `settings.contact.default_thickness_m`)"
        } else {
            "object '{name}' takes no part in contact: it has no contact thickness (set `contact_thickness_m` \
             in its material or `settings.contact.default_thickness_m`)"
        };
        ctx.err(
            at,
            format!(
                "{}; objects with contact: {}",
                why.replace("{name}", name),
                if with.is_empty() {
                    "none".to_string()
                } else {
                    with.join(", ")
                }
            ),
        )
    })
}

fn add_friction(
    sim: &mut Simulation,
    ctx: &Ctx,
    at: &At,
    objects: &[(String, SceneObject)],
    e: &FrictionEntry,
) -> Res<()> {
    let [a, b] = contact_pair(ctx, at, objects, &e.objects)?;
    if !(e.mu >= 0.0 && e.mu.is_finite()) {
        return Err(ctx.err(&at.key("mu"), format!("mu = {} must be non-negative and finite", e.mu)));
    }
    sim.contact
        .set_friction(a, b, e.mu)
        .map_err(|err| ctx.stark(&at.key("mu"), err))
}

fn add_disable_collision(
    sim: &mut Simulation,
    ctx: &Ctx,
    at: &At,
    objects: &[(String, SceneObject)],
    e: &DisableCollisionEntry,
) -> Res<()> {
    let [a, b] = contact_pair(ctx, at, objects, &e.objects)?;
    sim.contact
        .disable_collision(a, b)
        .map_err(|err| ctx.stark(&at.key("objects"), err))
}

/// Add the `[[friction]]` entries between objects present from the start; those naming a spawned
/// body (`spawned`: its entry index and entry) are returned per spawned body, to be set when
/// each copy is added.
pub(super) fn add_friction_entries(
    sim: &mut Simulation,
    ctx: &Ctx,
    objects: &[(String, SceneObject)],
    entries: &[FrictionEntry],
    spawned: &[(usize, &RigidBodyEntry)],
) -> Res<Vec<Vec<(FrictionPartner, f64)>>> {
    let mut spawned_friction: Vec<Vec<(FrictionPartner, f64)>> = vec![Vec::new(); spawned.len()];
    for (i, e) in entries.iter().enumerate() {
        let at = At::entry("friction", i);
        let sides = [
            spawned_count(spawned, &e.objects[0]),
            spawned_count(spawned, &e.objects[1]),
        ];
        if sides == [None, None] {
            add_friction(sim, ctx, &at, objects, e)?;
            continue;
        }
        if !(e.mu >= 0.0 && e.mu.is_finite()) {
            return Err(ctx.err(&at.key("mu"), format!("mu = {} must be non-negative and finite", e.mu)));
        }
        for side in 0..2 {
            let Some(k) = spawned.iter().position(|(_, s)| s.name == e.objects[side]) else {
                continue;
            };
            let other = &e.objects[1 - side];
            let partner = match sides[1 - side] {
                Some(count) => FrictionPartner::Spawned {
                    name: other.clone(),
                    count,
                },
                None => FrictionPartner::Present(contact_of(ctx, &at.key("objects").index(1 - side), objects, other)?),
            };
            spawned_friction[k].push((partner, e.mu));
            if e.objects[0] == e.objects[1] {
                break;
            }
        }
    }
    Ok(spawned_friction)
}

/// Add the `[[disable_collision]]` entries; none may name a spawned body.
pub(super) fn add_disable_collision_entries(
    sim: &mut Simulation,
    ctx: &Ctx,
    objects: &[(String, SceneObject)],
    entries: &[DisableCollisionEntry],
    spawned: &[(usize, &RigidBodyEntry)],
) -> Res<()> {
    for (i, e) in entries.iter().enumerate() {
        let at = At::entry("disable_collision", i);
        if let Some(name) = e.objects.iter().find(|n| spawned_count(spawned, n).is_some()) {
            return Err(ctx.err(
                &at.key("objects"),
                format!("'{name}' is spawned during the run: spawned bodies take `[[friction]]` entries but not `[[disable_collision]]`"),
            ));
        }
        add_disable_collision(sim, ctx, &at, objects, e)?;
    }
    Ok(())
}

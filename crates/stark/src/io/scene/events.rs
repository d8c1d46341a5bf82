//! Scripted changes over time: the [`Motion`] of prescribed targets (of `[[prescribed]]` nodes,
//! obstacles and fixed rigid bodies) and `[[gravity_ramp]]` entries.

use super::errors::{At, Ctx, Res};
use crate::deformables::PrescribedHandle;
use crate::error::Result;
use crate::simulation::Simulation;
use nalgebra::{Rotation3, Unit, Vector3};
use serde::{Deserialize, Serialize};

/// Scripted rigid motion of prescribed targets: at time `t` the targets are the reference
/// positions (the nodes' positions when prescribed) rotated by `ω·τ` about `axis` through
/// `center_m` and then translated by `v·τ`, with `τ = min(t, end_s) − start_s` (no motion
/// before `start_s`; the pose at `end_s` is held afterwards).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Motion {
    /// Time the motion starts, s (default: 0).
    pub start_s: f64,
    /// Time the motion stops, s (default: ∞, never; TOML `inf`).
    pub end_s: f64,
    /// Linear velocity `v`, m/s (default: 0).
    pub velocity_m_s: [f64; 3],
    /// Angular velocity `ω`, degrees/s, right-handed about `axis` (default: 0).
    pub angular_velocity_deg_s: f64,
    /// Rotation axis (normalised here); required when `angular_velocity_deg_s` ≠ 0
    /// (default: none).
    pub axis: Option<[f64; 3]>,
    /// A point on the rotation axis, m (default: the origin).
    pub center_m: [f64; 3],
}

impl Default for Motion {
    fn default() -> Self {
        Motion {
            start_s: 0.0,
            end_s: f64::INFINITY,
            velocity_m_s: [0.0; 3],
            angular_velocity_deg_s: 0.0,
            axis: None,
            center_m: [0.0; 3],
        }
    }
}

impl Motion {
    /// Check the values; the error names the field.
    pub fn validate(&self) -> std::result::Result<(), (&'static str, String)> {
        if !self.start_s.is_finite() {
            return Err(("start_s", format!("start_s = {} must be finite", self.start_s)));
        }
        if self.end_s.is_nan() || self.end_s <= self.start_s {
            return Err((
                "end_s",
                format!("end_s = {} must be greater than start_s = {}", self.end_s, self.start_s),
            ));
        }
        if !self.velocity_m_s.iter().all(|v| v.is_finite()) {
            return Err(("velocity_m_s", "velocity_m_s must be finite".into()));
        }
        if !self.center_m.iter().all(|v| v.is_finite()) {
            return Err(("center_m", "center_m must be finite".into()));
        }
        if !self.angular_velocity_deg_s.is_finite() {
            return Err(("angular_velocity_deg_s", "angular_velocity_deg_s must be finite".into()));
        }
        match self.axis {
            Some(a) if !a.iter().all(|v| v.is_finite()) || Vector3::from(a).norm() == 0.0 => {
                Err(("axis", format!("axis {a:?} must be finite and non-zero")))
            }
            None if self.angular_velocity_deg_s != 0.0 => {
                Err(("angular_velocity_deg_s", "a rotating motion needs an `axis`".into()))
            }
            _ => Ok(()),
        }
    }

    /// The target transform at time `t`: targets are `R·p + translation` for the reference
    /// positions `p`.
    pub fn transform_at(&self, t: f64) -> (Vector3<f64>, Rotation3<f64>) {
        let tau = (t.min(self.end_s) - self.start_s).max(0.0);
        let angle = (self.angular_velocity_deg_s * tau).to_radians();
        let rotation = match self.axis {
            Some(a) if angle != 0.0 => Rotation3::from_axis_angle(&Unit::new_normalize(Vector3::from(a)), angle),
            _ => Rotation3::identity(),
        };
        let c = Vector3::from(self.center_m);
        let translation = c - rotation * c + Vector3::from(self.velocity_m_s) * tau;
        (translation, rotation)
    }

    /// Move the targets of group `h` to their pose at time `t`.
    pub fn apply(&self, sim: &mut Simulation, h: PrescribedHandle, t: f64) -> Result<()> {
        let (translation, rotation) = self.transform_at(t);
        sim.deformables.prescribed.set_transform(h, translation, rotation)
    }
}

/// A `[[gravity_ramp]]`: gravity changes linearly from `from_m_s2` (default: the gravity at
/// the time) to `to_m_s2` between `start_s` and `end_s`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct GravityRampEntry {
    start_s: f64,
    end_s: f64,
    from_m_s2: Option<[f64; 3]>,
    to_m_s2: [f64; 3],
}

/// Add the gravity ramps as time events, in the order of their start times.
pub(super) fn add_gravity_ramps(sim: &mut Simulation, ctx: &Ctx, ramps: &[GravityRampEntry]) -> Res<()> {
    let mut order: Vec<usize> = (0..ramps.len()).collect();
    order.sort_by(|&i, &j| ramps[i].start_s.total_cmp(&ramps[j].start_s));
    for i in order {
        let r = &ramps[i];
        let at = At::entry("gravity_ramp", i);
        if !(r.start_s.is_finite() && r.end_s.is_finite() && r.end_s > r.start_s) {
            return Err(ctx.err(
                &at.key("end_s"),
                format!(
                    "the ramp from {} s to {} s needs finite times with end_s > start_s",
                    r.start_s, r.end_s
                ),
            ));
        }
        let from = Vector3::from(r.from_m_s2.unwrap_or(sim.settings.gravity_m_s2));
        let to = Vector3::from(r.to_m_s2);
        if !(from.iter().chain(to.iter()).all(|g| g.is_finite())) {
            return Err(ctx.err(&at.key("to_m_s2"), "gravity must be finite"));
        }
        let (start, end) = (r.start_s, r.end_s);
        sim.add_time_event(start, f64::INFINITY, move |sim, t| {
            let s = ((t - start) / (end - start)).clamp(0.0, 1.0);
            sim.set_gravity(from + (to - from) * s);
            Ok(())
        });
    }
    Ok(())
}

//! [`Simulation::add_joint`], which builds every [`JointKind`] (and [`Simulation::joint_by_label`]),
//! with the checks of its fields.

use super::builder::{perpendicular, Builder};
use super::kind::JointKind;
use super::{coupling, JointHandle, JointParams, Measure, Primitive, Servo, DEFAULT_CONTROLLER_DELAY};
use crate::error::{check_param, Result, StarkError};
use crate::rigidbodies::RigidBodyHandle;
use crate::simulation::Simulation;
use nalgebra::{Unit, UnitQuaternion, Vector3};

/// The value of a vector field, checked finite.
fn vector(label: &str, field: &str, v: [f64; 3]) -> Result<Vector3<f64>> {
    if v.iter().all(|c| c.is_finite()) {
        Ok(Vector3::from(v))
    } else {
        Err(StarkError::InvalidInput(format!(
            "joint '{label}': `{field}` = {v:?} must be finite"
        )))
    }
}

/// The value of a direction field, checked finite and non-zero (any length).
fn direction(label: &str, field: &str, v: [f64; 3]) -> Result<Vector3<f64>> {
    let d = Vector3::from(v);
    if d.iter().all(|c| c.is_finite()) && d.norm() >= 1e-12 {
        Ok(d)
    } else {
        Err(StarkError::InvalidInput(format!(
            "joint '{label}': `{field}` = {v:?} must be finite and non-zero"
        )))
    }
}

fn finite(label: &str, field: &'static str, x: f64) -> Result<f64> {
    check_param(label, field, x, x.is_finite(), "must be finite")?;
    Ok(x)
}

fn angle_deg(label: &str, field: &'static str, x: f64) -> Result<f64> {
    check_param(label, field, x, (0.0..=180.0).contains(&x), "must be in [0, 180]")?;
    Ok(x)
}

/// A controller's cap: N or N·m.
fn check_max(label: &str, field: &'static str, max: f64) -> Result<()> {
    check_param(label, field, max, max >= 0.0 && max.is_finite(), "must be non-negative")
}

/// A controller's delay (the velocity error at which it reaches its cap): m/s.
fn check_delay_m_s(label: &str, delay: f64) -> Result<f64> {
    check_param(
        label,
        "delay_m_s",
        delay,
        delay > 0.0 && delay.is_finite(),
        "must be positive",
    )?;
    Ok(delay)
}

fn response_time(label: &str, t: f64) -> Result<f64> {
    check_param(
        label,
        "response_time_s",
        t,
        t >= 0.0 && t.is_finite(),
        "must be non-negative (s)",
    )?;
    Ok(t)
}

/// A controller delay given in degrees/s, or the default 0.01 rad/s: rad/s.
fn delay_rad_s(label: &str, delay_deg_s: Option<f64>) -> Result<f64> {
    let Some(deg) = delay_deg_s else {
        return Ok(DEFAULT_CONTROLLER_DELAY);
    };
    check_param(
        label,
        "delay_deg_s",
        deg,
        deg > 0.0 && deg.is_finite(),
        "must be positive",
    )?;
    Ok(deg.to_radians())
}

fn invalid(label: &str, message: impl std::fmt::Display) -> StarkError {
    StarkError::InvalidInput(format!("joint '{label}': {message}"))
}

impl Simulation {
    /// The joint labelled `label` (a clear error if there is none, or several).
    pub fn joint_by_label(&self, label: &str) -> Result<JointHandle> {
        let joints = &self.rigid_bodies.named_joints;
        let found: Vec<_> = joints.iter().filter(|j| j.label == label).collect();
        match found[..] {
            [h] => Ok(h.clone()),
            [] => {
                let known: Vec<_> = joints.iter().map(|j| format!("'{}'", j.label)).collect();
                Err(StarkError::InvalidInput(format!(
                    "no joint is labelled '{label}'; the joints are {}",
                    if known.is_empty() {
                        "none yet".to_string()
                    } else {
                        known.join(", ")
                    }
                )))
            }
            _ => Err(StarkError::InvalidInput(format!(
                "{} joints are labelled '{label}': give them unique labels",
                found.len()
            ))),
        }
    }

    /// Add a joint of any kind between body `a` (`None`: the world) and body `b` (`None` only
    /// for the couplings, which name their joints inside `kind`), with the hard constraints'
    /// `params`. Errors name the joint's label and the field of `kind` (its serde name).
    pub fn add_joint(
        &mut self,
        label: &str,
        a: Option<RigidBodyHandle>,
        b: Option<RigidBodyHandle>,
        kind: JointKind,
        params: JointParams,
    ) -> Result<JointHandle> {
        use JointKind::*;
        let type_name = kind.type_name();
        let acts_on_joints = matches!(kind, JointCoupling { .. } | JointSpring { .. });
        if acts_on_joints && (a.is_some() || b.is_some()) {
            return Err(invalid(
                label,
                format_args!("a {type_name} acts on joints named by label: `a` and `b` must be None"),
            ));
        }
        let b = match (b, acts_on_joints) {
            (Some(b), _) => Some(b),
            (None, true) => None,
            (None, false) => {
                return Err(invalid(
                    label,
                    format_args!(
                    "`b` must be a rigid body (a {type_name} joint moves body b relative to a; `a` may be the world)"
                ),
                ))
            }
        };
        let l = label;
        // The builder of a joint between a and b (after the checks of its fields).
        macro_rules! new {
            ($sim:expr) => {
                Builder::new($sim, l, a, b, params)
            };
        }
        let j = match kind {
            Ball { point_m } => {
                let p = vector(l, "point_m", point_m)?;
                let mut j = new!(self)?;
                j.point(&p);
                j
            }
            BallCone {
                point_m,
                axis,
                limit_deg,
            } => {
                let (p, axis) = (vector(l, "point_m", point_m)?, direction(l, "axis", axis)?);
                let limit = angle_deg(l, "limit_deg", limit_deg)?;
                let mut j = new!(self)?;
                j.point(&p);
                j.angle_limit(&axis, limit.to_radians());
                j
            }
            Hinge { point_m, axis } | HingeLimit { point_m, axis, .. } => {
                let (p, axis) = (vector(l, "point_m", point_m)?, direction(l, "axis", axis)?);
                let limit = match kind {
                    HingeLimit { limit_deg, .. } => Some(angle_deg(l, "limit_deg", limit_deg)?),
                    _ => None,
                };
                let mut j = new!(self)?;
                j.point(&p);
                j.direction(&axis);
                j.angle_measure(&axis);
                if let Some(limit) = limit {
                    j.angle_limit(&perpendicular(&axis), limit.to_radians());
                }
                j
            }
            HingeRange {
                point_m,
                axis,
                limits_deg,
            } => {
                vector(l, "point_m", point_m)?;
                let axis = direction(l, "axis", axis)?;
                let [lower, upper] = limits_deg.map(f64::to_radians);
                if !(lower.is_finite() && upper.is_finite() && lower <= 1e-12 && upper >= -1e-12) {
                    return Err(invalid(
                        l,
                        format_args!("`limits_deg` = {limits_deg:?} must be finite and contain the current angle 0"),
                    ));
                }
                if upper - lower > std::f64::consts::TAU {
                    return Err(invalid(
                        l,
                        format_args!("`limits_deg` = {limits_deg:?} is wider than a turn"),
                    ));
                }
                let u = perpendicular(&axis);
                let middle = UnitQuaternion::from_axis_angle(&Unit::new_normalize(axis), 0.5 * (lower + upper));
                let mut j = new!(self)?;
                let [a0, a1] = j.a.direction(&(middle * u));
                let [b0, b1] = j.b.direction(&u);
                j.push(
                    Primitive::AngleLimit {
                        limit_rad: 0.5 * (upper - lower),
                    },
                    &[a0, a1, b0, b1],
                );
                j
            }
            Universal {
                point_m,
                axis_a,
                axis_b,
            } => {
                let p = vector(l, "point_m", point_m)?;
                let (da, db) = (direction(l, "axis_a", axis_a)?, direction(l, "axis_b", axis_b)?);
                if da.normalize().dot(&db.normalize()).abs() > 1e-6 {
                    return Err(invalid(
                        l,
                        format_args!("`axis_b` = {axis_b:?} must be perpendicular to `axis_a` = {axis_a:?}"),
                    ));
                }
                let mut j = new!(self)?;
                j.point(&p);
                let [a0, a1] = j.a.direction(&da);
                let [b0, b1] = j.b.direction(&db);
                j.push(Primitive::Perpendicular, &[a0, a1, b0, b1]);
                j
            }
            Slider { point_m, axis } | Prismatic { point_m, axis } => {
                let (p, axis) = (vector(l, "point_m", point_m)?, direction(l, "axis", axis)?);
                let mut j = new!(self)?;
                j.point_on_axis(&p, &axis);
                j.direction(&axis);
                j.position_measure(&p, &axis);
                if matches!(kind, Prismatic { .. }) {
                    j.direction(&perpendicular(&axis));
                }
                j
            }
            SliderRange {
                point_m,
                axis,
                limits_m,
            } => {
                let (p, axis) = (vector(l, "point_m", point_m)?, direction(l, "axis", axis)?);
                let [lower, upper] = limits_m;
                if !(lower.is_finite() && upper.is_finite() && lower <= 1e-12 && upper >= -1e-12) {
                    return Err(invalid(
                        l,
                        format_args!("`limits_m` = {limits_m:?} must be finite and contain the current position 0"),
                    ));
                }
                let n = axis.normalize();
                let reach = 1.0 + (upper - lower);
                let mut j = new!(self)?;
                let nodes = [j.a.point(&(p + n * (lower - reach))), j.b.point(&p)];
                j.push(
                    Primitive::DistanceLimits {
                        min_m: reach,
                        max_m: reach + (upper - lower),
                    },
                    &nodes,
                );
                j
            }
            PointOnAxis { point_m, axis } => {
                let (p, axis) = (vector(l, "point_m", point_m)?, direction(l, "axis", axis)?);
                let mut j = new!(self)?;
                j.point_on_axis(&p, &axis);
                j.position_measure(&p, &axis);
                j
            }
            Planar { point_m, normal } => {
                let (p, normal) = (vector(l, "point_m", point_m)?, direction(l, "normal", normal)?);
                let mut j = new!(self)?;
                let nodes = [j.a.point(&p), j.a.point(&(p + normal.normalize())), j.b.point(&p)];
                j.push(Primitive::PointOnPlane, &nodes);
                j.direction(&normal);
                j
            }
            PrismaticPress {
                point_m,
                axis,
                target_velocity_m_s,
                max_force_n,
                delay_m_s,
            } => {
                let (p, axis) = (vector(l, "point_m", point_m)?, direction(l, "axis", axis)?);
                let target = finite(l, "target_velocity_m_s", target_velocity_m_s)?;
                check_max(l, "max_force_n", max_force_n)?;
                let delay_m_s = check_delay_m_s(l, delay_m_s)?;
                let mut j = new!(self)?;
                j.point_on_axis(&p, &axis);
                j.direction(&axis);
                j.position_measure(&p, &axis);
                j.direction(&perpendicular(&axis));
                j.linear_velocity(&p, &axis, target, max_force_n, delay_m_s);
                j
            }
            Motor {
                point_m,
                axis,
                target_velocity_deg_s,
                max_torque_n_m,
                delay_deg_s,
            } => {
                let (p, axis) = (vector(l, "point_m", point_m)?, direction(l, "axis", axis)?);
                let target = finite(l, "target_velocity_deg_s", target_velocity_deg_s)?.to_radians();
                let delay = delay_rad_s(l, delay_deg_s)?;
                check_max(l, "max_torque_n_m", max_torque_n_m)?;
                let mut j = new!(self)?;
                j.point(&p);
                j.direction(&axis);
                j.angle_measure(&axis);
                j.angular_velocity(&axis, target, max_torque_n_m, delay);
                j
            }
            HingeServo {
                point_m,
                axis,
                target_deg,
                max_torque_n_m,
                response_time_s,
            } => {
                let (p, axis) = (vector(l, "point_m", point_m)?, direction(l, "axis", axis)?);
                let target = finite(l, "target_deg", target_deg)?.to_radians();
                let response_time_s = response_time(l, response_time_s)?;
                let delay = DEFAULT_CONTROLLER_DELAY;
                check_max(l, "max_torque_n_m", max_torque_n_m)?;
                let mut j = new!(self)?;
                j.point(&p);
                j.direction(&axis);
                j.angle_measure(&axis);
                j.angular_velocity(&axis, 0.0, max_torque_n_m, delay);
                j.servo(target, response_time_s);
                j
            }
            PrismaticServo {
                point_m,
                axis,
                target_m,
                max_force_n,
                response_time_s,
            } => {
                let (p, axis) = (vector(l, "point_m", point_m)?, direction(l, "axis", axis)?);
                let target = finite(l, "target_m", target_m)?;
                let response_time_s = response_time(l, response_time_s)?;
                let delay = DEFAULT_CONTROLLER_DELAY;
                check_max(l, "max_force_n", max_force_n)?;
                let mut j = new!(self)?;
                j.point_on_axis(&p, &axis);
                j.direction(&axis);
                j.position_measure(&p, &axis);
                j.direction(&perpendicular(&axis));
                j.linear_velocity(&p, &axis, 0.0, max_force_n, delay);
                j.servo(target, response_time_s);
                j
            }
            Fix {} | Attachment {} => {
                match (&kind, a) {
                    (Fix {}, Some(_)) => {
                        return Err(invalid(
                            l,
                            "a fix joint holds body b in the world: `a` must be the world (leave it out)",
                        ))
                    }
                    (Attachment {}, None) => return Err(invalid(
                        l,
                        "an attachment glues two bodies: `a` must be a rigid body (a fix joint holds b in the world)",
                    )),
                    _ => {}
                }
                let mut j = new!(self)?;
                let at = match kind {
                    Fix {} => j.b.t,
                    _ => 0.5 * (j.a.t + j.b.t),
                };
                j.point(&at);
                j.direction(&Vector3::z());
                j.direction(&Vector3::x());
                j
            }
            Distance { point_a_m, point_b_m } => {
                let (pa, pb) = (vector(l, "point_a_m", point_a_m)?, vector(l, "point_b_m", point_b_m)?);
                let mut j = new!(self)?;
                let nodes = [j.a.point(&pa), j.b.point(&pb)];
                j.push(
                    Primitive::Distance {
                        target_m: (pb - pa).norm(),
                    },
                    &nodes,
                );
                j
            }
            DistanceLimits {
                point_a_m,
                point_b_m,
                min_m,
                max_m,
            } => {
                let (pa, pb) = (vector(l, "point_a_m", point_a_m)?, vector(l, "point_b_m", point_b_m)?);
                let d = (pb - pa).norm();
                if !(min_m >= 0.0 && min_m <= max_m && d >= min_m - 1e-12 && d <= max_m + 1e-12) {
                    return Err(invalid(
                        l,
                        format_args!(
                            "`min_m` = {min_m}, `max_m` = {max_m}: need 0 ≤ min_m ≤ current distance {d} ≤ max_m"
                        ),
                    ));
                }
                let mut j = new!(self)?;
                let nodes = [j.a.point(&pa), j.b.point(&pb)];
                j.push(Primitive::DistanceLimits { min_m, max_m }, &nodes);
                j
            }
            Spring {
                point_a_m,
                point_b_m,
                spring_stiffness_n_m,
                damping_n_s_m,
                limits_m,
            } => {
                let (pa, pb) = (vector(l, "point_a_m", point_a_m)?, vector(l, "point_b_m", point_b_m)?);
                let k = spring_stiffness_n_m;
                check_param(
                    l,
                    "spring_stiffness_n_m",
                    k,
                    k >= 0.0 && k.is_finite(),
                    "must be non-negative (N/m)",
                )?;
                let d = damping_n_s_m;
                check_param(
                    l,
                    "damping_n_s_m",
                    d,
                    d >= 0.0 && d.is_finite(),
                    "must be non-negative (N·s/m)",
                )?;
                let rest = (pb - pa).norm();
                if let Some([min, max]) = limits_m {
                    if !(min >= 0.0 && min <= rest && rest <= max) {
                        return Err(invalid(
                            l,
                            format_args!("`limits_m` = [{min}, {max}]: need 0 ≤ min ≤ rest length {rest} ≤ max"),
                        ));
                    }
                }
                let mut j = new!(self)?;
                let nodes = [j.a.point(&pa), j.b.point(&pb)];
                let e = j.push(
                    Primitive::Spring {
                        rest_length_m: rest,
                        damping_n_s_m: d,
                    },
                    &nodes,
                );
                j.sim.rigid_bodies.joints.potential.elements[e as usize].stiffness = k;
                j.driver = Some(e);
                if let Some([min_m, max_m]) = limits_m {
                    j.push(Primitive::DistanceLimits { min_m, max_m }, &nodes);
                }
                j
            }
            Direction { axis } => {
                let axis = direction(l, "axis", axis)?;
                let mut j = new!(self)?;
                j.direction(&axis);
                j
            }
            AngleLimit { axis, limit_deg } => {
                let axis = direction(l, "axis", axis)?;
                let limit = angle_deg(l, "limit_deg", limit_deg)?;
                let mut j = new!(self)?;
                j.angle_limit(&axis, limit.to_radians());
                j
            }
            LinearVelocity {
                point_m,
                axis,
                target_velocity_m_s,
                max_force_n,
                delay_m_s,
            } => {
                let (p, axis) = (vector(l, "point_m", point_m)?, direction(l, "axis", axis)?);
                let target = finite(l, "target_velocity_m_s", target_velocity_m_s)?;
                check_max(l, "max_force_n", max_force_n)?;
                let delay_m_s = check_delay_m_s(l, delay_m_s)?;
                let mut j = new!(self)?;
                j.linear_velocity(&p, &axis, target, max_force_n, delay_m_s);
                j
            }
            AngularVelocity {
                axis,
                target_velocity_deg_s,
                max_torque_n_m,
                delay_deg_s,
            } => {
                let axis = direction(l, "axis", axis)?;
                let target = finite(l, "target_velocity_deg_s", target_velocity_deg_s)?.to_radians();
                let delay = delay_rad_s(l, delay_deg_s)?;
                check_max(l, "max_torque_n_m", max_torque_n_m)?;
                let mut j = new!(self)?;
                j.angular_velocity(&axis, target, max_torque_n_m, delay);
                j
            }
            JointCoupling {
                joint_a,
                joint_b,
                multiplier,
                offset,
            } => {
                let multiplier = finite(l, "multiplier", multiplier)?;
                let offset = finite(l, "offset", offset)?;
                let ma = self.coordinate_of(l, "joint_a", &joint_a)?;
                let mb = self.coordinate_of(l, "joint_b", &joint_b)?;
                let c = coupling::Coupling {
                    a: Some(coupling::CoupledCoordinate::new(ma)),
                    b: coupling::CoupledCoordinate::new(mb),
                    multiplier,
                    offset,
                    damping: 0.0,
                    hard: true,
                };
                self.coupling_builder(l, c, params)?
            }
            JointSpring {
                joint,
                spring_stiffness,
                rest,
                damping,
            } => {
                let k = spring_stiffness;
                check_param(
                    l,
                    "spring_stiffness",
                    k,
                    k >= 0.0 && k.is_finite(),
                    "must be non-negative",
                )?;
                let rest = finite(l, "rest", rest)?;
                check_param(
                    l,
                    "damping",
                    damping,
                    damping >= 0.0 && damping.is_finite(),
                    "must be non-negative",
                )?;
                let m = self.coordinate_of(l, "joint", &joint)?;
                let c = coupling::Coupling {
                    a: None,
                    b: coupling::CoupledCoordinate::new(m),
                    multiplier: 0.0,
                    offset: rest,
                    damping,
                    hard: false,
                };
                let j = self.coupling_builder(l, c, params)?;
                let e = j.elements[0] as usize;
                j.sim.rigid_bodies.joints.potential.elements[e].stiffness = k;
                j
            }
        };
        Ok(j.finish())
    }

    /// The coordinate of the joint labelled `joint` (the field `field` of joint `label`).
    fn coordinate_of(&self, label: &str, field: &str, joint: &str) -> Result<Measure> {
        let h = self
            .joint_by_label(joint)
            .map_err(|e| invalid(label, format_args!("`{field}`: {e}")))?;
        h.measure.ok_or_else(|| {
            invalid(
                label,
                format_args!("`{field}` = '{joint}' has no coordinate (hinges, sliders, prismatic and point-on-axis joints have)"),
            )
        })
    }

    /// A builder holding one coupling element, between the bodies of its last coordinate.
    fn coupling_builder(&mut self, label: &str, c: coupling::Coupling, params: JointParams) -> Result<Builder<'_>> {
        let (parent, child) = match c.b.measure {
            Measure::Angle { a, b, .. } | Measure::Position { a, b, .. } => (a, b),
        };
        let handle = |i: Option<u32>| i.map(|index| RigidBodyHandle { index });
        let child = handle(child).ok_or_else(|| invalid(label, "no body"))?;
        let mut j = Builder::new(self, label, handle(parent), Some(child), params)?;
        let nodes = c.nodes();
        j.push(Primitive::Coupling(Box::new(c)), &nodes);
        Ok(j)
    }
}

impl Builder<'_> {
    /// Make the driver a position servo of the joint's coordinate.
    fn servo(&mut self, target: f64, response_time_s: f64) {
        let e = self.driver.expect("a servo drives a controller") as usize;
        let measure = self.measure.expect("a servo measures its coordinate");
        self.sim.rigid_bodies.joints.potential.elements[e].servo = Some(Servo {
            target,
            response_time_s,
            measure,
        });
    }
}

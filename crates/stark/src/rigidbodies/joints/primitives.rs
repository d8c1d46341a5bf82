//! The primitive joint energies, each written once in world positions of body-fixed points
//! ([`Node::Rigid`](crate::energy::Node::Rigid)), world points ([`Node::World`](crate::energy::Node::World))
//! or body angular velocities. Every composed joint (hinge, slider, motor, …) is a sum of these.
//!
//! Directions are differences of two points of one body one unit apart, so a direction
//! constraint is the chord penalty `½k‖d_b − d_a‖²` of Stark (stiffness in N/m like the point
//! constraints). Velocity controllers use the smooth capped force law of Stark's
//! `add_constraint_*_velocity`: with the velocity error `u`, the force is `−(F/δ)u` for `|u| < δ`
//! and `−F·sign(u)` beyond, the derivative of `Φ(u)`; the step energy is `dt·Φ(u)`, so its
//! gradient with respect to the velocity DOFs is the impulse `dt·F`.

use crate::energy::{Scalar, Stencil, Vec3};
use nalgebra::Vector3;

/// Which primitive a joint element is, with its parameters.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Primitive {
    /// Two points coincide: `½k‖x_b − x_a‖²` (nodes: a, b). Violation: distance, m.
    Point,
    /// Point b stays on the line through a0 along the unit direction a1 − a0:
    /// `½k‖r − (r·d)d‖²`, `r = b − a0` (nodes: a0, a1, b). Violation: distance, m.
    PointOnAxis,
    /// Two points keep a distance: `½k(‖x_b − x_a‖ − L)²` (nodes: a, b). Violation, m.
    Distance {
        /// Target distance L, m.
        target_m: f64,
    },
    /// Distance kept within limits: quadratic outside `[min, max]` (nodes: a, b). Violation, m.
    DistanceLimits {
        /// Lower limit, m.
        min_m: f64,
        /// Upper limit, m.
        max_m: f64,
    },
    /// Two unit directions align: `½k‖d_b − d_a‖²` (nodes: a0, a1, b0, b1). Violation: angle, rad.
    Direction,
    /// The angle between two directions stays below a limit: `k/3·(‖d_b − d_a‖ − c)³` beyond the
    /// chord `c = √(2 − 2cos θ_max)` (nodes: a0, a1, b0, b1). Violation: excess angle, rad.
    AngleLimit {
        /// Largest angle, rad.
        limit_rad: f64,
    },
    /// Two directions stay perpendicular (the cross of a universal joint): `½k(d_a·d_b)²`
    /// (nodes: a0, a1, b0, b1). Violation: deviation from 90°, rad.
    Perpendicular,
    /// A damped spring: `½k(l − L)² + ½c(l − l0)²/dt` (damping force `c·l̇`; nodes: a, b). Soft.
    Spring {
        /// Rest length L, m.
        rest_length_m: f64,
        /// Damping c, N·s/m.
        damping_n_s_m: f64,
    },
    /// Relative velocity of b's point with respect to a's along the unit direction a1 − a0 driven
    /// to a target with a capped force (nodes: a0, a1, b at a0). Soft.
    LinearVelocity {
        /// Target velocity, m/s.
        target_m_s: f64,
        /// Largest force, N.
        max_force_n: f64,
        /// Velocity error below which the force is linear, m/s.
        delay_m_s: f64,
    },
    /// Relative angular velocity of b with respect to a about the unit axis a1 − a0 driven to a
    /// target with a capped torque (nodes: ω_a, ω_b, a0, a1). Soft.
    AngularVelocity {
        /// Target angular velocity, rad/s.
        target_rad_s: f64,
        /// Largest torque, N·m.
        max_torque_n_m: f64,
        /// Angular velocity error below which the torque is linear, rad/s.
        delay_rad_s: f64,
    },
}

/// `Φ(u)` of the capped controllers: `½(F/δ)u²` for `|u| < δ`, `F(|u| − δ/2)` beyond.
fn capped<S: Scalar>(u: S, max: f64, delay: f64) -> S {
    S::select_gt(
        u * u,
        S::constant(delay * delay),
        || {
            let abs = S::select_gt(u, S::zero(), || u, || -u);
            (abs - 0.5 * delay) * max
        },
        || u * u * (0.5 * max / delay),
    )
}

fn chord_of(angle_rad: f64) -> f64 {
    (2.0 - 2.0 * angle_rad.cos()).max(0.0).sqrt()
}

fn angle_of_chord(chord: f64) -> f64 {
    2.0 * (0.5 * chord).clamp(-1.0, 1.0).asin()
}

impl Primitive {
    /// Number of nodes the primitive uses (its element is padded to 4 with world points).
    pub fn num_nodes(&self) -> usize {
        match self {
            Primitive::Point
            | Primitive::Distance { .. }
            | Primitive::DistanceLimits { .. }
            | Primitive::Spring { .. } => 2,
            Primitive::PointOnAxis | Primitive::LinearVelocity { .. } => 3,
            _ => 4,
        }
    }

    /// Whether the primitive is a hard constraint (hardened to a tolerance).
    pub fn is_hard(&self) -> bool {
        !matches!(
            self,
            Primitive::Spring { .. } | Primitive::LinearVelocity { .. } | Primitive::AngularVelocity { .. }
        )
    }

    /// Whether the violation is an angle (rad) rather than a length (m).
    pub fn is_angular(&self) -> bool {
        matches!(
            self,
            Primitive::Direction | Primitive::AngleLimit { .. } | Primitive::Perpendicular
        )
    }

    /// Energy at positions `x` with stiffness `k`.
    pub fn energy<S: Scalar>(&self, x: &[Vec3<S>; 4], s: &Stencil<4>, k: f64) -> S {
        let dt = s.dt;
        match *self {
            Primitive::Point => (x[1] - x[0]).norm_sq() * (0.5 * k),
            Primitive::PointOnAxis => {
                let r = x[2] - x[0];
                let d = x[1] - x[0];
                let perp = r - d * (r.dot(&d) / d.norm_sq());
                perp.norm_sq() * (0.5 * k)
            }
            Primitive::Distance { target_m } => ((x[1] - x[0]).norm() - target_m).sq() * (0.5 * k),
            Primitive::DistanceLimits { min_m, max_m } => {
                let l = (x[1] - x[0]).norm();
                ((l - max_m).positive_part().sq() + (-(l - min_m)).positive_part().sq()) * (0.5 * k)
            }
            Primitive::Direction => ((x[3] - x[2]) - (x[1] - x[0])).norm_sq() * (0.5 * k),
            Primitive::AngleLimit { limit_rad } => {
                let c = chord_of(limit_rad);
                let excess = (((x[3] - x[2]) - (x[1] - x[0])).norm() - c).positive_part();
                excess * excess * excess * (k / 3.0)
            }
            Primitive::Perpendicular => (x[1] - x[0]).dot(&(x[3] - x[2])).sq() * (0.5 * k),
            Primitive::Spring {
                rest_length_m,
                damping_n_s_m,
            } => {
                let l = (x[1] - x[0]).norm();
                let l0 = (s.x0[1] - s.x0[0]).norm();
                (l - rest_length_m).sq() * (0.5 * k) + (l - l0).sq() * (0.5 * damping_n_s_m / dt)
            }
            Primitive::LinearVelocity {
                target_m_s,
                max_force_n,
                delay_m_s,
            } => {
                let d = x[1] - x[0];
                let rel = (x[2].sub_f64(&s.x0[2]) - x[0].sub_f64(&s.x0[0])) * S::constant(1.0 / dt);
                let u = rel.dot(&d) - target_m_s;
                capped(u, max_force_n, delay_m_s) * dt
            }
            Primitive::AngularVelocity {
                target_rad_s,
                max_torque_n_m,
                delay_rad_s,
            } => {
                let axis = x[3] - x[2];
                let u = (x[1] - x[0]).dot(&axis) - target_rad_s;
                capped(u, max_torque_n_m, delay_rad_s) * dt
            }
        }
    }

    /// Violation at positions `x`: m, or rad for [`Primitive::is_angular`]; 0 for soft ones.
    pub fn violation(&self, x: &[Vector3<f64>; 4]) -> f64 {
        match *self {
            Primitive::Point => (x[1] - x[0]).norm(),
            Primitive::PointOnAxis => {
                let r = x[2] - x[0];
                let d = (x[1] - x[0]).normalize();
                (r - d * r.dot(&d)).norm()
            }
            Primitive::Distance { target_m } => ((x[1] - x[0]).norm() - target_m).abs(),
            Primitive::DistanceLimits { min_m, max_m } => {
                let l = (x[1] - x[0]).norm();
                (l - max_m).max(min_m - l).max(0.0)
            }
            Primitive::Direction => angle_of_chord(((x[3] - x[2]) - (x[1] - x[0])).norm()),
            Primitive::AngleLimit { limit_rad } => {
                (angle_of_chord(((x[3] - x[2]) - (x[1] - x[0])).norm()) - limit_rad).max(0.0)
            }
            Primitive::Perpendicular => (x[1] - x[0]).dot(&(x[3] - x[2])).clamp(-1.0, 1.0).asin().abs(),
            _ => 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn capped_law_is_c1_with_the_right_force() {
        let (f, d) = (5.0, 0.01);
        let h = 1e-7;
        for u in [-0.1, -0.01, -0.005, 0.0, 0.003, 0.01, 0.2] {
            let slope = (capped(u + h, f, d) - capped(u - h, f, d)) / (2.0 * h);
            let expected = if u.abs() < d { f * u / d } else { f * u.signum() };
            assert!((slope - expected).abs() < 1e-5, "u {u}: {slope} vs {expected}");
        }
    }

    #[test]
    fn chord_and_angle_are_inverse() {
        for a in [0.0, 0.1, 1.0, 3.0] {
            assert!((angle_of_chord(chord_of(a)) - a).abs() < 1e-12);
        }
    }
}

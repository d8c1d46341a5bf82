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

use super::coupling::Coupling;
use crate::energy::{HyperDual, Scalar, Stencil, Vec3};
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
    ///
    /// Stark's cubic: it starts with zero stiffness at the limit (C² contact), so it holds a
    /// torque `τ` at a penetration of about `√(τ/k)` and hardening has to raise `k` to about
    /// `τ/tol²` (2e7–8e7 for 10–110 N·m within 0.1°, against 1e5 for the quadratic primitives).
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
    /// Point b stays on the plane through a0 with the unit normal a1 − a0: `½k((b − a0)·n)²`
    /// (nodes: a0, a1, b). Violation: distance, m.
    PointOnPlane,
    /// A linear relation between two joint coordinates (mimic), or a spring–damper on one
    /// (nodes: parent and child of each coordinate; see [`Coupling`]). Hard if `hard`. Violation:
    /// rad or m, of the following coordinate.
    Coupling(Box<Coupling>),
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
        /// Drives only: the torque never opposes the target's direction, so a joint turning
        /// faster than its target (pushed, or rolling downhill) is not braked (a motor whose
        /// driver cannot regenerate). Zero target: no torque at all.
        #[serde(default)]
        drive_only: bool,
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
            Primitive::PointOnAxis | Primitive::PointOnPlane | Primitive::LinearVelocity { .. } => 3,
            _ => 4,
        }
    }

    /// Whether the primitive is a hard constraint (hardened to a tolerance).
    pub fn is_hard(&self) -> bool {
        if let Primitive::Coupling(c) = self {
            return c.hard;
        }
        !matches!(
            self,
            Primitive::Spring { .. } | Primitive::LinearVelocity { .. } | Primitive::AngularVelocity { .. }
        )
    }

    /// Whether the violation is an angle (rad) rather than a length (m).
    pub fn is_angular(&self) -> bool {
        if let Primitive::Coupling(c) = self {
            return c.b.is_angle();
        }
        matches!(
            self,
            Primitive::Direction | Primitive::AngleLimit { .. } | Primitive::Perpendicular
        )
    }

    /// Value, gradient and Hessian in closed form for the primitives that are a quadratic
    /// `½k‖Σₐ cₐxₐ‖²` (`Point`: c = (−1, 1, 0, 0); `Direction`: c = (1, −1, −1, 1)), whose Hessian
    /// is the constant `k cₐc_b I`, written into `out`; `false` (nothing written) for the others,
    /// which take hyper-duals. Ball, fixed and hinge joints are made of these, and hyper-duals
    /// cost ~150 flops per operation at 4 nodes.
    pub fn quadratic_derivatives(&self, x: &[Vector3<f64>; 4], k: f64, out: &mut HyperDual<4>) -> bool {
        let c: [f64; 4] = match self {
            Primitive::Point => [-1.0, 1.0, 0.0, 0.0],
            Primitive::Direction => [1.0, -1.0, -1.0, 1.0],
            _ => return false,
        };
        let r: Vector3<f64> = (0..4).map(|a| x[a] * c[a]).sum();
        out.value = 0.5 * k * r.norm_squared();
        for a in 0..4 {
            for i in 0..3 {
                out.grad[a][i] = k * c[a] * r[i];
                for b in 0..4 {
                    for j in 0..3 {
                        out.hess[a][i][b][j] = if i == j { k * c[a] * c[b] } else { 0.0 };
                    }
                }
            }
        }
        true
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
            Primitive::PointOnPlane => {
                let n = x[1] - x[0];
                ((x[2] - x[0]).dot(&n).sq() / n.norm_sq()) * (0.5 * k)
            }
            Primitive::Coupling(ref c) => c.energy(x, s, k),
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
                drive_only,
            } => {
                let axis = x[3] - x[2];
                let u = (x[1] - x[0]).dot(&axis) - target_rad_s;
                if drive_only && target_rad_s == 0.0 {
                    S::zero()
                } else if drive_only {
                    // Φ only where the torque drives toward the target (u opposite to it):
                    // C¹ at u = 0, where both sides have zero torque.
                    let driving = if target_rad_s > 0.0 { -u } else { u };
                    S::select_gt(
                        driving,
                        S::zero(),
                        || capped(u, max_torque_n_m, delay_rad_s) * dt,
                        S::zero,
                    )
                } else {
                    capped(u, max_torque_n_m, delay_rad_s) * dt
                }
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
            Primitive::PointOnPlane => (x[2] - x[0]).dot(&(x[1] - x[0]).normalize()).abs(),
            // Measured from the poses by the joint set (it needs the bodies' orientations).
            _ => 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energy::potential::{FastDerivatives, Potential};
    use crate::energy::testing::{derivative_errors, term_element_derivative_errors, TestState};
    use crate::energy::{Node, PotentialTerm};
    use crate::state::BodyArrays;
    use nalgebra::{Matrix3, UnitQuaternion};
    use rand::rngs::StdRng;
    use rand::{Rng, SeedableRng};

    const DT: f64 = 0.01;

    /// One primitive as a potential, for the derivative checks.
    struct One {
        primitive: Primitive,
        nodes: [Node; 4],
        k: f64,
    }

    impl Potential<4> for One {
        fn name(&self) -> &str {
            "one joint primitive"
        }
        fn num_elements(&self) -> usize {
            1
        }
        fn nodes(&self, _e: usize) -> [Node; 4] {
            self.nodes
        }
        fn energy<S: Scalar>(&self, _e: usize, x: &[Vec3<S>; 4], stencil: &Stencil<4>) -> S {
            self.primitive.energy(x, stencil, self.k)
        }
        fn derivatives(&self, _e: usize, s: &Stencil<4>, _project: bool, out: &mut HyperDual<4>) -> FastDerivatives {
            if self.primitive.quadratic_derivatives(&s.x, self.k, out) {
                FastDerivatives::Exact
            } else {
                FastDerivatives::Unavailable
            }
        }
    }

    fn rvec(rng: &mut StdRng, s: f64) -> Vector3<f64> {
        Vector3::new(
            rng.random_range(-s..s),
            rng.random_range(-s..s),
            rng.random_range(-s..s),
        )
    }

    /// Two bodies at random poses with random start velocities.
    fn random_bodies(rng: &mut StdRng) -> BodyArrays {
        let mut b = BodyArrays::default();
        for _ in 0..2 {
            b.position.push(rvec(rng, 1.0));
            b.orientation.push(UnitQuaternion::from_scaled_axis(rvec(rng, 2.0)));
            b.velocity.push(rvec(rng, 1.0));
            b.angular_velocity.push(rvec(rng, 3.0));
            b.mass.push(1.0);
            b.inertia_local.push(Matrix3::identity());
            b.force.push(Vector3::zeros());
            b.torque.push(Vector3::zeros());
            b.acceleration.push(Vector3::zeros());
            b.angular_acceleration.push(Vector3::zeros());
        }
        b
    }

    fn state(bodies: &BodyArrays, body_v: &[(Vector3<f64>, Vector3<f64>)]) -> TestState {
        TestState::new(vec![], vec![], vec![], vec![], DT).with_bodies(bodies.clone(), body_v)
    }

    /// Body `b`'s point `local` (or a world point when `b` is `None`).
    fn point(b: Option<u32>, local: &Vector3<f64>) -> Node {
        match b {
            Some(b) => Node::rigid(b as usize, local),
            None => Node::World((*local).into()),
        }
    }

    /// A unit direction of body `b` (or the world) as two points one unit apart.
    fn direction(rng: &mut StdRng, b: Option<u32>) -> [Node; 2] {
        let p = rvec(rng, 0.3);
        let d = rvec(rng, 1.0).normalize();
        [point(b, &p), point(b, &(p + d))]
    }

    fn omega(b: Option<u32>) -> Node {
        b.map_or(Node::World([0.0; 3]), Node::AngularVelocity)
    }

    fn pad(nodes: &[Node]) -> [Node; 4] {
        let mut all = [Node::World([0.0; 3]); 4];
        all[..nodes.len()].copy_from_slice(nodes);
        all
    }

    /// Every primitive in every regime (limits active on either side, controllers below and
    /// beyond their cap), between bodies 0 and 1 and between the world and body 1, at the
    /// trial state `st`.
    fn cases(rng: &mut StdRng, st: &TestState) -> Vec<(String, Primitive, [Node; 4])> {
        let eval = st.eval();
        let at = |n: &[Node; 4]| Stencil::new(*n, &eval);
        let mut out = Vec::new();
        for a in [Some(0u32), None] {
            let b = Some(1u32);
            let side = if a.is_some() { "body-body" } else { "world-body" };
            let pa = point(a, &rvec(rng, 0.5));
            let pb = point(b, &rvec(rng, 0.5));
            let two = pad(&[pa, pb]);
            let l = {
                let s = at(&two);
                (s.x[1] - s.x[0]).norm()
            };
            let [a0, a1] = direction(rng, a);
            let [b0, b1] = direction(rng, b);
            let dirs = pad(&[a0, a1, b0, b1]);
            let angle = {
                let s = at(&dirs);
                (s.x[1] - s.x[0]).angle(&(s.x[3] - s.x[2]))
            };
            let axis_pb = pad(&[a0, a1, pb]);
            let mut push = |name: &str, p: Primitive, n: [Node; 4]| out.push((format!("{name} ({side})"), p, n));
            push("point", Primitive::Point, two);
            push("point on axis", Primitive::PointOnAxis, axis_pb);
            push("distance", Primitive::Distance { target_m: 0.7 * l }, two);
            push(
                "distance limits, above max",
                Primitive::DistanceLimits {
                    min_m: 0.5 * l,
                    max_m: 0.8 * l,
                },
                two,
            );
            push(
                "distance limits, below min",
                Primitive::DistanceLimits {
                    min_m: 1.2 * l,
                    max_m: 1.5 * l,
                },
                two,
            );
            push("direction", Primitive::Direction, dirs);
            push("angle limit", Primitive::AngleLimit { limit_rad: 0.6 * angle }, dirs);
            push("perpendicular", Primitive::Perpendicular, dirs);
            push("point on plane", Primitive::PointOnPlane, axis_pb);
            // Couplings: a hinge angle of (a, b) driving a slider position of (a, b), and a
            // damped spring on the slider alone.
            let angle = super::super::Measure::Angle {
                a,
                b,
                axis_a: rvec(rng, 1.0).normalize(),
                ref_a: Vector3::x(),
                ref_b: Vector3::x(),
            };
            let position = super::super::Measure::Position {
                a,
                b,
                anchor_a: rvec(rng, 0.3),
                anchor_b: rvec(rng, 0.3),
                axis_a: rvec(rng, 1.0).normalize(),
            };
            let coord = |m, q0: f64, r: &mut StdRng| super::super::coupling::CoupledCoordinate {
                measure: m,
                q0,
                axis: rvec(r, 1.0).normalize().into(),
            };
            let ca = coord(angle, 0.3, rng);
            let cb = coord(position, -0.02, rng);
            let mimic = Coupling {
                a: Some(ca),
                b: cb,
                multiplier: 0.7,
                offset: 0.01,
                damping: 0.4,
                hard: true,
            };
            let spring = Coupling {
                a: None,
                b: cb,
                multiplier: 0.0,
                offset: 0.05,
                damping: 2.0,
                hard: false,
            };
            push("coupling, mimic", Primitive::Coupling(Box::new(mimic)), mimic.nodes());
            push(
                "coupling, spring",
                Primitive::Coupling(Box::new(spring)),
                spring.nodes(),
            );
            let mut push = |name: &str, p: Primitive, n: [Node; 4]| out.push((format!("{name} ({side})"), p, n));
            push(
                "spring",
                Primitive::Spring {
                    rest_length_m: 0.8 * l,
                    damping_n_s_m: 3.0,
                },
                two,
            );
            // Controllers: velocity error u at the trial state, target set to put u in a regime.
            let lin_u = {
                let s = at(&axis_pb);
                let d = s.x[1] - s.x[0];
                ((s.x[2] - s.x0[2]) - (s.x[0] - s.x0[0])).dot(&d) / DT
            };
            let ang_nodes = pad(&[omega(a), omega(b), a0, a1]);
            let ang_u = {
                let s = at(&ang_nodes);
                (s.x[1] - s.x[0]).dot(&(s.x[3] - s.x[2]))
            };
            for (regime, offset) in [("linear", 0.4), ("capped", -3.0)] {
                let delay = 0.05;
                push(
                    &format!("linear velocity, {regime}"),
                    Primitive::LinearVelocity {
                        target_m_s: lin_u - offset * delay,
                        max_force_n: 7.0,
                        delay_m_s: delay,
                    },
                    axis_pb,
                );
                push(
                    &format!("angular velocity, {regime}"),
                    Primitive::AngularVelocity {
                        target_rad_s: ang_u - offset * delay,
                        max_torque_n_m: 3.0,
                        delay_rad_s: delay,
                        drive_only: false,
                    },
                    ang_nodes,
                );
                // Drive only: the error opposes the target's sign (the driving side), so the
                // case is active.
                let toward = f64::abs(offset) * delay * if ang_u >= 0.0 { 1.0 } else { -1.0 };
                push(
                    &format!("angular velocity, drive only, {regime}"),
                    Primitive::AngularVelocity {
                        target_rad_s: ang_u + toward,
                        max_torque_n_m: 3.0,
                        delay_rad_s: delay,
                        drive_only: true,
                    },
                    ang_nodes,
                );
            }
        }
        out
    }

    #[test]
    fn derivatives_match_finite_differences_in_positions_and_body_velocities() {
        let mut rng = StdRng::seed_from_u64(4);
        let mut worst = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        for _trial in 0..3 {
            let bodies = random_bodies(&mut rng);
            let body_v: Vec<_> = (0..2).map(|_| (rvec(&mut rng, 1.0), rvec(&mut rng, 3.0))).collect();
            let st = state(&bodies, &body_v);
            for (name, primitive, nodes) in cases(&mut rng, &st) {
                let one = One {
                    primitive,
                    nodes,
                    k: 1e3,
                };
                let (eg, eh, ef) = derivative_errors(&one, &st.eval(), 1e-6);
                assert!(eg < 1e-6, "{name}: position gradient vs FD, relative error {eg:e}");
                assert!(eh < 1e-6, "{name}: position Hessian vs FD, relative error {eh:e}");
                // The closed forms of the quadratic primitives against hyper-duals.
                assert!(ef < 1e-12, "{name}: closed form vs hyper-duals, relative error {ef:e}");
                // DOF-space gradient and Hessian of the element (through the kinematic map)
                // against central differences in the bodies' (v, ω).
                let mapped = term_element_derivative_errors(&PotentialTerm::new(one), 0, &st, 1e-5);
                let (mg, mh) = (mapped.gradient, mapped.hessian_of_gradient);
                assert!(
                    mapped.gradient_norm > 1e-6,
                    "{name}: the case is inactive (zero gradient)"
                );
                assert!(mg < 1e-6, "{name}: (v, ω) gradient vs FD, relative error {mg:e}");
                assert!(mh < 1e-6, "{name}: (v, ω) Hessian vs FD, relative error {mh:e}");
                worst = (worst.0.max(eg), worst.1.max(eh), worst.2.max(mg), worst.3.max(mh));
            }
        }
        eprintln!(
            "worst relative errors: position gradient {:.1e}, Hessian {:.1e}; (v, ω) gradient {:.1e}, Hessian {:.1e}",
            worst.0, worst.1, worst.2, worst.3
        );
    }

    #[test]
    fn capped_law_is_c1_with_the_right_force() {
        let (f, d) = (5.0, 0.01);
        let h = 1e-7;
        for u in [-0.1, -0.01, -0.005, 0.0, 0.003, 0.01, 0.2] {
            let slope = (capped(u + h, f, d) - capped(u - h, f, d)) / (2.0 * h);
            let expected = if u.abs() < d { f * u / d } else { f * u.signum() };
            // Central differences straddling the kink at |u| = δ err by up to F·h/(4δ).
            assert!(
                (slope - expected).abs() < 1e-6 + f * h / d,
                "u {u}: {slope} vs {expected}"
            );
        }
    }

    #[test]
    fn chord_and_angle_are_inverse() {
        for a in [0.0, 0.1, 1.0, 3.0] {
            assert!((angle_of_chord(chord_of(a)) - a).abs() < 1e-12);
        }
    }
}

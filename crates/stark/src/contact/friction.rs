//! Lagged, smoothed Coulomb friction (IPC, Li et al. 2020, §5; the original Stark's lagging).
//!
//! For each contact pair at the start of the step, with its closest points `Σᵢ cᵢ xᵢ⁰ = d n̂`
//! (weights `cᵢ` from the closest-point parameters), the normal force `λ = κ |∂(m b)/∂d|`, an
//! orthonormal tangent basis `T` (3×2, `Tᵀ n̂ = 0`) and the weights are frozen. The tangential
//! relative displacement over the step is `u = Tᵀ Σᵢ cᵢ xᵢ − u₀` (`u₀ = Tᵀ Σᵢ cᵢ xᵢ⁰`), and the
//! friction energy is `D = μ λ f₀(‖u‖)` with IPC's C¹ smoothing
//! `f₀(y) = −y³/(3ε²) + y²/ε + ε/3` for `y < ε` and `f₀(y) = y` beyond, `ε = ε_v dt`
//! (`ε_v` = the stick–slide velocity threshold). Sliding, the force `−∂D/∂x` has magnitude `μλ`
//! opposite to the slip; sticking it is a spring of stiffness `2μλ/ε`.
//!
//! `D` depends on `x` only through the 2-vector `u`, whose Hessian
//! `μλ [(f₁/y) I + ((f₁′y − f₁)/y³) u uᵀ]` is already positive semi-definite for this `f₀`
//! (eigenvalues `f₁/y ≥ 0` and `f₁′ ≥ 0`), so no projection is needed.
//!
//! Sliding, that Hessian is flat along the slip, and a Newton step that stops or reverses the
//! slip lands far beyond (the line search then cuts the whole step). Newton's globalisation
//! replaces it by the majoriser `μλ (f₁/y) I` (IRLS: the element's own minimiser is zero slip):
//! for all elements far from the solution, and per element for a few iterations after a step
//! that would have carried its slip across zero ([`FrictionElement::stops_or_reverses`]; the
//! contact term's `refine_hessian`).

use crate::energy::{HyperDual, Scalar, Vec3};
use nalgebra::Vector3;

/// Regularisation of `‖u‖` at zero slip, relative to `ε` (keeps derivatives finite).
const SLIP_REGULARISER: f64 = 1e-9;

/// One lagged friction element.
#[derive(Clone, Copy, Debug)]
pub struct FrictionElement {
    /// Global node indices; the first `len` are used.
    pub nodes: [u32; 4],
    /// Number of nodes.
    pub len: usize,
    /// Weights of the nodes in the relative displacement (positive on one side, negative on the
    /// other).
    pub weights: [f64; 4],
    /// Orthonormal tangent basis (two unit vectors orthogonal to the normal).
    pub basis: [Vector3<f64>; 2],
    /// `μ λ`, N.
    pub mu_lambda: f64,
    /// Stick–slide threshold `ε = ε_v dt`, m.
    pub eps_m: f64,
    /// `Tᵀ Σᵢ cᵢ xᵢ⁰`, m.
    pub u0: [f64; 2],
    /// Take the majorising Hessian while sliding (a Newton step carried this element's slip
    /// across zero: see [`FrictionElement::stops_or_reverses`]).
    pub majorize: bool,
    /// Newton iterations this step that began with `majorize` set and in which the slip did
    /// not halve.
    pub majorized_iterations: u8,
    /// The slip `‖u‖` at the start of the last majorised iteration, m.
    pub majorized_slip_m: f64,
}

impl FrictionElement {
    /// Build from the start-of-step positions `x0` (the origin of the slip): `normal` is the
    /// contact normal (taken from the lagged state, which a re-lag moves to the converged end of
    /// the step), the basis is any orthonormal pair orthogonal to it.
    pub fn new(
        nodes: [u32; 4],
        len: usize,
        weights: [f64; 4],
        normal: Vector3<f64>,
        x0: &[Vector3<f64>; 4],
        mu_lambda: f64,
        eps_m: f64,
    ) -> Self {
        let n = normal.try_normalize(1e-300).unwrap_or_else(Vector3::z);
        let helper = if n.x.abs() < 0.9 { Vector3::x() } else { Vector3::y() };
        let t0 = n.cross(&helper).normalize();
        let t1 = n.cross(&t0);
        let rel: Vector3<f64> = (0..len).map(|i| x0[i] * weights[i]).sum();
        FrictionElement {
            nodes,
            len,
            weights,
            basis: [t0, t1],
            mu_lambda,
            eps_m,
            u0: [t0.dot(&rel), t1.dot(&rel)],
            majorize: false,
            majorized_iterations: 0,
            majorized_slip_m: f64::INFINITY,
        }
    }

    fn slip_f64(&self, x: &[Vector3<f64>; 4]) -> [f64; 2] {
        let mut u = [-self.u0[0], -self.u0[1]];
        for i in 0..self.len {
            for (k, uk) in u.iter_mut().enumerate() {
                *uk += self.basis[k].dot(&x[i]) * self.weights[i];
            }
        }
        u
    }

    /// Whether going from `from` (sliding) to `to` the slip along its current direction falls
    /// below the stick threshold: the element would stop or reverse, and its exact sliding
    /// Hessian (flat along the slip) predicted neither.
    pub fn stops_or_reverses(&self, from: &[Vector3<f64>; 4], to: &[Vector3<f64>; 4]) -> bool {
        let a = self.slip_f64(from);
        let y = (a[0] * a[0] + a[1] * a[1]).sqrt();
        if y < self.eps_m {
            return false;
        }
        let b = self.slip_f64(to);
        (a[0] * b[0] + a[1] * b[1]) / y < self.eps_m
    }

    /// `‖u‖` at `x`, m.
    pub fn slip_norm(&self, x: &[Vector3<f64>; 4]) -> f64 {
        let a = self.slip_f64(x);
        (a[0] * a[0] + a[1] * a[1]).sqrt()
    }

    fn slip<S: Scalar>(&self, x: &[Vec3<S>; 4]) -> [S; 2] {
        let mut u = [S::constant(-self.u0[0]), S::constant(-self.u0[1])];
        for i in 0..self.len {
            for (k, uk) in u.iter_mut().enumerate() {
                *uk += x[i].dot_f64(&self.basis[k]) * self.weights[i];
            }
        }
        u
    }

    /// Energy, written generically (the oracle).
    pub fn energy<S: Scalar>(&self, x: &[Vec3<S>; 4]) -> S {
        let [u0, u1] = self.slip(x);
        let eps = self.eps_m;
        let y = (u0.sq() + u1.sq() + (SLIP_REGULARISER * eps).powi(2)).sqrt();
        let f0 = S::select_gt(
            y,
            S::constant(eps),
            || y,
            || -y.powi(3) * (1.0 / (3.0 * eps * eps)) + y.sq() * (1.0 / eps) + eps / 3.0,
        );
        f0 * self.mu_lambda
    }

    /// Value, gradient and Hessian (closed form, PSD) into `out`; unused nodes get zeros. With
    /// `majorizer`, a sliding element's Hessian is `μλ (f₁/y) I` instead: the exact one has no
    /// curvature along the slip, so Newton from a sliding iterate jumps far past a solution that
    /// sticks (a light rolling wheel: its spin is held by friction alone).
    pub fn derivatives(&self, x: &[Vector3<f64>; 4], majorizer: bool, out: &mut HyperDual<4>) {
        let u = self.slip_f64(x);
        let majorizer = majorizer || self.majorize;
        let eps = self.eps_m;
        let y = (u[0] * u[0] + u[1] * u[1] + (SLIP_REGULARISER * eps).powi(2)).sqrt();
        let ml = self.mu_lambda;
        // f₀, f₁/y and (f₁′y − f₁)/y³.
        let (f0, f1_over_y, q) = if y < eps {
            (
                -y * y * y / (3.0 * eps * eps) + y * y / eps + eps / 3.0,
                -y / (eps * eps) + 2.0 / eps,
                -1.0 / (y * eps * eps),
            )
        } else if majorizer {
            (y, 1.0 / y, 0.0)
        } else {
            (y, 1.0 / y, -1.0 / (y * y * y))
        };
        let gu = [ml * f1_over_y * u[0], ml * f1_over_y * u[1]];
        let hu = [
            [ml * (f1_over_y + q * u[0] * u[0]), ml * q * u[0] * u[1]],
            [ml * q * u[1] * u[0], ml * (f1_over_y + q * u[1] * u[1])],
        ];
        out.value = ml * f0;
        // ∂u_k/∂x_{i,d} = c_i T_k[d]: the gradient is c_i (T g_u) and the Hessian's block (i, j)
        // is c_i c_j (T H_u Tᵀ), one 3×3 matrix for all blocks.
        let t = &self.basis;
        let gx: [f64; 3] = std::array::from_fn(|d| t[0][d] * gu[0] + t[1][d] * gu[1]);
        let m: [[f64; 3]; 3] = std::array::from_fn(|d| {
            std::array::from_fn(|e| {
                let mut h = 0.0;
                for k in 0..2 {
                    for l in 0..2 {
                        h += t[k][d] * hu[k][l] * t[l][e];
                    }
                }
                h
            })
        });
        let c: [f64; 4] = std::array::from_fn(|i| if i < self.len { self.weights[i] } else { 0.0 });
        for i in 0..4 {
            for d in 0..3 {
                out.grad[i][d] = c[i] * gx[d];
            }
            for j in 0..4 {
                let cc = c[i] * c[j];
                for d in 0..3 {
                    for e in 0..3 {
                        out.hess[i][d][j][e] = cc * m[d][e];
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energy::potential::symmetrize;

    #[test]
    fn derivatives_match_oracle_sticking_and_sliding() {
        let x0 = [
            Vector3::new(0.0, 0.0, 0.01),
            Vector3::new(-0.1, -0.1, 0.0),
            Vector3::new(0.1, -0.1, 0.0),
            Vector3::new(0.0, 0.1, 0.0),
        ];
        let weights = [1.0, -0.3, -0.3, -0.4];
        let el = FrictionElement::new([0, 1, 2, 3], 4, weights, Vector3::z(), &x0, 2.5, 1e-3);
        for slip in [0.0, 2e-4, 9e-4, 5e-3, 0.2] {
            let mut x = x0;
            x[0] += Vector3::new(slip * 0.8, slip * 0.6, 1e-4);
            x[2] += Vector3::new(-slip * 0.1, 0.0, 0.0);
            let mut fast = HyperDual::<4>::constant(0.0);
            el.derivatives(&x, false, &mut fast);
            let mut oracle = el.energy(&HyperDual::<4>::variables(&x));
            symmetrize(&mut oracle);
            assert!((fast.value - oracle.value).abs() < 1e-12);
            for (a, b) in fast.gradient_flat().iter().zip(oracle.gradient_flat()) {
                assert!((a - b).abs() < 1e-9 * 2.5, "slip {slip}: {a} vs {b}");
            }
            let fh = fast.hess.as_flattened().as_flattened().as_flattened();
            let oh = oracle.hess.as_flattened().as_flattened().as_flattened();
            for (a, b) in fh.iter().zip(oh) {
                assert!((a - b).abs() < 1e-6 * (2.5 / 1e-3), "slip {slip}: {a} vs {b}");
            }
            // Sliding: the force magnitude on the point is μλ·|c₀|.
            if slip > 1e-3 {
                let g = Vector3::from(fast.grad[0]);
                assert!((g.norm() - 2.5).abs() < 1e-6, "{}", g.norm());
            }
        }
    }

    /// The sliding stand-in majorises the friction energy around the iterate (`f₀(√s)` is
    /// concave in `s = ‖u‖²`): the quadratic model with it lies above `D` everywhere, so a full
    /// step on it cannot increase the friction energy, whereas the exact Hessian's model (no
    /// curvature along the slip) lies below `D` for steps across the stick zone.
    #[test]
    fn sliding_majorizer_lies_above_the_energy() {
        let x0 = [Vector3::zeros(); 4];
        let (ml, eps) = (2.0, 1e-4);
        let el = FrictionElement::new([0, 0, 0, 0], 1, [1.0, 0.0, 0.0, 0.0], Vector3::z(), &x0, ml, eps);
        let energy = |p: Vector3<f64>| {
            let mut d = HyperDual::<4>::constant(0.0);
            el.derivatives(&[p, p, p, p], false, &mut d);
            d.value
        };
        let mut below_exact = 0;
        for (slip, dir) in [(3e-3, 0.3), (2e-4, 1.1), (1.5e-4, -2.0), (0.05, 2.5)] {
            let x = Vector3::new(slip * f64::cos(dir), slip * f64::sin(dir), 0.0);
            for maj in [true, false] {
                let mut d = HyperDual::<4>::constant(0.0);
                el.derivatives(&[x, x0[1], x0[2], x0[3]], maj, &mut d);
                let g = Vector3::from(d.grad[0]);
                let h = nalgebra::Matrix3::from_fn(|i, j| d.hess[0][i][0][j]);
                for k in 0..200 {
                    // Trial points around and across the stick zone.
                    let a = 0.1 * k as f64;
                    let step = Vector3::new(-x.x * (k as f64 / 50.0), -x.y * (k as f64 / 60.0), 0.0)
                        + Vector3::new(a.cos(), a.sin(), 0.0) * (eps * (k % 7) as f64);
                    let model = d.value + g.dot(&step) + 0.5 * step.dot(&(h * step));
                    let truth = energy(x + step);
                    if maj {
                        assert!(model >= truth - 1e-12 * ml, "slip {slip}, trial {k}: {model} < {truth}");
                    } else if model < truth - 1e-9 * ml {
                        below_exact += 1;
                    }
                }
            }
        }
        assert!(below_exact > 0, "the exact model was expected to undershoot somewhere");
    }

    /// A step is flagged as crossing the kink exactly when the slip along its current direction
    /// would fall below the stick threshold (stop or reverse); sticking elements are never
    /// flagged, and the per-element flag switches the sliding Hessian to the majoriser.
    #[test]
    fn steps_that_stop_or_reverse_a_slide_are_flagged() {
        let x0 = [Vector3::zeros(); 4];
        let eps = 1e-4;
        let mut el = FrictionElement::new([0, 0, 0, 0], 1, [1.0, 0.0, 0.0, 0.0], Vector3::z(), &x0, 2.0, eps);
        let at = |x: f64, y: f64| [Vector3::new(x, y, 0.0), x0[1], x0[2], x0[3]];
        // Sliding along +x at 10ε.
        let from = at(10.0 * eps, 0.0);
        assert!(el.slip_norm(&from) >= eps);
        assert!(
            !el.stops_or_reverses(&from, &at(20.0 * eps, 3.0 * eps)),
            "keeps sliding"
        );
        assert!(
            !el.stops_or_reverses(&from, &at(2.0 * eps, 0.0)),
            "slows, still beyond ε"
        );
        assert!(el.stops_or_reverses(&from, &at(0.5 * eps, 0.0)), "stops");
        assert!(el.stops_or_reverses(&from, &at(-5.0 * eps, 0.0)), "reverses");
        assert!(
            el.stops_or_reverses(&from, &at(0.0, 30.0 * eps)),
            "turns across the slip"
        );
        // Sticking now: the exact Hessian has the stick curvature, no flag.
        assert!(!el.stops_or_reverses(&at(0.5 * eps, 0.0), &at(-5.0 * eps, 0.0)));
        // The flag gives the majoriser's curvature μλ/‖u‖ along the slip.
        let hessian_xx = |el: &FrictionElement| {
            let mut d = HyperDual::<4>::constant(0.0);
            el.derivatives(&from, false, &mut d);
            d.hess[0][0][0][0]
        };
        assert!(hessian_xx(&el).abs() < 1e-9);
        el.majorize = true;
        assert!((hessian_xx(&el) - 2.0 / (10.0 * eps)).abs() < 1e-6 * 2.0 / eps);
    }

    /// A re-lag (`friction_iterations` > 1) takes the normal force, tangents and weights from the
    /// converged state but must keep measuring the slip from the start of the step: a point that
    /// slid `s ≫ ε` over the step has the sliding energy `μλs` after the re-lag too. (Measuring
    /// from the converged state gave `μλε/3`, the zero-slip value, so every extra friction
    /// iteration let the next solve slide up to another `ε` further: a block sliding down an
    /// incline gained +5% acceleration per extra iteration at ε_v = 1e-3 m/s, and a sticking one
    /// crept that much faster; `tests/physics/incline_friction.rs`.)
    #[test]
    fn relag_keeps_the_start_of_step_as_slip_origin() {
        use crate::contact::barrier::{barrier, BarrierKind};
        use crate::contact::Contact;
        use crate::energy::{EnergyTerm, StepCheck};
        use crate::state::NodeSetHandle;
        use crate::state::{EvalState, NodeArrays};
        let (dt, mu, thickness, gap, slide) = (0.01, 0.5, 1e-3, 5e-4, 1e-3);
        let mut nodes = NodeArrays::default();
        nodes.push(&[
            Vector3::new(-1.0, -1.0, 0.0),
            Vector3::new(1.0, -1.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
            Vector3::new(0.0, 0.0, gap),
        ]);
        let mut contact = Contact::default();
        contact.settings.friction_iterations = 2;
        contact.settings.friction_stick_slide_threshold_m_s = 1e-3;
        let rest = nodes.rest.clone();
        let floor = NodeSetHandle {
            index: 0,
            first: 0,
            len: 3,
        };
        let point = NodeSetHandle {
            index: 1,
            first: 3,
            len: 1,
        };
        let a = contact
            .add_object(
                "floor",
                floor,
                &rest,
                &[[0, 1, 2]],
                &[[0, 1], [1, 2], [0, 2]],
                &[0, 1, 2],
                thickness,
            )
            .unwrap();
        let b = contact
            .add_object("point", point, &rest, &[], &[], &[0], thickness)
            .unwrap();
        contact.set_friction(a, b, mu).unwrap();
        contact.initialize_stiffness(&[1.0; 4], dt, 0.0);
        let zeros = vec![Vector3::zeros(); 4];
        let mut x_end = nodes.x.clone();
        x_end[3].x += slide;
        let v_end: Vec<_> = nodes.x.iter().zip(&x_end).map(|(a, b)| (b - a) / dt).collect();
        let bodies = crate::state::BodyArrays::default();
        let at = |x, v| EvalState {
            dt,
            time: dt,
            gravity: Vector3::zeros(),
            nodes: &nodes,
            v,
            x,
            bodies: &bodies,
            poses: &[],
        };
        contact.before_step(&at(&nodes.x, &zeros));
        // No barrier pairs are prepared, so `energy` is the friction energy alone.
        let lambda = contact.stiffness() * barrier(BarrierKind::Log, gap, 2.0 * thickness).1.abs();
        let expected = mu * lambda * slide;
        let first = contact.energy(&at(&x_end, &v_end));
        assert!((first - expected).abs() < 1e-6 * expected, "{first} vs {expected}");
        assert!(matches!(
            contact.check_converged_step(&at(&x_end, &v_end)),
            StepCheck::Retry(_)
        ));
        let relagged = contact.energy(&at(&x_end, &v_end));
        assert!(
            (relagged - expected).abs() < 1e-6 * expected,
            "after the re-lag: {relagged} vs μλs = {expected}"
        );
    }
}

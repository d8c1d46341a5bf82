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
//! **The Hessian is the primal–dual one.** `D`'s exact Hessian in `u`,
//! `μλ [(f₁/y) I + (f₁′ − f₁/y) û ûᵀ]`, has no curvature along a sliding slip, so Newton from a
//! sliding iterate jumps far past a solution that sticks or reverses (a light rolling wheel, whose
//! spin only friction holds: throws of several rad/s, cut to 1/256 by the line search). As in
//! the primal–dual Newton method for total variation (Chan, Golub & Mulet 1999), each element
//! carries the friction force's direction as a second unknown `w ≈ f₁(y) û` (`‖w‖ ≤ 1`): Newton
//! on `{∇E_rest + μλ T w = 0, φ(y) w = u}` with `φ = y/f₁`, `w` eliminated, keeps the exact
//! gradient and has the Hessian `μλ/φ [I − φ′ sym(w ûᵀ)]` in `u`, positive semi-definite for
//! `‖w‖ ≤ 1` (`φ′ ∈ [¼, 1]`). With `w = f₁û` it is the exact Hessian (quadratic convergence at
//! the end); with `w = 0`, where every step starts, the majoriser `μλ (f₁/y) I` (iteratively
//! reweighted least squares); where the slip turns against `w` it adds up to `2μλ/y` along the
//! slip. After each accepted Newton step `w` takes its Newton update ([`FrictionElement::update_dual`]).

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
    /// The dual variable `w`: the friction force over `−μλ` as the Newton iterations estimate
    /// it (`f₁(y) û` at the solution, `‖w‖ ≤ 1`), in the tangent basis. Zero at the start of a
    /// step.
    pub dual: [f64; 2],
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
            dual: [0.0; 2],
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

    /// `‖u‖`, regularised at zero slip, m.
    fn slip_norm(&self, u: &[f64; 2]) -> f64 {
        (u[0] * u[0] + u[1] * u[1] + (SLIP_REGULARISER * self.eps_m).powi(2)).sqrt()
    }

    /// `φ(y) = y/f₁(y)` (m) and `φ′(y)`: `y` sliding, `ε²/(2ε − y)` sticking.
    fn phi(&self, y: f64) -> (f64, f64) {
        let eps = self.eps_m;
        if y < eps {
            let d = 2.0 * eps - y;
            (eps * eps / d, eps * eps / (d * d))
        } else {
            (y, 1.0)
        }
    }

    /// The dual variable's Newton update for the accepted step `from → to`: the linearisation
    /// of `φ(y) w = u` at `from`, `w ← (u_to − φ′ (û·Δu) w) / φ`, projected onto `‖w‖ ≤ 1`. A
    /// zero step sets `w = f₁(y) û`, its value at the solution.
    pub fn update_dual(&mut self, from: &[Vector3<f64>; 4], to: &[Vector3<f64>; 4]) {
        let a = self.slip_f64(from);
        let b = self.slip_f64(to);
        let y = self.slip_norm(&a);
        let (phi, dphi) = self.phi(y);
        let along = (a[0] * (b[0] - a[0]) + a[1] * (b[1] - a[1])) / y;
        let w = self.dual;
        let next = [(b[0] - dphi * along * w[0]) / phi, (b[1] - dphi * along * w[1]) / phi];
        let norm = (next[0] * next[0] + next[1] * next[1]).sqrt();
        self.dual = if norm > 1.0 {
            [next[0] / norm, next[1] / norm]
        } else {
            next
        };
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

    /// Value, gradient and the primal–dual Hessian (closed form, positive semi-definite; see
    /// the module's doc) into `out`; unused nodes get zeros.
    pub fn derivatives(&self, x: &[Vector3<f64>; 4], out: &mut HyperDual<4>) {
        *out = HyperDual::constant(0.0);
        self.add_derivatives(x, out);
    }

    /// [`FrictionElement::derivatives`] added to `out` (a barrier pair's on the same nodes).
    pub fn add_derivatives(&self, x: &[Vector3<f64>; 4], out: &mut HyperDual<4>) {
        let u = self.slip_f64(x);
        let eps = self.eps_m;
        let y = self.slip_norm(&u);
        let ml = self.mu_lambda;
        let f0 = if y < eps {
            -y * y * y / (3.0 * eps * eps) + y * y / eps + eps / 3.0
        } else {
            y
        };
        // The gradient μλ f₁ û is μλ u/φ, and μλ/φ also scales the Hessian.
        let (phi, dphi) = self.phi(y);
        let c = ml / phi;
        let gu = [c * u[0], c * u[1]];
        let unit = [u[0] / y, u[1] / y];
        let w = self.dual;
        let sym = |k: usize, l: usize| 0.5 * (w[k] * unit[l] + unit[k] * w[l]);
        let hu = [
            [c * (1.0 - dphi * sym(0, 0)), -c * dphi * sym(0, 1)],
            [-c * dphi * sym(1, 0), c * (1.0 - dphi * sym(1, 1))],
        ];
        out.value += ml * f0;
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
                out.grad[i][d] += c[i] * gx[d];
            }
            for j in 0..4 {
                let cc = c[i] * c[j];
                for d in 0..3 {
                    for e in 0..3 {
                        out.hess[i][d][j][e] += cc * m[d][e];
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
            // With the dual variable at its value for this slip, the exact Hessian.
            let mut el = el;
            el.update_dual(&x, &x);
            let mut fast = HyperDual::<4>::constant(0.0);
            el.derivatives(&x, &mut fast);
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

    /// At `w = 0` (each step's start) the Hessian is the majoriser `μλ (f₁/y) I`: the quadratic
    /// model lies above `D` everywhere (`f₀(√s)` is concave in `s = ‖u‖²`), so a full step on it
    /// cannot raise the friction energy, whereas the exact Hessian's model (no curvature along
    /// the slip) lies below `D` for steps across the stick zone. For any `‖w‖ ≤ 1` the Hessian is
    /// positive semi-definite.
    #[test]
    fn zero_dual_majorises_and_every_dual_is_definite() {
        let x0 = [Vector3::zeros(); 4];
        let (ml, eps) = (2.0, 1e-4);
        let el = FrictionElement::new([0, 0, 0, 0], 1, [1.0, 0.0, 0.0, 0.0], Vector3::z(), &x0, ml, eps);
        let energy = |p: Vector3<f64>| {
            let mut d = HyperDual::<4>::constant(0.0);
            el.derivatives(&[p, p, p, p], &mut d);
            d.value
        };
        let mut below_exact = 0;
        for (slip, dir) in [(3e-3, 0.3), (2e-4, 1.1), (1.5e-4, -2.0), (0.05, 2.5), (5e-5, 0.7)] {
            let x = Vector3::new(slip * f64::cos(dir), slip * f64::sin(dir), 0.0);
            let at = [x, x0[1], x0[2], x0[3]];
            let mut consistent = el;
            consistent.update_dual(&at, &at);
            for (el, majorises) in [(el, true), (consistent, false)] {
                let mut d = HyperDual::<4>::constant(0.0);
                el.derivatives(&at, &mut d);
                let g = Vector3::from(d.grad[0]);
                let h = nalgebra::Matrix3::from_fn(|i, j| d.hess[0][i][0][j]);
                for k in 0..200 {
                    // Trial points around and across the stick zone.
                    let a = 0.1 * k as f64;
                    let step = Vector3::new(-x.x * (k as f64 / 50.0), -x.y * (k as f64 / 60.0), 0.0)
                        + Vector3::new(a.cos(), a.sin(), 0.0) * (eps * (k % 7) as f64);
                    let model = d.value + g.dot(&step) + 0.5 * step.dot(&(h * step));
                    let truth = energy(x + step);
                    if majorises {
                        assert!(model >= truth - 1e-12 * ml, "slip {slip}, trial {k}: {model} < {truth}");
                    } else if model < truth - 1e-9 * ml {
                        below_exact += 1;
                    }
                }
            }
            // Any dual in the unit disc: the smallest eigenvalue is not negative.
            for k in 0..50 {
                let (r, a) = ((k % 5) as f64 / 4.0, 0.37 * k as f64);
                let mut el = el;
                el.dual = [r * a.cos(), r * a.sin()];
                let mut d = HyperDual::<4>::constant(0.0);
                el.derivatives(&at, &mut d);
                let h = nalgebra::Matrix3::from_fn(|i, j| d.hess[0][i][0][j]);
                let smallest = h.symmetric_eigenvalues().min();
                assert!(
                    smallest > -1e-12 * h.norm(),
                    "dual {:?}, slip {slip}: {smallest}",
                    el.dual
                );
            }
        }
        assert!(below_exact > 0, "the exact model was expected to undershoot somewhere");
    }

    /// One point under a spring pulling it to `a` (`½k‖x − a‖²`) against friction: Newton with
    /// the primal–dual Hessian and a backtracking line search converges to the analytic
    /// equilibrium in few iterations, sticking (`k‖a‖ < μλ`: `k(y − ‖a‖) + μλ f₁(y) = 0` along
    /// `a`) and sliding (`x = a (1 − μλ/(k‖a‖))`), from starts that slide the wrong way, where
    /// the exact Hessian (no curvature along the slip) throws the iterate far across the stick
    /// zone and needs the line search to cut it.
    #[test]
    fn primal_dual_newton_finds_the_stick_and_the_slide() {
        let x0 = [Vector3::zeros(); 4];
        let (ml, eps) = (1.0, 1e-4);
        let el0 = FrictionElement::new([0, 0, 0, 0], 1, [1.0, 0.0, 0.0, 0.0], Vector3::z(), &x0, ml, eps);
        let solve = |k: f64, a: Vector3<f64>, start: Vector3<f64>, exact: bool| -> (Vector3<f64>, usize) {
            let mut el = el0;
            let mut x = start;
            let derivs = |el: &FrictionElement, x: Vector3<f64>| {
                let mut d = HyperDual::<4>::constant(0.0);
                el.derivatives(&[x, x0[1], x0[2], x0[3]], &mut d);
                let g = Vector3::from(d.grad[0]) + k * (x - a);
                let h = nalgebra::Matrix3::from_fn(|i, j| d.hess[0][i][0][j]) + nalgebra::Matrix3::identity() * k;
                (d.value + 0.5 * k * (x - a).norm_squared(), g, h)
            };
            for it in 0..100 {
                if exact {
                    el.update_dual(&[x, x0[1], x0[2], x0[3]], &[x, x0[1], x0[2], x0[3]]);
                }
                let (e, g, h) = derivs(&el, x);
                if g.norm() < 1e-12 {
                    return (x, it);
                }
                let dx = -h.cholesky().expect("positive definite").solve(&g);
                let mut alpha = 1.0;
                while derivs(&el, x + dx * alpha).0 > e + 1e-4 * alpha * g.dot(&dx) {
                    alpha *= 0.5;
                }
                let next = x + dx * alpha;
                el.update_dual(&[x, x0[1], x0[2], x0[3]], &[next, x0[1], x0[2], x0[3]]);
                x = next;
            }
            panic!("no convergence: k {k}, a {a:?}, start {start:?}, exact {exact}");
        };
        let a_dir = Vector3::new(0.6, 0.8, 0.0);
        // Sticking: the spring pulls with half the friction bound; the equilibrium slip by
        // bisection on k(y − ‖a‖) + μλ f₁(y) = 0.
        let (k, a_norm) = (100.0, 5e-3);
        let f1 = |y: f64| {
            if y < eps {
                y * (2.0 * eps - y) / (eps * eps)
            } else {
                1.0
            }
        };
        let (mut lo, mut hi) = (0.0, eps);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if k * (mid - a_norm) + ml * f1(mid) > 0.0 {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        let stick = a_dir * lo;
        // Sliding: the spring pulls with four times the bound.
        let (k2, a2) = (400.0, 1e-2);
        let slide = a_dir * (a2 - ml / k2);
        let mut exact_iterations = 0;
        let mut pd_iterations = 0;
        for (k, a, expected) in [(k, a_dir * a_norm, stick), (k2, a_dir * a2, slide)] {
            for start in [-a_dir * 3e-3, Vector3::new(0.8, -0.6, 0.0) * 2e-3, a_dir * 2e-2] {
                let (x, its) = solve(k, a, start, false);
                assert!((x - expected).norm() < 1e-9, "k {k}: {x:?} vs {expected:?}");
                assert!(its <= 12, "k {k}, start {start:?}: {its} iterations");
                pd_iterations += its;
                exact_iterations += solve(k, a, start, true).1;
            }
        }
        assert!(
            pd_iterations < exact_iterations,
            "primal–dual {pd_iterations} vs exact {exact_iterations} iterations"
        );
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

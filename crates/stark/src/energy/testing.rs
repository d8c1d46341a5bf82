//! Checks of energy derivatives against central finite differences, for the crate's tests and for
//! users writing their own potentials.

use super::dual::HyperDual;
use super::kinematics::{apply_kinematic_map, BodyPose};
use super::potential::{dual_derivatives, FastDerivatives, Potential, Stencil};
use super::scalar::Scalar;
use super::tensor::Vec3;
use super::term::{element_stride, EnergyTerm, EvalMode, NO_DOF};
use crate::state::{BodyArrays, EvalState, NodeArrays, NO_BODY};
use nalgebra::Vector3;

/// A self-contained state for evaluating energies in tests.
#[derive(Clone)]
pub struct TestState {
    /// Node arrays (start-of-step positions and velocities).
    pub nodes: NodeArrays,
    /// Trial velocities.
    pub v: Vec<Vector3<f64>>,
    /// Trial positions `x0 + dt·v`.
    pub x: Vec<Vector3<f64>>,
    /// Time step, s.
    pub dt: f64,
    /// Gravity, m/s².
    pub gravity: Vector3<f64>,
    /// Start-of-step rigid bodies (none unless added with [`TestState::with_bodies`]).
    pub bodies: BodyArrays,
    /// Trial body poses.
    pub poses: Vec<BodyPose>,
}

impl TestState {
    /// Nodes with rest and start positions `x0`, start velocities `v0`, trial velocities `v`.
    pub fn new(
        rest: Vec<Vector3<f64>>,
        x0: Vec<Vector3<f64>>,
        v0: Vec<Vector3<f64>>,
        v: Vec<Vector3<f64>>,
        dt: f64,
    ) -> Self {
        let n = x0.len();
        let nodes = NodeArrays {
            rest,
            x: x0,
            v: v0,
            force: vec![Vector3::zeros(); n],
            acceleration: vec![Vector3::zeros(); n],
            body: vec![NO_BODY; n],
        };
        let mut s = TestState {
            nodes,
            v,
            x: Vec::new(),
            dt,
            gravity: Vector3::new(0.0, 0.0, -9.81),
            bodies: BodyArrays::default(),
            poses: Vec::new(),
        };
        s.place();
        s
    }

    /// Add rigid bodies with trial linear and angular velocities `body_v` (one pair per body).
    pub fn with_bodies(mut self, bodies: BodyArrays, body_v: &[(Vector3<f64>, Vector3<f64>)]) -> Self {
        self.v.truncate(self.nodes.len());
        for (v, w) in body_v {
            self.v.push(*v);
            self.v.push(*w);
        }
        self.bodies = bodies;
        self.place();
        self
    }

    /// The same state with component `i` of DOF block `block` of the trial velocities moved by
    /// `h` (positions and poses follow through the kinematic map).
    pub fn with_dof_moved(&self, block: u32, i: usize, h: f64) -> Self {
        let mut s = self.clone();
        s.v[block as usize][i] += h;
        s.place();
        s
    }

    fn place(&mut self) {
        apply_kinematic_map(
            &self.nodes,
            &self.bodies,
            &self.v,
            self.dt,
            &mut self.x,
            &mut self.poses,
        );
    }

    /// The evaluation view.
    pub fn eval(&self) -> EvalState<'_> {
        EvalState {
            dt: self.dt,
            time: 0.0,
            gravity: self.gravity,
            nodes: &self.nodes,
            v: &self.v,
            x: &self.x,
            bodies: &self.bodies,
            poses: &self.poses,
        }
    }
}

fn rel_err(a: &[f64], b: &[f64]) -> f64 {
    let diff: f64 = a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum::<f64>().sqrt();
    let scale: f64 = b
        .iter()
        .map(|y| y * y)
        .sum::<f64>()
        .sqrt()
        .max(a.iter().map(|x| x * x).sum::<f64>().sqrt());
    if scale == 0.0 {
        diff
    } else {
        diff / scale
    }
}

/// Largest relative errors over all elements of `p`: `(gradient vs FD of the energy, Hessian vs
/// FD of the exact gradient, fast path vs hyper-duals)`. The step is `step_m` (m).
pub fn derivative_errors<P: Potential<N>, const N: usize>(p: &P, state: &EvalState, step_m: f64) -> (f64, f64, f64) {
    let n = 3 * N;
    let (mut eg, mut eh, mut ef) = (0.0f64, 0.0f64, 0.0f64);
    for e in 0..p.num_elements() {
        let stencil = Stencil::new(p.nodes(e), state);
        let exact = dual_derivatives(p, e, &stencil);
        let energy_at = |x: &[Vector3<f64>; N]| {
            let xs: [Vec3<f64>; N] = x.map(|q| Vec3::constant(&q));
            p.energy(e, &xs, &stencil)
        };
        let grad_at = |x: &[Vector3<f64>; N]| {
            let xs = HyperDual::<N>::variables(x);
            p.energy(e, &xs, &stencil).grad
        };
        let mut fd_grad = vec![0.0; n];
        let mut fd_hess = vec![0.0; n * n];
        for k in 0..n {
            let (a, i) = (k / 3, k % 3);
            let mut xp = stencil.x;
            let mut xm = stencil.x;
            xp[a][i] += step_m;
            xm[a][i] -= step_m;
            fd_grad[k] = (energy_at(&xp) - energy_at(&xm)) / (2.0 * step_m);
            let (gp, gm) = (grad_at(&xp), grad_at(&xm));
            for l in 0..n {
                fd_hess[l * n + k] = (gp[l / 3][l % 3] - gm[l / 3][l % 3]) / (2.0 * step_m);
            }
        }
        eg = eg.max(rel_err(&fd_grad, exact.gradient_flat()));
        eh = eh.max(rel_err(
            &fd_hess,
            exact.hess.as_flattened().as_flattened().as_flattened(),
        ));
        let mut fast = HyperDual::<N>::constant(0.0);
        if p.derivatives(e, &stencil, false, &mut fast) == FastDerivatives::Exact {
            let mut a = vec![fast.value];
            a.extend_from_slice(fast.gradient_flat());
            a.extend_from_slice(fast.hess.as_flattened().as_flattened().as_flattened());
            let mut b = vec![exact.value];
            b.extend_from_slice(exact.gradient_flat());
            b.extend_from_slice(exact.hess.as_flattened().as_flattened().as_flattened());
            ef = ef.max(rel_err(&a, &b));
        }
    }
    (eg, eh, ef)
}

/// Assert that every element's gradient and Hessian agree with central finite differences to a
/// relative error below `1e-5`, and any fast path agrees with hyper-duals to `1e-9`.
pub fn assert_derivatives<P: Potential<N>, const N: usize>(p: &P, state: &EvalState, step_m: f64) {
    let (eg, eh, ef) = derivative_errors(p, state, step_m);
    assert!(
        eg < 1e-5,
        "{}: gradient vs finite differences, relative error {eg:e}",
        p.name()
    );
    assert!(
        eh < 1e-5,
        "{}: Hessian vs finite differences, relative error {eh:e}",
        p.name()
    );
    assert!(
        ef < 1e-9,
        "{}: generated derivatives vs hyper-duals, relative error {ef:e}",
        p.name()
    );
}

/// Relative errors of one element of an [`EnergyTerm`] in DOF space (velocity blocks, through the
/// kinematic map), from [`term_element_derivative_errors`].
#[derive(Clone, Copy, Debug)]
pub struct TermDerivativeErrors {
    /// Gradient against central differences of the element's energy.
    pub gradient: f64,
    /// Hessian against central differences of the element's gradient.
    pub hessian_of_gradient: f64,
    /// Hessian against second central differences of the element's energy (independent of the
    /// hand-written gradient).
    pub hessian_of_energy: f64,
    /// Norm of the gradient, so a test can tell an inactive element (all errors trivially 0).
    pub gradient_norm: f64,
}

/// Compare the gradient and exact Hessian that element `e` of `term` writes with central
/// differences, in every DOF block of its stencil, at `state`. First derivatives use the step
/// `step` (m/s or rad/s); second differences of the energy use `100·step`, since their rounding
/// error grows as `1/step²`.
pub fn term_element_derivative_errors<T: EnergyTerm + ?Sized>(
    term: &T,
    e: usize,
    state: &TestState,
    step: f64,
) -> TermDerivativeErrors {
    let eval = state.eval();
    let w = term.stencil_width(&eval);
    let mut stencils = vec![NO_DOF; w * term.num_elements()];
    term.write_stencils(&eval, &mut stencils);
    let blocks = &stencils[w * e..w * (e + 1)];
    let element_at = |s: &TestState| {
        let mut out = vec![0.0; element_stride(w)];
        term.evaluate_element(e, &s.eval(), EvalMode::ExactHessian, &mut out);
        out
    };
    let out = element_at(state);
    let n = 3 * w;
    let gradient = &out[1..1 + n];
    let exact_hessian = &out[1 + n..];
    // Entry (row, col) of the element's Hessian: block (a, b) at 9(a·w + b), row-major within. Rows
    // and columns of padding blocks stay 0 in the differences, as the element must write them.
    let hessian_index = |row: usize, col: usize| 9 * ((row / 3) * w + col / 3) + 3 * (row % 3) + col % 3;
    let dofs: Vec<(usize, u32, usize)> = blocks
        .iter()
        .enumerate()
        .filter(|(_, &blk)| blk != NO_DOF)
        .flat_map(|(a, &blk)| (0..3).map(move |i| (3 * a + i, blk, i)))
        .collect();
    let mut fd_gradient = vec![0.0; n];
    let mut fd_hessian = vec![0.0; n * n];
    let mut fd2_hessian = vec![0.0; n * n];
    let h2 = 100.0 * step;
    for &(col, blk, i) in &dofs {
        let (plus, minus) = (
            element_at(&state.with_dof_moved(blk, i, step)),
            element_at(&state.with_dof_moved(blk, i, -step)),
        );
        fd_gradient[col] = (plus[0] - minus[0]) / (2.0 * step);
        for &(row, blk_r, r) in &dofs {
            let at = hessian_index(row, col);
            fd_hessian[at] = (plus[1 + row] - minus[1 + row]) / (2.0 * step);
            let energy_at = |hc: f64, hr: f64| {
                let mut s = state.with_dof_moved(blk, i, hc);
                s.v[blk_r as usize][r] += hr;
                s.place();
                element_at(&s)[0]
            };
            fd2_hessian[at] =
                (energy_at(h2, h2) - energy_at(h2, -h2) - energy_at(-h2, h2) + energy_at(-h2, -h2)) / (4.0 * h2 * h2);
        }
    }
    TermDerivativeErrors {
        gradient: rel_err(gradient, &fd_gradient),
        hessian_of_gradient: rel_err(exact_hessian, &fd_hessian),
        hessian_of_energy: rel_err(exact_hessian, &fd2_hessian),
        gradient_norm: gradient.iter().map(|g| g * g).sum::<f64>().sqrt(),
    }
}

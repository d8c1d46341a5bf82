//! A user's own element energy with run-time generated derivatives (the JIT path).
//!
//! The energy of one element is a function of its nodes' end-of-step positions `x`, velocities
//! `v = (x − x0)/dt`, the step `dt` and named parameters; it is traced once with the symbolic
//! scalar, differentiated and compiled ([`super::jit`]). [`UserEnergy`] is a [`Potential`], so it
//! gets the same kinematic map (deformable nodes and rigid-body points alike) and PSD projection
//! as the built-in energies. Parameters can be changed between steps without recompiling.
//!
//! Layout of the compiled function: inputs `x` (3 per node), parameters `[x0 (3 per node), dt,
//! user parameters]`.

use super::dual::HyperDual;
use super::jit::{self, JitKernel};
use super::potential::{FastDerivatives, Node, Potential, PotentialTerm, Stencil};
use super::scalar::Scalar;
use super::symbolic::{self, Sym, TracedEnergy};
use super::tensor::Vec3;
use super::term::EnergyTerm;
use crate::error::{Result, StarkError};
use std::any::Any;
use std::sync::Arc;

/// Largest number of nodes per element of a [`UserEnergy`] (the built-in stencils' size).
pub const MAX_NODES: usize = 4;

/// What an element energy reads: per node, positions `x` (m) and velocities `v` (m/s), the
/// start-of-step positions `x0` (m), the step `dt` (s) and the parameters, in declaration order.
#[derive(Clone, Debug)]
pub struct ElementArgs<S> {
    /// End-of-step positions, m (the differentiated variables).
    pub x: Vec<Vec3<S>>,
    /// End-of-step velocities `(x − x0)/dt`, m/s.
    pub v: Vec<Vec3<S>>,
    /// Start-of-step positions, m.
    pub x0: Vec<Vec3<S>>,
    /// Time step, s.
    pub dt: S,
    /// Parameters, in the order of their names.
    pub p: Vec<S>,
}

/// Trace an element energy of `n_nodes` nodes and `n_params` parameters. The closure may fail
/// (a Python energy raising); its error is returned.
pub fn trace_element(
    n_nodes: usize,
    n_params: usize,
    energy: impl FnOnce(&ElementArgs<Sym>) -> Result<Sym>,
) -> Result<TracedEnergy> {
    symbolic::trace(3 * n_nodes, 3 * n_nodes + 1 + n_params, |x, p| {
        let node = |s: &[Sym], a: usize| Vec3::new(s[3 * a], s[3 * a + 1], s[3 * a + 2]);
        let xs: Vec<Vec3<Sym>> = (0..n_nodes).map(|a| node(x, a)).collect();
        let x0: Vec<Vec3<Sym>> = (0..n_nodes).map(|a| node(p, a)).collect();
        let dt = p[3 * n_nodes];
        let inv_dt = dt.recip();
        let v = xs
            .iter()
            .zip(&x0)
            .map(|(x, x0)| {
                let d = *x - *x0;
                Vec3::new(d.0[0] * inv_dt, d.0[1] * inv_dt, d.0[2] * inv_dt)
            })
            .collect();
        let args = ElementArgs {
            x: xs,
            v,
            x0,
            dt,
            p: p[3 * n_nodes + 1..].to_vec(),
        };
        energy(&args)
    })
}

/// A user energy on elements of `N` nodes, derived and compiled at run time.
pub struct UserEnergy<const N: usize> {
    name: String,
    elements: Vec<[Node; N]>,
    param_names: Vec<String>,
    /// Parameters, `n_params` per element.
    params: Vec<f64>,
    traced: TracedEnergy,
    kernel: Arc<JitKernel>,
}

impl<const N: usize> UserEnergy<N> {
    /// An energy named `name` on `elements`, with parameters `param_names` whose values are
    /// `params` (one value per name, shared by all elements, or `n_params` per element).
    /// `traced` comes from [`trace_element`] with `N` nodes and as many parameters as names.
    pub fn new(
        name: &str,
        elements: Vec<[Node; N]>,
        param_names: Vec<String>,
        params: &[f64],
        traced: TracedEnergy,
    ) -> Result<Self> {
        if N == 0 || N > MAX_NODES {
            return Err(StarkError::InvalidInput(format!(
                "energy '{name}': elements have {N} nodes, supported are 1 to {MAX_NODES}"
            )));
        }
        let n_params = param_names.len();
        if traced.n_inputs != 3 * N || traced.n_params != 3 * N + 1 + n_params {
            return Err(StarkError::InvalidInput(format!(
                "energy '{name}': traced for {} nodes and {} parameters, registered with {N} nodes and {n_params}",
                traced.n_inputs / 3,
                traced.n_params.saturating_sub(traced.n_inputs + 1)
            )));
        }
        let mut e = UserEnergy {
            name: name.to_string(),
            params: vec![0.0; elements.len() * n_params],
            elements,
            param_names,
            kernel: jit::compile(&traced)?,
            traced,
        };
        if params.len() == n_params {
            for (k, name) in e.param_names.clone().iter().enumerate() {
                e.set_param(name, &[params[k]])?;
            }
        } else if params.len() == n_params * e.elements.len() {
            e.check_finite(params)?;
            e.params.copy_from_slice(params);
        } else {
            return Err(StarkError::InvalidInput(format!(
                "energy '{name}': {} parameter values for {n_params} parameters and {} elements (give {n_params} or {})",
                params.len(),
                e.elements.len(),
                n_params * e.elements.len()
            )));
        }
        Ok(e)
    }

    fn check_finite(&self, values: &[f64]) -> Result<()> {
        let n_params = self.param_names.len().max(1);
        match values.iter().position(|v| !v.is_finite()) {
            None => Ok(()),
            Some(i) => Err(StarkError::InvalidInput(format!(
                "energy '{}': parameter '{}' = {} is not finite",
                self.name,
                self.param_names[i % n_params],
                values[i]
            ))),
        }
    }

    /// The compiled kernel.
    pub fn kernel(&self) -> &Arc<JitKernel> {
        &self.kernel
    }

    /// The elements' nodes.
    pub fn elements(&self) -> &[[Node; N]] {
        &self.elements
    }

    fn param_index(&self, name: &str) -> Result<usize> {
        self.param_names.iter().position(|n| n == name).ok_or_else(|| {
            StarkError::InvalidInput(format!(
                "energy '{}' has no parameter '{name}' (it has: {})",
                self.name,
                self.param_names.join(", ")
            ))
        })
    }

    /// Values of parameter `name`, one per element.
    pub fn param(&self, name: &str) -> Result<Vec<f64>> {
        let k = self.param_index(name)?;
        let n = self.param_names.len();
        Ok(self.params.chunks(n).map(|c| c[k]).collect())
    }

    /// Set parameter `name`: one value for every element, or one per element. Must be finite.
    pub fn set_param(&mut self, name: &str, values: &[f64]) -> Result<()> {
        let k = self.param_index(name)?;
        if let Some(v) = values.iter().find(|v| !v.is_finite()) {
            return Err(StarkError::InvalidInput(format!(
                "energy '{}': parameter '{name}' = {v} is not finite",
                self.name
            )));
        }
        let n = self.param_names.len();
        let m = self.elements.len();
        match values.len() {
            1 => self.params.chunks_mut(n).for_each(|c| c[k] = values[0]),
            l if l == m => self.params.chunks_mut(n).zip(values).for_each(|(c, v)| c[k] = *v),
            l => {
                return Err(StarkError::InvalidInput(format!(
                    "energy '{}': {l} values for parameter '{name}' (give 1 or one per element, {m})",
                    self.name
                )))
            }
        }
        Ok(())
    }

    /// The compiled function's parameters of element `e`: `[x0, dt, user parameters]`.
    #[inline]
    fn kernel_params(&self, e: usize, stencil: &Stencil<N>, out: &mut [f64]) {
        for (a, x0) in stencil.x0.iter().enumerate() {
            out[3 * a..3 * a + 3].copy_from_slice(x0.as_slice());
        }
        out[3 * N] = stencil.dt;
        let n = self.param_names.len();
        out[3 * N + 1..].copy_from_slice(&self.params[e * n..(e + 1) * n]);
    }

    /// Parameter buffer on the stack when it fits (no allocation per element).
    #[inline]
    fn with_params<R>(&self, e: usize, stencil: &Stencil<N>, f: impl FnOnce(&[f64]) -> R) -> R {
        let len = 3 * N + 1 + self.param_names.len();
        if len <= 64 {
            let mut buf = [0.0; 64];
            self.kernel_params(e, stencil, &mut buf[..len]);
            f(&buf[..len])
        } else {
            let mut buf = vec![0.0; len];
            self.kernel_params(e, stencil, &mut buf);
            f(&buf)
        }
    }
}

impl<const N: usize> Potential<N> for UserEnergy<N> {
    fn name(&self) -> &str {
        &self.name
    }
    fn num_elements(&self) -> usize {
        self.elements.len()
    }
    fn nodes(&self, e: usize) -> [Node; N] {
        self.elements[e]
    }
    fn energy<S: Scalar>(&self, e: usize, x: &[Vec3<S>; N], stencil: &Stencil<N>) -> S {
        self.with_params(e, stencil, |p| {
            // Plain values (line search) run the compiled value function; other scalar types
            // (hyper-duals in tests) interpret the traced graph.
            if let Some(xf) = (x as &dyn Any).downcast_ref::<[Vec3<f64>; N]>() {
                let mut flat = [0.0; 3 * MAX_NODES];
                for (a, q) in xf.iter().enumerate() {
                    flat[3 * a..3 * a + 3].copy_from_slice(&q.0);
                }
                let v = self.kernel.value(&flat[..3 * N], p);
                return *(&v as &dyn Any).downcast_ref::<S>().expect("S is f64 when x is");
            }
            let xs: Vec<S> = x.iter().flat_map(|q| q.0).collect();
            let ps: Vec<S> = p.iter().map(|&c| S::constant(c)).collect();
            self.traced.evaluate(&xs, &ps)
        })
    }
    fn derivatives(&self, e: usize, stencil: &Stencil<N>, _project: bool, out: &mut HyperDual<N>) -> FastDerivatives {
        self.with_params(e, stencil, |p| self.kernel.derivatives(&stencil.x, p, out))
    }
}

/// A user energy as the simulation stores it: a solver term whose parameters can be read and
/// changed by name, whatever its number of nodes per element.
pub trait UserEnergyTerm: EnergyTerm {
    /// Parameter names, in order.
    fn param_names(&self) -> &[String];
    /// Values of parameter `name`, one per element.
    fn param(&self, name: &str) -> Result<Vec<f64>>;
    /// Set parameter `name` (one value, or one per element).
    fn set_param(&mut self, name: &str, values: &[f64]) -> Result<()>;
    /// Nodes per element.
    fn nodes_per_element(&self) -> usize;
    /// The compiled kernel.
    fn kernel(&self) -> &Arc<JitKernel>;
}

impl<const N: usize> UserEnergyTerm for PotentialTerm<UserEnergy<N>, N> {
    fn param_names(&self) -> &[String] {
        &self.potential.param_names
    }
    fn param(&self, name: &str) -> Result<Vec<f64>> {
        self.potential.param(name)
    }
    fn set_param(&mut self, name: &str, values: &[f64]) -> Result<()> {
        self.potential.set_param(name, values)
    }
    fn nodes_per_element(&self) -> usize {
        N
    }
    fn kernel(&self) -> &Arc<JitKernel> {
        &self.potential.kernel
    }
}

/// A [`UserEnergy`] of any supported element size (1 to [`MAX_NODES`] nodes) as a solver term;
/// every element has the same number of nodes.
pub fn user_energy_term(
    name: &str,
    elements: &[Vec<Node>],
    param_names: Vec<String>,
    params: &[f64],
    traced: TracedEnergy,
) -> Result<Box<dyn UserEnergyTerm>> {
    let n = traced.n_inputs / 3;
    if let Some((i, e)) = elements.iter().enumerate().find(|(_, e)| e.len() != n) {
        return Err(StarkError::InvalidInput(format!(
            "energy '{name}': element {i} has {} nodes, the energy is written for {n}",
            e.len()
        )));
    }
    fn make<const N: usize>(
        name: &str,
        elements: &[Vec<Node>],
        names: Vec<String>,
        params: &[f64],
        traced: TracedEnergy,
    ) -> Result<Box<dyn UserEnergyTerm>> {
        let els = elements.iter().map(|e| std::array::from_fn(|a| e[a])).collect();
        Ok(Box::new(PotentialTerm::new(UserEnergy::<N>::new(
            name, els, names, params, traced,
        )?)))
    }
    match n {
        1 => make::<1>(name, elements, param_names, params, traced),
        2 => make::<2>(name, elements, param_names, params, traced),
        3 => make::<3>(name, elements, param_names, params, traced),
        4 => make::<4>(name, elements, param_names, params, traced),
        _ => Err(StarkError::InvalidInput(format!(
            "energy '{name}': elements have {n} nodes, supported are 1 to {MAX_NODES}"
        ))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energy::testing::{assert_derivatives, TestState};
    use crate::energy::{EvalMode, PotentialTerm};
    use crate::state::BodyArrays;
    use nalgebra::{Matrix3, UnitQuaternion, Vector3};
    use rand::{Rng, SeedableRng};

    /// A spring of rest length `p[1]` and stiffness `p[0]` with a damper `p[2]` on the relative
    /// velocity (Rayleigh dissipation `dt·½c‖Δv‖²`), written once for every scalar type.
    fn spring<S: Scalar>(x: &[Vec3<S>], v: &[Vec3<S>], dt: S, p: &[S]) -> S {
        let d = x[1] - x[0];
        let len = (d.norm_sq() + 1e-12).sqrt();
        let dv = v[1] - v[0];
        p[0] * (len - p[1]).sq() * 0.5 + p[2] * dt * dv.norm_sq() * 0.5
    }

    /// The magnet of `magnetic_deformables`: `−k/‖x − m‖`.
    fn magnet<S: Scalar>(x: &[Vec3<S>], p: &[S]) -> S {
        let d = x[0] - Vec3::new(p[1], p[2], p[3]);
        -p[0] / d.norm()
    }

    fn traced_spring() -> TracedEnergy {
        trace_element(2, 3, |a| Ok(spring(&a.x, &a.v, a.dt, &a.p))).unwrap()
    }

    fn rvec(rng: &mut rand::rngs::StdRng, s: f64) -> Vector3<f64> {
        Vector3::new(
            rng.random_range(-s..s),
            rng.random_range(-s..s),
            rng.random_range(-s..s),
        )
    }

    fn nodes_state(rng: &mut rand::rngs::StdRng, x0: Vec<Vector3<f64>>) -> TestState {
        let n = x0.len();
        let v: Vec<_> = (0..n).map(|_| rvec(rng, 0.5)).collect();
        TestState::new(x0.clone(), x0, vec![Vector3::zeros(); n], v, 0.01)
    }

    #[test]
    fn traced_energies_match_finite_differences() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        for case in 0..12 {
            // Random states, then near-degenerate ones: a spring of almost zero length and a
            // node 1 mm from the magnet.
            let degenerate = case >= 6;
            let a = rvec(&mut rng, 1.0);
            let b = if degenerate {
                a + rvec(&mut rng, 1e-4)
            } else {
                rvec(&mut rng, 1.0)
            };
            let st = nodes_state(&mut rng, vec![a, b]);
            let e = UserEnergy::<2>::new(
                "spring",
                vec![[Node::Point(0), Node::Point(1)]],
                vec!["k".into(), "rest_m".into(), "c".into()],
                &[50.0, 0.3, 2.0],
                traced_spring(),
            )
            .unwrap();
            assert_derivatives(&e, &st.eval(), if degenerate { 1e-8 } else { 1e-6 });

            let m = rvec(&mut rng, 1.0);
            let gap = if degenerate { 1e-3 } else { 0.5 };
            let x = m + rvec(&mut rng, 1.0).normalize() * gap;
            let st = nodes_state(&mut rng, vec![x]);
            let traced = trace_element(1, 4, |a| Ok(magnet(&a.x, &a.p))).unwrap();
            let e = UserEnergy::<1>::new(
                "magnet",
                vec![[Node::Point(0)]],
                vec!["k".into(), "mx".into(), "my".into(), "mz".into()],
                &[0.1, m.x, m.y, m.z],
                traced,
            )
            .unwrap();
            assert_derivatives(&e, &st.eval(), gap * 1e-5);
        }
    }

    /// Every operation the tracer knows, compiled, against hyper-duals of the generic function.
    #[test]
    fn compiled_code_matches_hyper_duals_for_every_operation() {
        fn f<S: Scalar>(x: &[S], p: &[S]) -> S {
            let a = x[0] * x[1] - x[2] / x[0] + p[0];
            let b = (x[1] * x[1] + x[2] * x[2]).sqrt().ln() * p[1];
            let c = x[2].atan2(x[0]) + (x[1] * 0.3).acos() + x[0].sin() * x[2].cos() + (-x[1]).exp();
            let d = S::select_gt(a, S::constant(0.5), || (a - 0.5).powi(3), || -a);
            a * b + c + d + x[0].powi(-2) + x[1].powi(5) + x[2].powi(13) * 0.01
        }
        let kernel = jit::compile_fn(3, 2, f).unwrap();
        let mut rng = rand::rngs::StdRng::seed_from_u64(3);
        for _ in 0..20 {
            let x: Vec<f64> = (0..3).map(|_| rng.random_range(0.2..1.5)).collect();
            let p = [rng.random_range(-2.0..2.0), rng.random_range(-2.0..2.0)];
            let xd: Vec<HyperDual<1>> = (0..3).map(|i| HyperDual::variable(x[i], 0, i)).collect();
            let pd: Vec<HyperDual<1>> = p.iter().map(|&c| HyperDual::constant(c)).collect();
            let r = f(&xd, &pd);
            let hd = r.hessian_full();
            let (mut g, mut h) = ([0.0; 3], [0.0; 9]);
            let v = kernel.evaluate(&x, &p, &mut g, &mut h);
            assert!((v - r.value).abs() < 1e-12 * (1.0 + v.abs()), "{v} {}", r.value);
            assert!((kernel.value(&x, &p) - v).abs() < 1e-12 * (1.0 + v.abs()));
            for i in 0..3 {
                assert!((g[i] - r.grad[0][i]).abs() < 1e-10 * (1.0 + g[i].abs()), "grad {i}");
            }
            for k in 0..9 {
                assert!(
                    (h[k] - hd[k]).abs() < 1e-9 * (1.0 + hd[k].abs()),
                    "hess {k}: {} {}",
                    h[k],
                    hd[k]
                );
            }
        }
    }

    #[test]
    fn kernels_are_cached_in_memory_and_on_disk() {
        let traced = traced_spring();
        let a = jit::compile(&traced).unwrap();
        let b = jit::compile(&traced_spring()).unwrap();
        assert!(
            Arc::ptr_eq(&a, &b),
            "the second trace of the same energy hits the memory cache"
        );
        let dir = tempfile::tempdir().unwrap();
        let first = jit::compile_uncached(&traced, Some(dir.path().into())).unwrap();
        let second = jit::compile_uncached(&traced, Some(dir.path().into())).unwrap();
        assert!(!first.timings.from_disk && second.timings.from_disk);
        assert_eq!(second.timings.differentiate_ms, 0.0);
        let x = [0.1, 0.2, 0.3, 0.7, -0.2, 0.4];
        let p = [0.0, 0.1, 0.2, 0.6, -0.1, 0.5, 0.01, 50.0, 0.3, 2.0];
        let (mut g1, mut h1, mut g2, mut h2) = ([0.0; 6], [0.0; 36], [0.0; 6], [0.0; 36]);
        assert_eq!(
            first.evaluate(&x, &p, &mut g1, &mut h1),
            second.evaluate(&x, &p, &mut g2, &mut h2)
        );
        assert_eq!((g1, h1), (g2, h2));
        // A corrupt or foreign file is not used.
        let file = dir.path().join(format!("{:016x}.prog", traced.hash()));
        std::fs::write(&file, b"STARKJIT1\n garbage").unwrap();
        let third = jit::compile_uncached(&traced, Some(dir.path().into())).unwrap();
        assert!(!third.timings.from_disk);
        let other = trace_element(2, 3, |a| Ok(spring(&a.x, &a.v, a.dt, &a.p) * 2.0)).unwrap();
        std::fs::copy(&file, dir.path().join(format!("{:016x}.prog", other.hash()))).unwrap();
        let fourth = jit::compile_uncached(&other, Some(dir.path().into())).unwrap();
        assert!(!fourth.timings.from_disk, "a file made from another graph is rejected");
    }

    /// One free point and two rigid bodies at random poses and velocities.
    fn two_random_bodies(seed: u64) -> TestState {
        let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
        let mut bodies = BodyArrays::default();
        for _ in 0..2 {
            bodies.position.push(rvec(&mut rng, 1.0));
            bodies
                .orientation
                .push(UnitQuaternion::from_scaled_axis(rvec(&mut rng, 2.0)));
            bodies.velocity.push(rvec(&mut rng, 1.0));
            bodies.angular_velocity.push(rvec(&mut rng, 2.0));
            bodies.mass.push(1.0);
            bodies.inertia_local.push(Matrix3::identity());
            bodies.force.push(Vector3::zeros());
            bodies.torque.push(Vector3::zeros());
            bodies.acceleration.push(Vector3::zeros());
            bodies.angular_acceleration.push(Vector3::zeros());
        }
        let body_v: Vec<_> = (0..2).map(|_| (rvec(&mut rng, 1.0), rvec(&mut rng, 2.0))).collect();
        TestState::new(
            vec![Vector3::x()],
            vec![Vector3::x()],
            vec![Vector3::zeros()],
            vec![Vector3::y()],
            0.01,
        )
        .with_bodies(bodies, &body_v)
    }

    /// A convex element on rigid bodies (`½k‖x_b − x_a‖²`, stretched: its force makes the
    /// bodies' second-order rotation terms indefinite) is indefinite in the exact mode and
    /// positive semi-definite in the projected one, where only those terms are projected.
    #[test]
    fn a_convex_element_on_rigid_bodies_is_projected_in_its_rotation_terms() {
        struct Tie([Node; 2]);
        impl Potential<2> for Tie {
            fn name(&self) -> &str {
                "tie"
            }
            fn num_elements(&self) -> usize {
                1
            }
            fn nodes(&self, _e: usize) -> [Node; 2] {
                self.0
            }
            fn energy<S: Scalar>(&self, _e: usize, x: &[Vec3<S>; 2], _st: &Stencil<2>) -> S {
                (x[1] - x[0]).norm_sq() * 500.0
            }
            fn is_convex(&self) -> bool {
                true
            }
        }
        let st = two_random_bodies(5);
        let eval = st.eval();
        let term = PotentialTerm::new(Tie([
            Node::rigid(0, &Vector3::new(0.1, 0.0, 0.05)),
            Node::rigid(1, &Vector3::new(-0.1, 0.02, 0.0)),
        ]));
        let w = term.stencil_width(&eval);
        let hessian = |mode| {
            let mut out = vec![0.0; crate::energy::term::element_stride(w)];
            term.evaluate_element(0, &eval, mode, &mut out);
            let (n, base) = (3 * w, 1 + 3 * w);
            let mut h = vec![0.0; n * n];
            for a in 0..w {
                for b in 0..w {
                    for k in 0..9 {
                        h[(3 * a + k / 3) * n + 3 * b + k % 3] = out[base + 9 * (a * w + b) + k];
                    }
                }
            }
            h
        };
        use crate::energy::psd::is_positive_semidefinite;
        assert!(!is_positive_semidefinite(&hessian(EvalMode::ExactHessian), 3 * w));
        assert!(is_positive_semidefinite(&hessian(EvalMode::ProjectedHessian), 3 * w));
    }

    /// The same energy on rigid-body points: the JIT term and a hyper-dual potential give the
    /// same DOF-space value, gradient and projected Hessian through the kinematic map.
    #[test]
    fn rigid_points_get_the_same_kinematic_map_as_hyper_duals() {
        struct DualSpring(Vec<[Node; 2]>);
        impl Potential<2> for DualSpring {
            fn name(&self) -> &str {
                "dual spring"
            }
            fn num_elements(&self) -> usize {
                self.0.len()
            }
            fn nodes(&self, e: usize) -> [Node; 2] {
                self.0[e]
            }
            fn energy<S: Scalar>(&self, _e: usize, x: &[Vec3<S>; 2], st: &Stencil<2>) -> S {
                let dt = S::constant(st.dt);
                let v: Vec<Vec3<S>> = (0..2).map(|a| (x[a].sub_f64(&st.x0[a])) * dt.recip()).collect();
                spring(x, &v, dt, &[S::constant(50.0), S::constant(0.3), S::constant(2.0)])
            }
        }
        let st = two_random_bodies(11);
        let eval = st.eval();
        let elements = vec![
            [
                Node::rigid(0, &Vector3::new(0.1, 0.0, 0.05)),
                Node::rigid(1, &Vector3::new(-0.1, 0.02, 0.0)),
            ],
            [Node::Point(0), Node::rigid(1, &Vector3::new(0.0, 0.1, 0.0))],
        ];
        let jit_term = PotentialTerm::new(
            UserEnergy::<2>::new(
                "spring",
                elements.clone(),
                vec!["k".into(), "rest_m".into(), "c".into()],
                &[50.0, 0.3, 2.0],
                traced_spring(),
            )
            .unwrap(),
        );
        let dual_term = PotentialTerm::new(DualSpring(elements));
        let w = jit_term.stencil_width(&eval);
        assert_eq!(w, dual_term.stencil_width(&eval));
        let len = crate::energy::term::element_stride(w);
        for e in 0..2 {
            for mode in [EvalMode::ExactHessian, EvalMode::ProjectedHessian] {
                let (mut a, mut b) = (vec![0.0; len], vec![0.0; len]);
                jit_term.evaluate_element(e, &eval, mode, &mut a);
                dual_term.evaluate_element(e, &eval, mode, &mut b);
                let scale = b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                let err = a.iter().zip(&b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
                assert!(err < 1e-10 * scale, "element {e} {mode:?}: {err:e} of {scale:e}");
            }
        }
        assert!((jit_term.energy(&eval) - dual_term.energy(&eval)).abs() < 1e-12);
    }

    /// A hand-written potential opting into the JIT path: its generic `energy` stays the
    /// hyper-dual oracle, `derivatives` runs the kernel compiled from the same function.
    #[test]
    fn a_hand_written_potential_can_use_the_jit_path() {
        fn anchored<S: Scalar>(x: &Vec3<S>, p: &[S]) -> S {
            let d = *x - Vec3::new(p[1], p[2], p[3]);
            p[0] * (d.norm_sq() + 1e-4).sqrt()
        }
        struct Anchor {
            kernel: Arc<JitKernel>,
            params: [f64; 4],
        }
        impl Potential<1> for Anchor {
            fn name(&self) -> &str {
                "anchor"
            }
            fn num_elements(&self) -> usize {
                2
            }
            fn nodes(&self, e: usize) -> [Node; 1] {
                [Node::Point(e as u32)]
            }
            fn energy<S: Scalar>(&self, _e: usize, x: &[Vec3<S>; 1], _st: &Stencil<1>) -> S {
                anchored(&x[0], &self.params.map(S::constant))
            }
            fn derivatives(
                &self,
                _e: usize,
                st: &Stencil<1>,
                _project: bool,
                out: &mut HyperDual<1>,
            ) -> FastDerivatives {
                self.kernel.derivatives(&st.x, &self.params, out)
            }
        }
        let anchor = Anchor {
            kernel: jit::compile_fn(3, 4, |x, p| anchored(&Vec3::new(x[0], x[1], x[2]), p)).unwrap(),
            params: [3.0, 0.1, -0.2, 0.3],
        };
        let mut rng = rand::rngs::StdRng::seed_from_u64(5);
        let first = rvec(&mut rng, 1.0);
        let st = nodes_state(&mut rng, vec![first, Vector3::new(0.1, -0.2, 0.3001)]);
        // Fast path vs the hyper-duals of the hand-written generic energy to 1e-9, both vs FD.
        assert_derivatives(&anchor, &st.eval(), 1e-7);
    }

    #[test]
    fn bad_input_is_a_clear_error() {
        let names = || vec!["k".to_string(), "rest_m".to_string(), "c".to_string()];
        let el = vec![[Node::Point(0), Node::Point(1)]];
        let err = UserEnergy::<2>::new("spring", el.clone(), names(), &[1.0, f64::NAN, 0.0], traced_spring())
            .err()
            .unwrap()
            .to_string();
        assert!(err.contains("'spring'") && err.contains("'rest_m' = NaN"), "{err}");
        let err = UserEnergy::<2>::new("spring", el.clone(), names(), &[1.0, 2.0], traced_spring())
            .err()
            .unwrap()
            .to_string();
        assert!(err.contains("2 parameter values for 3 parameters"), "{err}");
        let err = UserEnergy::<3>::new(
            "spring",
            vec![[Node::Point(0); 3]],
            names(),
            &[1.0, 2.0, 3.0],
            traced_spring(),
        )
        .err()
        .unwrap()
        .to_string();
        assert!(err.contains("traced for 2 nodes"), "{err}");
        let mut e = UserEnergy::<2>::new("spring", el, names(), &[1.0, 2.0, 3.0], traced_spring()).unwrap();
        let err = e.set_param("stiffness", &[1.0]).unwrap_err().to_string();
        assert!(err.contains("no parameter 'stiffness' (it has: k, rest_m, c)"), "{err}");
        let err = e.set_param("k", &[f64::INFINITY]).unwrap_err().to_string();
        assert!(err.contains("'k' = inf is not finite"), "{err}");
        e.set_param("k", &[4.0]).unwrap();
        assert_eq!(e.param("k").unwrap(), vec![4.0]);

        let mut sim = crate::Simulation::new(crate::Settings::default()).unwrap();
        let err = sim
            .add_user_energy(
                "spring",
                &[vec![Node::Point(0), Node::Point(5)]],
                names(),
                &[1.0, 2.0, 3.0],
                traced_spring(),
            )
            .unwrap_err()
            .to_string();
        assert!(err.contains("energy 'spring': element 0 refers to Point(0)"), "{err}");
        let err = user_energy_term(
            "big",
            &[vec![Node::Point(0); 5]],
            vec![],
            &[],
            trace_element(5, 0, |a| Ok(a.x[4].norm_sq())).unwrap(),
        )
        .err()
        .unwrap()
        .to_string();
        assert!(err.contains("5 nodes, supported are 1 to 4"), "{err}");
    }
}

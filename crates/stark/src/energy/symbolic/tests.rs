//! Tests of the symbolic scalar: derivatives against hyper-dual numbers and the generated code.

use super::*;
use crate::energy::dual::HyperDual;

/// Evaluate a traced graph numerically (used by tests to check the differentiation rules without
/// compiling the emitted code).
fn evaluate(spec: &KernelSpec, x: &[f64], p: &[f64]) -> (f64, Vec<f64>, Vec<f64>) {
    reset();
    let n = spec.n_inputs;
    let xs: Vec<Sym> = (0..n).map(Sym::input).collect();
    let ps: Vec<Sym> = (0..spec.n_params).map(Sym::param).collect();
    let value = (spec.energy)(&xs, &ps).0;
    with_graph(|g| {
        let grad = g.gradient(value, n, &mut HashMap::new());
        let mut hess = vec![Id(0); n * n];
        for j in 0..n {
            let col = g.tangents(&grad, j);
            for (i, id) in col.into_iter().enumerate() {
                hess[i * n + j] = id;
            }
        }
        let mut vals = vec![0.0; g.ops.len()];
        for (i, op) in g.ops.iter().enumerate() {
            let v = |id: Id| vals[id.0 as usize];
            vals[i] = match *op {
                Op::Const(b) => f64::from_bits(b),
                Op::Input(k) => x[k as usize],
                Op::Param(k) => p[k as usize],
                Op::Add(a, b) => v(a) + v(b),
                Op::Mul(a, b) => v(a) * v(b),
                Op::Neg(a) => -v(a),
                Op::Recip(a) => 1.0 / v(a),
                Op::Sqrt(a) => v(a).sqrt(),
                Op::Ln(a) => v(a).ln(),
                Op::Exp(a) => v(a).exp(),
                Op::Sin(a) => v(a).sin(),
                Op::Cos(a) => v(a).cos(),
                Op::Acos(a) => v(a).acos(),
                Op::Atan2(a, b) => v(a).atan2(v(b)),
                Op::Powi(a, k) => v(a).powi(k),
                Op::SelectGt(a, b, t, e) => {
                    if v(a) > v(b) {
                        v(t)
                    } else {
                        v(e)
                    }
                }
            };
        }
        let get = |id: Id| vals[id.0 as usize];
        (
            get(value),
            grad.iter().map(|&i| get(i)).collect(),
            hess.iter().map(|&i| get(i)).collect(),
        )
    })
}

fn f<S: Scalar>(x: &[S], p: &[S]) -> S {
    let a = x[0] * x[1] - x[2] / x[0] + p[0];
    let b = (x[1] * x[1] + x[2] * x[2]).sqrt().ln() * p[1];
    let c = x[2].atan2(x[0]) + (x[1] * 0.3).acos() + x[0].sin() * x[2].cos() + (-x[1]).exp();
    let d = S::select_gt(a, S::constant(0.5), || (a - 0.5).powi(3), || -a);
    a * b + c + d + x[0].powi(-2)
}

#[test]
fn traced_derivatives_match_hyper_duals() {
    let spec = KernelSpec {
        name: "f",
        n_inputs: 3,
        n_params: 2,
        energy: |x, p| f(x, p),
    };
    for (x, p) in [([0.7, 1.3, -0.4], [0.2, 1.5]), ([1.1, -0.9, 0.6], [-2.0, 0.5])] {
        let (v, g, h) = evaluate(&spec, &x, &p);
        let xd: Vec<HyperDual<1>> = (0..3).map(|i| HyperDual::variable(x[i], 0, i)).collect();
        let pd: Vec<HyperDual<1>> = p.iter().map(|&c| HyperDual::constant(c)).collect();
        let r = f(&xd, &pd);
        assert!((v - r.value).abs() < 1e-12);
        for i in 0..3 {
            assert!(
                (g[i] - r.grad[0][i]).abs() < 1e-10,
                "grad {i}: {} vs {}",
                g[i],
                r.grad[0][i]
            );
        }
        let hd = r.hessian_full();
        for k in 0..9 {
            assert!(
                (h[k] - hd[k]).abs() < 1e-9 * (1.0 + hd[k].abs()),
                "hess {k}: {} vs {}",
                h[k],
                hd[k]
            );
        }
    }
}

#[test]
fn untaken_branch_with_infinite_derivative_does_not_poison_gradient() {
    // √(y² + z²) has an infinite derivative at 0, but only inside the branch not taken.
    let spec = KernelSpec {
        name: "g",
        n_inputs: 3,
        n_params: 0,
        energy: |x, _| {
            let r = (x[1] * x[1] + x[2] * x[2]).sqrt();
            x[0] * x[0] * x[1] + Sym::select_gt(r, Sym::constant(1.0), || (r - 1.0).powi(3), Sym::zero)
        },
    };
    let (v, g, h) = evaluate(&spec, &[0.5, 0.0, 0.0], &[]);
    assert_eq!(v, 0.0);
    assert!(g.iter().chain(h.iter()).all(|x| x.is_finite()), "{g:?} {h:?}");
    assert!((g[1] - 0.25).abs() < 1e-15 && (h[1] - 1.0).abs() < 1e-15);
}

#[test]
fn emitted_code_has_expected_shape() {
    let spec = KernelSpec {
        name: "quad",
        n_inputs: 2,
        n_params: 1,
        energy: |x, p| x[0] * x[0] * p[0] + x[0] * x[1],
    };
    let code = generate_kernel(&spec);
    assert!(code.contains("pub fn quad("));
    assert!(code.contains("grad[1] = x[0];"), "{code}");
    assert!(!code.contains("let t"), "{code}");
    // ∂²/∂x0² = 2 p0 is emitted as an expression of p[0].
    assert!(code.contains("hess[0] = "), "{code}");
    assert!(code.contains("hess[3] = 0.0;"), "{code}");
}

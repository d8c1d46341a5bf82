//! Code generation: [`generate_kernel`] emits straight-line Rust for the value, gradient and
//! Hessian of a [`KernelSpec`]'s traced energy.

use super::{reset, with_graph, Graph, Id, Op, Sym};
use std::collections::HashMap;
use std::fmt::Write;

/// A kernel to generate: a traced energy of `n_inputs` coordinates and `n_params` parameters.
pub struct KernelSpec {
    /// Function name in the generated code.
    pub name: &'static str,
    /// Number of differentiated inputs (`3 ×` stencil nodes).
    pub n_inputs: usize,
    /// Number of run-time parameters.
    pub n_params: usize,
    /// The energy, traced with symbolic inputs and parameters.
    pub energy: fn(&[Sym], &[Sym]) -> Sym,
}

fn literal(v: f64) -> String {
    if v.is_nan() {
        "f64::NAN".into()
    } else if v.is_infinite() {
        if v > 0.0 {
            "f64::INFINITY".into()
        } else {
            "f64::NEG_INFINITY".into()
        }
    } else if v < 0.0 {
        format!("({v:?})")
    } else {
        format!("{v:?}")
    }
}

/// Trace `spec`, differentiate, and return the Rust source of
/// `pub fn NAME(x: &[f64], p: &[f64], grad: &mut [f64], hess: &mut [f64]) -> f64`
/// (value returned; gradient of length `n`; full row-major `n × n` Hessian).
pub fn generate_kernel(spec: &KernelSpec) -> String {
    reset();
    let n = spec.n_inputs;
    let x: Vec<Sym> = (0..n).map(Sym::input).collect();
    let p: Vec<Sym> = (0..spec.n_params).map(Sym::param).collect();
    let value = (spec.energy)(&x, &p).0;
    let (grad, hess) = with_graph(|g| {
        let grad = g.gradient(value, n, &mut HashMap::new());
        let mut hess = vec![vec![Id(0); n]; n];
        for j in 0..n {
            let rows: Vec<Id> = grad[j..].to_vec();
            let col = g.tangents(&rows, j);
            for (k, id) in col.into_iter().enumerate() {
                hess[j + k][j] = id;
            }
        }
        (grad, hess)
    });
    with_graph(|g| emit(g, spec, value, &grad, &hess))
}

fn emit(g: &Graph, spec: &KernelSpec, value: Id, grad: &[Id], hess: &[Vec<Id>]) -> String {
    let n = spec.n_inputs;
    let mut outputs: Vec<Id> = vec![value];
    outputs.extend_from_slice(grad);
    for (i, row) in hess.iter().enumerate() {
        outputs.extend_from_slice(&row[..=i]);
    }
    // Dead-code elimination and use counts.
    let limit = outputs.iter().map(|o| o.0 as usize + 1).max().unwrap_or(0);
    let mut live = vec![false; limit];
    let mut stack = outputs.clone();
    while let Some(id) = stack.pop() {
        if live[id.0 as usize] {
            continue;
        }
        live[id.0 as usize] = true;
        stack.extend(g.children(id).into_iter().flatten());
    }
    // Temporaries live in one local array rather than one `let` each: thousands of `let`s nest
    // scopes deeply enough to overflow rustc's stack.
    let mut slot = vec![u32::MAX; limit];
    let mut n_slots = 0u32;
    for (idx, &is_live) in live.iter().enumerate() {
        if is_live && !matches!(g.ops[idx], Op::Const(_) | Op::Input(_) | Op::Param(_)) {
            slot[idx] = n_slots;
            n_slots += 1;
        }
    }
    let name_of = |id: Id| -> String {
        match g.ops[id.0 as usize] {
            Op::Const(bits) => literal(f64::from_bits(bits)),
            Op::Input(i) => format!("x[{i}]"),
            Op::Param(k) => format!("p[{k}]"),
            _ => format!("t[{}]", slot[id.0 as usize]),
        }
    };
    let mut body = String::new();
    let mut count = 0usize;
    for (idx, &is_live) in live.iter().enumerate() {
        if !is_live {
            continue;
        }
        let id = Id(idx as u32);
        let a = |c: Id| name_of(c);
        let expr = match g.ops[idx] {
            Op::Const(_) | Op::Input(_) | Op::Param(_) => continue,
            Op::Add(x, y) => match g.ops[y.0 as usize] {
                Op::Neg(z) => format!("{} - {}", a(x), a(z)),
                _ => format!("{} + {}", a(x), a(y)),
            },
            Op::Mul(x, y) => format!("{} * {}", a(x), a(y)),
            Op::Neg(x) => format!("-{}", a(x)),
            Op::Recip(x) => format!("1.0 / {}", a(x)),
            Op::Sqrt(x) => format!("{}.sqrt()", a(x)),
            Op::Ln(x) => format!("{}.ln()", a(x)),
            Op::Exp(x) => format!("{}.exp()", a(x)),
            Op::Sin(x) => format!("{}.sin()", a(x)),
            Op::Cos(x) => format!("{}.cos()", a(x)),
            Op::Acos(x) => format!("{}.acos()", a(x)),
            Op::Atan2(y, x) => format!("{}.atan2({})", a(y), a(x)),
            Op::Powi(x, 2) => format!("{0} * {0}", a(x)),
            Op::Powi(x, 3) => format!("{0} * {0} * {0}", a(x)),
            Op::Powi(x, k) => format!("{}.powi({k})", a(x)),
            Op::SelectGt(p, q, t, e) => {
                format!("if {} > {} {{ {} }} else {{ {} }}", a(p), a(q), a(t), a(e))
            }
        };
        count += 1;
        let _ = writeln!(body, "    {} = {};", name_of(id), expr);
    }
    let mut out = String::new();
    let _ = writeln!(
        out,
        "/// Value, gradient and Hessian of `{}` ({} inputs, {} parameters, {} operations).",
        spec.name, n, spec.n_params, count
    );
    let _ = writeln!(
        out,
        "pub fn {}(x: &[f64], p: &[f64], grad: &mut [f64], hess: &mut [f64]) -> f64 {{",
        spec.name
    );
    let _ = writeln!(out, "    let x: &[f64; {n}] = x.try_into().expect(\"input length\");");
    if spec.n_params > 0 {
        let _ = writeln!(
            out,
            "    let p: &[f64; {}] = p.try_into().expect(\"parameter length\");",
            spec.n_params
        );
    } else {
        let _ = writeln!(out, "    let _ = p;");
    }
    let _ = writeln!(
        out,
        "    let grad: &mut [f64; {n}] = grad.try_into().expect(\"gradient length\");"
    );
    let _ = writeln!(
        out,
        "    let hess: &mut [f64; {}] = hess.try_into().expect(\"Hessian length\");",
        n * n
    );
    let _ = writeln!(out, "    let mut t = [0.0f64; {}];", n_slots.max(1));
    out.push_str(&body);
    for (i, &gi) in grad.iter().enumerate() {
        let _ = writeln!(out, "    grad[{i}] = {};", name_of(gi));
    }
    for i in 0..n {
        for j in 0..=i {
            let h = name_of(hess[i][j]);
            if i == j {
                let _ = writeln!(out, "    hess[{}] = {h};", i * n + j);
            } else {
                let _ = writeln!(out, "    hess[{}] = {h};", i * n + j);
                let _ = writeln!(out, "    hess[{}] = {h};", j * n + i);
            }
        }
    }
    let _ = writeln!(out, "    {}", name_of(value));
    let _ = writeln!(out, "}}");
    out
}

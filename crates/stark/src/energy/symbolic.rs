//! A symbolic scalar that traces a generic energy into an expression graph, differentiates it, and
//! emits straight-line Rust code for value, gradient and Hessian (our counterpart of SymX, run at
//! development time by `stark-codegen`, so no compiler is needed at run time).
//!
//! - Construction is hash-consed, so equal subexpressions are one node (common-subexpression
//!   elimination for free), with constant folding and algebraic identities (`x·1`, `x+0`, `−−x`).
//! - The gradient is built by reverse mode over the graph (one adjoint sweep).
//! - The Hessian is built forward-over-reverse: one tangent sweep per input direction `j`,
//!   restricted to the nodes the gradient entries `i ≥ j` depend on.
//! - Branches are `SelectGt` nodes; their derivatives are selects of the branch derivatives.
//!
//! The graph is thread-local: tracing is single-threaded and starts with [`reset`].
//!
//! The graph and [`Sym`] are here; code generation in `symbolic/codegen.rs`, run-time tracing
//! (the JIT path) in `symbolic/trace.rs`.

mod codegen;
mod trace;

use super::scalar::Scalar;
use std::cell::RefCell;
use std::collections::HashMap;
use std::ops::{Add, AddAssign, Div, Mul, MulAssign, Neg, Sub, SubAssign};

pub use codegen::{generate_kernel, KernelSpec};
pub use trace::{interpret, trace, Program, TracedEnergy, TracedOp};

#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, PartialOrd, Ord)]
struct Id(u32);

#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
enum Op {
    Const(u64),
    Input(u32),
    Param(u32),
    Add(Id, Id),
    Mul(Id, Id),
    Neg(Id),
    Recip(Id),
    Sqrt(Id),
    Ln(Id),
    Exp(Id),
    Sin(Id),
    Cos(Id),
    Acos(Id),
    Atan2(Id, Id),
    Powi(Id, i32),
    /// `if a > b { then } else { otherwise }`
    SelectGt(Id, Id, Id, Id),
}

#[derive(Default)]
struct Graph {
    ops: Vec<Op>,
    index: HashMap<Op, Id>,
}

thread_local! {
    static GRAPH: RefCell<Graph> = RefCell::new(Graph::default());
}

fn with_graph<R>(f: impl FnOnce(&mut Graph) -> R) -> R {
    GRAPH.with(|g| f(&mut g.borrow_mut()))
}

/// Clear the thread's graph before tracing a new energy.
pub fn reset() {
    with_graph(|g| *g = Graph::default());
}

impl Graph {
    fn konst(&self, id: Id) -> Option<f64> {
        match self.ops[id.0 as usize] {
            Op::Const(bits) => Some(f64::from_bits(bits)),
            _ => None,
        }
    }

    fn intern(&mut self, op: Op) -> Id {
        if let Some(&id) = self.index.get(&op) {
            return id;
        }
        let id = Id(self.ops.len() as u32);
        self.ops.push(op);
        self.index.insert(op, id);
        id
    }

    fn c(&mut self, v: f64) -> Id {
        // Canonical zero: avoid distinct nodes for 0.0 and -0.0.
        let v = if v == 0.0 { 0.0 } else { v };
        self.intern(Op::Const(v.to_bits()))
    }

    fn add(&mut self, a: Id, b: Id) -> Id {
        match (self.konst(a), self.konst(b)) {
            (Some(x), Some(y)) => return self.c(x + y),
            (Some(0.0), None) => return b,
            (None, Some(0.0)) => return a,
            _ => {}
        }
        if let Op::Neg(x) = self.ops[b.0 as usize] {
            if x == a {
                return self.c(0.0);
            }
        }
        if let Op::Neg(x) = self.ops[a.0 as usize] {
            if x == b {
                return self.c(0.0);
            }
        }
        let (a, b) = if a <= b { (a, b) } else { (b, a) };
        self.intern(Op::Add(a, b))
    }

    fn mul(&mut self, a: Id, b: Id) -> Id {
        match (self.konst(a), self.konst(b)) {
            (Some(x), Some(y)) => return self.c(x * y),
            (Some(0.0), _) => return a,
            (_, Some(0.0)) => return b,
            (Some(1.0), _) => return b,
            (_, Some(1.0)) => return a,
            (Some(-1.0), _) => return self.neg(b),
            (_, Some(-1.0)) => return self.neg(a),
            _ => {}
        }
        // Pull negations out so that −a·b and a·(−b) share a node.
        if let Op::Neg(x) = self.ops[a.0 as usize] {
            let m = self.mul(x, b);
            return self.neg(m);
        }
        if let Op::Neg(y) = self.ops[b.0 as usize] {
            let m = self.mul(a, y);
            return self.neg(m);
        }
        let (a, b) = if a <= b { (a, b) } else { (b, a) };
        self.intern(Op::Mul(a, b))
    }

    fn neg(&mut self, a: Id) -> Id {
        if let Some(x) = self.konst(a) {
            return self.c(-x);
        }
        if let Op::Neg(x) = self.ops[a.0 as usize] {
            return x;
        }
        self.intern(Op::Neg(a))
    }

    fn sub(&mut self, a: Id, b: Id) -> Id {
        if a == b {
            return self.c(0.0);
        }
        let nb = self.neg(b);
        self.add(a, nb)
    }

    fn recip(&mut self, a: Id) -> Id {
        if let Some(x) = self.konst(a) {
            return self.c(1.0 / x);
        }
        match self.ops[a.0 as usize] {
            Op::Recip(x) => x,
            Op::Neg(x) => {
                let r = self.recip(x);
                self.neg(r)
            }
            _ => self.intern(Op::Recip(a)),
        }
    }

    fn unary(&mut self, a: Id, op: fn(Id) -> Op, f: fn(f64) -> f64) -> Id {
        if let Some(x) = self.konst(a) {
            return self.c(f(x));
        }
        self.intern(op(a))
    }

    fn powi(&mut self, a: Id, n: i32) -> Id {
        match n {
            0 => return self.c(1.0),
            1 => return a,
            -1 => return self.recip(a),
            _ => {}
        }
        if let Some(x) = self.konst(a) {
            return self.c(x.powi(n));
        }
        self.intern(Op::Powi(a, n))
    }

    fn atan2(&mut self, y: Id, x: Id) -> Id {
        if let (Some(a), Some(b)) = (self.konst(y), self.konst(x)) {
            return self.c(a.atan2(b));
        }
        self.intern(Op::Atan2(y, x))
    }

    fn select_gt(&mut self, a: Id, b: Id, t: Id, e: Id) -> Id {
        if t == e {
            return t;
        }
        if let (Some(x), Some(y)) = (self.konst(a), self.konst(b)) {
            return if x > y { t } else { e };
        }
        self.intern(Op::SelectGt(a, b, t, e))
    }

    fn children(&self, id: Id) -> [Option<Id>; 4] {
        match self.ops[id.0 as usize] {
            Op::Const(_) | Op::Input(_) | Op::Param(_) => [None; 4],
            Op::Add(a, b) | Op::Mul(a, b) | Op::Atan2(a, b) => [Some(a), Some(b), None, None],
            Op::Neg(a)
            | Op::Recip(a)
            | Op::Sqrt(a)
            | Op::Ln(a)
            | Op::Exp(a)
            | Op::Sin(a)
            | Op::Cos(a)
            | Op::Acos(a)
            | Op::Powi(a, _) => [Some(a), None, None, None],
            Op::SelectGt(a, b, t, e) => [Some(a), Some(b), Some(t), Some(e)],
        }
    }

    /// Reverse-mode gradient of `out` with respect to inputs `0..n_inputs`.
    ///
    /// A `SelectGt` node does not pass its adjoint into its branches: the gradient of each branch
    /// is built by its own sweep and the two are selected per input. Otherwise a derivative that
    /// is non-finite only in the branch not taken (e.g. of `√s` at `s = 0`) would reach shared
    /// subexpressions as `0·∞ = NaN`.
    fn gradient(&mut self, out: Id, n_inputs: usize, memo: &mut HashMap<Id, Vec<Id>>) -> Vec<Id> {
        if let Some(g) = memo.get(&out) {
            return g.clone();
        }
        let n = out.0 as usize + 1;
        let mut adj: Vec<Option<Id>> = vec![None; n];
        let mut input_adj: Vec<Option<Id>> = vec![None; n_inputs];
        adj[out.0 as usize] = Some(self.c(1.0));
        let acc = |g: &mut Graph, slot: &mut Option<Id>, contrib: Id| {
            *slot = Some(match *slot {
                Some(prev) => g.add(prev, contrib),
                None => contrib,
            });
        };
        for idx in (0..n).rev() {
            let Some(a) = adj[idx] else { continue };
            if self.konst(a) == Some(0.0) {
                continue;
            }
            let me = Id(idx as u32);
            let mut push = |g: &mut Graph, target: Id, contrib: Id| {
                let mut slot = adj[target.0 as usize];
                acc(g, &mut slot, contrib);
                adj[target.0 as usize] = slot;
            };
            match self.ops[idx] {
                Op::Const(_) | Op::Param(_) => {}
                Op::Input(i) => {
                    if (i as usize) < n_inputs {
                        acc(self, &mut input_adj[i as usize], a);
                    }
                }
                Op::Add(x, y) => {
                    push(self, x, a);
                    push(self, y, a);
                }
                Op::Mul(x, y) => {
                    let cx = self.mul(a, y);
                    push(self, x, cx);
                    let cy = self.mul(a, x);
                    push(self, y, cy);
                }
                Op::Neg(x) => {
                    let c = self.neg(a);
                    push(self, x, c);
                }
                Op::Recip(x) => {
                    let r2 = self.mul(me, me);
                    let m = self.mul(a, r2);
                    let c = self.neg(m);
                    push(self, x, c);
                }
                Op::Sqrt(x) => {
                    let r = self.recip(me);
                    let h = self.c(0.5);
                    let hr = self.mul(h, r);
                    let c = self.mul(a, hr);
                    push(self, x, c);
                }
                Op::Ln(x) => {
                    let r = self.recip(x);
                    let c = self.mul(a, r);
                    push(self, x, c);
                }
                Op::Exp(x) => {
                    let c = self.mul(a, me);
                    push(self, x, c);
                }
                Op::Sin(x) => {
                    let cs = self.intern(Op::Cos(x));
                    let c = self.mul(a, cs);
                    push(self, x, c);
                }
                Op::Cos(x) => {
                    let s = self.intern(Op::Sin(x));
                    let m = self.mul(a, s);
                    let c = self.neg(m);
                    push(self, x, c);
                }
                Op::Acos(x) => {
                    let d = self.acos_derivative(x);
                    let c = self.mul(a, d);
                    push(self, x, c);
                }
                Op::Atan2(y, x) => {
                    let (dy, dx) = self.atan2_partials(y, x);
                    let cy = self.mul(a, dy);
                    push(self, y, cy);
                    let cx = self.mul(a, dx);
                    push(self, x, cx);
                }
                Op::Powi(x, k) => {
                    let d = self.powi_derivative(x, k);
                    let c = self.mul(a, d);
                    push(self, x, c);
                }
                Op::SelectGt(p, q, t, e) => {
                    let gt = self.gradient(t, n_inputs, memo);
                    let ge = self.gradient(e, n_inputs, memo);
                    for i in 0..n_inputs {
                        let s = self.select_gt(p, q, gt[i], ge[i]);
                        if self.konst(s) == Some(0.0) {
                            continue;
                        }
                        let c = self.mul(a, s);
                        acc(self, &mut input_adj[i], c);
                    }
                }
            }
        }
        let g: Vec<Id> = input_adj
            .into_iter()
            .map(|a| a.unwrap_or_else(|| self.c(0.0)))
            .collect();
        memo.insert(out, g.clone());
        g
    }

    /// d/dx acos(x) = −1/√(1 − x²)
    fn acos_derivative(&mut self, x: Id) -> Id {
        let x2 = self.mul(x, x);
        let one = self.c(1.0);
        let r = self.sub(one, x2);
        let s = self.intern(Op::Sqrt(r));
        let inv = self.recip(s);
        self.neg(inv)
    }

    /// ∂atan2(y, x)/∂y = x/(x² + y²), ∂/∂x = −y/(x² + y²)
    fn atan2_partials(&mut self, y: Id, x: Id) -> (Id, Id) {
        let x2 = self.mul(x, x);
        let y2 = self.mul(y, y);
        let r2 = self.add(x2, y2);
        let inv = self.recip(r2);
        let dy = self.mul(x, inv);
        let m = self.mul(y, inv);
        (dy, self.neg(m))
    }

    /// d/dx xᵏ = k·xᵏ⁻¹
    fn powi_derivative(&mut self, x: Id, k: i32) -> Id {
        let p = self.powi(x, k - 1);
        let kc = self.c(k as f64);
        self.mul(kc, p)
    }

    /// Directional derivative (tangent) of the `targets` along input `dir`, forward mode.
    fn tangents(&mut self, targets: &[Id], dir: usize) -> Vec<Id> {
        let limit = targets.iter().map(|t| t.0 as usize + 1).max().unwrap_or(0);
        // Nodes the targets depend on.
        let mut needed = vec![false; limit];
        let mut stack: Vec<Id> = targets.to_vec();
        while let Some(id) = stack.pop() {
            let i = id.0 as usize;
            if needed[i] {
                continue;
            }
            needed[i] = true;
            for c in self.children(id).into_iter().flatten() {
                if !needed[c.0 as usize] {
                    stack.push(c);
                }
            }
        }
        let mut tan: Vec<Option<Id>> = vec![None; limit];
        for idx in 0..limit {
            if !needed[idx] {
                continue;
            }
            let me = Id(idx as u32);
            let t = |tan: &Vec<Option<Id>>, c: Id| tan[c.0 as usize];
            let result: Option<Id> = match self.ops[idx] {
                Op::Const(_) | Op::Param(_) => None,
                Op::Input(i) => (i as usize == dir).then(|| self.c(1.0)),
                Op::Add(a, b) => match (t(&tan, a), t(&tan, b)) {
                    (None, None) => None,
                    (Some(x), None) | (None, Some(x)) => Some(x),
                    (Some(x), Some(y)) => Some(self.add(x, y)),
                },
                Op::Mul(a, b) => {
                    let ta = t(&tan, a).map(|x| self.mul(x, b));
                    let tb = t(&tan, b).map(|y| self.mul(a, y));
                    match (ta, tb) {
                        (None, None) => None,
                        (Some(x), None) | (None, Some(x)) => Some(x),
                        (Some(x), Some(y)) => Some(self.add(x, y)),
                    }
                }
                Op::Neg(a) => t(&tan, a).map(|x| self.neg(x)),
                Op::Recip(a) => t(&tan, a).map(|x| {
                    let r2 = self.mul(me, me);
                    let m = self.mul(r2, x);
                    self.neg(m)
                }),
                Op::Sqrt(a) => t(&tan, a).map(|x| {
                    let r = self.recip(me);
                    let h = self.c(0.5);
                    let hr = self.mul(h, r);
                    self.mul(hr, x)
                }),
                Op::Ln(a) => t(&tan, a).map(|x| {
                    let r = self.recip(a);
                    self.mul(r, x)
                }),
                Op::Exp(a) => t(&tan, a).map(|x| self.mul(me, x)),
                Op::Sin(a) => t(&tan, a).map(|x| {
                    let c = self.intern(Op::Cos(a));
                    self.mul(c, x)
                }),
                Op::Cos(a) => t(&tan, a).map(|x| {
                    let s = self.intern(Op::Sin(a));
                    let m = self.mul(s, x);
                    self.neg(m)
                }),
                Op::Acos(a) => t(&tan, a).map(|x| {
                    let d = self.acos_derivative(a);
                    self.mul(d, x)
                }),
                Op::Atan2(y, x) => {
                    let (ty, tx) = (t(&tan, y), t(&tan, x));
                    if ty.is_none() && tx.is_none() {
                        None
                    } else {
                        let (dy, dx) = self.atan2_partials(y, x);
                        let a = ty.map(|v| self.mul(dy, v));
                        let b = tx.map(|v| self.mul(dx, v));
                        match (a, b) {
                            (Some(p), Some(q)) => Some(self.add(p, q)),
                            (Some(p), None) | (None, Some(p)) => Some(p),
                            (None, None) => None,
                        }
                    }
                }
                Op::Powi(a, k) => t(&tan, a).map(|x| {
                    let d = self.powi_derivative(a, k);
                    self.mul(d, x)
                }),
                Op::SelectGt(p, q, th, el) => match (t(&tan, th), t(&tan, el)) {
                    (None, None) => None,
                    (a, b) => {
                        let z = self.c(0.0);
                        Some(self.select_gt(p, q, a.unwrap_or(z), b.unwrap_or(z)))
                    }
                },
            };
            tan[idx] = result;
        }
        targets
            .iter()
            .map(|t| tan[t.0 as usize].unwrap_or_else(|| self.c(0.0)))
            .collect()
    }
}

/// A traced scalar: a node of the thread-local expression graph.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sym(Id);

impl Sym {
    /// Input variable `i` (a stencil coordinate, `x[i]` in the generated code).
    pub fn input(i: usize) -> Sym {
        Sym(with_graph(|g| g.intern(Op::Input(i as u32))))
    }
    /// Parameter `k` (`p[k]` in the generated code): per-element data read at run time.
    pub fn param(k: usize) -> Sym {
        Sym(with_graph(|g| g.intern(Op::Param(k as u32))))
    }
}

macro_rules! sym_binop {
    ($tr:ident, $f:ident, $body:expr) => {
        impl $tr for Sym {
            type Output = Sym;
            fn $f(self, o: Sym) -> Sym {
                Sym(with_graph(|g| $body(g, self.0, o.0)))
            }
        }
        impl $tr<f64> for Sym {
            type Output = Sym;
            fn $f(self, o: f64) -> Sym {
                Sym(with_graph(|g| {
                    let c = g.c(o);
                    $body(g, self.0, c)
                }))
            }
        }
    };
}
sym_binop!(Add, add, |g: &mut Graph, a, b| g.add(a, b));
sym_binop!(Sub, sub, |g: &mut Graph, a, b| g.sub(a, b));
sym_binop!(Mul, mul, |g: &mut Graph, a, b| g.mul(a, b));
sym_binop!(Div, div, |g: &mut Graph, a, b| {
    let r = g.recip(b);
    g.mul(a, r)
});

impl Neg for Sym {
    type Output = Sym;
    fn neg(self) -> Sym {
        Sym(with_graph(|g| g.neg(self.0)))
    }
}
impl AddAssign for Sym {
    fn add_assign(&mut self, o: Sym) {
        *self = *self + o;
    }
}
impl SubAssign for Sym {
    fn sub_assign(&mut self, o: Sym) {
        *self = *self - o;
    }
}
impl MulAssign for Sym {
    fn mul_assign(&mut self, o: Sym) {
        *self = *self * o;
    }
}

impl Scalar for Sym {
    fn constant(value: f64) -> Self {
        Sym(with_graph(|g| g.c(value)))
    }
    fn sqrt(self) -> Self {
        Sym(with_graph(|g| g.unary(self.0, Op::Sqrt, f64::sqrt)))
    }
    fn ln(self) -> Self {
        Sym(with_graph(|g| g.unary(self.0, Op::Ln, f64::ln)))
    }
    fn exp(self) -> Self {
        Sym(with_graph(|g| g.unary(self.0, Op::Exp, f64::exp)))
    }
    fn sin(self) -> Self {
        Sym(with_graph(|g| g.unary(self.0, Op::Sin, f64::sin)))
    }
    fn cos(self) -> Self {
        Sym(with_graph(|g| g.unary(self.0, Op::Cos, f64::cos)))
    }
    fn acos(self) -> Self {
        Sym(with_graph(|g| g.unary(self.0, Op::Acos, f64::acos)))
    }
    fn atan2(self, x: Self) -> Self {
        Sym(with_graph(|g| g.atan2(self.0, x.0)))
    }
    fn powi(self, n: i32) -> Self {
        Sym(with_graph(|g| g.powi(self.0, n)))
    }
    fn recip(self) -> Self {
        Sym(with_graph(|g| g.recip(self.0)))
    }
    fn select_gt(a: Self, b: Self, then: impl FnOnce() -> Self, otherwise: impl FnOnce() -> Self) -> Self {
        let t = then();
        let e = otherwise();
        Sym(with_graph(|g| g.select_gt(a.0, b.0, t.0, e.0)))
    }
}

#[cfg(test)]
mod tests;

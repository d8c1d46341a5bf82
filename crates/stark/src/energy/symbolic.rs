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

use super::scalar::Scalar;
use std::cell::RefCell;
use std::collections::HashMap;
use std::fmt::Write;
use std::ops::{Add, AddAssign, Div, Mul, MulAssign, Neg, Sub, SubAssign};

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

// ---------------------------------------------------------------------------------------------
// Run-time tracing (the JIT path, `energy::jit`): a traced energy as data rather than source.

/// An operation of a compacted expression graph: operands are indices of earlier operations.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TracedOp {
    /// A constant.
    Const(f64),
    /// Differentiated input `i`.
    Input(u32),
    /// Parameter `k` (not differentiated).
    Param(u32),
    /// `a + b`
    Add(u32, u32),
    /// `a − b` (only in [`Program`]s: an `Add` of a negation)
    Sub(u32, u32),
    /// `a · b`
    Mul(u32, u32),
    /// `−a`
    Neg(u32),
    /// `1/a`
    Recip(u32),
    /// `√a`
    Sqrt(u32),
    /// `ln a`
    Ln(u32),
    /// `exp a`
    Exp(u32),
    /// `sin a`
    Sin(u32),
    /// `cos a`
    Cos(u32),
    /// `acos a`
    Acos(u32),
    /// `atan2(y, x)`
    Atan2(u32, u32),
    /// `aᵏ`
    Powi(u32, i32),
    /// `if a > b { t } else { e }`
    SelectGt(u32, u32, u32, u32),
}

impl TracedOp {
    /// Operands, all earlier in the list.
    pub fn operands(&self) -> impl Iterator<Item = u32> {
        let (a, b, c, d) = match *self {
            TracedOp::Const(_) | TracedOp::Input(_) | TracedOp::Param(_) => (None, None, None, None),
            TracedOp::Add(a, b) | TracedOp::Sub(a, b) | TracedOp::Mul(a, b) | TracedOp::Atan2(a, b) => {
                (Some(a), Some(b), None, None)
            }
            TracedOp::Neg(a)
            | TracedOp::Recip(a)
            | TracedOp::Sqrt(a)
            | TracedOp::Ln(a)
            | TracedOp::Exp(a)
            | TracedOp::Sin(a)
            | TracedOp::Cos(a)
            | TracedOp::Acos(a)
            | TracedOp::Powi(a, _) => (Some(a), None, None, None),
            TracedOp::SelectGt(a, b, t, e) => (Some(a), Some(b), Some(t), Some(e)),
        };
        [a, b, c, d].into_iter().flatten()
    }
}

/// Operations `roots` depend on, compacted in graph order, and the new index of each root.
/// With `fuse_sub`, `a + (−b)` becomes `a − b` (the negation is then often dead).
fn compact(g: &Graph, roots: &[Id], fuse_sub: bool) -> (Vec<TracedOp>, Vec<u32>) {
    let limit = roots.iter().map(|o| o.0 as usize + 1).max().unwrap_or(0);
    let mut live = vec![false; limit];
    let mut stack: Vec<Id> = roots.to_vec();
    let fused = |id: Id| -> Option<(Id, Id)> {
        if let Op::Add(x, y) = g.ops[id.0 as usize] {
            if let Op::Neg(z) = g.ops[y.0 as usize] {
                return Some((x, z));
            }
        }
        None
    };
    while let Some(id) = stack.pop() {
        if live[id.0 as usize] {
            continue;
        }
        live[id.0 as usize] = true;
        match fused(id).filter(|_| fuse_sub) {
            Some((x, z)) => stack.extend([x, z]),
            None => stack.extend(g.children(id).into_iter().flatten()),
        }
    }
    let mut new = vec![u32::MAX; limit];
    let mut ops = Vec::new();
    for idx in 0..limit {
        if !live[idx] {
            continue;
        }
        let m = |c: Id| new[c.0 as usize];
        let op = match g.ops[idx] {
            _ if fuse_sub && fused(Id(idx as u32)).is_some() => {
                let (x, z) = fused(Id(idx as u32)).expect("checked");
                TracedOp::Sub(m(x), m(z))
            }
            Op::Const(b) => TracedOp::Const(f64::from_bits(b)),
            Op::Input(i) => TracedOp::Input(i),
            Op::Param(k) => TracedOp::Param(k),
            Op::Add(a, b) => TracedOp::Add(m(a), m(b)),
            Op::Mul(a, b) => TracedOp::Mul(m(a), m(b)),
            Op::Neg(a) => TracedOp::Neg(m(a)),
            Op::Recip(a) => TracedOp::Recip(m(a)),
            Op::Sqrt(a) => TracedOp::Sqrt(m(a)),
            Op::Ln(a) => TracedOp::Ln(m(a)),
            Op::Exp(a) => TracedOp::Exp(m(a)),
            Op::Sin(a) => TracedOp::Sin(m(a)),
            Op::Cos(a) => TracedOp::Cos(m(a)),
            Op::Acos(a) => TracedOp::Acos(m(a)),
            Op::Atan2(a, b) => TracedOp::Atan2(m(a), m(b)),
            Op::Powi(a, k) => TracedOp::Powi(m(a), k),
            Op::SelectGt(a, b, t, e) => TracedOp::SelectGt(m(a), m(b), m(t), m(e)),
        };
        new[idx] = ops.len() as u32;
        ops.push(op);
    }
    let roots = roots.iter().map(|r| new[r.0 as usize]).collect();
    (ops, roots)
}

/// A traced energy: the compacted graph of its value (simplified and CSE'd while it was built).
#[derive(Clone, Debug, PartialEq)]
pub struct TracedEnergy {
    /// Number of differentiated inputs.
    pub n_inputs: usize,
    /// Number of parameters.
    pub n_params: usize,
    /// Operations in dependency order; the last one is the value.
    pub ops: Vec<TracedOp>,
}

/// A differentiated energy: one straight-line program computing value, gradient and the lower
/// triangle of the Hessian, ready to compile (or to interpret).
#[derive(Clone, Debug, PartialEq)]
pub struct Program {
    /// Number of differentiated inputs `n`.
    pub n_inputs: usize,
    /// Number of parameters.
    pub n_params: usize,
    /// Operations in dependency order (no `Add` of a `Neg`: those are `Sub`).
    pub ops: Vec<TracedOp>,
    /// The value, then the `n` gradient entries, then the Hessian's lower triangle row by row
    /// (`H[i][j]`, `j ≤ i`): indices into `ops`.
    pub outputs: Vec<u32>,
}

/// Trace `energy` with `n_inputs` symbolic inputs and `n_params` symbolic parameters into a
/// [`TracedEnergy`]. The closure may fail (a Python energy raising); the error is passed on.
///
/// Uses (and clears) this thread's graph.
pub fn trace<E>(
    n_inputs: usize,
    n_params: usize,
    energy: impl FnOnce(&[Sym], &[Sym]) -> Result<Sym, E>,
) -> Result<TracedEnergy, E> {
    reset();
    let x: Vec<Sym> = (0..n_inputs).map(Sym::input).collect();
    let p: Vec<Sym> = (0..n_params).map(Sym::param).collect();
    let value = energy(&x, &p);
    let out = value.map(|v| {
        with_graph(|g| {
            let (ops, _) = compact(g, &[v.0], false);
            TracedEnergy {
                n_inputs,
                n_params,
                ops,
            }
        })
    });
    reset();
    out
}

impl TracedEnergy {
    /// The graph as a [`Graph`], and the id of the value.
    fn to_graph(&self) -> (Graph, Id) {
        let mut g = Graph::default();
        let mut map: Vec<Id> = Vec::with_capacity(self.ops.len());
        for op in &self.ops {
            let m = |k: u32| map[k as usize];
            let id = match *op {
                TracedOp::Const(v) => g.intern(Op::Const(v.to_bits())),
                TracedOp::Input(i) => g.intern(Op::Input(i)),
                TracedOp::Param(k) => g.intern(Op::Param(k)),
                TracedOp::Add(a, b) => g.intern(Op::Add(m(a), m(b))),
                TracedOp::Sub(a, b) => {
                    let nb = g.neg(m(b));
                    g.add(m(a), nb)
                }
                TracedOp::Mul(a, b) => g.intern(Op::Mul(m(a), m(b))),
                TracedOp::Neg(a) => g.intern(Op::Neg(m(a))),
                TracedOp::Recip(a) => g.intern(Op::Recip(m(a))),
                TracedOp::Sqrt(a) => g.intern(Op::Sqrt(m(a))),
                TracedOp::Ln(a) => g.intern(Op::Ln(m(a))),
                TracedOp::Exp(a) => g.intern(Op::Exp(m(a))),
                TracedOp::Sin(a) => g.intern(Op::Sin(m(a))),
                TracedOp::Cos(a) => g.intern(Op::Cos(m(a))),
                TracedOp::Acos(a) => g.intern(Op::Acos(m(a))),
                TracedOp::Atan2(a, b) => g.intern(Op::Atan2(m(a), m(b))),
                TracedOp::Powi(a, k) => g.intern(Op::Powi(m(a), k)),
                TracedOp::SelectGt(a, b, t, e) => g.intern(Op::SelectGt(m(a), m(b), m(t), m(e))),
            };
            map.push(id);
        }
        let value = *map.last().unwrap_or(&Id(0));
        if self.ops.is_empty() {
            let z = g.c(0.0);
            return (g, z);
        }
        (g, value)
    }

    /// Differentiate: gradient by reverse mode, Hessian forward-over-reverse (as `stark-codegen`
    /// does for the built-in kernels), then dead-code elimination.
    pub fn differentiate(&self) -> Program {
        let n = self.n_inputs;
        let (mut g, value) = self.to_graph();
        let grad = g.gradient(value, n, &mut HashMap::new());
        let mut lower = vec![Id(0); n * (n + 1) / 2];
        for j in 0..n {
            let col = g.tangents(&grad[j..], j);
            for (k, id) in col.into_iter().enumerate() {
                let i = j + k;
                lower[i * (i + 1) / 2 + j] = id;
            }
        }
        let mut roots = vec![value];
        roots.extend_from_slice(&grad);
        roots.extend_from_slice(&lower);
        let (ops, outputs) = compact(&g, &roots, true);
        Program {
            n_inputs: n,
            n_params: self.n_params,
            ops,
            outputs,
        }
    }

    /// The value at inputs `x` and parameters `p`, in any scalar type (hyper-duals give the test
    /// oracle's derivatives of the traced graph).
    pub fn evaluate<S: Scalar>(&self, x: &[S], p: &[S]) -> S {
        let vals = interpret(&self.ops, x, p);
        vals.last().copied().unwrap_or_else(S::zero)
    }

    /// A stable 64-bit hash of the graph (FNV-1a of its serialized bytes): the cache key.
    pub fn hash(&self) -> u64 {
        let mut bytes = Vec::new();
        write_header(&mut bytes, self.n_inputs, self.n_params);
        write_ops(&mut bytes, &self.ops);
        fnv1a(&bytes)
    }
}

/// Evaluate `ops` in order for any scalar type.
pub fn interpret<S: Scalar>(ops: &[TracedOp], x: &[S], p: &[S]) -> Vec<S> {
    let mut v: Vec<S> = Vec::with_capacity(ops.len());
    for op in ops {
        let a = |k: u32| v[k as usize];
        let r = match *op {
            TracedOp::Const(c) => S::constant(c),
            TracedOp::Input(i) => x[i as usize],
            TracedOp::Param(k) => p[k as usize],
            TracedOp::Add(a0, b0) => a(a0) + a(b0),
            TracedOp::Sub(a0, b0) => a(a0) - a(b0),
            TracedOp::Mul(a0, b0) => a(a0) * a(b0),
            TracedOp::Neg(a0) => -a(a0),
            TracedOp::Recip(a0) => a(a0).recip(),
            TracedOp::Sqrt(a0) => a(a0).sqrt(),
            TracedOp::Ln(a0) => a(a0).ln(),
            TracedOp::Exp(a0) => a(a0).exp(),
            TracedOp::Sin(a0) => a(a0).sin(),
            TracedOp::Cos(a0) => a(a0).cos(),
            TracedOp::Acos(a0) => a(a0).acos(),
            TracedOp::Atan2(y, x0) => a(y).atan2(a(x0)),
            TracedOp::Powi(a0, k) => a(a0).powi(k),
            TracedOp::SelectGt(p0, q, t, e) => {
                let (t, e) = (a(t), a(e));
                S::select_gt(a(p0), a(q), || t, || e)
            }
        };
        v.push(r);
    }
    v
}

impl Program {
    /// Value, gradient and full row-major Hessian by interpreting the program (a reference for
    /// the compiled code).
    pub fn interpret(&self, x: &[f64], p: &[f64], grad: &mut [f64], hess: &mut [f64]) -> f64 {
        let v = interpret(&self.ops, x, p);
        let n = self.n_inputs;
        let o = |k: usize| v[self.outputs[k] as usize];
        for i in 0..n {
            grad[i] = o(1 + i);
            for j in 0..=i {
                let h = o(1 + n + i * (i + 1) / 2 + j);
                hess[i * n + j] = h;
                hess[j * n + i] = h;
            }
        }
        o(0)
    }

    /// Serialize (the on-disk cache format, with the traced energy it came from).
    pub fn to_bytes(&self, traced: &TracedEnergy) -> Vec<u8> {
        let mut b = Vec::new();
        b.extend_from_slice(MAGIC);
        write_header(&mut b, traced.n_inputs, traced.n_params);
        write_ops(&mut b, &traced.ops);
        write_ops(&mut b, &self.ops);
        b.extend_from_slice(&(self.outputs.len() as u32).to_le_bytes());
        for o in &self.outputs {
            b.extend_from_slice(&o.to_le_bytes());
        }
        b
    }

    /// Parse [`Program::to_bytes`]; `None` unless the bytes are well formed and were made from
    /// exactly `traced` (so a hash collision or a stale file is never used).
    pub fn from_bytes(bytes: &[u8], traced: &TracedEnergy) -> Option<Program> {
        let mut r = Reader { b: bytes, at: 0 };
        if r.take(MAGIC.len())? != MAGIC {
            return None;
        }
        let (n_inputs, n_params) = (r.u32()? as usize, r.u32()? as usize);
        let energy_ops = r.ops(n_inputs, n_params)?;
        if n_inputs != traced.n_inputs || n_params != traced.n_params || energy_ops != traced.ops {
            return None;
        }
        let ops = r.ops(n_inputs, n_params)?;
        let n_out = r.u32()? as usize;
        if n_out != 1 + n_inputs + n_inputs * (n_inputs + 1) / 2 {
            return None;
        }
        let mut outputs = Vec::with_capacity(n_out);
        for _ in 0..n_out {
            let o = r.u32()?;
            if o as usize >= ops.len() {
                return None;
            }
            outputs.push(o);
        }
        (r.at == bytes.len()).then_some(Program {
            n_inputs,
            n_params,
            ops,
            outputs,
        })
    }
}

/// File magic and format version of serialized programs.
const MAGIC: &[u8] = b"STARKJIT1\n";

fn fnv1a(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in bytes {
        h ^= b as u64;
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    h
}

fn write_header(b: &mut Vec<u8>, n_inputs: usize, n_params: usize) {
    b.extend_from_slice(&(n_inputs as u32).to_le_bytes());
    b.extend_from_slice(&(n_params as u32).to_le_bytes());
}

fn write_ops(b: &mut Vec<u8>, ops: &[TracedOp]) {
    b.extend_from_slice(&(ops.len() as u32).to_le_bytes());
    for op in ops {
        let (tag, args): (u8, [u64; 4]) = match *op {
            TracedOp::Const(v) => (0, [v.to_bits(), 0, 0, 0]),
            TracedOp::Input(i) => (1, [i as u64, 0, 0, 0]),
            TracedOp::Param(k) => (2, [k as u64, 0, 0, 0]),
            TracedOp::Add(a, c) => (3, [a as u64, c as u64, 0, 0]),
            TracedOp::Sub(a, c) => (4, [a as u64, c as u64, 0, 0]),
            TracedOp::Mul(a, c) => (5, [a as u64, c as u64, 0, 0]),
            TracedOp::Neg(a) => (6, [a as u64, 0, 0, 0]),
            TracedOp::Recip(a) => (7, [a as u64, 0, 0, 0]),
            TracedOp::Sqrt(a) => (8, [a as u64, 0, 0, 0]),
            TracedOp::Ln(a) => (9, [a as u64, 0, 0, 0]),
            TracedOp::Exp(a) => (10, [a as u64, 0, 0, 0]),
            TracedOp::Sin(a) => (11, [a as u64, 0, 0, 0]),
            TracedOp::Cos(a) => (12, [a as u64, 0, 0, 0]),
            TracedOp::Acos(a) => (13, [a as u64, 0, 0, 0]),
            TracedOp::Atan2(a, c) => (14, [a as u64, c as u64, 0, 0]),
            TracedOp::Powi(a, k) => (15, [a as u64, k as u32 as u64, 0, 0]),
            TracedOp::SelectGt(a, c, t, e) => (16, [a as u64, c as u64, t as u64, e as u64]),
        };
        b.push(tag);
        for a in args {
            b.extend_from_slice(&a.to_le_bytes());
        }
    }
}

struct Reader<'a> {
    b: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take(&mut self, n: usize) -> Option<&[u8]> {
        let s = self.b.get(self.at..self.at.checked_add(n)?)?;
        self.at += n;
        Some(s)
    }
    fn u32(&mut self) -> Option<u32> {
        Some(u32::from_le_bytes(self.take(4)?.try_into().ok()?))
    }
    fn u64(&mut self) -> Option<u64> {
        Some(u64::from_le_bytes(self.take(8)?.try_into().ok()?))
    }
    /// Operations whose operands point backwards and whose inputs and parameters are in range.
    fn ops(&mut self, n_inputs: usize, n_params: usize) -> Option<Vec<TracedOp>> {
        let n = self.u32()? as usize;
        let mut ops = Vec::with_capacity(n.min(1 << 20));
        for k in 0..n {
            let tag = *self.take(1)?.first()?;
            let a: [u64; 4] = [self.u64()?, self.u64()?, self.u64()?, self.u64()?];
            let id = |v: u64| -> Option<u32> { ((v as usize) < k).then_some(v as u32) };
            let op = match tag {
                0 => TracedOp::Const(f64::from_bits(a[0])),
                1 => TracedOp::Input(((a[0] as usize) < n_inputs).then_some(a[0] as u32)?),
                2 => TracedOp::Param(((a[0] as usize) < n_params).then_some(a[0] as u32)?),
                3 => TracedOp::Add(id(a[0])?, id(a[1])?),
                4 => TracedOp::Sub(id(a[0])?, id(a[1])?),
                5 => TracedOp::Mul(id(a[0])?, id(a[1])?),
                6 => TracedOp::Neg(id(a[0])?),
                7 => TracedOp::Recip(id(a[0])?),
                8 => TracedOp::Sqrt(id(a[0])?),
                9 => TracedOp::Ln(id(a[0])?),
                10 => TracedOp::Exp(id(a[0])?),
                11 => TracedOp::Sin(id(a[0])?),
                12 => TracedOp::Cos(id(a[0])?),
                13 => TracedOp::Acos(id(a[0])?),
                14 => TracedOp::Atan2(id(a[0])?, id(a[1])?),
                15 => TracedOp::Powi(id(a[0])?, a[1] as u32 as i32),
                16 => TracedOp::SelectGt(id(a[0])?, id(a[1])?, id(a[2])?, id(a[3])?),
                _ => return None,
            };
            ops.push(op);
        }
        Some(ops)
    }
}

/// Evaluate a traced graph numerically (used by tests to check the differentiation rules without
/// compiling the emitted code).
#[cfg(test)]
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::energy::dual::HyperDual;

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
}

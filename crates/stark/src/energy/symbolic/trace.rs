//! Run-time tracing (the JIT path, `energy::jit`): a traced energy as data rather than source
//! ([`TracedEnergy`], [`Program`]), its compaction, interpreter and byte encoding.

use super::{reset, with_graph, Graph, Id, Op, Scalar, Sym};
use std::collections::HashMap;

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

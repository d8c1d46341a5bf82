//! Run-time generated derivatives: a traced energy compiled to native code with Cranelift
//! (DESIGN §2, path 2, at run time; our counterpart of SymX's JIT, with no C/C++ compiler and no
//! cargo needed).
//!
//! 1. The energy is traced once with the symbolic scalar ([`symbolic::trace`]): the graph is
//!    simplified and CSE'd while it is built.
//! 2. The gradient and the Hessian are derived symbolically, exactly as `stark-codegen` does for
//!    the built-in kernels ([`TracedEnergy::differentiate`]).
//! 3. The straight-line program is lowered to Cranelift IR and compiled for the host
//!    ([`JitKernel`]): one function `(x, p, grad, hess) -> value` with the full row-major Hessian,
//!    and one value-only function for line searches.
//!
//! Kernels are cached by the hash of the traced graph: in memory for the process (compiled code
//! is never freed, so kernels are `'static`), and on disk as the differentiated program (the
//! machine code of `cranelift-jit` is not relocatable, so it is recompiled, which is the
//! cheaper half). The disk cache lives in `$STARK_JIT_CACHE` if set (`off` disables it), else
//! `$XDG_CACHE_HOME/stark-rs/jit`, else `$HOME/.cache/stark-rs/jit`; files are
//! `<hash>.prog`, checked against the traced graph before use.

use super::symbolic::{self, Program, Sym, TracedEnergy, TracedOp};
use crate::error::{Result, StarkError};
use cranelift_codegen::ir::condcodes::FloatCC;
use cranelift_codegen::ir::{types, AbiParam, FuncRef, InstBuilder, MemFlags, Value};
use cranelift_codegen::settings::{self, Configurable};
use cranelift_frontend::{FunctionBuilder, FunctionBuilderContext};
use cranelift_jit::{JITBuilder, JITModule};
use cranelift_module::{default_libcall_names, Linkage, Module};
use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::{Arc, Mutex, OnceLock};
use std::time::Instant;

/// Value, gradient and full row-major Hessian: `(x, p, grad, hess) -> value`.
type FullFn = unsafe extern "C" fn(*const f64, *const f64, *mut f64, *mut f64) -> f64;
/// Value only: `(x, p) -> value`.
type ValueFn = unsafe extern "C" fn(*const f64, *const f64) -> f64;

/// Where a kernel came from and what it cost, ms.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct JitTimings {
    /// Symbolic differentiation (0 when the program came from the disk cache).
    pub differentiate_ms: f64,
    /// Cranelift compilation of both functions.
    pub compile_ms: f64,
    /// Whether the differentiated program was read from the disk cache.
    pub from_disk: bool,
    /// Operations of the differentiated program.
    pub program_ops: usize,
}

/// A compiled energy: value, gradient and Hessian at native speed.
pub struct JitKernel {
    n_inputs: usize,
    n_params: usize,
    hash: u64,
    full: FullFn,
    value: ValueFn,
    /// Cost of making this kernel.
    pub timings: JitTimings,
}

impl std::fmt::Debug for JitKernel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("JitKernel")
            .field("n_inputs", &self.n_inputs)
            .field("n_params", &self.n_params)
            .field("hash", &format_args!("{:016x}", self.hash))
            .field("timings", &self.timings)
            .finish()
    }
}

impl JitKernel {
    /// Number of differentiated inputs.
    pub fn n_inputs(&self) -> usize {
        self.n_inputs
    }
    /// Number of parameters.
    pub fn n_params(&self) -> usize {
        self.n_params
    }
    /// The cache key (hash of the traced graph).
    pub fn hash(&self) -> u64 {
        self.hash
    }

    /// Value, gradient (length `n`) and full row-major Hessian (`n × n`) at `x` (length `n`)
    /// with parameters `p`.
    ///
    /// # Panics
    /// When a slice has the wrong length (a programming error, like indexing out of bounds).
    #[inline]
    pub fn evaluate(&self, x: &[f64], p: &[f64], grad: &mut [f64], hess: &mut [f64]) -> f64 {
        let n = self.n_inputs;
        assert!(
            x.len() == n && p.len() == self.n_params && grad.len() == n && hess.len() == n * n,
            "JIT kernel called with wrong lengths"
        );
        // SAFETY: the compiled code reads exactly `n` inputs and `n_params` parameters and writes
        // `n` gradient and `n²` Hessian entries (lengths checked above); it is never freed.
        unsafe { (self.full)(x.as_ptr(), p.as_ptr(), grad.as_mut_ptr(), hess.as_mut_ptr()) }
    }

    /// Value, gradient and Hessian with respect to the stencil positions `x` (the kernel's
    /// inputs, 3 per node) with parameters `p`, written into `out`: what a hand-written
    /// [`Potential`](super::Potential) returns from `derivatives` to use this kernel instead of
    /// hyper-duals.
    ///
    /// # Panics
    /// When the kernel was not traced for `3·N` inputs and `p.len()` parameters.
    #[inline]
    pub fn derivatives<const N: usize>(
        &self,
        x: &[nalgebra::Vector3<f64>; N],
        p: &[f64],
        out: &mut super::HyperDual<N>,
    ) -> super::FastDerivatives {
        let mut flat = [0.0; 3 * super::user_energy::MAX_NODES];
        super::tensor::flat_from_points(x, &mut flat);
        out.value = self.evaluate(
            &flat[..3 * N],
            p,
            out.grad.as_flattened_mut(),
            out.hess.as_flattened_mut().as_flattened_mut().as_flattened_mut(),
        );
        super::FastDerivatives::Exact
    }

    /// The value alone (line searches).
    ///
    /// # Panics
    /// When a slice has the wrong length.
    #[inline]
    pub fn value(&self, x: &[f64], p: &[f64]) -> f64 {
        assert!(
            x.len() == self.n_inputs && p.len() == self.n_params,
            "JIT kernel called with wrong lengths"
        );
        // SAFETY: as in `evaluate`, reads only.
        unsafe { (self.value)(x.as_ptr(), p.as_ptr()) }
    }
}

/// Trace `energy` with the symbolic scalar and compile it (or take it from the cache).
pub fn compile_fn(
    n_inputs: usize,
    n_params: usize,
    energy: impl FnOnce(&[Sym], &[Sym]) -> Sym,
) -> Result<Arc<JitKernel>> {
    let traced = symbolic::trace(n_inputs, n_params, |x, p| Ok::<_, StarkError>(energy(x, p)))?;
    compile(&traced)
}

/// Compiled kernels by hash; each hash keeps its graphs, so a collision is never served.
type MemoryCache = Mutex<HashMap<u64, Vec<(TracedEnergy, Arc<JitKernel>)>>>;

fn memory_cache() -> &'static MemoryCache {
    static CACHE: OnceLock<MemoryCache> = OnceLock::new();
    CACHE.get_or_init(Default::default)
}

/// The disk cache directory (see the module docs), `None` when disabled or unknown.
pub fn cache_dir() -> Option<PathBuf> {
    match std::env::var_os("STARK_JIT_CACHE") {
        Some(v) if v == "off" || v.is_empty() => None,
        Some(v) => Some(PathBuf::from(v)),
        None => std::env::var_os("XDG_CACHE_HOME")
            .map(PathBuf::from)
            .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))
            .map(|c| c.join("stark-rs").join("jit")),
    }
}

/// Compile a traced energy, using the memory cache, then the disk cache.
pub fn compile(traced: &TracedEnergy) -> Result<Arc<JitKernel>> {
    let hash = traced.hash();
    {
        let cache = memory_cache().lock().unwrap_or_else(|e| e.into_inner());
        if let Some((_, k)) = cache.get(&hash).and_then(|v| v.iter().find(|(t, _)| t == traced)) {
            return Ok(k.clone());
        }
    }
    let kernel = Arc::new(compile_uncached(traced, cache_dir())?);
    let mut cache = memory_cache().lock().unwrap_or_else(|e| e.into_inner());
    let same = cache.entry(hash).or_default();
    // Another thread may have compiled the same energy meanwhile: one kernel per energy.
    if let Some((_, k)) = same.iter().find(|(t, _)| t == traced) {
        return Ok(k.clone());
    }
    same.push((traced.clone(), kernel.clone()));
    Ok(kernel)
}

/// Compile without the memory cache; `disk` is the disk cache directory to use, if any
/// (benchmarks measure the three cases with it).
pub fn compile_uncached(traced: &TracedEnergy, disk: Option<PathBuf>) -> Result<JitKernel> {
    if traced.ops.is_empty() {
        return Err(StarkError::InvalidInput("the traced energy is empty".into()));
    }
    let hash = traced.hash();
    let file = disk.as_ref().map(|d| d.join(format!("{hash:016x}.prog")));
    let start = Instant::now();
    let cached = file
        .as_ref()
        .and_then(|f| std::fs::read(f).ok())
        .and_then(|b| Program::from_bytes(&b, traced));
    let from_disk = cached.is_some();
    let program = match cached {
        Some(p) => p,
        None => {
            let p = traced.differentiate();
            if let (Some(dir), Some(f)) = (&disk, &file) {
                // A cache that cannot be written only costs time next run: ignore errors, and
                // write through a temporary file so readers never see a partial program.
                if std::fs::create_dir_all(dir).is_ok() {
                    let tmp = f.with_extension(format!("tmp{}", std::process::id()));
                    if std::fs::write(&tmp, p.to_bytes(traced)).is_ok() {
                        let _ = std::fs::rename(&tmp, f);
                    }
                }
            }
            p
        }
    };
    let differentiate_ms = if from_disk { 0.0 } else { ms(start) };
    let start = Instant::now();
    let (full, value) = lower(&program, traced)?;
    Ok(JitKernel {
        n_inputs: traced.n_inputs,
        n_params: traced.n_params,
        hash,
        full,
        value,
        timings: JitTimings {
            differentiate_ms,
            compile_ms: ms(start),
            from_disk,
            program_ops: program.ops.len(),
        },
    })
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

fn jit_err(what: &str, e: impl std::fmt::Display) -> StarkError {
    StarkError::InvalidInput(format!("JIT compilation failed ({what}): {e}"))
}

// Elementary functions Cranelift has no instruction for, called from the compiled code.
extern "C" fn jit_ln(x: f64) -> f64 {
    x.ln()
}
extern "C" fn jit_exp(x: f64) -> f64 {
    x.exp()
}
extern "C" fn jit_sin(x: f64) -> f64 {
    x.sin()
}
extern "C" fn jit_cos(x: f64) -> f64 {
    x.cos()
}
extern "C" fn jit_acos(x: f64) -> f64 {
    x.acos()
}
extern "C" fn jit_atan2(y: f64, x: f64) -> f64 {
    y.atan2(x)
}
extern "C" fn jit_powi(x: f64, k: i32) -> f64 {
    x.powi(k)
}

/// Compile the full and the value-only function of one energy into one module.
fn lower(program: &Program, traced: &TracedEnergy) -> Result<(FullFn, ValueFn)> {
    let mut flags = settings::builder();
    for (k, v) in [
        ("use_colocated_libcalls", "false"),
        ("is_pic", "false"),
        ("opt_level", "speed"),
    ] {
        flags.set(k, v).map_err(|e| jit_err("settings", e))?;
    }
    let isa = cranelift_native::builder()
        .map_err(|e| jit_err("host", e))?
        .finish(settings::Flags::new(flags))
        .map_err(|e| jit_err("host", e))?;
    let mut jb = JITBuilder::with_isa(isa, default_libcall_names());
    jb.symbol("stark_jit_ln", jit_ln as *const u8);
    jb.symbol("stark_jit_exp", jit_exp as *const u8);
    jb.symbol("stark_jit_sin", jit_sin as *const u8);
    jb.symbol("stark_jit_cos", jit_cos as *const u8);
    jb.symbol("stark_jit_acos", jit_acos as *const u8);
    jb.symbol("stark_jit_atan2", jit_atan2 as *const u8);
    jb.symbol("stark_jit_powi", jit_powi as *const u8);
    let mut module = JITModule::new(jb);
    let ptr = module.target_config().pointer_type();
    let mut fctx = FunctionBuilderContext::new();

    let mut full_sig = module.make_signature();
    full_sig.params.extend([AbiParam::new(ptr); 4]);
    full_sig.returns.push(AbiParam::new(types::F64));
    let full_id = module
        .declare_function("full", Linkage::Local, &full_sig)
        .map_err(|e| jit_err("declare", e))?;
    let mut ctx = module.make_context();
    ctx.func.signature = full_sig;
    {
        let mut b = FunctionBuilder::new(&mut ctx.func, &mut fctx);
        let imports = Imports::declare(&mut module, &mut b)?;
        let block = b.create_block();
        b.append_block_params_for_function_params(block);
        b.switch_to_block(block);
        b.seal_block(block);
        let args = b.block_params(block).to_vec();
        let vals = emit_ops(&mut b, &imports, &program.ops, args[0], args[1]);
        let n = program.n_inputs;
        let out = |k: usize| vals[program.outputs[k] as usize];
        let flags = MemFlags::trusted();
        for i in 0..n {
            b.ins().store(flags, out(1 + i), args[2], (8 * i) as i32);
            for j in 0..=i {
                let h = out(1 + n + i * (i + 1) / 2 + j);
                b.ins().store(flags, h, args[3], (8 * (i * n + j)) as i32);
                if j != i {
                    b.ins().store(flags, h, args[3], (8 * (j * n + i)) as i32);
                }
            }
        }
        b.ins().return_(&[out(0)]);
        b.finalize();
    }
    module
        .define_function(full_id, &mut ctx)
        .map_err(|e| jit_err("full kernel", e))?;
    module.clear_context(&mut ctx);

    let mut value_sig = module.make_signature();
    value_sig.params.extend([AbiParam::new(ptr); 2]);
    value_sig.returns.push(AbiParam::new(types::F64));
    let value_id = module
        .declare_function("value", Linkage::Local, &value_sig)
        .map_err(|e| jit_err("declare", e))?;
    ctx.func.signature = value_sig;
    {
        let mut b = FunctionBuilder::new(&mut ctx.func, &mut fctx);
        let imports = Imports::declare(&mut module, &mut b)?;
        let block = b.create_block();
        b.append_block_params_for_function_params(block);
        b.switch_to_block(block);
        b.seal_block(block);
        let args = b.block_params(block).to_vec();
        let vals = emit_ops(&mut b, &imports, &traced.ops, args[0], args[1]);
        let v = *vals.last().expect("non-empty, checked by the caller");
        b.ins().return_(&[v]);
        b.finalize();
    }
    module
        .define_function(value_id, &mut ctx)
        .map_err(|e| jit_err("value kernel", e))?;
    module.clear_context(&mut ctx);
    module.finalize_definitions().map_err(|e| jit_err("finalize", e))?;
    let full = module.get_finalized_function(full_id);
    let value = module.get_finalized_function(value_id);
    // The module owns the executable memory; kernels live as long as the process (they are
    // cached by hash), so it is never freed.
    std::mem::forget(module);
    // SAFETY: both functions were defined with exactly these signatures (pointer arguments and
    // an f64 result, the platform's default calling convention, which `extern "C"` matches).
    unsafe {
        Ok((
            std::mem::transmute::<*const u8, FullFn>(full),
            std::mem::transmute::<*const u8, ValueFn>(value),
        ))
    }
}

/// Imported elementary functions of one function being built.
struct Imports {
    ln: FuncRef,
    exp: FuncRef,
    sin: FuncRef,
    cos: FuncRef,
    acos: FuncRef,
    atan2: FuncRef,
    powi: FuncRef,
}

impl Imports {
    fn declare(module: &mut JITModule, b: &mut FunctionBuilder) -> Result<Imports> {
        let mut unary = module.make_signature();
        unary.params.push(AbiParam::new(types::F64));
        unary.returns.push(AbiParam::new(types::F64));
        let mut binary = unary.clone();
        binary.params.push(AbiParam::new(types::F64));
        let mut powi = unary.clone();
        powi.params.push(AbiParam::new(types::I32));
        let mut import = |name: &str, sig: &cranelift_codegen::ir::Signature| -> Result<FuncRef> {
            let id = module
                .declare_function(name, Linkage::Import, sig)
                .map_err(|e| jit_err("import", e))?;
            Ok(module.declare_func_in_func(id, b.func))
        };
        Ok(Imports {
            ln: import("stark_jit_ln", &unary)?,
            exp: import("stark_jit_exp", &unary)?,
            sin: import("stark_jit_sin", &unary)?,
            cos: import("stark_jit_cos", &unary)?,
            acos: import("stark_jit_acos", &unary)?,
            atan2: import("stark_jit_atan2", &binary)?,
            powi: import("stark_jit_powi", &powi)?,
        })
    }
}

/// Lower the operations to IR; the IR value of every operation.
fn emit_ops(b: &mut FunctionBuilder, im: &Imports, ops: &[TracedOp], x: Value, p: Value) -> Vec<Value> {
    let flags = MemFlags::trusted().with_readonly();
    let mut v: Vec<Value> = Vec::with_capacity(ops.len());
    let call = |b: &mut FunctionBuilder, f: FuncRef, args: &[Value]| {
        let inst = b.ins().call(f, args);
        b.inst_results(inst)[0]
    };
    for op in ops {
        let a = |k: u32| v[k as usize];
        let r = match *op {
            TracedOp::Const(c) => b.ins().f64const(c),
            TracedOp::Input(i) => b.ins().load(types::F64, flags, x, (8 * i) as i32),
            TracedOp::Param(k) => b.ins().load(types::F64, flags, p, (8 * k) as i32),
            TracedOp::Add(l, r) => b.ins().fadd(a(l), a(r)),
            TracedOp::Sub(l, r) => b.ins().fsub(a(l), a(r)),
            TracedOp::Mul(l, r) => b.ins().fmul(a(l), a(r)),
            TracedOp::Neg(l) => b.ins().fneg(a(l)),
            TracedOp::Recip(l) => {
                let one = b.ins().f64const(1.0);
                b.ins().fdiv(one, a(l))
            }
            TracedOp::Sqrt(l) => b.ins().sqrt(a(l)),
            TracedOp::Ln(l) => call(b, im.ln, &[a(l)]),
            TracedOp::Exp(l) => call(b, im.exp, &[a(l)]),
            TracedOp::Sin(l) => call(b, im.sin, &[a(l)]),
            TracedOp::Cos(l) => call(b, im.cos, &[a(l)]),
            TracedOp::Acos(l) => call(b, im.acos, &[a(l)]),
            TracedOp::Atan2(y, x0) => call(b, im.atan2, &[a(y), a(x0)]),
            TracedOp::Powi(l, k) if (1..=8).contains(&k.unsigned_abs()) => {
                // Small integer powers by repeated squaring, as rustc does for `powi` of a
                // constant exponent (same rounding as the generated kernels' `x * x * x`).
                let base = a(l);
                let m = k.unsigned_abs();
                let mut acc: Option<Value> = None;
                let mut sq = base;
                let mut e = m;
                let mut first = true;
                while e > 0 {
                    if !first {
                        sq = b.ins().fmul(sq, sq);
                    }
                    first = false;
                    if e & 1 == 1 {
                        acc = Some(match acc {
                            None => sq,
                            Some(q) => b.ins().fmul(q, sq),
                        });
                    }
                    e >>= 1;
                }
                let pos = acc.expect("k ≠ 0");
                if k < 0 {
                    let one = b.ins().f64const(1.0);
                    b.ins().fdiv(one, pos)
                } else {
                    pos
                }
            }
            TracedOp::Powi(l, k) => {
                let kv = b.ins().iconst(types::I32, k as i64);
                call(b, im.powi, &[a(l), kv])
            }
            TracedOp::SelectGt(l, r, t, e) => {
                let c = b.ins().fcmp(FloatCC::GreaterThan, a(l), a(r));
                b.ins().select(c, a(t), a(e))
            }
        };
        v.push(r);
    }
    v
}

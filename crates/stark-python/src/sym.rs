//! `starkrs.sym` primitives and `Simulation.add_energy`: a user energy written in Python.
//!
//! The Python function is called once, with symbolic values ([`Expr`], a node of the library's
//! expression graph); the graph is then differentiated and compiled by the library
//! (`stark::energy::jit`), so stepping never calls Python. Vectors, matrices, `min`/`max` and
//! parameter packing are written in Python on top of these scalars (`python/starkrs/sym.py`).
//!
//! A symbolic value belongs to the trace that made it: using one after `add_energy` returned (or
//! in another energy) raises `StarkError` instead of reading a node of some other graph.

use crate::convert::stark_err;
use crate::handles::{BodyArg, Issued, NodeSet};
use crate::simulation::Simulation;
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyTuple};
use stark::energy::symbolic::Sym;
use stark::energy::{Node, Scalar};
use std::cell::{Cell, RefCell};

thread_local! {
    /// The trace running on this thread, if any.
    static CURRENT: Cell<Option<u64>> = const { Cell::new(None) };
    static NEXT: Cell<u64> = const { Cell::new(1) };
}

/// A symbolic scalar of the energy being traced.
#[pyclass(module = "starkrs.sym", frozen, from_py_object)]
#[derive(Clone, Copy)]
pub struct Expr {
    sym: Sym,
    trace: u64,
}

/// A comparison `a > b` of symbolic scalars, for `select`.
#[pyclass(module = "starkrs.sym", frozen, from_py_object)]
#[derive(Clone, Copy)]
pub struct Condition {
    a: Sym,
    b: Sym,
    trace: u64,
}

fn active(trace: u64) -> PyResult<()> {
    if CURRENT.with(|c| c.get()) == Some(trace) {
        Ok(())
    } else {
        Err(stark_err(
            "a starkrs.sym value was used outside the energy function that made it (symbolic values exist only while add_energy calls the function)",
        ))
    }
}

fn current() -> PyResult<u64> {
    CURRENT
        .with(|c| c.get())
        .ok_or_else(|| stark_err("starkrs.sym values can only be made inside an energy function called by add_energy"))
}

/// An operand: a symbolic scalar of the current trace or a Python number.
fn operand(o: &Bound<'_, PyAny>) -> PyResult<Option<Sym>> {
    if let Ok(e) = o.cast::<Expr>() {
        let e = e.get();
        active(e.trace)?;
        return Ok(Some(e.sym));
    }
    if o.is_instance_of::<pyo3::types::PyBool>() {
        return Ok(None);
    }
    if let Ok(v) = o.extract::<f64>() {
        return Ok(Some(Sym::constant(v)));
    }
    Ok(None)
}

impl Expr {
    fn wrap(sym: Sym) -> PyResult<Expr> {
        Ok(Expr { sym, trace: current()? })
    }
    fn binary(&self, o: &Bound<'_, PyAny>, f: impl FnOnce(Sym, Sym) -> Sym) -> PyResult<Py<PyAny>> {
        active(self.trace)?;
        let py = o.py();
        match operand(o)? {
            Some(b) => Ok(Py::new(py, Expr::wrap(f(self.sym, b))?)?.into_any()),
            None => Ok(py.NotImplemented()),
        }
    }
}

/// `aᵉ`: integer exponents as `powi`, others as `exp(e ln a)`.
fn power(a: Sym, e: &Bound<'_, PyAny>) -> PyResult<Option<Sym>> {
    if let Ok(v) = e.extract::<f64>() {
        if e.cast::<Expr>().is_err() {
            if v.fract() == 0.0 && v.abs() <= 64.0 {
                return Ok(Some(a.powi(v as i32)));
            }
            if v == 0.5 {
                return Ok(Some(a.sqrt()));
            }
        }
    }
    Ok(operand(e)?.map(|b| (b * a.ln()).exp()))
}

#[pymethods]
impl Expr {
    fn __add__(&self, o: &Bound<'_, PyAny>) -> PyResult<Py<PyAny>> {
        self.binary(o, |a, b| a + b)
    }
    fn __radd__(&self, o: &Bound<'_, PyAny>) -> PyResult<Py<PyAny>> {
        self.binary(o, |a, b| b + a)
    }
    fn __sub__(&self, o: &Bound<'_, PyAny>) -> PyResult<Py<PyAny>> {
        self.binary(o, |a, b| a - b)
    }
    fn __rsub__(&self, o: &Bound<'_, PyAny>) -> PyResult<Py<PyAny>> {
        self.binary(o, |a, b| b - a)
    }
    fn __mul__(&self, o: &Bound<'_, PyAny>) -> PyResult<Py<PyAny>> {
        self.binary(o, |a, b| a * b)
    }
    fn __rmul__(&self, o: &Bound<'_, PyAny>) -> PyResult<Py<PyAny>> {
        self.binary(o, |a, b| b * a)
    }
    fn __truediv__(&self, o: &Bound<'_, PyAny>) -> PyResult<Py<PyAny>> {
        self.binary(o, |a, b| a / b)
    }
    fn __rtruediv__(&self, o: &Bound<'_, PyAny>) -> PyResult<Py<PyAny>> {
        self.binary(o, |a, b| b / a)
    }
    fn __pow__(&self, e: &Bound<'_, PyAny>, _modulo: Option<&Bound<'_, PyAny>>) -> PyResult<Py<PyAny>> {
        active(self.trace)?;
        let py = e.py();
        match power(self.sym, e)? {
            Some(s) => Ok(Py::new(py, Expr::wrap(s)?)?.into_any()),
            None => Ok(py.NotImplemented()),
        }
    }
    fn __rpow__(&self, b: &Bound<'_, PyAny>, _modulo: Option<&Bound<'_, PyAny>>) -> PyResult<Py<PyAny>> {
        self.binary(b, |e, base| (e * base.ln()).exp())
    }
    fn __neg__(&self) -> PyResult<Expr> {
        active(self.trace)?;
        Expr::wrap(-self.sym)
    }
    fn __pos__(&self) -> PyResult<Expr> {
        active(self.trace)?;
        Ok(*self)
    }
    fn __abs__(&self) -> PyResult<Expr> {
        active(self.trace)?;
        let s = self.sym;
        Expr::wrap(Sym::select_gt(s, Sym::zero(), || s, || -s))
    }
    fn __gt__(&self, o: &Bound<'_, PyAny>) -> PyResult<Condition> {
        self.compare(o, false)
    }
    fn __ge__(&self, o: &Bound<'_, PyAny>) -> PyResult<Condition> {
        self.compare(o, false)
    }
    fn __lt__(&self, o: &Bound<'_, PyAny>) -> PyResult<Condition> {
        self.compare(o, true)
    }
    fn __le__(&self, o: &Bound<'_, PyAny>) -> PyResult<Condition> {
        self.compare(o, true)
    }
    fn __bool__(&self) -> PyResult<bool> {
        Err(PyTypeError::new_err(
            "a symbolic value has no truth value while the energy is traced: use starkrs.sym.select(a > b, then, otherwise), min or max",
        ))
    }
    fn __float__(&self) -> PyResult<f64> {
        Err(PyTypeError::new_err(
            "a symbolic value has no number while the energy is traced (the function is called once with symbols)",
        ))
    }
    fn __repr__(&self) -> String {
        format!("sym.Expr({:?})", self.sym)
    }
}

impl Expr {
    fn compare(&self, o: &Bound<'_, PyAny>, flip: bool) -> PyResult<Condition> {
        active(self.trace)?;
        let b = operand(o)?.ok_or_else(|| PyTypeError::new_err("compare a symbolic value with a number or symbol"))?;
        let (a, b) = if flip { (b, self.sym) } else { (self.sym, b) };
        Ok(Condition {
            a,
            b,
            trace: self.trace,
        })
    }
}

#[pymethods]
impl Condition {
    fn __bool__(&self) -> PyResult<bool> {
        Err(PyTypeError::new_err(
            "a symbolic comparison has no truth value while the energy is traced: use starkrs.sym.select(condition, then, otherwise)",
        ))
    }
}

fn scalar_arg(o: &Bound<'_, PyAny>, what: &str) -> PyResult<Sym> {
    operand(o)?.ok_or_else(|| {
        PyTypeError::new_err(format!(
            "{what}: expected a number or a starkrs.sym scalar, got {}",
            o.get_type().name().map(|n| n.to_string()).unwrap_or_default()
        ))
    })
}

macro_rules! unary {
    ($name:ident, $f:expr, $num:expr) => {
        #[doc = concat!("`", stringify!($name), "` of a symbolic scalar (or of a number).")]
        #[pyfunction]
        fn $name(py: Python<'_>, a: &Bound<'_, PyAny>) -> PyResult<Py<PyAny>> {
            if a.cast::<Expr>().is_err() {
                if let Ok(v) = a.extract::<f64>() {
                    let f: fn(f64) -> f64 = $num;
                    return Ok(f(v).into_pyobject(py)?.into_any().unbind());
                }
            }
            let s = scalar_arg(a, stringify!($name))?;
            let f: fn(Sym) -> Sym = $f;
            Ok(Py::new(py, Expr::wrap(f(s))?)?.into_any())
        }
    };
}
unary!(sqrt, |s| s.sqrt(), f64::sqrt);
unary!(log, |s| s.ln(), f64::ln);
unary!(exp, |s| s.exp(), f64::exp);
unary!(sin, |s| s.sin(), f64::sin);
unary!(cos, |s| s.cos(), f64::cos);
unary!(acos, |s| s.acos(), f64::acos);

/// Four-quadrant arc tangent of `y/x`.
#[pyfunction]
fn atan2(y: &Bound<'_, PyAny>, x: &Bound<'_, PyAny>) -> PyResult<Expr> {
    let (y, x) = (scalar_arg(y, "atan2")?, scalar_arg(x, "atan2")?);
    Expr::wrap(y.atan2(x))
}

/// `a ** e` (integer `e` is exact repeated multiplication).
#[pyfunction]
fn pow(a: &Bound<'_, PyAny>, e: &Bound<'_, PyAny>) -> PyResult<Expr> {
    let base = scalar_arg(a, "pow")?;
    let s = power(base, e)?.ok_or_else(|| PyTypeError::new_err("pow: the exponent must be a number or symbol"))?;
    Expr::wrap(s)
}

/// `then` where the condition holds, else `otherwise` (both are traced; derivatives follow the
/// branch taken).
#[pyfunction]
fn select(cond: &Bound<'_, PyAny>, then: &Bound<'_, PyAny>, otherwise: &Bound<'_, PyAny>) -> PyResult<Expr> {
    let c = cond.cast::<Condition>().map_err(|_| {
        PyTypeError::new_err("select: the condition must be a comparison of symbolic values, e.g. select(a > b, a, b)")
    })?;
    let c = c.get();
    active(c.trace)?;
    let (t, e) = (scalar_arg(then, "select")?, scalar_arg(otherwise, "select")?);
    Expr::wrap(Sym::select_gt(c.a, c.b, || t, || e))
}

/// A constant as a symbolic scalar.
#[pyfunction]
fn constant(v: f64) -> PyResult<Expr> {
    Expr::wrap(Sym::constant(v))
}

/// The `starkrs._starkrs._sym` module (re-exported with vectors and matrices by `starkrs.sym`).
pub fn module(py: Python<'_>) -> PyResult<Bound<'_, PyModule>> {
    let m = PyModule::new(py, "_sym")?;
    m.add_class::<Expr>()?;
    m.add_class::<Condition>()?;
    m.add_function(wrap_pyfunction!(sqrt, &m)?)?;
    m.add_function(wrap_pyfunction!(log, &m)?)?;
    m.add_function(wrap_pyfunction!(exp, &m)?)?;
    m.add_function(wrap_pyfunction!(sin, &m)?)?;
    m.add_function(wrap_pyfunction!(cos, &m)?)?;
    m.add_function(wrap_pyfunction!(acos, &m)?)?;
    m.add_function(wrap_pyfunction!(atan2, &m)?)?;
    m.add_function(wrap_pyfunction!(pow, &m)?)?;
    m.add_function(wrap_pyfunction!(select, &m)?)?;
    m.add_function(wrap_pyfunction!(constant, &m)?)?;
    m.add_class::<EnergyHandle>()?;
    Ok(m)
}

/// A user energy added with `Simulation.add_energy`.
#[pyclass(module = "starkrs", frozen, from_py_object)]
#[derive(Clone, Debug)]
pub struct EnergyHandle {
    /// Its name.
    #[pyo3(get)]
    pub name: String,
    /// Parameter names as given (vector parameters once).
    #[pyo3(get)]
    pub params: Vec<String>,
    /// Nodes per element.
    #[pyo3(get)]
    pub nodes_per_element: usize,
    /// Number of elements.
    #[pyo3(get)]
    pub num_elements: usize,
    /// Trace, differentiation and compile time, ms, and whether the program came from the disk
    /// cache.
    #[pyo3(get)]
    pub compile_info: (f64, f64, f64, bool),
    handle: stark::UserEnergyHandle,
    sim: u64,
}

#[pymethods]
impl EnergyHandle {
    fn __repr__(&self) -> String {
        format!(
            "EnergyHandle('{}', {} elements of {} nodes)",
            self.name, self.num_elements, self.nodes_per_element
        )
    }
}

impl Issued for EnergyHandle {
    fn simulation_id(&self) -> u64 {
        self.sim
    }
}

/// Runs a trace: sets and clears this thread's current trace id.
struct TraceGuard;
impl TraceGuard {
    fn start() -> (TraceGuard, u64) {
        let id = NEXT.with(|n| {
            let id = n.get();
            n.set(id + 1);
            id
        });
        CURRENT.with(|c| c.set(Some(id)));
        (TraceGuard, id)
    }
}
impl Drop for TraceGuard {
    fn drop(&mut self) {
        CURRENT.with(|c| c.set(None));
    }
}

impl Simulation {
    /// One node reference of `element_nodes`: an int, a node set (all its nodes) or a
    /// `(body, local_point_m)` pair.
    fn energy_nodes(&self, name: &str, item: &Bound<'_, PyAny>, out: &mut Vec<Node>) -> PyResult<()> {
        if let Ok(i) = item.extract::<i64>() {
            if i < 0 {
                return Err(stark_err(format!("energy '{name}': node index {i} is negative")));
            }
            out.push(Node::Point(i as u32));
            return Ok(());
        }
        if let Ok(set) = item.cast::<NodeSet>() {
            let set = *set.get();
            self.own(&set)?;
            out.extend((set.first..set.first + set.len).map(Node::Point));
            return Ok(());
        }
        if let Ok(t) = item.cast::<PyTuple>() {
            if t.len() == 2 {
                let body: BodyArg = t.get_item(0)?.extract()?;
                let local: crate::convert::V3 = t.get_item(1)?.extract()?;
                let b = self.body(&body)?;
                out.push(Node::rigid(b.index as usize, &local.0));
                return Ok(());
            }
        }
        if let Ok(attr) = item.getattr("nodes") {
            if let Ok(set) = attr.cast::<NodeSet>() {
                return self.energy_nodes(name, set.as_any(), out);
            }
        }
        Err(PyTypeError::new_err(format!(
            "energy '{name}': element_nodes entries are node indices, node sets (or objects with nodes) or (body, local_point_m) pairs, got {}",
            item.repr().map(|r| r.to_string()).unwrap_or_default()
        )))
    }
}

#[pymethods]
impl Simulation {
    /// Add an energy written in Python (README "Your own energy").
    ///
    /// `element_nodes` lists the nodes the energy may use: node indices, node sets (or objects,
    /// for all their nodes) and `(body, local_point_m)` rigid-body points. `elements` is a
    /// sequence of equal-length index lists into `element_nodes` (1 to 4 nodes each), or
    /// `None` for one element per node. `fn(x, v, dt, p)` is called once with symbolic values
    /// (`x[a]`, `v[a]`: `starkrs.sym.Vec3` position and velocity of node `a`; `dt`; `p.name`:
    /// the parameters) and returns the element's energy in J. `params` maps names to a number,
    /// a 3-vector, or per-element arrays of shape `(n,)` or `(n, 3)`.
    #[pyo3(signature = (name, element_nodes, elements, r#fn, params=None))]
    fn add_energy(
        &self,
        py: Python<'_>,
        name: &str,
        element_nodes: &Bound<'_, PyAny>,
        elements: Option<&Bound<'_, PyAny>>,
        r#fn: &Bound<'_, PyAny>,
        params: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<EnergyHandle> {
        if CURRENT.with(|c| c.get()).is_some() {
            return Err(stark_err(format!(
                "energy '{name}': add_energy cannot be called inside another energy's function"
            )));
        }
        if !r#fn.is_callable() {
            return Err(PyTypeError::new_err(format!("energy '{name}': fn must be callable")));
        }
        let mut nodes = Vec::new();
        let single = element_nodes.cast::<NodeSet>().is_ok()
            || element_nodes.extract::<i64>().is_ok()
            || (element_nodes.getattr("nodes").is_ok() && element_nodes.cast::<PyList>().is_err());
        if single {
            self.energy_nodes(name, element_nodes, &mut nodes)?;
        } else {
            for item in element_nodes.try_iter()? {
                self.energy_nodes(name, &item?, &mut nodes)?;
            }
        }
        let elements: Vec<Vec<Node>> = match elements {
            None => nodes.iter().map(|n| vec![*n]).collect(),
            Some(els) => {
                let mut out = Vec::new();
                for (i, el) in els.try_iter()?.enumerate() {
                    let idx: Vec<i64> = el?.extract().map_err(|_| {
                        PyTypeError::new_err(format!(
                            "energy '{name}': element {i} is not a sequence of node indices"
                        ))
                    })?;
                    let mut row = Vec::with_capacity(idx.len());
                    for k in idx {
                        if k < 0 || k as usize >= nodes.len() {
                            return Err(stark_err(format!(
                                "energy '{name}': element {i} refers to node {k}, but element_nodes has {} entries",
                                nodes.len()
                            )));
                        }
                        row.push(nodes[k as usize]);
                    }
                    out.push(row);
                }
                out
            }
        };
        let k = elements.first().map_or(0, |e| e.len());
        if elements.is_empty() || k == 0 || k > stark::energy::user_energy::MAX_NODES {
            return Err(stark_err(format!(
                "energy '{name}': needs at least one element of 1 to {} nodes (got {} elements of {k})",
                stark::energy::user_energy::MAX_NODES,
                elements.len()
            )));
        }
        let symmod = py.import("starkrs.sym")?;
        let empty = PyDict::new(py);
        let params = params.unwrap_or(&empty);
        // (flat names, layout for the Python wrapper, flat values: shared or per element)
        let prepared = symmod.call_method1("_prepare_params", (name, params, elements.len()))?;
        let (flat_names, layout, values): (Vec<String>, Py<PyAny>, Vec<f64>) = prepared.extract()?;
        let user_names: Vec<String> = params.keys().extract()?;
        let pending: RefCell<Option<PyErr>> = RefCell::new(None);
        let start = std::time::Instant::now();
        let traced = {
            let (_guard, id) = TraceGuard::start();
            stark::energy::trace_element(k, flat_names.len(), |a| {
                let wrap = |s: Sym| Expr { sym: s, trace: id };
                let vecs = |v: &[stark::energy::Vec3<Sym>]| -> Vec<(Expr, Expr, Expr)> {
                    v.iter().map(|q| (wrap(q.0[0]), wrap(q.0[1]), wrap(q.0[2]))).collect()
                };
                let ps: Vec<Expr> = a.p.iter().map(|&s| wrap(s)).collect();
                let result = symmod
                    .call_method1("_call", (name, r#fn, vecs(&a.x), vecs(&a.v), wrap(a.dt), ps, &layout))
                    .and_then(|r| {
                        if let Ok(e) = r.cast::<Expr>() {
                            active(e.get().trace)?;
                            return Ok(e.get().sym);
                        }
                        if r.cast::<pyo3::types::PyBool>().is_err() {
                            if let Ok(v) = r.extract::<f64>() {
                                return Ok(Sym::constant(v));
                            }
                        }
                        Err(stark_err(format!(
                            "energy '{name}': the function must return a scalar (a starkrs.sym expression), got {}",
                            r.get_type().name().map(|n| n.to_string()).unwrap_or_default()
                        )))
                    });
                result.map_err(|e| {
                    let msg = e.to_string();
                    *pending.borrow_mut() = Some(e);
                    stark::StarkError::InvalidInput(msg)
                })
            })
        };
        let trace_ms = start.elapsed().as_secs_f64() * 1e3;
        let traced = match traced {
            Ok(t) => t,
            Err(e) => return Err(pending.into_inner().unwrap_or_else(|| crate::convert::to_py_err(e))),
        };
        let handle = self.with(|s| s.add_user_energy(name, &elements, flat_names, &values, traced))?;
        let timings = self.with(|s| Ok(s.user_energy(handle)?.kernel().timings))?;
        Ok(EnergyHandle {
            name: name.to_string(),
            params: user_names,
            nodes_per_element: k,
            num_elements: elements.len(),
            compile_info: (
                trace_ms,
                timings.differentiate_ms,
                timings.compile_ms,
                timings.from_disk,
            ),
            handle,
            sim: self.id(),
        })
    }

    /// Change parameters of an energy added with `add_energy`: `{name: value}` with the shapes
    /// `add_energy` takes. Takes effect from the next step.
    fn set_energy_params(&self, py: Python<'_>, energy: &EnergyHandle, params: &Bound<'_, PyDict>) -> PyResult<()> {
        self.own(energy)?;
        let symmod = py.import("starkrs.sym")?;
        let updates: Vec<(String, Vec<f64>)> = symmod
            .call_method1("_update_params", (&energy.name, params, energy.num_elements))?
            .extract()?;
        self.with(|s| {
            for (n, v) in &updates {
                s.set_user_energy_param(energy.handle, n, v)?;
            }
            Ok(())
        })
    }

    /// Values of an energy's parameters: `{flat name: array per element}` (a vector parameter
    /// `m` appears as `m[0]`, `m[1]`, `m[2]`).
    fn energy_params<'py>(&self, py: Python<'py>, energy: &EnergyHandle) -> PyResult<Bound<'py, PyDict>> {
        self.own(energy)?;
        let values = self.with(|s| {
            let t = s.user_energy(energy.handle)?;
            t.param_names()
                .iter()
                .map(|n| Ok((n.clone(), t.param(n)?)))
                .collect::<stark::Result<Vec<_>>>()
        })?;
        let d = PyDict::new(py);
        for (n, v) in values {
            d.set_item(n, crate::convert::floats_out(py, v))?;
        }
        Ok(d)
    }
}

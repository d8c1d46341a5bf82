//! Conversions between NumPy arrays and the library's types, and between the library's errors
//! and Python exceptions.
//!
//! Points go in as anything NumPy can turn into an `(n, 3)` float64 array and come out as new
//! `(n, 3)` float64 arrays; element index arrays go in as `(m, k)` integer arrays. Single vectors
//! are `(3,)` arrays, rotations are unit quaternions `(w, x, y, z)` or `(3, 3)` rotation matrices.

use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};
use numpy::ndarray::{Array1, Array2};
use numpy::{AllowTypeChange, IntoPyArray, PyArray1, PyArray2, PyArrayLike1, PyArrayLike2, PyArrayLikeDyn};
use pyo3::exceptions::{PyException, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyString;
use std::any::Any;
use std::panic::{catch_unwind, AssertUnwindSafe};

pyo3::create_exception!(
    starkrs,
    StarkError,
    PyException,
    "Every error of the simulator: the message names the object and the field at fault."
);
pyo3::create_exception!(
    starkrs,
    SceneError,
    StarkError,
    "A scene file is invalid: the message names the file, line, column, entry and field."
);
pyo3::create_exception!(
    starkrs,
    StepFailedError,
    StarkError,
    "A time step failed even at the smallest allowed step size."
);
pyo3::create_exception!(
    starkrs,
    InvalidHandleError,
    StarkError,
    "A handle does not belong to this simulation."
);

/// The Python exception for a library error, carrying its message.
pub fn to_py_err(e: stark::StarkError) -> PyErr {
    let msg = e.to_string();
    match e {
        stark::StarkError::Scene(_) | stark::StarkError::SceneFile(_) => SceneError::new_err(msg),
        stark::StarkError::StepFailed { .. } => StepFailedError::new_err(msg),
        stark::StarkError::InvalidHandle { .. } => InvalidHandleError::new_err(msg),
        _ => StarkError::new_err(msg),
    }
}

/// A [`StarkError`] with `msg`.
pub fn stark_err(msg: impl Into<String>) -> PyErr {
    StarkError::new_err(msg.into())
}

/// The message of a caught panic.
pub fn panic_message(payload: &(dyn Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "unknown panic".to_string()
    }
}

/// Run `f`, turning its error into a Python exception and a panic into a [`StarkError`] (a
/// panic must never unwind into the interpreter).
pub fn guarded<R>(f: impl FnOnce() -> stark::Result<R>) -> PyResult<R> {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(r) => r.map_err(to_py_err),
        Err(p) => Err(stark_err(format!("internal error: {}", panic_message(&*p)))),
    }
}

/// A 3-vector from anything NumPy reads as three numbers.
#[derive(Clone, Copy, Debug)]
pub struct V3(pub Vector3<f64>);

impl<'a, 'py> FromPyObject<'a, 'py> for V3 {
    type Error = PyErr;
    fn extract(obj: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        let arr: PyArrayLike1<'py, f64, AllowTypeChange> = obj.extract()?;
        let a = arr.as_array();
        if a.len() != 3 {
            return Err(PyValueError::new_err(format!(
                "expected a vector of 3 numbers, got {} numbers",
                a.len()
            )));
        }
        Ok(V3(Vector3::new(a[0], a[1], a[2])))
    }
}

/// A `[f64; 3]` setting field that reads any 3-vector and shows as a NumPy array.
#[derive(Clone, Copy, Debug)]
pub struct Arr3(pub [f64; 3]);

impl<'a, 'py> FromPyObject<'a, 'py> for Arr3 {
    type Error = PyErr;
    fn extract(obj: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        let v: V3 = obj.extract()?;
        Ok(Arr3(v.0.into()))
    }
}

impl<'py> IntoPyObject<'py> for Arr3 {
    type Target = PyArray1<f64>;
    type Output = Bound<'py, PyArray1<f64>>;
    type Error = PyErr;
    fn into_pyobject(self, py: Python<'py>) -> PyResult<Self::Output> {
        Ok(PyArray1::from_slice(py, &self.0))
    }
}

/// An `(n, 3)` array of points.
#[derive(Clone, Debug)]
pub struct Points(pub Vec<Vector3<f64>>);

impl<'a, 'py> FromPyObject<'a, 'py> for Points {
    type Error = PyErr;
    fn extract(obj: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        let arr: PyArrayLike2<'py, f64, AllowTypeChange> = obj.extract()?;
        let a = arr.as_array();
        if a.ncols() != 3 {
            return Err(PyValueError::new_err(format!(
                "expected an (n, 3) array of points, got shape {:?}",
                a.shape()
            )));
        }
        Ok(Points(
            a.rows().into_iter().map(|r| Vector3::new(r[0], r[1], r[2])).collect(),
        ))
    }
}

/// An `(m, K)` array of node indices (segments, triangles, tets).
#[derive(Clone, Debug)]
pub struct Elements<const K: usize>(pub Vec<[usize; K]>);

impl<'a, 'py, const K: usize> FromPyObject<'a, 'py> for Elements<K> {
    type Error = PyErr;
    fn extract(obj: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        let arr: PyArrayLike2<'py, i64, AllowTypeChange> = obj.extract()?;
        let a = arr.as_array();
        if a.ncols() != K {
            return Err(PyValueError::new_err(format!(
                "expected an (m, {K}) array of node indices, got shape {:?}",
                a.shape()
            )));
        }
        let mut out = Vec::with_capacity(a.nrows());
        for (e, row) in a.rows().into_iter().enumerate() {
            let mut el = [0usize; K];
            for (k, &i) in row.iter().enumerate() {
                if i < 0 {
                    return Err(stark_err(format!("element {e} has a negative node index {i}")));
                }
                el[k] = i as usize;
            }
            out.push(el);
        }
        Ok(Elements(out))
    }
}

/// A 1-D array of non-negative indices.
#[derive(Clone, Debug)]
pub struct Indices(pub Vec<usize>);

impl<'a, 'py> FromPyObject<'a, 'py> for Indices {
    type Error = PyErr;
    fn extract(obj: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        let arr: PyArrayLike1<'py, i64, AllowTypeChange> = obj.extract()?;
        arr.as_array()
            .iter()
            .map(|&i| {
                if i < 0 {
                    Err(stark_err(format!("negative node index {i}")))
                } else {
                    Ok(i as usize)
                }
            })
            .collect::<PyResult<Vec<_>>>()
            .map(Indices)
    }
}

/// A 1-D array of floats.
#[derive(Clone, Debug)]
pub struct Floats(pub Vec<f64>);

impl<'a, 'py> FromPyObject<'a, 'py> for Floats {
    type Error = PyErr;
    fn extract(obj: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        let arr: PyArrayLike1<'py, f64, AllowTypeChange> = obj.extract()?;
        Ok(Floats(arr.as_array().iter().copied().collect()))
    }
}

/// A 3×3 matrix.
#[derive(Clone, Copy, Debug)]
pub struct M3(pub Matrix3<f64>);

impl<'a, 'py> FromPyObject<'a, 'py> for M3 {
    type Error = PyErr;
    fn extract(obj: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        let arr: PyArrayLike2<'py, f64, AllowTypeChange> = obj.extract()?;
        let a = arr.as_array();
        if a.shape() != [3, 3] {
            return Err(PyValueError::new_err(format!(
                "expected a (3, 3) matrix, got shape {:?}",
                a.shape()
            )));
        }
        Ok(M3(Matrix3::from_fn(|i, j| a[[i, j]])))
    }
}

/// A rotation: a quaternion `(w, x, y, z)` (normalised here) or a `(3, 3)` rotation matrix.
#[derive(Clone, Copy, Debug)]
pub struct Rot(pub UnitQuaternion<f64>);

impl<'a, 'py> FromPyObject<'a, 'py> for Rot {
    type Error = PyErr;
    fn extract(obj: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        let arr: PyArrayLikeDyn<'py, f64, AllowTypeChange> = obj.extract()?;
        let a = arr.as_array();
        let bad = || {
            PyValueError::new_err(format!(
                "expected a rotation: a quaternion (w, x, y, z) or a (3, 3) rotation matrix, got shape {:?}",
                a.shape()
            ))
        };
        if !a.iter().all(|c| c.is_finite()) {
            return Err(stark_err("the rotation has non-finite entries"));
        }
        match a.shape() {
            [4] => {
                let q = nalgebra::Quaternion::new(a[[0]], a[[1]], a[[2]], a[[3]]);
                if q.norm() == 0.0 {
                    return Err(stark_err("the quaternion (0, 0, 0, 0) is not a rotation"));
                }
                Ok(Rot(UnitQuaternion::from_quaternion(q)))
            }
            [3, 3] => {
                let m = Matrix3::from_fn(|i, j| a[[i, j]]);
                if (m.transpose() * m - Matrix3::identity()).norm() > 1e-6 || m.determinant() < 0.0 {
                    return Err(stark_err(format!("the matrix is not a rotation: {m:?}")));
                }
                Ok(Rot(UnitQuaternion::from_rotation_matrix(
                    &Rotation3::from_matrix_unchecked(m),
                )))
            }
            _ => Err(bad()),
        }
    }
}

/// A new `(n, 3)` float64 array.
pub fn points_out<'py>(py: Python<'py>, p: &[Vector3<f64>]) -> Bound<'py, PyArray2<f64>> {
    let flat: Vec<f64> = p.iter().flat_map(|v| [v.x, v.y, v.z]).collect();
    Array2::from_shape_vec((p.len(), 3), flat)
        .expect("shape matches")
        .into_pyarray(py)
}

/// A new `(m, K)` int64 array.
pub fn elements_out<'py, const K: usize>(py: Python<'py>, e: &[[usize; K]]) -> Bound<'py, PyArray2<i64>> {
    let flat: Vec<i64> = e.iter().flat_map(|el| el.map(|i| i as i64)).collect();
    Array2::from_shape_vec((e.len(), K), flat)
        .expect("shape matches")
        .into_pyarray(py)
}

/// A new `(3,)` float64 array.
pub fn v3_out<'py>(py: Python<'py>, v: &Vector3<f64>) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_slice(py, v.as_slice())
}

/// A new `(n,)` float64 array.
pub fn floats_out<'py>(py: Python<'py>, v: Vec<f64>) -> Bound<'py, PyArray1<f64>> {
    Array1::from(v).into_pyarray(py)
}

/// A new `(3, 3)` float64 array.
pub fn m3_out<'py>(py: Python<'py>, m: &Matrix3<f64>) -> Bound<'py, PyArray2<f64>> {
    Array2::from_shape_fn((3, 3), |(i, j)| m[(i, j)]).into_pyarray(py)
}

/// A new `(4,)` array `(w, x, y, z)`.
pub fn quat_out<'py>(py: Python<'py>, q: &UnitQuaternion<f64>) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_slice(py, &[q.w, q.i, q.j, q.k])
}

/// A serialisable value as plain Python data (dicts, lists, floats), through JSON.
pub fn to_python<'py>(py: Python<'py>, value: &impl serde::Serialize) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(value).map_err(|e| stark_err(format!("cannot convert to Python: {e}")))?;
    py.import("json")?.call_method1("loads", (PyString::new(py, &text),))
}

/// A pose from optional arguments: the origin and no rotation by default.
pub(crate) fn pose(position_m: Option<V3>, orientation: Option<Rot>) -> (Vector3<f64>, UnitQuaternion<f64>) {
    (
        position_m.map(|p| p.0).unwrap_or_else(Vector3::zeros),
        orientation.map(|q| q.0).unwrap_or_else(UnitQuaternion::identity),
    )
}

//! Plain-data classes mirroring the library's settings, energy parameters and materials.
//!
//! Each class has every field of its Rust struct as a read/write attribute (same names, same
//! units, same defaults), a keyword constructor (`InertiaParams(density=0.2)`), `to_dict()`,
//! `copy()` and `==`. Nested settings (`settings.newton`, `material.strain`) are shared objects,
//! so `material.strain.youngs_modulus = 1e4` changes the material. Values are checked when they
//! enter a simulation (`Simulation(settings)`, `add_surface`, `set_params`), with the library's
//! messages.
//!
//! Settings and materials are mirror classes (`mirror!`: an attribute per field, of the Python
//! type that stands for the Rust one, checked complete by the compiler), their docs taken from
//! the library's `Documented` tables. The model parameter classes (`InertiaParams`,
//! `TetStrainParams`, ...) wrap the library struct and take their attributes and docs from its
//! field table (`stark::params`). So docs are written only in the library; `param_list.rs` names
//! the classes.

use crate::convert::{stark_err, Arr3};
use pyo3::exceptions::{PyAttributeError, PyTypeError, PyValueError};
use pyo3::panic::PanicException;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyString, PyType};
use serde::de::DeserializeOwned;
use serde::Serialize;
use stark::params::{doc_text, Documented, FieldDoc, FieldKind, FieldValue, ParamFields};
use std::ffi::{c_int, c_void, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::PathBuf;

/// A Python class that mirrors a Rust struct.
pub trait Mirror: Sized {
    /// The Rust struct.
    type Rust;
    /// A Python value from the Rust one.
    fn from_rust(py: Python<'_>, r: &Self::Rust) -> PyResult<Self>;
    /// The Rust value.
    fn to_rust(&self, py: Python<'_>) -> PyResult<Self::Rust>;
}

/// The attributes of a class made by `mirror!`.
pub trait MirrorFields {
    /// The attribute names, in the Rust struct's order.
    const FIELDS: &'static [&'static str];
}

/// A field of a mirror class and the Rust field it stands for.
pub trait Field<R>: Sized {
    /// The Python field from the Rust field.
    fn from_field(py: Python<'_>, r: &R) -> PyResult<Self>;
    /// The Rust field.
    fn to_field(&self, py: Python<'_>) -> PyResult<R>;
}

macro_rules! identity_field {
    ($($t:ty),*) => {$(
        impl Field<$t> for $t {
            fn from_field(_py: Python<'_>, r: &$t) -> PyResult<Self> {
                Ok(r.clone())
            }
            fn to_field(&self, _py: Python<'_>) -> PyResult<$t> {
                Ok(self.clone())
            }
        }
    )*};
}
identity_field!(f64, bool, usize, String, Option<f64>, PathBuf);

impl Field<[f64; 3]> for Arr3 {
    fn from_field(_py: Python<'_>, r: &[f64; 3]) -> PyResult<Self> {
        Ok(Arr3(*r))
    }
    fn to_field(&self, _py: Python<'_>) -> PyResult<[f64; 3]> {
        Ok(self.0)
    }
}

impl<M: Mirror + pyo3::PyClass<Frozen = pyo3::pyclass::boolean_struct::False> + Into<pyo3::PyClassInitializer<M>>>
    Field<M::Rust> for Py<M>
{
    fn from_field(py: Python<'_>, r: &M::Rust) -> PyResult<Self> {
        Py::new(py, M::from_rust(py, r)?)
    }
    fn to_field(&self, py: Python<'_>) -> PyResult<M::Rust> {
        self.bind(py).borrow().to_rust(py)
    }
}

/// A Rust enum shown as its snake_case name (`"pcg"`, `"cholesky"`); assigning an unknown name
/// raises `ValueError` at once.
#[derive(Clone, Copy, Debug)]
pub struct Choice<E>(pub E);

impl<E: Clone> Field<E> for Choice<E> {
    fn from_field(_py: Python<'_>, r: &E) -> PyResult<Self> {
        Ok(Choice(r.clone()))
    }
    fn to_field(&self, _py: Python<'_>) -> PyResult<E> {
        Ok(self.0.clone())
    }
}

impl<'py, E: Serialize> IntoPyObject<'py> for Choice<E> {
    type Target = PyString;
    type Output = Bound<'py, PyString>;
    type Error = PyErr;
    fn into_pyobject(self, py: Python<'py>) -> PyResult<Self::Output> {
        match serde_json::to_value(&self.0) {
            Ok(serde_json::Value::String(s)) => Ok(PyString::new(py, &s)),
            _ => Err(stark_err("enum value has no name")),
        }
    }
}

impl<'a, 'py, E: DeserializeOwned> FromPyObject<'a, 'py> for Choice<E> {
    type Error = PyErr;
    fn extract(obj: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        let s: String = obj.extract()?;
        serde_json::from_value(serde_json::Value::String(s.clone()))
            .map(Choice)
            .map_err(|e| PyValueError::new_err(format!("'{s}': {e}")))
    }
}

/// Defines a mirror class: the struct with every field as an attribute (of the Python type that
/// stands for the Rust field's), its conversions, a keyword constructor, `__repr__`, `==`,
/// `to_dict()` and `copy()`. The Rust struct's constructor in `to_rust` names every field, so
/// the compiler rejects a mirror that misses one; the docs come from the library's table when the
/// class is registered ([`install_docs`]).
macro_rules! mirror {
    (
        $name:ident => $rust:path {
            $( $field:ident : $ty:ty ),* $(,)?
        }
    ) => {
        #[pyclass(module = "starkrs", get_all, set_all)]
        pub struct $name {
            $( pub $field: $ty, )*
        }

        impl $crate::params::MirrorFields for $name {
            const FIELDS: &'static [&'static str] = &[$(stringify!($field)),*];
        }

        impl $crate::params::Mirror for $name {
            type Rust = $rust;
            fn from_rust(py: Python<'_>, r: &$rust) -> PyResult<Self> {
                #[allow(unused_imports)]
                use $crate::params::Field;
                Ok(Self { $( $field: Field::from_field(py, &r.$field)?, )* })
            }
            fn to_rust(&self, py: Python<'_>) -> PyResult<$rust> {
                #[allow(unused_imports)]
                use $crate::params::Field;
                type R = $rust;
                Ok(R { $( $field: self.$field.to_field(py)?, )* })
            }
        }

        #[pymethods]
        impl $name {
            /// Defaults of the library, with the given fields replaced.
            #[new]
            #[pyo3(signature = (**fields))]
            fn py_new(py: Python<'_>, fields: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
                use $crate::params::Mirror;
                let mut me = Self::from_rust(py, &<$rust as Default>::default())?;
                if let Some(fields) = fields {
                    for (k, v) in fields.iter() {
                        let k: String = k.extract()?;
                        match k.as_str() {
                            $( stringify!($field) => me.$field = v.extract()?, )*
                            _ => {
                                return Err(PyAttributeError::new_err(format!(
                                    "{} has no field '{}' (fields: {})",
                                    stringify!($name),
                                    k,
                                    <Self as $crate::params::MirrorFields>::FIELDS.join(", ")
                                )))
                            }
                        }
                    }
                }
                Ok(me)
            }

            fn __repr__(slf: &Bound<'_, Self>) -> PyResult<String> {
                let mut parts = Vec::new();
                for f in <Self as $crate::params::MirrorFields>::FIELDS {
                    parts.push(format!("{}={}", f, slf.getattr(*f)?.repr()?));
                }
                Ok(format!("{}({})", stringify!($name), parts.join(", ")))
            }

            fn __eq__(&self, py: Python<'_>, other: &Bound<'_, PyAny>) -> PyResult<bool> {
                use $crate::params::Mirror;
                match other.cast::<Self>() {
                    Ok(o) => Ok(self.to_rust(py)? == o.borrow().to_rust(py)?),
                    Err(_) => Ok(false),
                }
            }

            /// The fields as a plain dict (nested settings as nested dicts).
            fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
                use $crate::params::Mirror;
                $crate::convert::to_python(py, &self.to_rust(py)?)
            }

            /// A deep copy (nested settings are copied too).
            fn copy(&self, py: Python<'_>) -> PyResult<Self> {
                use $crate::params::Mirror;
                Self::from_rust(py, &self.to_rust(py)?)
            }

            fn __copy__(&self, py: Python<'_>) -> PyResult<Self> {
                self.copy(py)
            }

            fn __deepcopy__(&self, py: Python<'_>, _memo: &Bound<'_, PyAny>) -> PyResult<Self> {
                self.copy(py)
            }
        }
    };
}

// ---------------------------------------------------------------------------------------------
// Settings
// ---------------------------------------------------------------------------------------------

mirror! {
    NewtonSettings => stark::solver::settings::NewtonSettings {
        residual_tolerance_n: f64,
        step_tolerance_m_s: f64,
        max_iterations: usize,
        linear_solver: Choice<stark::solver::settings::LinearSolver>,
        cg_max_iterations: usize,
        cg_relative_tolerance: f64,
        armijo: f64,
        max_line_search_iterations: usize,
        projection: Choice<stark::solver::settings::Projection>,
        definite_far_from_solution: bool,
    }
}

mirror! {
    OutputSettings => stark::solver::settings::OutputSettings {
        directory: PathBuf,
        fps: f64,
        frames: bool,
        frame_format: Choice<stark::solver::settings::FrameFormat>,
        step_log: bool,
        bodies_log: bool,
        joints_log: bool,
    }
}

mirror! {
    ContactSettings => stark::contact::ContactSettings {
        default_thickness_m: Option<f64>,
        barrier: Choice<stark::contact::BarrierKind>,
        stiffness: Option<f64>,
        min_distance_fraction: f64,
        max_stiffness_factor: f64,
        friction_stick_slide_threshold_m_s: f64,
        friction_iterations: usize,
        hessian: Choice<stark::contact::PairHessian>,
        ccd: bool,
    }
}

mirror! {
    Settings => stark::Settings {
        name: String,
        time_step_s: f64,
        adaptive_time_step: bool,
        min_time_step_s: f64,
        time_step_growth: f64,
        gravity_m_s2: Arr3,
        threads: usize,
        newton: Py<NewtonSettings>,
        output: Py<OutputSettings>,
        contact: Py<ContactSettings>,
        max_hardening_retries: usize,
    }
}

#[pymethods]
impl Settings {
    /// Check the values; raises `StarkError` naming the field.
    fn validate(&self, py: Python<'_>) -> PyResult<()> {
        self.to_rust(py)?.validate().map_err(crate::convert::to_py_err)
    }
}

// ---------------------------------------------------------------------------------------------
// Model parameters: one class per library struct, its attributes made from the struct's field
// table (`stark::params`), so fields and their docs are written once, in the library.
// ---------------------------------------------------------------------------------------------

/// A Python class wrapping a library parameter struct.
pub trait ParamClass: pyo3::PyClass<Frozen = pyo3::pyclass::boolean_struct::False> {
    /// The library struct.
    type Struct: ParamFields;
    /// The struct.
    fn inner(&self) -> &Self::Struct;
    /// The struct, to change.
    fn inner_mut(&mut self) -> &mut Self::Struct;
    /// A new Python object holding `p`.
    fn new_object(py: Python<'_>, p: Self::Struct) -> PyResult<Bound<'_, PyAny>>;
}

/// Defines the parameter classes of `param_list.rs` and `register_param_classes`.
macro_rules! define_param_classes {
    ($($name:ident => $rust:path),* $(,)?) => {
        $(
            #[pyclass(module = "starkrs")]
            pub struct $name(pub $rust);

            impl ParamClass for $name {
                type Struct = $rust;
                fn inner(&self) -> &$rust {
                    &self.0
                }
                fn inner_mut(&mut self) -> &mut $rust {
                    &mut self.0
                }
                fn new_object(py: Python<'_>, p: $rust) -> PyResult<Bound<'_, PyAny>> {
                    Ok(Bound::new(py, Self(p))?.into_any())
                }
            }

            impl Mirror for $name {
                type Rust = $rust;
                fn from_rust(_py: Python<'_>, r: &$rust) -> PyResult<Self> {
                    Ok(Self(r.clone()))
                }
                fn to_rust(&self, _py: Python<'_>) -> PyResult<$rust> {
                    Ok(self.0.clone())
                }
            }

            #[pymethods]
            impl $name {
                /// Defaults of the library, with the given fields replaced.
                #[new]
                #[pyo3(signature = (**fields))]
                fn py_new(fields: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
                    let mut me = Self(Default::default());
                    set_fields(&mut me.0, stringify!($name), fields)?;
                    Ok(me)
                }

                fn __repr__(slf: &Bound<'_, Self>) -> PyResult<String> {
                    param_repr::<$rust>(stringify!($name), slf.as_any())
                }

                fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
                    other.cast::<Self>().is_ok_and(|o| o.borrow().0 == self.0)
                }

                /// The fields as a plain dict (nested settings as nested dicts).
                fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
                    $crate::convert::to_python(py, &self.0)
                }

                /// A deep copy (nested settings are copied too).
                fn copy(&self) -> Self {
                    Self(self.0.clone())
                }

                fn __copy__(&self) -> Self {
                    self.copy()
                }

                fn __deepcopy__(&self, _memo: &Bound<'_, PyAny>) -> Self {
                    self.copy()
                }
            }
        )*

        /// Register the parameter classes, with their fields and docs from the tables.
        fn register_param_classes(m: &Bound<'_, PyModule>) -> PyResult<()> {
            $(
                m.add_class::<$name>()?;
                install_fields::<$name>(&m.py().get_type::<$name>())?;
            )*
            Ok(())
        }
    };
}
crate::param_list::param_classes!(define_param_classes);

/// Set the keyword arguments of a constructor; an unknown name raises `AttributeError`.
fn set_fields<P: ParamFields>(p: &mut P, class: &str, fields: Option<&Bound<'_, PyDict>>) -> PyResult<()> {
    for (k, v) in fields.into_iter().flat_map(|d| d.iter()) {
        let k: String = k.extract()?;
        let Some(field) = P::FIELDS.iter().find(|f| f.name == k) else {
            let names: Vec<_> = P::FIELDS.iter().map(|f| f.name).collect();
            return Err(PyAttributeError::new_err(format!(
                "{class} has no field '{k}' (fields: {})",
                names.join(", ")
            )));
        };
        p.set(field.name, field_from_py(field, &v)?)
            .map_err(crate::convert::to_py_err)?;
    }
    Ok(())
}

/// `Name(field=value, ...)` with the values' Python reprs.
fn param_repr<P: ParamFields>(class: &str, slf: &Bound<'_, PyAny>) -> PyResult<String> {
    let mut parts = Vec::new();
    for f in P::FIELDS {
        parts.push(format!("{}={}", f.name, slf.getattr(f.name)?.repr()?));
    }
    Ok(format!("{class}({})", parts.join(", ")))
}

/// A Python value as a field of kind `field.kind` (`TypeError` if it is not one).
fn field_from_py(field: &FieldDoc, v: &Bound<'_, PyAny>) -> PyResult<FieldValue> {
    Ok(match field.kind {
        FieldKind::Float => FieldValue::Float(v.extract()?),
        FieldKind::Bool => FieldValue::Bool(v.extract()?),
    })
}

/// A field value as a Python object.
fn field_to_py(py: Python<'_>, v: FieldValue) -> Bound<'_, PyAny> {
    match v {
        FieldValue::Float(x) => PyFloat::new(py, x).into_any(),
        FieldValue::Bool(b) => PyBool::new(py, b).to_owned().into_any(),
    }
}

/// Give class `C` its docstring and a getset descriptor per field of its table (the attribute
/// kind `#[pyo3(get, set)]` makes), with the field's doc.
fn install_fields<C: ParamClass>(ty: &Bound<'_, PyType>) -> PyResult<()> {
    ty.setattr("__doc__", doc_text(C::Struct::DOC))?;
    for (i, f) in C::Struct::FIELDS.iter().enumerate() {
        // CPython keeps pointers to the definition and its strings for as long as the descriptor
        // lives, which is as long as the class: leaked, once per field when the module loads.
        let def = Box::leak(Box::new(pyo3::ffi::PyGetSetDef {
            name: CString::new(f.name)?.into_raw(),
            get: Some(get_field::<C>),
            set: Some(set_field::<C>),
            doc: CString::new(f.doc_text())?.into_raw(),
            closure: i as *mut c_void,
        }));
        // SAFETY: `ty` is a live type object and `def` is never freed.
        let descr =
            unsafe { Bound::from_owned_ptr_or_err(ty.py(), pyo3::ffi::PyDescr_NewGetSet(ty.as_type_ptr(), def)) }?;
        ty.setattr(f.name, descr)?;
    }
    Ok(())
}

/// Run a getter or setter body: its error, or a panic as `PanicException`, is raised in Python.
fn descriptor_call<T>(py: Python<'_>, failed: T, body: impl FnOnce() -> PyResult<T>) -> T {
    match catch_unwind(AssertUnwindSafe(body)) {
        Ok(Ok(v)) => v,
        Ok(Err(e)) => {
            e.restore(py);
            failed
        }
        Err(_) => {
            PanicException::new_err("panic in a parameter attribute").restore(py);
            failed
        }
    }
}

/// The getter of field number `closure` of class `C`.
unsafe extern "C" fn get_field<C: ParamClass>(
    slf: *mut pyo3::ffi::PyObject,
    closure: *mut c_void,
) -> *mut pyo3::ffi::PyObject {
    // SAFETY: CPython calls a getter with the GIL held and `slf` an instance of the class the
    // descriptor was made for (it checks the type first).
    let py = unsafe { Python::assume_attached() };
    descriptor_call(py, std::ptr::null_mut(), || {
        let slf = unsafe { Bound::from_borrowed_ptr(py, slf) };
        let obj = slf.cast::<C>()?;
        let field = &C::Struct::FIELDS[closure as usize];
        let value = obj.try_borrow()?.inner().get(field.name).expect("a field of the table");
        Ok(field_to_py(py, value).into_ptr())
    })
}

/// The setter of field number `closure` of class `C`.
unsafe extern "C" fn set_field<C: ParamClass>(
    slf: *mut pyo3::ffi::PyObject,
    value: *mut pyo3::ffi::PyObject,
    closure: *mut c_void,
) -> c_int {
    // SAFETY: as in `get_field`; `value` is null for `del`.
    let py = unsafe { Python::assume_attached() };
    descriptor_call(py, -1, || {
        let slf = unsafe { Bound::from_borrowed_ptr(py, slf) };
        let obj = slf.cast::<C>()?;
        let field = &C::Struct::FIELDS[closure as usize];
        if value.is_null() {
            return Err(PyAttributeError::new_err(format!(
                "can't delete attribute '{}'",
                field.name
            )));
        }
        let v = field_from_py(field, unsafe { &Bound::from_borrowed_ptr(py, value) })?;
        obj.try_borrow_mut()?
            .inner_mut()
            .set(field.name, v)
            .map_err(crate::convert::to_py_err)?;
        Ok(0)
    })
}

// ---------------------------------------------------------------------------------------------
// Materials
// ---------------------------------------------------------------------------------------------

mirror! {
    LineMaterial => stark::presets::LineMaterial {
        inertia: Py<InertiaParams>,
        strain: Py<SegmentStrainParams>,
        contact_thickness_m: Option<f64>,
    }
}

#[pymethods]
impl LineMaterial {
    /// Elastic rubber band: 0.05 kg/m, r = 2 mm, E = 1e4 Pa, strain limit 10%.
    #[staticmethod]
    fn elastic_rubber_band(py: Python<'_>) -> PyResult<Self> {
        Self::from_rust(py, &stark::presets::LineMaterial::elastic_rubber_band())
    }
}

mirror! {
    VolumeMaterial => stark::presets::VolumeMaterial {
        inertia: Py<InertiaParams>,
        strain: Py<TetStrainParams>,
        contact_thickness_m: Option<f64>,
    }
}

#[pymethods]
impl VolumeMaterial {
    /// Soft rubber: 1000 kg/m³, E = 1e4 Pa, ν = 0.3, strain limit 100%, inertial damping 0.1/s.
    #[staticmethod]
    fn soft_rubber(py: Python<'_>) -> PyResult<Self> {
        Self::from_rust(py, &stark::presets::VolumeMaterial::soft_rubber())
    }
}

/// The bending of a surface material: None, a `FlatBendingParams` or a `DihedralBendingParams`.
pub enum BendingField {
    /// No bending stiffness.
    None,
    /// Flat bending.
    Flat(Py<FlatBendingParams>),
    /// Discrete-shell bending.
    Dihedral(Py<DihedralBendingParams>),
}

impl Field<stark::presets::Bending> for BendingField {
    fn from_field(py: Python<'_>, r: &stark::presets::Bending) -> PyResult<Self> {
        use stark::presets::Bending as B;
        Ok(match r {
            B::None => BendingField::None,
            B::Flat(p) => BendingField::Flat(Py::new(py, FlatBendingParams::from_rust(py, p)?)?),
            B::Dihedral(p) => BendingField::Dihedral(Py::new(py, DihedralBendingParams::from_rust(py, p)?)?),
        })
    }
    fn to_field(&self, py: Python<'_>) -> PyResult<stark::presets::Bending> {
        use stark::presets::Bending as B;
        Ok(match self {
            BendingField::None => B::None,
            BendingField::Flat(p) => B::Flat(p.bind(py).borrow().to_rust(py)?),
            BendingField::Dihedral(p) => B::Dihedral(p.bind(py).borrow().to_rust(py)?),
        })
    }
}

impl<'a, 'py> FromPyObject<'a, 'py> for BendingField {
    type Error = PyErr;
    fn extract(obj: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        if obj.is_none() {
            Ok(BendingField::None)
        } else if let Ok(p) = obj.cast::<FlatBendingParams>() {
            Ok(BendingField::Flat(p.to_owned().unbind()))
        } else if let Ok(p) = obj.cast::<DihedralBendingParams>() {
            Ok(BendingField::Dihedral(p.to_owned().unbind()))
        } else {
            Err(PyTypeError::new_err(
                "bending must be None, a FlatBendingParams or a DihedralBendingParams",
            ))
        }
    }
}

impl<'py> IntoPyObject<'py> for &BendingField {
    type Target = PyAny;
    type Output = Bound<'py, PyAny>;
    type Error = PyErr;
    fn into_pyobject(self, py: Python<'py>) -> PyResult<Self::Output> {
        Ok(match self {
            BendingField::None => py.None().into_bound(py),
            BendingField::Flat(p) => p.bind(py).clone().into_any(),
            BendingField::Dihedral(p) => p.bind(py).clone().into_any(),
        })
    }
}

mirror! {
    SurfaceMaterial => stark::presets::SurfaceMaterial {
        inertia: Py<InertiaParams>,
        strain: Py<TriangleStrainParams>,
        bending: BendingField,
        contact_thickness_m: Option<f64>,
    }
}

#[pymethods]
impl SurfaceMaterial {
    /// Cotton fabric: 0.2 kg/m², 1 mm thick, E = 5e3 Pa, ν = 0.3, strain limit 10%, flat bending 1e-6 N·m.
    #[staticmethod]
    fn cotton_fabric(py: Python<'_>) -> PyResult<Self> {
        Self::from_rust(py, &stark::presets::SurfaceMaterial::cotton_fabric())
    }
}

/// Convert an optional Python settings object into Rust settings (defaults for None).
pub fn settings_from(py: Python<'_>, s: Option<&Bound<'_, Settings>>) -> PyResult<stark::Settings> {
    match s {
        Some(s) => s.borrow().to_rust(py),
        None => Ok(stark::Settings::default()),
    }
}

/// The attachment parameters of an optional `params` argument (the defaults when it is omitted).
pub(crate) fn attachment_params_arg(
    py: Python<'_>,
    p: Option<&Bound<'_, AttachmentParams>>,
) -> PyResult<stark::deformables::AttachmentParams> {
    match p {
        Some(p) => p.borrow().to_rust(py),
        None => Ok(Default::default()),
    }
}

/// Give mirror class `C` its docstring and its fields' docs from the library's table: each field's
/// attribute becomes a `property` around pyo3's descriptor with the field's doc. The table and
/// the class must name the same fields in the same order.
fn install_docs<C>(ty: &Bound<'_, PyType>) -> PyResult<()>
where
    C: Mirror + MirrorFields + pyo3::PyTypeInfo,
    C::Rust: Documented,
{
    let table: Vec<_> = C::Rust::FIELDS.iter().map(|f| f.name).collect();
    if table != C::FIELDS {
        return Err(PyTypeError::new_err(format!(
            "{}: the fields {:?} differ from the library's {:?}",
            ty.name()?,
            C::FIELDS,
            table
        )));
    }
    ty.setattr("__doc__", doc_text(C::Rust::DOC))?;
    let property = ty.py().import("builtins")?.getattr("property")?;
    for f in C::Rust::FIELDS {
        let descriptor = ty.getattr(f.name)?;
        let wrapped = property.call1((
            descriptor.getattr("__get__")?,
            descriptor.getattr("__set__")?,
            ty.py().None(),
            f.doc_text(),
        ))?;
        ty.setattr(f.name, wrapped)?;
    }
    Ok(())
}

/// Register the classes: settings, model parameters, materials (the lists of `param_list.rs`).
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    macro_rules! mirrors {
        ($($name:ident => $rust:path),* $(,)?) => {$(
            m.add_class::<$name>()?;
            install_docs::<$name>(&m.py().get_type::<$name>())?;
        )*};
    }
    crate::param_list::settings_classes!(mirrors);
    register_param_classes(m)?;
    crate::param_list::material_classes!(mirrors);
    Ok(())
}

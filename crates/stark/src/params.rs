//! Field tables of the model parameter structs (`TetStrainParams`, `InertiaParams`, ...).
//!
//! Each struct is defined with [`param_struct!`], which turns the definition into the struct and
//! an implementation of [`ParamFields`]: every field's name, kind and doc text, and access by
//! name. Bindings (the Python module and its type stubs) are built from these tables, so a
//! field and its documentation are written once, next to the model.

use crate::error::{Result, StarkError};

/// The value type of a parameter field.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FieldKind {
    /// `f64`.
    Float,
    /// `bool`.
    Bool,
}

/// The value of a parameter field.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FieldValue {
    /// An `f64` field.
    Float(f64),
    /// A `bool` field.
    Bool(bool),
}

/// A field of a parameter struct.
#[derive(Clone, Copy, Debug)]
pub struct FieldDoc {
    /// The Rust field name (also the serde and Python name).
    pub name: &'static str,
    /// Its value type.
    pub kind: FieldKind,
    /// Its doc comment, one entry per `///` line as written.
    pub doc: &'static [&'static str],
}

impl FieldDoc {
    /// The doc comment as text.
    pub fn doc_text(&self) -> String {
        doc_text(self.doc)
    }
}

/// The text of doc-comment lines: each line without the space after `///`, joined by newlines.
pub fn doc_text(lines: &[&str]) -> String {
    lines
        .iter()
        .map(|l| l.strip_prefix(' ').unwrap_or(l).trim_end())
        .collect::<Vec<_>>()
        .join("\n")
}

/// A parameter struct whose fields are known by name (implemented by [`param_struct!`]).
pub trait ParamFields: Clone + Default + PartialEq {
    /// The struct's doc comment, one entry per line.
    const DOC: &'static [&'static str];
    /// The fields in declaration order.
    const FIELDS: &'static [FieldDoc];
    /// The value of field `name`; None if there is no such field.
    fn get(&self, name: &str) -> Option<FieldValue>;
    /// Set field `name`; an error if there is no such field or the value has another kind.
    fn set(&mut self, name: &str, value: FieldValue) -> Result<()>;
}

/// A field type a parameter struct may have.
pub trait FieldType: Sized {
    /// Its kind.
    const KIND: FieldKind;
    /// As a value.
    fn to_value(&self) -> FieldValue;
    /// From a value of the same kind.
    fn from_value(v: FieldValue) -> Option<Self>;
}

impl FieldType for f64 {
    const KIND: FieldKind = FieldKind::Float;
    fn to_value(&self) -> FieldValue {
        FieldValue::Float(*self)
    }
    fn from_value(v: FieldValue) -> Option<Self> {
        match v {
            FieldValue::Float(x) => Some(x),
            FieldValue::Bool(_) => None,
        }
    }
}

impl FieldType for bool {
    const KIND: FieldKind = FieldKind::Bool;
    fn to_value(&self) -> FieldValue {
        FieldValue::Bool(*self)
    }
    fn from_value(v: FieldValue) -> Option<Self> {
        match v {
            FieldValue::Bool(b) => Some(b),
            FieldValue::Float(_) => None,
        }
    }
}

/// A field of a documented struct (settings, materials): its name, its Rust type as written
/// and its doc comment.
#[derive(Clone, Copy, Debug)]
pub struct FieldText {
    /// The Rust field name (also the serde and Python name).
    pub name: &'static str,
    /// The field's type as `stringify!` writes it (spacing may vary: see [`FieldText::rust_type`]).
    pub rust_type_text: &'static str,
    /// Its doc comment, one entry per `///` line as written.
    pub doc: &'static [&'static str],
}

impl FieldText {
    /// The field's type without spaces (`Option<f64>`, `[f64;3]`).
    pub fn rust_type(&self) -> String {
        self.rust_type_text.chars().filter(|c| !c.is_whitespace()).collect()
    }

    /// The doc comment as text.
    pub fn doc_text(&self) -> String {
        doc_text(self.doc)
    }
}

/// A struct whose doc comments are known as data (implemented by [`documented_struct!`]): the
/// settings and materials, whose Python classes and stubs take their docs from here.
pub trait Documented {
    /// The struct's doc comment, one entry per line.
    const DOC: &'static [&'static str];
    /// The fields in declaration order.
    const FIELDS: &'static [FieldText];
}

/// Defines a struct and its [`Documented`] table (the doc comments written once, for Rust and
/// the bindings). Fields may have any type.
macro_rules! documented_struct {
    (
        $(#[doc = $doc:literal])*
        #[derive($($derive:path),* $(,)?)]
        $(#[serde($($serde:tt)*)])?
        pub struct $name:ident {
            $( $(#[doc = $fdoc:literal])* $(#[serde($($fserde:tt)*)])? pub $field:ident : $ty:ty ),* $(,)?
        }
    ) => {
        $(#[doc = $doc])*
        #[derive($($derive),*)]
        $(#[serde($($serde)*)])?
        pub struct $name {
            $( $(#[doc = $fdoc])* $(#[serde($($fserde)*)])? pub $field: $ty, )*
        }

        impl $crate::params::Documented for $name {
            const DOC: &'static [&'static str] = &[$($doc),*];
            const FIELDS: &'static [$crate::params::FieldText] = &[$(
                $crate::params::FieldText {
                    name: stringify!($field),
                    rust_type_text: stringify!($ty),
                    doc: &[$($fdoc),*],
                }
            ),*];
        }
    };
}
pub(crate) use documented_struct;

/// The error of [`ParamFields::set`].
#[doc(hidden)]
pub fn field_error(struct_name: &str, name: &str, fields: &[FieldDoc], kind_ok: bool) -> StarkError {
    if kind_ok {
        let names: Vec<_> = fields.iter().map(|f| f.name).collect();
        StarkError::InvalidInput(format!(
            "{struct_name} has no field '{name}' (fields: {})",
            names.join(", ")
        ))
    } else {
        StarkError::InvalidInput(format!("{struct_name}.{name}: wrong value type"))
    }
}

/// Defines a parameter struct and its [`ParamFields`] table. The doc comments are written once:
/// they document the Rust struct and fields and are the table's doc text (the Python classes'
/// docstrings and stubs). Fields are `f64` or `bool`. The struct is made by
/// [`documented_struct!`], so it is [`Documented`] too.
macro_rules! param_struct {
    (
        $(#[doc = $doc:literal])*
        #[derive($($derive:path),* $(,)?)]
        $(#[serde($($serde:tt)*)])?
        pub struct $name:ident {
            $( $(#[doc = $fdoc:literal])* pub $field:ident : $ty:ty ),* $(,)?
        }
    ) => {
        $crate::params::documented_struct! {
            $(#[doc = $doc])*
            #[derive($($derive),*)]
            $(#[serde($($serde)*)])?
            pub struct $name {
                $( $(#[doc = $fdoc])* pub $field: $ty, )*
            }
        }

        impl $crate::params::ParamFields for $name {
            const DOC: &'static [&'static str] = &[$($doc),*];
            const FIELDS: &'static [$crate::params::FieldDoc] = &[$(
                $crate::params::FieldDoc {
                    name: stringify!($field),
                    kind: <$ty as $crate::params::FieldType>::KIND,
                    doc: &[$($fdoc),*],
                }
            ),*];

            fn get(&self, name: &str) -> Option<$crate::params::FieldValue> {
                match name {
                    $( stringify!($field) => Some($crate::params::FieldType::to_value(&self.$field)), )*
                    _ => None,
                }
            }

            fn set(&mut self, name: &str, value: $crate::params::FieldValue) -> $crate::Result<()> {
                let kind_ok = match name {
                    $( stringify!($field) => match <$ty as $crate::params::FieldType>::from_value(value) {
                        Some(v) => {
                            self.$field = v;
                            return Ok(());
                        }
                        None => false,
                    }, )*
                    _ => true,
                };
                Err($crate::params::field_error(stringify!($name), name, Self::FIELDS, kind_ok))
            }
        }
    };
}
pub(crate) use param_struct;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::deformables as d;
    use crate::rigidbodies::{joints::JointParams, RigidBodyParams};
    use serde::Serialize;

    /// The table names every serialized field, in order, and get/set reach each field.
    fn check<P: ParamFields + Serialize>() {
        let p = P::default();
        let json = serde_json::to_value(&p).unwrap();
        let keys: Vec<_> = json.as_object().unwrap().keys().cloned().collect();
        let names: Vec<_> = P::FIELDS.iter().map(|f| f.name.to_string()).collect();
        let (mut sorted_keys, mut sorted_names) = (keys.clone(), names.clone());
        sorted_keys.sort();
        sorted_names.sort();
        assert_eq!(sorted_keys, sorted_names);
        assert!(!P::DOC.is_empty());
        for f in P::FIELDS {
            assert!(!f.doc_text().is_empty(), "{} has no doc", f.name);
            let mut q = p.clone();
            let (new, json) = match q.get(f.name).unwrap() {
                FieldValue::Float(x) => (FieldValue::Float(x * 2.0 + 1.0), serde_json::json!(x * 2.0 + 1.0)),
                FieldValue::Bool(b) => (FieldValue::Bool(!b), serde_json::json!(!b)),
            };
            let kind = if matches!(new, FieldValue::Float(_)) {
                FieldKind::Float
            } else {
                FieldKind::Bool
            };
            assert_eq!(f.kind, kind, "{}", f.name);
            q.set(f.name, new).unwrap();
            assert_eq!(q.get(f.name), Some(new));
            assert_eq!(serde_json::to_value(&q).unwrap()[f.name], json);
        }
        assert!(p.clone().set("no_such_field", FieldValue::Float(1.0)).is_err());
        assert!(p.get("no_such_field").is_none());
    }

    #[test]
    fn tables_match_the_structs() {
        check::<d::InertiaParams>();
        check::<d::TriangleStrainParams>();
        check::<d::TetStrainParams>();
        check::<d::SegmentStrainParams>();
        check::<d::FlatBendingParams>();
        check::<d::DihedralBendingParams>();
        check::<d::PrescribedParams>();
        check::<d::AttachmentParams>();
        check::<RigidBodyParams>();
        check::<JointParams>();
    }

    #[test]
    fn set_checks_the_kind_and_the_name() {
        let mut p = d::InertiaParams::default();
        let e = p.set("quasistatic", FieldValue::Float(1.0)).unwrap_err().to_string();
        assert!(e.contains("quasistatic"), "{e}");
        let e = p.set("densty", FieldValue::Float(1.0)).unwrap_err().to_string();
        assert!(e.contains("no field 'densty'") && e.contains("density"), "{e}");
        assert_eq!(doc_text(&[" a", " b "]), "a\nb");
    }
}

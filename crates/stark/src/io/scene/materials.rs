//! Materials: a preset plus overrides merged in TOML-value space. The override is merged into the
//! serialised preset and the result deserialised, so field names and checks are exactly those of
//! the material structs; an error is traced to the first override key that fails on its own.

use super::errors::{At, Ctx, Res, SceneError};
use crate::error::StarkError;
use crate::presets::{LineMaterial, SurfaceMaterial, VolumeMaterial};
use serde::de::DeserializeOwned;
use serde::Serialize;

/// A material with named presets (`cotton_fabric`, `default`, ...).
pub(super) trait MaterialPresets: Serialize + DeserializeOwned {
    const KIND: &'static str;
    fn presets() -> Vec<(&'static str, Self)>;
}

impl MaterialPresets for SurfaceMaterial {
    const KIND: &'static str = "surface";
    fn presets() -> Vec<(&'static str, Self)> {
        vec![
            ("cotton_fabric", SurfaceMaterial::cotton_fabric()),
            ("default", SurfaceMaterial::default()),
        ]
    }
}

impl MaterialPresets for VolumeMaterial {
    const KIND: &'static str = "volume";
    fn presets() -> Vec<(&'static str, Self)> {
        vec![
            ("soft_rubber", VolumeMaterial::soft_rubber()),
            ("default", VolumeMaterial::default()),
        ]
    }
}

impl MaterialPresets for LineMaterial {
    const KIND: &'static str = "line";
    fn presets() -> Vec<(&'static str, Self)> {
        vec![
            ("elastic_rubber_band", LineMaterial::elastic_rubber_band()),
            ("default", LineMaterial::default()),
        ]
    }
}

/// A preset value that is a one-key table (an externally tagged enum such as `bending`) is
/// replaced, not merged, by a one-key override naming another variant.
fn is_variant_switch(base: &toml::Table, over: &toml::Table) -> bool {
    base.len() == 1 && over.len() == 1 && base.keys().next() != over.keys().next()
}

/// Merge `over` into `base`: tables key by key, anything else replaced.
fn merge(base: &mut toml::Value, over: &toml::Value) {
    match (base, over) {
        (toml::Value::Table(b), toml::Value::Table(o)) if !is_variant_switch(b, o) => {
            for (k, v) in o {
                match b.get_mut(k) {
                    Some(bv) => merge(bv, v),
                    None => {
                        b.insert(k.clone(), v.clone());
                    }
                }
            }
        }
        (b, o) => *b = o.clone(),
    }
}

/// `value` nested under `path`.
fn nest(path: &[String], value: &toml::Value) -> toml::Value {
    path.iter().rev().fold(value.clone(), |v, k| {
        let mut t = toml::Table::new();
        t.insert(k.clone(), v);
        toml::Value::Table(t)
    })
}

fn value_at<'v>(base: &'v toml::Value, path: &[String]) -> Option<&'v toml::Value> {
    path.iter().try_fold(base, |v, k| v.as_table()?.get(k))
}

/// The first override key that fails on its own (the innermost one where possible), with the
/// deserialisation error it causes.
fn find_culprit<M: DeserializeOwned>(
    base: &toml::Value,
    over: &toml::Table,
    prefix: &mut Vec<String>,
) -> Option<(Vec<String>, String)> {
    for (k, v) in over {
        prefix.push(k.clone());
        let mut merged = base.clone();
        merge(&mut merged, &nest(prefix, v));
        if let Err(e) = merged.try_into::<M>() {
            if let (toml::Value::Table(t), Some(toml::Value::Table(b))) = (v, value_at(base, prefix)) {
                if !is_variant_switch(b, t) {
                    if let Some(found) = find_culprit::<M>(base, t, prefix) {
                        return Some(found);
                    }
                }
            }
            return Some((prefix.clone(), e.message().trim_end().to_string()));
        }
        prefix.pop();
    }
    None
}

/// The path of the first key called `key` in `over`.
fn find_key(over: &toml::Table, key: &str) -> Option<Vec<String>> {
    for (k, v) in over {
        if k == key {
            return Some(vec![k.clone()]);
        }
        if let toml::Value::Table(t) = v {
            if let Some(mut p) = find_key(t, key) {
                p.insert(0, k.clone());
                return Some(p);
            }
        }
    }
    None
}

/// The material of the entry at `at` from its `material` value.
pub(super) fn resolve_material<M: MaterialPresets>(ctx: &Ctx, at: &At, value: &toml::Value) -> Res<M> {
    let at = at.key("material");
    let (preset_name, preset_at, overrides) = match value {
        toml::Value::String(s) => (s.as_str(), at.clone(), None),
        toml::Value::Table(t) => {
            let mut overrides = t.clone();
            let name = match overrides.remove("preset") {
                None => "default",
                Some(toml::Value::String(_)) => t["preset"].as_str().unwrap_or("default"),
                Some(other) => {
                    return Err(ctx.err(
                        &at.key("preset"),
                        format!("invalid type: {}, expected a preset name", other.type_str()),
                    ))
                }
            };
            (name, at.key("preset"), Some(overrides))
        }
        other => {
            return Err(ctx.err(
                &at,
                format!(
                    "invalid type: {}, expected a preset name or a table {{ preset = \"...\", ... }}",
                    other.type_str()
                ),
            ))
        }
    };
    let presets = M::presets();
    let Some((_, preset)) = presets.into_iter().find(|(n, _)| *n == preset_name) else {
        let names: Vec<_> = M::presets().iter().map(|(n, _)| *n).collect();
        return Err(ctx.err(
            &preset_at,
            format!(
                "unknown {} material preset '{preset_name}', expected one of {}",
                M::KIND,
                names.join(", ")
            ),
        ));
    };
    let Some(overrides) = overrides else {
        return Ok(preset);
    };
    let base = toml::Value::try_from(&preset).map_err(|e| ctx.err(&at, format!("cannot serialise the preset: {e}")))?;
    let mut merged = base.clone();
    merge(&mut merged, &toml::Value::Table(overrides.clone()));
    merged
        .try_into::<M>()
        .map_err(|e| match find_culprit::<M>(&base, &overrides, &mut Vec::new()) {
            Some((path, message)) => ctx.err(&at.keys(&path), message),
            None => ctx.err(&at, e.message().trim_end()),
        })
}

/// Locate a library error raised by `add_surface`/`add_volume`/`add_line`: a parameter in the
/// material, anything else in the geometry.
pub(super) fn object_error(
    ctx: &Ctx,
    at: &At,
    material: &toml::Value,
    geometry_key: &str,
    e: StarkError,
) -> SceneError {
    match &e {
        StarkError::InvalidParameter { field, .. } => {
            let path = material.as_table().and_then(|t| find_key(t, field)).unwrap_or_default();
            ctx.stark(&at.key("material").keys(&path), e)
        }
        _ => ctx.stark(&at.key(geometry_key), e),
    }
}

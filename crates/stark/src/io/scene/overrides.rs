//! `--set key.path=value` overrides: a change of the scene's document before it is read.

use super::errors::{json_error, SceneError};
use super::{load_scene_with, parse_scene_with, LoadedScene};
use crate::error::Result;
use crate::settings::Settings;
use std::path::Path;

/// [`load_scene_with`] after applying `overrides`, each `key.path=value`, to the file's document
/// before it is read: `settings.time_step_s=0.01`, `surface.cloth.material.strain.youngs_modulus=1e5`
/// (an entry of an array of tables is chosen by its `name` or its index), `duration_s=2`. The
/// value is TOML (`1e5`, `true`, `[0, 0, -9.81]`, `"text"`; a bare word is taken as a string).
/// Tables missing on the way are created, so any field can be set, and a misspelt key is
/// reported as the unknown field it is; an index or name that selects no entry, or a key below a
/// value that is not a table, is an error naming the override.
pub fn load_scene_with_overrides(
    path: &Path,
    overrides: &[String],
    configure: impl FnOnce(&mut Settings),
) -> Result<LoadedScene> {
    let origin = crate::io::SceneOrigin::File {
        path: std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf()),
        overrides: overrides.to_vec(),
    };
    let mut loaded = if overrides.is_empty() {
        load_scene_with(path, configure)?
    } else {
        let file = path.display().to_string();
        let scene_err = |message: String| SceneError {
            file: file.clone(),
            line: None,
            column: None,
            path: String::new(),
            message,
        };
        let text = std::fs::read_to_string(path).map_err(|e| scene_err(format!("cannot read the scene file: {e}")))?;
        let mut doc: toml::Table = if file.to_ascii_lowercase().ends_with(".json") {
            serde_json::from_str(&text).map_err(|e| json_error(&file, &e))?
        } else {
            toml::from_str(&text).map_err(|e| scene_err(e.message().trim_end().to_string()))?
        };
        for o in overrides {
            apply_override(&mut doc, o).map_err(|m| scene_err(format!("--set {o}: {m}")))?;
        }
        // The name defaults to the file's stem; the rewritten document has no file of its own.
        let stem = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        if let toml::Value::Table(settings) = doc
            .entry("settings")
            .or_insert_with(|| toml::Value::Table(toml::Table::new()))
        {
            settings.entry("name").or_insert(toml::Value::String(stem));
        }
        let text = toml::to_string(&doc).map_err(|e| scene_err(format!("cannot write the overridden scene: {e}")))?;
        let base_dir = path.parent().unwrap_or(Path::new("."));
        parse_scene_with(&text, &format!("{file} (with --set overrides)"), base_dir, configure)?
    };
    loaded.simulation.set_scene_origin(origin);
    Ok(loaded)
}

/// Apply one `key.path=value` override to a scene document (see [`load_scene_with_overrides`]).
pub fn apply_override(doc: &mut toml::Table, spec: &str) -> std::result::Result<(), String> {
    let (key, raw) = spec
        .split_once('=')
        .ok_or_else(|| "expected key.path=value".to_string())?;
    let keys: Vec<&str> = key.trim().split('.').collect();
    if keys.iter().any(|k| k.is_empty()) {
        return Err(format!("`{key}` has an empty key"));
    }
    let raw = raw.trim();
    let value = match toml::from_str::<toml::Table>(&format!("v = {raw}")) {
        Ok(mut t) => t.remove("v").expect("parsed key"),
        Err(_) => toml::Value::String(raw.to_string()),
    };
    let mut current = doc;
    let mut walked = String::new();
    let (last, parents) = keys.split_last().expect("at least one key");
    for (i, k) in parents.iter().enumerate() {
        let next_is_index = keys[i + 1].parse::<usize>().is_ok();
        let entry = current.entry(k.to_string()).or_insert_with(|| {
            if next_is_index {
                toml::Value::Array(Vec::new())
            } else {
                toml::Value::Table(toml::Table::new())
            }
        });
        walked = if walked.is_empty() {
            k.to_string()
        } else {
            format!("{walked}.{k}")
        };
        current = match entry {
            toml::Value::Table(t) => t,
            toml::Value::Array(entries) => {
                // An array of tables: the next key names an entry (by `name` or index).
                return set_in_array(entries, &walked, &keys[i + 1..], value);
            }
            other => {
                return Err(format!(
                    "`{walked}` is a {}, not a table, so it has no `{}`",
                    other.type_str(),
                    keys[i + 1]
                ))
            }
        };
    }
    current.insert(last.to_string(), value);
    Ok(())
}

fn set_in_array(
    entries: &mut [toml::Value],
    walked: &str,
    keys: &[&str],
    value: toml::Value,
) -> std::result::Result<(), String> {
    let sel = keys[0];
    let names: Vec<String> = entries
        .iter()
        .enumerate()
        .map(|(i, e)| {
            e.get("name")
                .and_then(|n| n.as_str())
                .map(str::to_string)
                .unwrap_or_else(|| i.to_string())
        })
        .collect();
    let index = match sel.parse::<usize>() {
        Ok(i) if i < entries.len() => i,
        Ok(i) => {
            return Err(format!(
                "`{walked}` has {} entries, there is no entry {i}",
                entries.len()
            ))
        }
        Err(_) => names.iter().position(|n| n == sel).ok_or_else(|| {
            format!(
                "`{walked}` has no entry named '{sel}' (its entries: {})",
                if names.is_empty() {
                    "none".to_string()
                } else {
                    names.join(", ")
                }
            )
        })?,
    };
    let walked = format!("{walked}.{sel}");
    if keys.len() == 1 {
        entries[index] = value;
        return Ok(());
    }
    match &mut entries[index] {
        toml::Value::Table(t) => {
            let rest = keys[1..].join(".");
            apply_override(t, &format!("{rest}={}", toml_value_text(&value))).map_err(|m| format!("in `{walked}`: {m}"))
        }
        other => Err(format!(
            "`{walked}` is a {}, not a table, so it has no `{}`",
            other.type_str(),
            keys[1]
        )),
    }
}

/// A value written back as TOML (for a recursive [`apply_override`]).
fn toml_value_text(v: &toml::Value) -> String {
    match v {
        toml::Value::String(s) => toml::Value::String(s.clone()).to_string(),
        other => other.to_string(),
    }
}

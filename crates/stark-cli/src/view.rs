//! `stark view`: TEMPORARY.
use std::path::{Path, PathBuf};
pub fn write_viewer(_dir: &Path, _out: Option<&Path>) -> stark::Result<PathBuf> {
    Err(stark::StarkError::InvalidInput("todo".into()))
}

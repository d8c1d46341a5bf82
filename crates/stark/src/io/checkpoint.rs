//! Checkpoints: the whole state the next step depends on, in one versioned binary file, so that
//! a run continues from it bit-identically.
//!
//! A checkpoint does not hold the scene itself: the program that made the run builds it again
//! (a scene file, a built-in scene, or its own code), then
//! [`Simulation::restore_checkpoint`] puts the state back. What is saved:
//!
//! - node and rigid-body state (positions, velocities, poses, external forces), time, the current
//!   `dt` (its growth after failed steps continues), the settings (time events may change
//!   gravity or any other setting), the run's counters and the output's frame counter and frame
//!   times;
//! - every energy term's own mutable state through
//!   [`EnergyTerm::save_state`](crate::energy::EnergyTerm::save_state): hardened joint,
//!   attachment and prescribed stiffnesses, prescribed targets, joint targets and anchors,
//!   parameters changed at run time, the adaptive barrier stiffness;
//! - with `linear_solver = "amg"`, the multigrid hierarchy's interpolation (its prolongators,
//!   ~10 MB for a 128² cloth) and CG counts, which the next steps' solves reuse.
//!
//! Time events come back with the scene: a scene file's events are rebuilt with it, and a program
//! that registered closures (`add_time_event`) registers them again before restoring. Lagged
//! friction and contact pairs are recomputed from the positions at the start of every step, so
//! they need no saving.
//!
//! The file is a postcard-encoded [`CheckpointHeader`] (magic, format version, a hash of the
//! scene's structure, where the scene came from, the state's length and checksum) followed by the
//! postcard-encoded state; the settings and the run's totals inside it carry their field names,
//! so that a checkpoint resumes in a build that added a setting (it takes its default). Reading checks each in turn, so a file of another scene, a truncated
//! file or one of another format version is refused with a message saying which.

use crate::error::{Result, StarkError};
use crate::settings::Settings;
use crate::simulation::RunSummary;
use crate::state::{BodyArrays, NodeArrays};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The format version this build writes (3: Newton's initial-guess factor saved; 4: the
/// multigrid hierarchy's interpolation). It reads 3 too.
pub const CHECKPOINT_FORMAT_VERSION: u32 = 4;

/// The oldest format version this build reads: a version-3 state is a version-4 state without
/// its last field, the kept preconditioner (none).
const OLDEST_READ_FORMAT_VERSION: u32 = 3;

/// First bytes of every checkpoint file.
const MAGIC: [u8; 8] = *b"STARKCKP";

/// Where a simulation's scene came from, so that `stark resume` can build it again.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum SceneOrigin {
    /// A built-in scene (`stark list`).
    Builtin {
        /// Its name.
        name: String,
    },
    /// A scene file with `--set` overrides applied in order.
    File {
        /// The file (absolute when written by `stark run`).
        path: PathBuf,
        /// `key.path=value` overrides.
        overrides: Vec<String>,
    },
    /// Built by a program: that program restores it.
    Program,
}

/// The header of a checkpoint file: everything needed to decide whether (and how) to restore it.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CheckpointHeader {
    magic: [u8; 8],
    /// Format version of the file.
    pub format_version: u32,
    /// Hash of the scene's structure ([`Simulation::scene_hash`](crate::Simulation::scene_hash)).
    pub scene_hash: u64,
    /// Scene name.
    pub scene: String,
    /// Where the scene came from.
    pub origin: SceneOrigin,
    /// Output directory of the run that wrote it.
    pub output_directory: PathBuf,
    /// Simulated time at the checkpoint, s.
    pub time_s: f64,
    /// Accepted steps at the checkpoint.
    pub steps: u64,
    state_len: u64,
    state_checksum: u64,
}

/// The state after the header.
#[derive(Serialize, Deserialize)]
pub(crate) struct SimulationState {
    pub nodes: NodeArrays,
    pub bodies: BodyArrays,
    /// Self-describing (field names), so that a checkpoint still resumes after a new setting
    /// (with its default) or a new summary counter was added.
    #[serde(with = "self_describing")]
    pub settings: Settings,
    pub time_s: f64,
    pub dt_s: f64,
    /// The factor on the last velocities that makes the next step's initial guess.
    pub guess_scale: f64,
    #[serde(with = "self_describing")]
    pub summary: RunSummary,
    pub frames_written: usize,
    pub next_frame_time_s: f64,
    pub frame_times_s: Vec<f64>,
    /// Each term's name and saved state, in the simulation's term order.
    pub terms: Vec<(String, Vec<u8>)>,
    /// What the linear solver keeps from step to step (a multigrid hierarchy's interpolation),
    /// postcard-encoded; empty when nothing (format 3 had no such field).
    pub kept_preconditioner: Vec<u8>,
}

/// A value as MessagePack with field names inside the postcard stream (MessagePack keeps
/// infinities and every bit of a float, unlike JSON); missing fields take their defaults.
mod self_describing {
    use serde::de::{DeserializeOwned, Error as _};
    use serde::ser::Error as _;
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    pub fn serialize<T: Serialize, S: Serializer>(value: &T, s: S) -> Result<S::Ok, S::Error> {
        let bytes = rmp_serde::to_vec_named(value).map_err(S::Error::custom)?;
        bytes.serialize(s)
    }

    pub fn deserialize<'de, T: DeserializeOwned, D: Deserializer<'de>>(d: D) -> Result<T, D::Error> {
        let bytes = Vec::<u8>::deserialize(d)?;
        rmp_serde::from_slice(&bytes).map_err(D::Error::custom)
    }
}

/// FNV-1a, 64 bit: a stable hash (the standard library's is not stable across builds).
#[derive(Clone, Copy)]
pub(crate) struct Fnv(u64);

impl Default for Fnv {
    fn default() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv {
    pub fn bytes(&mut self, b: &[u8]) {
        for &x in b {
            self.0 ^= u64::from(x);
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
    }
    pub fn u64(&mut self, v: u64) {
        self.bytes(&v.to_le_bytes());
    }
    pub fn f64(&mut self, v: f64) {
        self.u64(v.to_bits());
    }
    pub fn str(&mut self, s: &str) {
        self.u64(s.len() as u64);
        self.bytes(s.as_bytes());
    }
    pub fn finish(self) -> u64 {
        self.0
    }
}

fn err(path: &Path, message: impl Into<String>) -> StarkError {
    StarkError::Checkpoint {
        path: path.display().to_string(),
        message: message.into(),
    }
}

/// Write `header` (its length and checksum filled in) and `state` to `path`, atomically: a
/// temporary file renamed over the target, so an interrupted write never leaves a broken file.
pub(crate) fn write(path: &Path, mut header: CheckpointHeader, state: &SimulationState) -> Result<()> {
    let body = postcard::to_allocvec(state).map_err(|e| err(path, format!("cannot encode the state: {e}")))?;
    header.magic = MAGIC;
    header.format_version = CHECKPOINT_FORMAT_VERSION;
    header.state_len = body.len() as u64;
    let mut h = Fnv::default();
    h.bytes(&body);
    header.state_checksum = h.finish();
    let mut bytes = postcard::to_allocvec(&header).map_err(|e| err(path, format!("cannot encode the header: {e}")))?;
    bytes.extend_from_slice(&body);
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| err(path, format!("cannot create its directory: {e}")))?;
    }
    let tmp = path.with_extension("ckpt-partial");
    std::fs::write(&tmp, &bytes).map_err(|e| err(path, format!("cannot write: {e}")))?;
    std::fs::rename(&tmp, path).map_err(|e| err(path, format!("cannot rename the finished file into place: {e}")))
}

/// Build a header for [`write`] (length and checksum are filled in there).
pub(crate) fn header(
    scene_hash: u64,
    scene: &str,
    origin: SceneOrigin,
    output_directory: &Path,
    time_s: f64,
    steps: u64,
) -> CheckpointHeader {
    CheckpointHeader {
        magic: MAGIC,
        format_version: CHECKPOINT_FORMAT_VERSION,
        scene_hash,
        scene: scene.to_string(),
        origin,
        output_directory: output_directory.to_path_buf(),
        time_s,
        steps,
        state_len: 0,
        state_checksum: 0,
    }
}

fn read_bytes(path: &Path) -> Result<Vec<u8>> {
    std::fs::read(path).map_err(|e| err(path, format!("cannot read: {e}")))
}

fn parse_header<'a>(path: &Path, bytes: &'a [u8]) -> Result<(CheckpointHeader, &'a [u8])> {
    if bytes.len() < MAGIC.len() || bytes[..MAGIC.len()] != MAGIC {
        return Err(err(path, "not a Stark checkpoint (its first bytes are not STARKCKP)"));
    }
    // The version follows the magic; check it before decoding the rest of a header whose layout
    // may have changed.
    let (version, _): (u32, _) = postcard::take_from_bytes(&bytes[MAGIC.len()..])
        .map_err(|_| err(path, "the file is truncated inside its header"))?;
    if !(OLDEST_READ_FORMAT_VERSION..=CHECKPOINT_FORMAT_VERSION).contains(&version) {
        return Err(err(
            path,
            format!(
                "format version {version}; this build reads versions {OLDEST_READ_FORMAT_VERSION} to {CHECKPOINT_FORMAT_VERSION}"
            ),
        ));
    }
    let (header, rest): (CheckpointHeader, _) =
        postcard::take_from_bytes(bytes).map_err(|_| err(path, "the file is truncated inside its header"))?;
    if (rest.len() as u64) < header.state_len {
        return Err(err(
            path,
            format!(
                "the file is truncated: {} bytes of state, the header announces {}",
                rest.len(),
                header.state_len
            ),
        ));
    }
    let body = &rest[..header.state_len as usize];
    let mut h = Fnv::default();
    h.bytes(body);
    if h.finish() != header.state_checksum {
        return Err(err(path, "the state does not match its checksum (the file is damaged)"));
    }
    Ok((header, body))
}

/// Read only the header of a checkpoint (to find the scene to build again).
pub fn read_header(path: &Path) -> Result<CheckpointHeader> {
    let bytes = read_bytes(path)?;
    Ok(parse_header(path, &bytes)?.0)
}

/// Read a checkpoint, checking that it belongs to a scene of hash `scene_hash`.
pub(crate) fn read(path: &Path, scene_hash: u64, scene: &str) -> Result<(CheckpointHeader, SimulationState)> {
    let bytes = read_bytes(path)?;
    let (header, body) = parse_header(path, &bytes)?;
    if header.scene_hash != scene_hash {
        return Err(err(
            path,
            format!(
                "it is a checkpoint of scene '{}' (structure hash {:016x}), not of this scene '{scene}' ({scene_hash:016x}): \
                 objects, elements, bodies, joints or events differ",
                header.scene, header.scene_hash
            ),
        ));
    }
    // Format 3 ends before the kept preconditioner: an empty one (postcard: a zero length).
    let body: std::borrow::Cow<[u8]> = if header.format_version == 3 {
        [body, &[0u8][..]].concat().into()
    } else {
        body.into()
    };
    let state: SimulationState =
        postcard::from_bytes(&body).map_err(|e| err(path, format!("the state does not decode: {e}")))?;
    Ok((header, state))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A checkpoint written before a setting existed resumes with that setting's default.
    #[test]
    fn settings_missing_a_field_decode_with_its_default() {
        #[derive(Serialize, Deserialize)]
        struct Holder {
            #[serde(with = "self_describing")]
            settings: Settings,
        }
        let mut settings = Settings::default();
        settings.newton.residual_tolerance_n = 3e-7;
        settings.newton.definite_far_from_solution = false;
        let mut older = serde_json::to_value(&settings).unwrap();
        older["newton"]
            .as_object_mut()
            .unwrap()
            .remove("definite_far_from_solution");
        #[derive(Serialize)]
        struct OlderHolder(#[serde(with = "bytes_of")] serde_json::Value);
        mod bytes_of {
            pub fn serialize<S: serde::Serializer>(v: &serde_json::Value, s: S) -> Result<S::Ok, S::Error> {
                serde::Serialize::serialize(&rmp_serde::to_vec_named(v).unwrap(), s)
            }
        }
        let file = postcard::to_allocvec(&OlderHolder(older)).unwrap();
        let back: Holder = postcard::from_bytes(&file).unwrap();
        assert_eq!(back.settings.newton.residual_tolerance_n, 3e-7);
        assert!(back.settings.newton.definite_far_from_solution, "the default");
        // And the current settings round-trip exactly.
        let file = postcard::to_allocvec(&Holder {
            settings: settings.clone(),
        })
        .unwrap();
        assert_eq!(postcard::from_bytes::<Holder>(&file).unwrap().settings, settings);
    }

    /// A format-3 file (no kept preconditioner) reads as a current one with none; a current one
    /// round-trips its kept preconditioner.
    #[test]
    fn format_3_files_read_with_no_kept_preconditioner() {
        let dir = tempfile::tempdir().unwrap();
        let state = |kept: Vec<u8>| SimulationState {
            nodes: NodeArrays::default(),
            bodies: BodyArrays::default(),
            settings: Settings::default(),
            time_s: 0.25,
            dt_s: 0.01,
            guess_scale: 1.0,
            summary: RunSummary::default(),
            frames_written: 3,
            next_frame_time_s: 0.3,
            frame_times_s: vec![0.0, 0.1, 0.2],
            terms: vec![("gravity".into(), vec![1, 2, 3])],
            kept_preconditioner: kept,
        };
        let head = || header(7, "probe", SceneOrigin::Program, Path::new("out"), 0.25, 25);

        let current = dir.path().join("current.ckpt");
        write(&current, head(), &state(vec![9, 8, 7])).unwrap();
        let (h, back) = read(&current, 7, "probe").unwrap();
        assert_eq!(h.format_version, CHECKPOINT_FORMAT_VERSION);
        assert_eq!(back.kept_preconditioner, vec![9, 8, 7]);

        // Version 3: the same state without its last field (an empty one encodes as one 0 byte).
        let body = postcard::to_allocvec(&state(Vec::new())).unwrap();
        assert_eq!(body.last(), Some(&0));
        let body = &body[..body.len() - 1];
        let mut old = head();
        old.format_version = 3;
        old.state_len = body.len() as u64;
        let mut hash = Fnv::default();
        hash.bytes(body);
        old.state_checksum = hash.finish();
        let mut bytes = postcard::to_allocvec(&old).unwrap();
        bytes.extend_from_slice(body);
        let older = dir.path().join("older.ckpt");
        std::fs::write(&older, bytes).unwrap();
        let (h, back) = read(&older, 7, "probe").unwrap();
        assert_eq!(h.format_version, 3);
        assert!(back.kept_preconditioner.is_empty());
        assert_eq!(back.terms, vec![("gravity".to_string(), vec![1, 2, 3])]);
        assert_eq!(back.frame_times_s, vec![0.0, 0.1, 0.2]);
    }
}

//! Errors a user can act on: each names the object and the field or element at fault.

/// Everything that can go wrong in the library.
#[derive(Debug, thiserror::Error)]
pub enum StarkError {
    /// A parameter value is out of its valid range.
    #[error("`{field}` = {value} on '{object}' {expected}")]
    InvalidParameter {
        /// Object label.
        object: String,
        /// Parameter name.
        field: &'static str,
        /// The offending value.
        value: f64,
        /// What was expected, e.g. "must lie in (0, 0.5)".
        expected: &'static str,
    },
    /// A rest element is degenerate or inverted.
    #[error("{kind} {index} of '{object}': {detail}")]
    BadElement {
        /// Object label.
        object: String,
        /// Element kind ("tet", "triangle", "segment", "hinge").
        kind: &'static str,
        /// Element index within the object.
        index: usize,
        /// What is wrong.
        detail: String,
    },
    /// An element refers to a node that does not exist.
    #[error("{kind} {index} of '{object}' refers to node {node}, but the object has {n_nodes} nodes")]
    NodeOutOfRange {
        /// Object label.
        object: String,
        /// Element kind.
        kind: &'static str,
        /// Element index.
        index: usize,
        /// The node index.
        node: usize,
        /// Number of nodes.
        n_nodes: usize,
    },
    /// A handle does not belong to this simulation.
    #[error("invalid {kind} handle {index}: the simulation has {len}")]
    InvalidHandle {
        /// Handle kind.
        kind: &'static str,
        /// Index in the handle.
        index: usize,
        /// Number of valid objects of that kind.
        len: usize,
    },
    /// Invalid input that is not a single parameter.
    #[error("{0}")]
    InvalidInput(String),
    /// A mesh file could not be read. The loader's error (`io::MeshFileError`) is boxed, so that
    /// this ground floor does not depend on the loaders.
    #[error(transparent)]
    Mesh(Box<dyn std::error::Error + Send + Sync>),
    /// A scene file is invalid.
    #[error("{0}")]
    Scene(String),
    /// A scene file is invalid: the error names the file, the line and column where known, the
    /// entry and the field.
    #[error(transparent)]
    SceneFile(#[from] SceneError),
    /// Writing output failed.
    #[error("cannot write '{path}': {source}")]
    Output {
        /// The file or directory.
        path: String,
        /// The I/O error.
        source: std::io::Error,
    },
    /// A time step could not be completed: its last attempt failed and no retry was left.
    #[error("time step at t = {time_s:.6} s failed at dt = {dt_s:e} s: {reason} ({no_retry})")]
    StepFailed {
        /// Simulation time, s.
        time_s: f64,
        /// Last attempted dt, s.
        dt_s: f64,
        /// Minimum dt, s.
        dt_min_s: f64,
        /// Why the last attempt failed.
        reason: String,
        /// Why it was not retried: the time step is fixed, halving it would go below the
        /// minimum, or the hardening retries are used up.
        no_retry: String,
    },
    /// A run was interrupted (Ctrl-C) between steps; every accepted step is kept.
    #[error("interrupted at t = {time_s:.6} s")]
    Interrupted {
        /// Simulated time when the run stopped, s.
        time_s: f64,
    },
    /// A checkpoint could not be written or read.
    #[error("checkpoint '{path}': {message}")]
    Checkpoint {
        /// The file.
        path: String,
        /// What went wrong.
        message: String,
    },
}

/// An invalid scene file: where the problem is and what it is. Plain data, so it lives here
/// (the scene loader in `io::scene` makes it and re-exports it).
#[derive(Clone, Debug, PartialEq)]
pub struct SceneError {
    /// The file as given to the loader.
    pub file: String,
    /// 1-based line, where known.
    pub line: Option<usize>,
    /// 1-based column in characters, where known.
    pub column: Option<usize>,
    /// The entry and field, e.g. `surface 'cloth' material.strain` (empty for the whole file).
    pub path: String,
    /// What is wrong.
    pub message: String,
}

impl std::fmt::Display for SceneError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.file)?;
        if let Some(line) = self.line {
            write!(f, ":{line}")?;
            if let Some(column) = self.column {
                write!(f, ":{column}")?;
            }
        }
        write!(f, ": ")?;
        if self.path.is_empty() {
            write!(f, "{}", self.message)
        } else if let Some((head, tail)) = self.message.split_once(", expected") {
            write!(f, "{head} in {}, expected{tail}", self.path)
        } else {
            write!(f, "{} in {}", self.message, self.path)
        }
    }
}

impl std::error::Error for SceneError {}

/// Result with [`StarkError`].
pub type Result<T, E = StarkError> = std::result::Result<T, E>;

/// Check that `value` is finite and satisfies `ok`; otherwise an [`StarkError::InvalidParameter`].
pub fn check_param(object: &str, field: &'static str, value: f64, ok: bool, expected: &'static str) -> Result<()> {
    if value.is_nan() || !ok {
        return Err(StarkError::InvalidParameter {
            object: object.to_string(),
            field,
            value,
            expected,
        });
    }
    Ok(())
}

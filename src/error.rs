//! User-facing errors. Every error about input names the file and the field or line, so a
//! user can fix the input without reading the source.

use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: {message}")]
    Parse { path: PathBuf, message: String },
    #[error("{path}: field `{field}`: {message}")]
    Field {
        path: PathBuf,
        field: String,
        message: String,
    },
    /// Bad use of the command line or of a library entry point: an unknown name, a value out
    /// of range, options that do not go together.
    #[error("{0}")]
    Usage(String),
    /// A check that ran and failed: a cross-check disagreement, a stress failure, a χ² test
    /// below its significance level.
    #[error("{0}")]
    Check(String),
    /// A tracer backend that cannot be built or used here: Embree not compiled in or failing,
    /// an ISA this CPU lacks, a BVH the packet backend cannot hold.
    #[error("{0}")]
    Backend(String),
    #[error("{path}: {message}")]
    Output { path: PathBuf, message: String },
    /// A size or count from a flag or a file that would need more memory than there is,
    /// found before anything was allocated (`bounded`).
    #[error(
        "{what}: needs about {} of memory, {} available",
        crate::bounded::human_bytes(*need),
        crate::bounded::human_bytes(*available)
    )]
    Memory {
        what: String,
        need: u64,
        available: u64,
    },
    /// Ctrl-C or SIGTERM: the command stopped early after writing what was complete.
    #[error("interrupted: {0}")]
    Interrupted(String),
}

pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    pub fn field(
        path: impl Into<PathBuf>,
        field: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        Error::Field {
            path: path.into(),
            field: field.into(),
            message: message.into(),
        }
    }

    /// The same kind of error with `prefix: ` before its message (a usage error for kinds
    /// without a plain message).
    pub fn prefixed(self, prefix: &str) -> Self {
        match self {
            Error::Check(m) => Error::Check(format!("{prefix}: {m}")),
            Error::Backend(m) => Error::Backend(format!("{prefix}: {m}")),
            e => Error::Usage(format!("{prefix}: {e}")),
        }
    }

    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }
}

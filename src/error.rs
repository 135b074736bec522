//! The crate-wide error type.
//!
//! Every error that comes from user input names *where* the problem is: the
//! file, and when known the line and/or the field (JSON path, column name),
//! and says what was expected. Use [`Error::parse`] / [`Error::invalid`] and
//! the [`Location`] builder rather than formatting paths by hand.
//! Errors name fields and parameters (`sensor`, `tilt_deg`), never
//! command-line flags: the command line adds those.

use std::fmt;
use std::path::{Path, PathBuf};

/// Where in the user's input a problem was found.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Location {
    /// The file, when the input came from one.
    pub path: Option<PathBuf>,
    /// 1-based line number.
    pub line: Option<usize>,
    /// 1-based column (characters) on that line.
    pub column: Option<usize>,
    /// Field name or JSON path (`objects[2].parts[0].material`).
    pub field: Option<String>,
}

impl Location {
    /// A location in a file.
    pub fn file(path: impl AsRef<Path>) -> Self {
        Location {
            path: Some(path.as_ref().to_path_buf()),
            ..Default::default()
        }
    }
    /// A location naming only a field (e.g. a command-line option).
    pub fn field(field: impl Into<String>) -> Self {
        Location {
            field: Some(field.into()),
            ..Default::default()
        }
    }
    /// The same location at a 1-based line.
    pub fn at_line(mut self, line: usize) -> Self {
        self.line = Some(line);
        self
    }
    /// The same location at a 1-based line and column.
    pub fn at(mut self, line: usize, column: usize) -> Self {
        self.line = Some(line);
        self.column = Some(column);
        self
    }
    /// The same location with a field name / JSON path.
    pub fn with_field(mut self, field: impl Into<String>) -> Self {
        self.field = Some(field.into());
        self
    }
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut wrote = false;
        if let Some(p) = &self.path {
            write!(f, "{}", p.display())?;
            wrote = true;
        }
        if let Some(l) = self.line {
            write!(f, "{}line {l}", if wrote { ":" } else { "" })?;
            if let Some(c) = self.column {
                write!(f, ": column {c}")?;
            }
            wrote = true;
        }
        if let Some(fl) = &self.field {
            write!(f, "{}field `{fl}`", if wrote { ": " } else { "" })?;
            wrote = true;
        }
        if !wrote {
            write!(f, "<input>")?;
        }
        Ok(())
    }
}

/// The crate's error type.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A file could not be read or written.
    // The OS error is part of the message, not a `#[source]`: `{:#}` chains
    // would otherwise print it twice.
    #[error("{}: {error}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        error: std::io::Error,
    },
    /// Input that could not be parsed or failed validation.
    #[error("{location}: {message}")]
    Parse {
        /// Where.
        location: Location,
        /// What was wrong and what was expected.
        message: String,
    },
    /// An argument or value outside its valid domain (not tied to a file).
    #[error("{field}: {message}")]
    Invalid {
        /// The parameter's name.
        field: String,
        /// What was wrong and what was expected.
        message: String,
    },
    /// An error reported by Embree (through its device error callback).
    #[error("Embree: {0}")]
    Embree(String),
    /// Anything else.
    #[error("{0}")]
    Other(String),
}

impl Error {
    /// An I/O error on `path`.
    pub fn io(path: impl AsRef<Path>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.as_ref().to_path_buf(),
            error: source,
        }
    }
    /// A parse/validation error at `location`.
    pub fn parse(location: Location, message: impl Into<String>) -> Self {
        Error::Parse {
            location,
            message: message.into(),
        }
    }
    /// An invalid parameter value.
    pub fn invalid(field: impl Into<String>, message: impl Into<String>) -> Self {
        Error::Invalid {
            field: field.into(),
            message: message.into(),
        }
    }
}

/// Result with the crate's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

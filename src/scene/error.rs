//! Scene errors: the file and a [`SceneErrorKind`] naming the key.

use std::fmt;
use std::path::{Path, PathBuf};

/// What is wrong with a scene. Every variant except [`Syntax`](Self::Syntax),
/// [`Io`](Self::Io) and [`Read`](Self::Read) names the offending key in TOML notation (`beam.length[3]`,
/// `loads.point[0].node`, `control.values`).
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum SceneErrorKind {
    /// The text is not valid TOML.
    Syntax {
        /// 1-based line of the error, when known.
        line: Option<usize>,
        /// 1-based column (in characters) of the error, when known.
        column: Option<usize>,
        /// The parser's description.
        message: String,
    },
    /// Two ways of giving the same quantities were both used (`beam.length` with `[pipe]`).
    ExclusiveKeys {
        /// The key given with `other`.
        key: String,
        /// The key or table it excludes.
        other: String,
        /// What to give instead.
        note: String,
    },
    /// A key that the format does not have.
    UnknownKey {
        /// The full key, e.g. `beam.lenght`.
        key: String,
        /// The keys allowed at that place.
        expected: Vec<String>,
    },
    /// A required key is absent.
    MissingKey {
        /// The full key, e.g. `time.step`.
        key: String,
        /// Why it is required, when that depends on other keys.
        note: Option<String>,
    },
    /// A value of the wrong TOML type (a string for a number, a float for a count, ...).
    WrongType {
        /// The full key.
        key: String,
        /// What the key takes, e.g. `a number or an array of numbers`.
        expected: String,
        /// What was found, e.g. `string "abc"`.
        found: String,
    },
    /// A value of the right type but not allowed: non-finite, out of range, unknown name, over a
    /// size limit.
    InvalidValue {
        /// The full key.
        key: String,
        /// What is wrong, e.g. `must be positive and finite, got -1`.
        reason: String,
    },
    /// A node index outside 1..=n.
    NodeOutOfRange {
        /// The full key, e.g. `loads.point[0].node`.
        key: String,
        /// The node given.
        node: i64,
        /// The number of pendulums n.
        n: usize,
    },
    /// An array with the wrong number of values.
    WrongCount {
        /// The full key, e.g. `control.values`.
        key: String,
        /// The number of values required.
        expected: usize,
        /// The number of values given.
        found: usize,
    },
    /// A key given twice (TOML allows each key once per table).
    DuplicateKey {
        /// The full key, e.g. `time.steps`.
        key: String,
        /// 1-based line of the second occurrence.
        line: usize,
        /// 1-based column (in characters) of the second occurrence.
        column: usize,
        /// 1-based line of the first occurrence, when found.
        first_line: Option<usize>,
    },
    /// A load's time-series file (`loads.point[i].series`) is missing, unreadable or invalid.
    SeriesFile {
        /// The full key, e.g. `loads.point[0].series`.
        key: String,
        /// The series file, as named in the scene.
        file: PathBuf,
        /// 1-based line of the file, when the problem is on one line.
        line: Option<usize>,
        /// What is wrong, e.g. `times must increase strictly: t = 0.5 after t = 0.6 (line 4)`.
        reason: String,
    },
    /// The scene file could not be read.
    Io {
        /// The operating system's message.
        message: String,
    },
    /// The scene file is not an input the bounded reader accepts
    /// ([`read_text_file`](super::read_text_file)): a directory, over the size limit, or not
    /// UTF-8 text (the reason gives the line).
    Read {
        /// What is wrong ([`ReadErrorKind::Io`](super::ReadErrorKind::Io) is reported as
        /// [`SceneErrorKind::Io`]).
        reason: super::ReadErrorKind,
    },
}

impl SceneErrorKind {
    /// The offending key, if the error has one.
    pub fn key(&self) -> Option<&str> {
        match self {
            Self::UnknownKey { key, .. }
            | Self::MissingKey { key, .. }
            | Self::ExclusiveKeys { key, .. }
            | Self::WrongType { key, .. }
            | Self::InvalidValue { key, .. }
            | Self::NodeOutOfRange { key, .. }
            | Self::WrongCount { key, .. }
            | Self::DuplicateKey { key, .. }
            | Self::SeriesFile { key, .. } => Some(key),
            Self::Syntax { .. } | Self::Io { .. } | Self::Read { .. } => None,
        }
    }
}

/// `key` for display: the document itself when empty.
fn show_key(key: &str) -> &str {
    if key.is_empty() {
        "<document>"
    } else {
        key
    }
}

impl fmt::Display for SceneErrorKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Syntax {
                line,
                column,
                message,
            } => match (line, column) {
                (Some(l), Some(c)) => write!(f, "syntax error at line {l}, column {c}: {message}"),
                (Some(l), None) => write!(f, "syntax error at line {l}: {message}"),
                _ => write!(f, "syntax error: {message}"),
            },
            Self::UnknownKey { key, expected } => {
                write!(f, "key `{}`: unknown key", show_key(key))?;
                if !expected.is_empty() {
                    let list: Vec<String> = expected.iter().map(|k| format!("`{k}`")).collect();
                    write!(f, " (expected one of {})", list.join(", "))?;
                }
                Ok(())
            }
            Self::ExclusiveKeys { key, other, note } => write!(
                f,
                "key `{}` cannot be given together with `{other}`: {note}",
                show_key(key)
            ),
            Self::MissingKey { key, note } => {
                write!(f, "key `{}`: missing required key", show_key(key))?;
                if let Some(note) = note {
                    write!(f, " ({note})")?;
                }
                Ok(())
            }
            Self::WrongType {
                key,
                expected,
                found,
            } => write!(
                f,
                "key `{}`: wrong type: expected {expected}, got {found}",
                show_key(key)
            ),
            Self::InvalidValue { key, reason } => write!(f, "key `{}`: {reason}", show_key(key)),
            Self::NodeOutOfRange { key, node, n } => write!(
                f,
                "key `{}`: node {node} is out of range (nodes are 1..={n})",
                show_key(key)
            ),
            Self::WrongCount {
                key,
                expected,
                found,
            } => write!(
                f,
                "key `{}`: expected {expected} value{}, got {found}",
                show_key(key),
                if *expected == 1 { "" } else { "s" }
            ),
            Self::DuplicateKey {
                key,
                line,
                column,
                first_line,
            } => {
                write!(
                    f,
                    "key `{}`: given twice, again at line {line}, column {column}",
                    show_key(key)
                )?;
                if let Some(first) = first_line {
                    write!(f, " (first at line {first})")?;
                }
                write!(f, "; each key may appear once")
            }
            Self::SeriesFile {
                key,
                file,
                line,
                reason,
            } => {
                write!(
                    f,
                    "key `{}`: series file `{}`",
                    show_key(key),
                    file.display()
                )?;
                if let Some(l) = line {
                    write!(f, ", line {l}")?;
                }
                write!(f, ": {reason}")
            }
            Self::Io { message } => write!(f, "cannot read scene file: {message}"),
            Self::Read { reason } => write!(f, "{reason}"),
        }
    }
}

/// `"<file>: "` or `"invalid scene: "`.
fn file_prefix(file: &Option<PathBuf>) -> String {
    match file {
        Some(p) => format!("{}: ", p.display()),
        None => "invalid scene: ".to_string(),
    }
}

/// A problem with a scene: the file it came from (if any) and what is wrong
/// ([`SceneErrorKind`], which names the key). Displayed as
/// ``scene.toml: key `beam.mass`: must be positive and finite, got -1``.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{}{kind}", file_prefix(.file))]
pub struct SceneError {
    /// The scene file, when the scene was read with [`Scene::from_file`](super::Scene::from_file).
    pub file: Option<PathBuf>,
    /// What is wrong.
    pub kind: SceneErrorKind,
}

impl SceneError {
    /// An error without a file.
    pub fn new(kind: SceneErrorKind) -> Self {
        Self { file: None, kind }
    }

    /// The same error, attributed to `file`.
    pub fn with_file(mut self, file: impl AsRef<Path>) -> Self {
        self.file = Some(file.as_ref().to_path_buf());
        self
    }

    /// The offending key, if the error has one (see [`SceneErrorKind::key`]).
    pub fn key(&self) -> Option<&str> {
        self.kind.key()
    }

    pub(super) fn invalid(key: impl Into<String>, reason: impl Into<String>) -> Self {
        Self::new(SceneErrorKind::InvalidValue {
            key: key.into(),
            reason: reason.into(),
        })
    }

    pub(super) fn count(key: impl Into<String>, expected: usize, found: usize) -> Self {
        Self::new(SceneErrorKind::WrongCount {
            key: key.into(),
            expected,
            found,
        })
    }
}

impl From<SceneErrorKind> for SceneError {
    fn from(kind: SceneErrorKind) -> Self {
        Self::new(kind)
    }
}

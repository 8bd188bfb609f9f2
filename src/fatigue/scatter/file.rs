//! The scatter-diagram CSV file (`chainbeam fatigue --scatter FILE`, the Python package's
//! `fatigue(scatter="FILE")`): one reader for every front end, through the bounded input reader
//! ([`crate::scene::read_text_file`]: at most 1 GiB, UTF-8 text, a directory refused), then the
//! `csv` crate.
//!
//! The format: a header naming the columns `hs`, `tp`, `probability` and optionally `direction`
//! (any order, each once, no other column), then one cell per row: H_s \[m\] > 0, T_p \[s\] > 0, a
//! probability in \[0, 1\] and a finite direction \[°\]. Fields are trimmed; lines starting with
//! `#` are comments. The diagram is checked as a whole where it is read: at least one cell, at
//! most [`MAX_SCATTER_CELLS`], and probabilities that
//! add up to more than 0 and at most 1 ([`crate::fatigue::combine_scatter`]'s rules).

use std::fmt;
use std::path::{Path, PathBuf};

use super::MAX_SCATTER_CELLS;
use super::{ScatterCell, SeaState};
use crate::fatigue::{combine_scatter, CellDamage, FatigueError};
use crate::input::{read_text_file, ReadErrorKind};

/// The columns of a scatter CSV, in the order of [`ScatterCell`]'s fields.
pub const SCATTER_COLUMNS: [&str; 4] = ["hs", "tp", "probability", "direction"];

/// What is wrong with a scatter file ([`ScatterFileError`]).
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum ScatterFileErrorKind {
    /// The file could not be read (the bounded reader's reason).
    Read(ReadErrorKind),
    /// The CSV itself is malformed (rows of unequal length, …).
    Csv {
        /// The `csv` crate's message.
        message: String,
    },
    /// A header column that is not one of [`SCATTER_COLUMNS`].
    UnknownColumn {
        /// 1-based column.
        column: usize,
        /// Its name.
        name: String,
    },
    /// A column named twice in the header (which one would be the cell's value is ambiguous).
    DuplicateColumn {
        /// The name.
        name: String,
        /// 1-based columns of its first and second appearance.
        columns: (usize, usize),
    },
    /// A required column (`hs`, `tp`, `probability`) is missing.
    MissingColumn {
        /// Its name.
        name: &'static str,
    },
    /// A field that is not a valid value of its column.
    BadValue {
        /// 1-based line.
        line: u64,
        /// 1-based column.
        column: usize,
        /// The column's name.
        name: &'static str,
        /// The field as written.
        field: String,
        /// What it must be.
        expected: &'static str,
    },
    /// More rows than [`MAX_SCATTER_CELLS`].
    TooManyCells {
        /// The line of the first row over the limit.
        line: u64,
    },
    /// No rows after the header.
    NoCells,
    /// The diagram as a whole: probabilities that add up to more than 1 or to 0.
    Diagram(FatigueError),
}

impl fmt::Display for ScatterFileErrorKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        const HEADER: &str = "the header is hs,tp,probability[,direction]";
        match self {
            Self::Read(k) => write!(f, "{k}"),
            Self::Csv { message } => f.write_str(message),
            Self::UnknownColumn { column, name } => {
                write!(
                    f,
                    "line 1, column {column}: unknown column `{name}` ({HEADER})"
                )
            }
            Self::DuplicateColumn { name, columns } => write!(
                f,
                "line 1, columns {} and {}: the column `{name}` is named twice ({HEADER}, each \
                 once)",
                columns.0, columns.1
            ),
            Self::MissingColumn { name } => write!(f, "line 1: no column `{name}` ({HEADER})"),
            Self::BadValue {
                line,
                column,
                name,
                field,
                expected,
            } => write!(
                f,
                "line {line}, column {column} (`{name}`): `{field}` is not {expected}"
            ),
            Self::TooManyCells { line } => {
                write!(f, "line {line}: more than {MAX_SCATTER_CELLS} cells")
            }
            Self::NoCells => f.write_str("no cells (rows after the header)"),
            Self::Diagram(e) => write!(f, "{e}"),
        }
    }
}

/// A scatter file that could not be read: the file (as named) and why, displayed as
/// `FILE: REASON` (`d.csv: line 3, column 2 (`tp`): `x` is not a positive number (T_p, s)`).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{}: {kind}", file.display())]
pub struct ScatterFileError {
    /// The file, as named by the caller.
    pub file: PathBuf,
    /// What is wrong.
    pub kind: ScatterFileErrorKind,
}

/// Reads a scatter-diagram CSV file (module docs).
///
/// # Errors
/// [`ScatterFileError`] naming the file and, for a bad field, its line and column.
pub fn read_scatter_file(path: impl AsRef<Path>) -> Result<Vec<ScatterCell>, ScatterFileError> {
    let path = path.as_ref();
    let fail = |kind| ScatterFileError {
        file: path.to_path_buf(),
        kind,
    };
    let text = read_text_file(path).map_err(|e| fail(ScatterFileErrorKind::Read(e.kind)))?;
    parse_scatter(&text).map_err(fail)
}

/// Parses the text of a scatter-diagram CSV (module docs).
///
/// # Errors
/// The [`ScatterFileErrorKind`] of the first problem.
pub fn parse_scatter(text: &str) -> Result<Vec<ScatterCell>, ScatterFileErrorKind> {
    let csv_error = |e: csv::Error| ScatterFileErrorKind::Csv {
        message: e.to_string(),
    };
    let mut reader = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .comment(Some(b'#'))
        .from_reader(text.as_bytes());
    let header = reader.headers().map_err(csv_error)?.clone();
    // Each column's place in the header, each name once.
    let mut place: [Option<usize>; 4] = [None; 4];
    for (i, h) in header.iter().enumerate() {
        let Some(c) = SCATTER_COLUMNS.iter().position(|&name| name == h) else {
            return Err(ScatterFileErrorKind::UnknownColumn {
                column: i + 1,
                name: h.to_string(),
            });
        };
        if let Some(first) = place[c] {
            return Err(ScatterFileErrorKind::DuplicateColumn {
                name: h.to_string(),
                columns: (first + 1, i + 1),
            });
        }
        place[c] = Some(i);
    }
    let required = |c: usize| {
        place[c].ok_or(ScatterFileErrorKind::MissingColumn {
            name: SCATTER_COLUMNS[c],
        })
    };
    let (hs_col, tp_col, p_col) = (required(0)?, required(1)?, required(2)?);
    let dir_col = place[3];
    let mut cells = Vec::new();
    for record in reader.records() {
        let record = record.map_err(csv_error)?;
        let line = record.position().map_or(0, |p| p.line());
        if cells.len() == MAX_SCATTER_CELLS {
            return Err(ScatterFileErrorKind::TooManyCells { line });
        }
        let value = |col: usize, name: &'static str, ok: fn(f64) -> bool, expected| {
            let field = record.get(col).unwrap_or("");
            match field.parse::<f64>() {
                Ok(v) if ok(v) => Ok(v),
                _ => Err(ScatterFileErrorKind::BadValue {
                    line,
                    column: col + 1,
                    name,
                    field: field.to_string(),
                    expected,
                }),
            }
        };
        let positive = |v: f64| v.is_finite() && v > 0.0;
        cells.push(ScatterCell {
            sea: SeaState {
                hs: value(hs_col, "hs", positive, "a positive number (H_s, m)")?,
                tp: value(tp_col, "tp", positive, "a positive number (T_p, s)")?,
                direction: match dir_col {
                    Some(c) => Some(value(
                        c,
                        "direction",
                        f64::is_finite,
                        "a finite angle (degrees)",
                    )?),
                    None => None,
                },
            },
            probability: value(
                p_col,
                "probability",
                |v| (0.0..=1.0).contains(&v),
                "a probability in [0, 1]",
            )?,
        });
    }
    if cells.is_empty() {
        return Err(ScatterFileErrorKind::NoCells);
    }
    check_diagram(&cells).map_err(ScatterFileErrorKind::Diagram)?;
    Ok(cells)
}

/// The diagram's probabilities as [`combine_scatter`] checks them (each in \[0, 1\], the sum in
/// (0, 1 + 10⁻⁶]), before any run: the one check of a diagram, wherever it comes from.
///
/// # Errors
/// [`FatigueError::InvalidProbability`], [`FatigueError::ProbabilitySum`],
/// [`FatigueError::EmptyDiagram`].
pub fn check_diagram(cells: &[ScatterCell]) -> Result<(), FatigueError> {
    let probe: Vec<CellDamage> = cells
        .iter()
        .map(|c| CellDamage {
            probability: c.probability,
            damage: 0.0,
            duration_s: 1.0,
        })
        .collect();
    combine_scatter(&probe).map(|_| ())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A repeated column is refused naming both places (the first used to win silently); the
    /// fields of a good file are the numbers written in it.
    #[test]
    fn columns_each_once() {
        let e = parse_scatter("hs,tp,probability,tp\n1,8,0.5,9\n").unwrap_err();
        assert_eq!(
            e,
            ScatterFileErrorKind::DuplicateColumn {
                name: "tp".into(),
                columns: (2, 4)
            }
        );
        assert!(e.to_string().contains("columns 2 and 4"), "{e}");
        let cells = parse_scatter("tp, hs ,probability\n# c\n8,1.5,0.25\n").unwrap();
        assert_eq!(cells.len(), 1);
        let bits = |c: &ScatterCell| [c.sea.hs, c.sea.tp, c.probability].map(f64::to_bits);
        assert_eq!(bits(&cells[0]), [1.5f64, 8.0, 0.25].map(f64::to_bits));
    }

    /// Probabilities that add up to 0 describe no time: refused, not an infinite life.
    #[test]
    fn zero_probabilities_are_refused() {
        let e = parse_scatter("hs,tp,probability\n1,8,0\n2,9,0.0\n").unwrap_err();
        assert_eq!(
            e,
            ScatterFileErrorKind::Diagram(FatigueError::EmptyDiagram { cells: 2 })
        );
        assert!(e.to_string().contains("add up to 0"), "{e}");
    }
}

//! Time series of a point load, (t, F_x, F_z) rows read from a CSV file and linearly interpolated
//! (docs/scene-format.md, "Time series files").

use std::path::{Path, PathBuf};

use crate::input::{read_text_file, ReadErrorKind, MAX_INPUT_BYTES};

use super::ranges::FORCE_RANGE;
use super::{SceneError, SceneErrorKind};

/// Largest series file read (1 GiB, the limit [`MAX_INPUT_BYTES`] of every input file), so that
/// a wrong file name fails at once instead of filling memory.
pub const MAX_SERIES_BYTES: u64 = MAX_INPUT_BYTES;

/// A load's time series: rows (t, F_x, F_z) with strictly increasing times, the force at other
/// times interpolated linearly between neighbouring rows (and held at the first and last rows
/// outside them; a scene's validation requires the rows to cover the times the load acts).
///
/// The file is CSV: one row `t, fx, fz` per line (\[s\], \[N\], \[N\], thesis sign: the load
/// enters H as +F·r), optionally a header line `t,fx,fz` first; blank lines and lines starting
/// with `#` are skipped.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadSeries {
    /// The file name as given (in a scene file: relative to the scene file's directory); written
    /// back by [`crate::Scene::to_toml_string`].
    pub file: PathBuf,
    /// The rows (t, F_x, F_z).
    pub samples: Vec<[f64; 3]>,
}

/// A problem with a series file: line (if any) and what is wrong.
struct RowError {
    line: Option<usize>,
    reason: String,
}

fn row_error(line: Option<usize>, reason: impl Into<String>) -> RowError {
    RowError {
        line,
        reason: reason.into(),
    }
}

impl LoadSeries {
    /// A series from rows given in code, validated as a file's rows are (the error names `key`
    /// and the row, counted from 1).
    pub fn new(file: impl Into<PathBuf>, samples: Vec<[f64; 3]>) -> Result<Self, SceneError> {
        let s = LoadSeries {
            file: file.into(),
            samples,
        };
        s.check("series")?;
        Ok(s)
    }

    /// Reads a series file (relative names from the current directory).
    pub fn read(path: impl AsRef<Path>) -> Result<Self, SceneError> {
        let path = path.as_ref();
        Self::read_at("series", path, path)
    }

    /// Reads the file `resolved`, reporting errors under `key` and the name `written`. The file
    /// goes through the bounded [`read_text_file`] (a regular file or a stream, at most
    /// [`MAX_SERIES_BYTES`], UTF-8 text: a bad byte is reported with its line).
    pub(super) fn read_at(key: &str, written: &Path, resolved: &Path) -> Result<Self, SceneError> {
        let text = read_text_file(resolved).map_err(|e| {
            let line = e.line();
            let reason = match e.kind {
                // The line is reported by the error's own field.
                ReadErrorKind::NotUtf8 { offset, .. } => {
                    format!("invalid UTF-8 (byte {offset}): the file must be UTF-8 text")
                }
                ReadErrorKind::NulByte { offset, .. } => {
                    format!("a NUL byte (byte {offset}): binary data, not a CSV file")
                }
                other => other.to_string(),
            };
            series_error(key, written, row_error(line, reason))
        })?;
        Self::parse_at(key, written, &text)
    }

    /// Parses the text of a series file called `file` (for messages).
    pub fn parse(text: &str, file: impl Into<PathBuf>) -> Result<Self, SceneError> {
        let file = file.into();
        Self::parse_at("series", &file.clone(), text)
    }

    fn parse_at(key: &str, file: &Path, text: &str) -> Result<Self, SceneError> {
        let rows = parse_rows(text).map_err(|e| series_error(key, file, e))?;
        Ok(LoadSeries {
            file: file.to_path_buf(),
            samples: rows,
        })
    }

    /// Checks rows given in code (a parsed file was checked line by line already).
    pub(super) fn check(&self, key: &str) -> Result<(), SceneError> {
        check_rows(&self.samples, |i| format!("row {}", i + 1), |_| None)
            .map_err(|e| series_error(key, &self.file, e))
    }

    /// The first and last times \[s\].
    pub fn span(&self) -> (f64, f64) {
        match (self.samples.first(), self.samples.last()) {
            (Some(a), Some(b)) => (a[0], b[0]),
            _ => (0.0, 0.0),
        }
    }

    /// (F_x, F_z) at time t: linear interpolation between the rows around t, the first or last
    /// row outside them. Exact at a row's time.
    #[inline]
    pub fn at(&self, t: f64) -> [f64; 2] {
        interpolate(&self.samples, t)
    }

    /// The series as CSV text with a header, numbers written so that they read back exactly.
    pub fn to_csv(&self) -> String {
        let mut s = String::from("t,fx,fz\n");
        for r in &self.samples {
            s.push_str(&format!("{},{},{}\n", r[0], r[1], r[2]));
        }
        s
    }
}

/// (F_x, F_z) at t from rows (t, F_x, F_z) sorted by t (see [`LoadSeries::at`]).
#[inline]
pub(crate) fn interpolate(rows: &[[f64; 3]], t: f64) -> [f64; 2] {
    let (Some(first), Some(last)) = (rows.first(), rows.last()) else {
        return [0.0, 0.0];
    };
    if t <= first[0] {
        return [first[1], first[2]];
    }
    if t >= last[0] {
        return [last[1], last[2]];
    }
    // first[0] < t < last[0]: 1 ≤ i ≤ len − 1
    let i = rows.partition_point(|r| r[0] <= t);
    let (a, b) = (rows[i - 1], rows[i]);
    let w = (t - a[0]) / (b[0] - a[0]);
    [a[1] + w * (b[1] - a[1]), a[2] + w * (b[2] - a[2])]
}

fn series_error(key: &str, file: &Path, e: RowError) -> SceneError {
    SceneErrorKind::SeriesFile {
        key: key.to_string(),
        file: file.to_path_buf(),
        line: e.line,
        reason: e.reason,
    }
    .into()
}

const COLUMNS: [&str; 3] = ["t", "fx", "fz"];

/// The rows of a series file, each line checked (numbers, finite, range, increasing times).
fn parse_rows(text: &str) -> Result<Vec<[f64; 3]>, RowError> {
    let mut rows = Vec::new();
    let mut lines_of = Vec::new();
    let mut header_allowed = true;
    for (i, raw) in text.lines().enumerate() {
        let line_no = i + 1;
        let line = raw.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        if header_allowed {
            header_allowed = false;
            let names: Vec<String> = fields.iter().map(|f| f.to_ascii_lowercase()).collect();
            if names == COLUMNS {
                continue;
            }
        }
        if fields.len() != 3 {
            return Err(row_error(
                Some(line_no),
                format!(
                    "expected 3 numbers `t, fx, fz` separated by commas, got {} field{}",
                    fields.len(),
                    if fields.len() == 1 { "" } else { "s" }
                ),
            ));
        }
        let mut row = [0.0; 3];
        for (c, f) in fields.iter().enumerate() {
            row[c] = f.parse::<f64>().map_err(|_| {
                row_error(
                    Some(line_no),
                    format!("`{f}` in column {} is not a number", COLUMNS[c]),
                )
            })?;
        }
        rows.push(row);
        lines_of.push(line_no);
    }
    check_rows(
        &rows,
        |i| format!("line {}", lines_of[i]),
        |i| Some(lines_of[i]),
    )?;
    Ok(rows)
}

/// The rules every series obeys: at least two rows, finite values, forces in range, strictly
/// increasing times. `name(i)` and `line(i)` say where row i came from.
fn check_rows(
    rows: &[[f64; 3]],
    name: impl Fn(usize) -> String,
    line: impl Fn(usize) -> Option<usize>,
) -> Result<(), RowError> {
    if rows.len() < 2 {
        return Err(row_error(
            None,
            format!(
                "a series needs at least 2 rows `t, fx, fz` to interpolate between, got {}",
                rows.len()
            ),
        ));
    }
    // `line(i)` already names the place when there is one; otherwise the reason does.
    let at = |i: usize| match line(i) {
        Some(_) => String::new(),
        None => format!("{}: ", name(i)),
    };
    for (i, r) in rows.iter().enumerate() {
        for c in 0..3 {
            if !r[c].is_finite() {
                return Err(row_error(
                    line(i),
                    format!(
                        "{}{} is {}; every value must be finite",
                        at(i),
                        COLUMNS[c],
                        r[c]
                    ),
                ));
            }
        }
        for c in 1..3 {
            if !FORCE_RANGE.contains(r[c]) {
                return Err(row_error(
                    line(i),
                    format!(
                        "{}{} = {} N is outside the supported range [{:e}, {:e}] N",
                        at(i),
                        COLUMNS[c],
                        r[c],
                        FORCE_RANGE.min,
                        FORCE_RANGE.max
                    ),
                ));
            }
        }
        if i > 0 && r[0] <= rows[i - 1][0] {
            return Err(row_error(
                line(i),
                format!(
                    "{}times must increase strictly: t = {} after t = {} ({})",
                    at(i),
                    r[0],
                    rows[i - 1][0],
                    name(i - 1)
                ),
            ));
        }
    }
    Ok(())
}

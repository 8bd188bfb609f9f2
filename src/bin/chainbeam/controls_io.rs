//! Reading `--controls FILE`: the controls that `optimize` (or `gradient`) wrote, or a column of a
//! CSV file, so that results round-trip between the subcommands.
//!
//! Accepted forms (the first non-blank character decides):
//! - **JSON object** (`{`): the array under `controls`, as `optimize` and `gradient` write it; its
//!   `control_kind` (`"constant"`, `"per-step"`, `"piecewise"`, with `pieces` for the last), when
//!   present, says how the values map to the forces u_0..u_N.
//! - **JSON array** (`[`): the values themselves.
//! - **CSV**: a header line and rows; the column named `control` is read (the last column of a
//!   `simulate` CSV). A file with a one-field header reads that column; a file whose first line
//!   is a number is a single column without a header. Blank lines and lines starting with `#`
//!   are skipped.
//!
//! Without a declared kind, 1 value is a constant force and N + 1 values are the per-step forces
//! u_0..u_N (N = `time.steps`); anything else is an error naming the file and both counts. Every
//! value must be finite.

use std::fs;
use std::path::{Path, PathBuf};

use chainbeam::{Parametrisation, PerStepControl, PiecewiseControl};

use crate::CliError;

/// How the values of a controls file map to forces, as declared in the file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Declared {
    /// One value for all steps.
    Constant,
    /// One value per time t_k, k = 0..=N.
    PerStep,
    /// `pieces` values, piecewise constant.
    Piecewise(usize),
}

/// A parsed controls file.
#[derive(Clone, Debug)]
pub struct ControlsFile {
    /// The file (for messages).
    pub path: PathBuf,
    /// The values, in file order.
    pub values: Vec<f64>,
    /// The kind the file declares (JSON `control_kind`), if any.
    pub declared: Option<Declared>,
}

fn err(path: &Path, what: impl std::fmt::Display) -> CliError {
    CliError::msg(format!("{}: {what}", path.display()))
}

/// Reads and checks (non-empty, finite) a controls file.
pub fn read(path: &Path) -> Result<ControlsFile, CliError> {
    let text = fs::read_to_string(path)
        .map_err(|e| err(path, format_args!("cannot read the controls file: {e}")))?;
    let trimmed = text.trim_start();
    let (values, declared) = if trimmed.starts_with('{') || trimmed.starts_with('[') {
        from_json(path, &text)?
    } else {
        (from_csv(path, &text)?, None)
    };
    if values.is_empty() {
        return Err(err(path, "the controls file holds no values"));
    }
    Ok(ControlsFile {
        path: path.to_path_buf(),
        values,
        declared,
    })
}

fn from_json(path: &Path, text: &str) -> Result<(Vec<f64>, Option<Declared>), CliError> {
    let v: serde_json::Value =
        serde_json::from_str(text).map_err(|e| err(path, format_args!("not valid JSON: {e}")))?;
    let (array, key) =
        match &v {
            serde_json::Value::Array(a) => (a, "the top-level array"),
            serde_json::Value::Object(o) => match o.get("controls") {
                Some(serde_json::Value::Array(a)) => (a, "key `controls`"),
                Some(other) => {
                    return Err(err(
                        path,
                        format_args!("key `controls`: expected an array of numbers, got {other}"),
                    ))
                }
                None => return Err(err(
                    path,
                    "key `controls` is missing (expected the JSON that `chainbeam optimize` or \
                     `gradient` writes)",
                )),
            },
            _ => unreachable!("the text starts with '{{' or '['"),
        };
    let mut values = Vec::with_capacity(array.len());
    for (i, x) in array.iter().enumerate() {
        match x.as_f64() {
            Some(f) if f.is_finite() => values.push(f),
            _ => {
                return Err(err(
                    path,
                    format_args!("{key}: entry {i} is not a finite number: {x}"),
                ))
            }
        }
    }
    let declared = match v.get("control_kind") {
        None => None,
        Some(k) => Some(match k.as_str() {
            Some("constant") => Declared::Constant,
            Some("per-step") => Declared::PerStep,
            Some("piecewise") => {
                let p = v
                    .get("pieces")
                    .and_then(serde_json::Value::as_u64)
                    .and_then(|p| usize::try_from(p).ok())
                    .ok_or_else(|| {
                        err(
                            path,
                            "key `pieces`: `control_kind` is \"piecewise\" but `pieces` is \
                             missing or not a whole number",
                        )
                    })?;
                Declared::Piecewise(p)
            }
            _ => {
                return Err(err(
                    path,
                    format_args!(
                        "key `control_kind`: expected \"constant\", \"per-step\" or \
                         \"piecewise\", got {k}"
                    ),
                ))
            }
        }),
    };
    Ok((values, declared))
}

fn parse_number(path: &Path, line: usize, field: &str) -> Result<f64, CliError> {
    let f = field.trim();
    match f.parse::<f64>() {
        Ok(x) if x.is_finite() => Ok(x),
        Ok(_) => Err(err(
            path,
            format_args!("line {line}: the control value `{f}` is not finite"),
        )),
        Err(_) => Err(err(
            path,
            format_args!("line {line}: the control value `{f}` is not a number"),
        )),
    }
}

fn from_csv(path: &Path, text: &str) -> Result<Vec<f64>, CliError> {
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
    let Some((first_no, first)) = lines.next() else {
        return Ok(Vec::new());
    };
    let fields: Vec<&str> = first.split(',').map(str::trim).collect();
    let mut values = Vec::new();
    let (column, width) = if fields.len() == 1 && fields[0].parse::<f64>().is_ok() {
        // A bare column of numbers.
        values.push(parse_number(path, first_no, fields[0])?);
        (0, 1)
    } else if let Some(c) = fields.iter().position(|f| *f == "control") {
        (c, fields.len())
    } else if fields.len() == 1 {
        (0, 1)
    } else {
        let shown: Vec<&str> = fields.iter().take(8).copied().collect();
        return Err(err(
            path,
            format_args!(
                "no `control` column in the CSV header (columns: {}{}); give the CSV that \
                 `chainbeam simulate` writes, a single column, or the JSON of `optimize`",
                shown.join(","),
                if fields.len() > 8 { ",..." } else { "" }
            ),
        ));
    };
    for (no, line) in lines {
        let row: Vec<&str> = line.split(',').collect();
        if row.len() != width {
            return Err(err(
                path,
                format_args!(
                    "line {no}: expected {width} field{}, got {}",
                    if width == 1 { "" } else { "s" },
                    row.len()
                ),
            ));
        }
        values.push(parse_number(path, no, row[column])?);
    }
    Ok(values)
}

impl ControlsFile {
    /// The parametrisation of these values on a scene with N = `steps` (module docs), checking
    /// the count.
    pub fn parametrisation(&self, steps: usize) -> Result<Parametrisation, CliError> {
        let got = self.values.len();
        let n1 = steps + 1;
        let want = |what: String| {
            Err(err(
                &self.path,
                format_args!("expected {what}, got {got} value{}", plural(got)),
            ))
        };
        match self.declared {
            Some(Declared::Constant) if got == 1 => Ok(Parametrisation::Constant),
            Some(Declared::Constant) => want("1 value (control_kind \"constant\")".into()),
            Some(Declared::PerStep) if got == n1 => {
                Ok(Parametrisation::PerStep(PerStepControl { steps }))
            }
            Some(Declared::PerStep) => want(format!(
                "N + 1 = {n1} values u_0..u_N for this scene (time.steps = {steps}; \
                 control_kind \"per-step\")"
            )),
            Some(Declared::Piecewise(p)) if p != got => {
                want(format!("pieces = {p} values (control_kind \"piecewise\")"))
            }
            Some(Declared::Piecewise(p)) if p == 0 || p > steps => Err(err(
                &self.path,
                format_args!(
                    "key `pieces`: {p} pieces do not fit this scene's N = {steps} steps \
                     (time.steps); expected 1..={steps}"
                ),
            )),
            Some(Declared::Piecewise(p)) => Ok(Parametrisation::Piecewise(PiecewiseControl {
                steps,
                pieces: p,
            })),
            None if got == 1 => Ok(Parametrisation::Constant),
            None if got == n1 => Ok(Parametrisation::PerStep(PerStepControl { steps })),
            None => want(format!(
                "N + 1 = {n1} values u_0..u_N for this scene (time.steps = {steps}), or 1 value \
                 (a constant force)"
            )),
        }
    }
}

fn plural(n: usize) -> &'static str {
    if n == 1 {
        ""
    } else {
        "s"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Vec<f64>, String> {
        let p = Path::new("c.csv");
        from_csv(p, text).map_err(|e| e.to_string())
    }

    #[test]
    fn csv_forms() {
        assert_eq!(parse("t,control\n0,1.5\n0.1,-2\n").unwrap(), [1.5, -2.0]);
        assert_eq!(parse("1\n2\n\n# note\n3\n").unwrap(), [1.0, 2.0, 3.0]);
        assert_eq!(parse("u\n4\n5\n").unwrap(), [4.0, 5.0]);
        let e = parse("t,energy\n0,1\n").unwrap_err();
        assert!(
            e.contains("no `control` column") && e.contains("t,energy"),
            "{e}"
        );
        let e = parse("t,control\n0,1\n0,2,3\n").unwrap_err();
        assert!(
            e.contains("line 3") && e.contains("expected 2 fields, got 3"),
            "{e}"
        );
        let e = parse("1\ninf\n").unwrap_err();
        assert!(e.contains("line 2") && e.contains("not finite"), "{e}");
        let e = parse("control\n1\nabc\n").unwrap_err();
        assert!(
            e.contains("line 3") && e.contains("`abc` is not a number"),
            "{e}"
        );
    }
}

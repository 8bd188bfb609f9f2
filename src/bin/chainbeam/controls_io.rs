//! Reading `--controls FILE`: the controls that `optimize` (or `gradient`) wrote, or a column of a
//! CSV file, so that results round-trip between the subcommands.
//!
//! Accepted forms (the first non-blank character decides):
//! - **JSON object** (`{`): the array under `controls`, as `optimize` and `gradient` write it; its
//!   `control_kind` (`"constant"`, `"per-step"`, `"piecewise"`, with `pieces` for the last), when
//!   present, says how the values map to the forces u_0..u_N.
//! - **JSON array** (`[`): the values themselves.
//! - **CSV**: a header line and rows; the column named `control` is read (the last column of a
//!   `simulate` CSV), and with it the column `control_x` when there is one (a spatial scene's
//!   `simulate` CSV). A file with a one-field header reads that column; a file whose first line
//!   is a number is a single column without a header. Blank lines and lines starting with `#`
//!   are skipped.
//!
//! A 2-axis control is written as in a scene file: every JSON entry a pair `[u_x, u_z]` (or a
//! CSV with `control_x` and `control` columns); otherwise every entry is a number, a force along
//! z. Without a declared kind, 1 value (or pair) is a constant force and N + 1 are the per-step
//! forces u_0..u_N (N = `time.steps`); anything else is an error naming the file and both counts.
//! Every value must be finite.

use std::path::{Path, PathBuf};

use chainbeam::scene::ReadErrorKind;
use chainbeam::{Parametrisation, PerStepControl, PiecewiseControl, Scene};

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
    /// The values, in file order (the z components u_z of a 2-axis control).
    pub values: Vec<f64>,
    /// The x components u_x of a 2-axis control (as many as `values`), `None` for a control
    /// along z.
    pub values_x: Option<Vec<f64>>,
    /// The kind the file declares (JSON `control_kind`), if any.
    pub declared: Option<Declared>,
}

fn err(path: &Path, what: impl std::fmt::Display) -> CliError {
    CliError::msg(format!("{}: {what}", path.display()))
}

/// Reads (by the bounded reader [`chainbeam::scene::read_text_file`]: at most 1 GiB, a regular
/// file or a stream, UTF-8 text) and checks (non-empty, finite) a controls file.
pub fn read(path: &Path) -> Result<ControlsFile, CliError> {
    let text = chainbeam::scene::read_text_file(path).map_err(|e| {
        let reason = match e.kind {
            ReadErrorKind::Io { message, .. } => message,
            other => other.to_string(),
        };
        err(
            path,
            format_args!("cannot read the controls file: {reason}"),
        )
    })?;
    let trimmed = text.trim_start();
    let ((values, values_x), declared) = if trimmed.starts_with('{') || trimmed.starts_with('[') {
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
        values_x,
        declared,
    })
}

/// The values u_z and, for a 2-axis control, u_x of a controls file.
type Columns = (Vec<f64>, Option<Vec<f64>>);

/// One entry of a JSON `controls` array: a number, or a pair [u_x, u_z] of a 2-axis control.
fn json_entry(x: &serde_json::Value) -> Option<(Option<f64>, f64)> {
    let finite = |v: &serde_json::Value| v.as_f64().filter(|f| f.is_finite());
    match x {
        serde_json::Value::Array(pair) if pair.len() == 2 => {
            Some((Some(finite(&pair[0])?), finite(&pair[1])?))
        }
        _ => Some((None, finite(x)?)),
    }
}

/// The numbers (or pairs [u_x, u_z]) of a JSON `controls` array; `key` names it in messages.
fn json_values(path: &Path, array: &[serde_json::Value], key: &str) -> Result<Columns, CliError> {
    let mut values = Vec::with_capacity(array.len());
    let mut values_x = Vec::new();
    let mut pairs = None;
    for (i, x) in array.iter().enumerate() {
        let Some((ux, uz)) = json_entry(x) else {
            return Err(err(
                path,
                format_args!(
                    "{key}: entry {i} is not a finite number or a pair [u_x, u_z] of finite \
                     numbers: {x}"
                ),
            ));
        };
        match (*pairs.get_or_insert(ux.is_some()), ux) {
            (true, Some(x)) => values_x.push(x),
            (false, None) => {}
            _ => {
                return Err(err(
                    path,
                    format_args!(
                        "{key}: entry {i} is {} but entry 0 is {}: every entry is a number (a \
                         force along z) or every entry a pair [u_x, u_z] (a 2-axis control)",
                        if ux.is_some() { "a pair" } else { "a number" },
                        if ux.is_some() { "a number" } else { "a pair" },
                    ),
                ))
            }
        }
        values.push(uz);
    }
    Ok((values, (pairs == Some(true)).then_some(values_x)))
}

fn from_json(path: &Path, text: &str) -> Result<(Columns, Option<Declared>), CliError> {
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
                        format_args!(
                            "key `controls`: expected an array of numbers or of pairs \
                             [u_x, u_z], got {other}"
                        ),
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
    let values = json_values(path, array, key)?;
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

fn from_csv(path: &Path, text: &str) -> Result<Columns, CliError> {
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
    let Some((first_no, first)) = lines.next() else {
        return Ok((Vec::new(), None));
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
    // A spatial scene's `simulate` CSV: the x components of a 2-axis control beside `control`.
    let column_x = (width > 1)
        .then(|| fields.iter().position(|f| *f == "control_x"))
        .flatten();
    let mut values_x = Vec::new();
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
        if let Some(cx) = column_x {
            values_x.push(parse_number(path, no, row[cx])?);
        }
    }
    Ok((values, column_x.map(|_| values_x)))
}

impl ControlsFile {
    /// Whether the file holds a 2-axis control (pairs [u_x, u_z], or `control_x` and `control`
    /// columns).
    pub fn is_two_axis(&self) -> bool {
        self.values_x.is_some()
    }

    /// θ laid out as the library's control problem takes it: the values, or for a 2-axis
    /// control θ = (θ_x; θ_z), the x components first (docs/conventions.md "Two-axis controls").
    pub fn theta(&self) -> Vec<f64> {
        let mut theta = self.values_x.clone().unwrap_or_default();
        theta.extend(&self.values);
        theta
    }

    /// Refuses a file with one number per value on a scene whose control is 2-axis: the x
    /// components would be lost without a word.
    pub fn check_axes(&self, scene: &Scene) -> Result<(), CliError> {
        if scene.has_two_axis_control() && !self.is_two_axis() {
            return Err(err(
                &self.path,
                "the scene's control is 2-axis (`control.values` are pairs [u_x, u_z]) but the \
                 controls file holds one number per value: write pairs [u_x, u_z] ([0, u] for a \
                 force along z alone), as `optimize` writes them, or give the CSV of `simulate` \
                 with its `control_x` and `control` columns",
            ));
        }
        Ok(())
    }

    /// The parametrisation of these values on a scene with N = `steps` (module docs), checking
    /// the count (of pairs, for a 2-axis control).
    pub fn parametrisation(&self, steps: usize) -> Result<Parametrisation, CliError> {
        let got = self.values.len();
        let n1 = steps + 1;
        let (one, many) = if self.is_two_axis() {
            ("pair [u_x, u_z]", "pairs [u_x, u_z]")
        } else {
            ("value", "values")
        };
        let want = |what: String| {
            let unit = if got == 1 { one } else { many };
            let unit = unit.split(' ').next().unwrap_or(unit);
            Err(err(
                &self.path,
                format_args!("expected {what}, got {got} {unit}"),
            ))
        };
        match self.declared {
            Some(Declared::Constant) if got == 1 => Ok(Parametrisation::Constant),
            Some(Declared::Constant) => want(format!("1 {one} (control_kind \"constant\")")),
            Some(Declared::PerStep) if got == n1 => {
                Ok(Parametrisation::PerStep(PerStepControl { steps }))
            }
            Some(Declared::PerStep) => want(format!(
                "N + 1 = {n1} {many} u_0..u_N for this scene (time.steps = {steps}; \
                 control_kind \"per-step\")"
            )),
            Some(Declared::Piecewise(p)) if p != got => {
                want(format!("pieces = {p} {many} (control_kind \"piecewise\")"))
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
                "N + 1 = {n1} {many} u_0..u_N for this scene (time.steps = {steps}), or 1 {one} \
                 (a constant force)"
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Vec<f64>, String> {
        let p = Path::new("c.csv");
        match from_csv(p, text) {
            Ok((v, None)) => Ok(v),
            Ok((_, Some(x))) => panic!("unexpected control_x column {x:?}"),
            Err(e) => Err(e.to_string()),
        }
    }

    fn json(text: &str) -> Result<Columns, String> {
        from_json(Path::new("u.json"), text)
            .map(|(c, _)| c)
            .map_err(|e| e.to_string())
    }

    /// A spatial `simulate` CSV gives both columns; pairs in JSON give a 2-axis control; mixed
    /// or malformed entries are refused with the entry's index.
    #[test]
    fn two_axis_forms() {
        let (v, x) = from_csv(
            Path::new("t.csv"),
            "t,moment,moment_x,control_x,control\n0,1,2,3,4\n1,5,6,7,8\n",
        )
        .unwrap();
        assert_eq!((v, x), (vec![4.0, 8.0], Some(vec![3.0, 7.0])));
        assert_eq!(
            json("{\"controls\": [[1, 2], [3, 4.5]]}").unwrap(),
            (vec![2.0, 4.5], Some(vec![1.0, 3.0]))
        );
        assert_eq!(json("[1, 2]").unwrap(), (vec![1.0, 2.0], None));
        let e = json("[[1, 2], 3]").unwrap_err();
        assert!(
            e.contains("entry 1 is a number but entry 0 is a pair"),
            "{e}"
        );
        let e = json("[1, [2, 3]]").unwrap_err();
        assert!(
            e.contains("entry 1 is a pair but entry 0 is a number"),
            "{e}"
        );
        let e = json("[[1, 2, 3]]").unwrap_err();
        assert!(
            e.contains("entry 0 is not a finite number or a pair") && e.contains("[u_x, u_z]"),
            "{e}"
        );
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

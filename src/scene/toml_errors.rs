//! Serde's and the TOML parser's errors mapped to keyed [`SceneError`]s: the key's dotted path,
//! its line and column in the file, and the message in one line (a duplicate key names both of
//! its places).

use std::ops::Range;

use toml::de::{DeTable, DeValue};
use toml::Spanned;

use super::{SceneError, SceneErrorKind};

/// 1-based line and column (in characters) of a byte offset.
fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().map_or(0, |s| s.chars().count()) + 1;
    (line, column)
}

fn one_line(message: &str) -> String {
    message.split_whitespace().collect::<Vec<_>>().join(" ")
}

pub(super) fn syntax_error(text: &str, err: &toml::de::Error) -> SceneError {
    if err.message() == "duplicate key" {
        if let Some(span) = err.span() {
            return duplicate_key(text, span);
        }
    }
    let (line, column) = match err.span() {
        Some(span) => {
            let (l, c) = line_column(text, span.start);
            (Some(l), Some(c))
        }
        None => (None, None),
    };
    SceneErrorKind::Syntax {
        line,
        column,
        message: one_line(err.message()),
    }
    .into()
}

/// A key given twice (toml's message is just "duplicate key"): the full key of the second
/// occurrence at `span`, from the document parsed up to the error, and where it was first given.
fn duplicate_key(text: &str, span: Range<usize>) -> SceneError {
    let (line, column) = line_column(text, span.start);
    let written = text.get(span.clone()).unwrap_or("").trim();
    let name = written
        .strip_prefix('"')
        .and_then(|s| s.strip_suffix('"'))
        .or_else(|| {
            written
                .strip_prefix('\'')
                .and_then(|s| s.strip_suffix('\''))
        })
        .unwrap_or(written);
    // The recovered document keeps the first occurrence: the latest key of that name before the
    // second one is the one it repeats.
    let (doc, _) = DeTable::parse_recoverable(text);
    let mut best: Option<(usize, String)> = None;
    find_key(doc.get_ref(), "", name, span.start, &mut best);
    let (key, first_line) = match best {
        Some((start, path)) => (
            path,
            (start < span.start).then(|| line_column(text, start).0),
        ),
        None => (segment(name), None),
    };
    SceneErrorKind::DuplicateKey {
        key,
        line,
        column,
        first_line,
    }
    .into()
}

/// The key named `name` with the largest span start before `before`, as (start, full path).
fn find_key(
    table: &DeTable<'_>,
    prefix: &str,
    name: &str,
    before: usize,
    best: &mut Option<(usize, String)>,
) {
    for (key, value) in table.iter() {
        let path = join(prefix, &segment(key.get_ref()));
        let start = key.span().start;
        // `<=`: a repeated table header is re-inserted at its second occurrence.
        if key.get_ref() == name && start <= before && best.as_ref().is_none_or(|b| start > b.0) {
            *best = Some((start, path.clone()));
        }
        match value.get_ref() {
            DeValue::Table(t) => find_key(t, &path, name, before, best),
            DeValue::Array(a) => {
                for (i, item) in a.iter().enumerate() {
                    if let DeValue::Table(t) = item.get_ref() {
                        find_key(t, &format!("{path}[{i}]"), name, before, best);
                    }
                }
            }
            _ => {}
        }
    }
}

/// A key as a path segment: bare if it may be written bare in TOML, else quoted.
fn segment(key: &str) -> String {
    if !key.is_empty()
        && key
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
    {
        key.to_string()
    } else {
        format!("{key:?}")
    }
}

fn join(prefix: &str, key: &str) -> String {
    if prefix.is_empty() {
        key.to_string()
    } else {
        format!("{prefix}.{key}")
    }
}

/// Where a serde error points: the key path and the TOML type of the value there.
struct Location {
    exact: bool,
    depth: usize,
    path: String,
    type_name: Option<&'static str>,
}

/// Keeps the better of `best` and a new candidate: exact span matches beat containing values,
/// deeper beats shallower.
fn consider(
    best: &mut Option<Location>,
    exact: bool,
    depth: usize,
    path: &str,
    type_name: Option<&'static str>,
) {
    let better = match best {
        None => true,
        Some(b) => (exact, depth) > (b.exact, b.depth),
    };
    if better {
        *best = Some(Location {
            exact,
            depth,
            path: path.to_string(),
            type_name,
        });
    }
}

fn contains(outer: &Range<usize>, inner: &Range<usize>) -> bool {
    outer.start < outer.end && outer.start <= inner.start && inner.end <= outer.end
}

fn walk_table(
    table: &DeTable<'_>,
    prefix: &str,
    depth: usize,
    target: &Range<usize>,
    best: &mut Option<Location>,
) {
    for (key, value) in table.iter() {
        let path = join(prefix, &segment(key.get_ref()));
        if key.span() == *target {
            consider(best, true, depth, &path, None);
        }
        walk_value(value, &path, depth, target, best);
    }
}

fn walk_value(
    value: &Spanned<DeValue<'_>>,
    path: &str,
    depth: usize,
    target: &Range<usize>,
    best: &mut Option<Location>,
) {
    let span = value.span();
    let type_name = Some(value.get_ref().type_str());
    if span == *target {
        consider(best, true, depth, path, type_name);
    } else if contains(&span, target) {
        consider(best, false, depth, path, type_name);
    }
    match value.get_ref() {
        DeValue::Table(t) => walk_table(t, path, depth + 1, target, best),
        DeValue::Array(a) => {
            for (i, item) in a.iter().enumerate() {
                walk_value(item, &format!("{path}[{i}]"), depth + 1, target, best);
            }
        }
        _ => {}
    }
}

/// The key or value at `span`: the deepest exact match, else (unless `exact_only`) the deepest
/// value containing it, else the document itself (empty path).
fn locate(doc: &Spanned<DeTable<'_>>, span: &Range<usize>, exact_only: bool) -> Location {
    let mut best = None;
    walk_table(doc.get_ref(), "", 1, span, &mut best);
    match best {
        Some(b) if b.exact || !exact_only => b,
        _ => Location {
            exact: false,
            depth: 0,
            path: String::new(),
            type_name: None,
        },
    }
}

/// The names between backticks in `s`.
fn backticked(s: &str) -> Vec<String> {
    s.split('`')
        .skip(1)
        .step_by(2)
        .map(str::to_string)
        .collect()
}

fn pretty_expected(s: &str) -> String {
    let s = s.trim();
    match s {
        "f64" => "a number".to_string(),
        "i64" => "an integer".to_string(),
        "a sequence" => "an array".to_string(),
        "a boolean" => "a boolean (true or false)".to_string(),
        _ if s.starts_with("struct ") => "a table".to_string(),
        _ if s.starts_with("enum ") => "a string".to_string(),
        _ => s.to_string(),
    }
}

fn pretty_found(s: &str) -> String {
    let s = s.trim();
    match s {
        "sequence" => "an array".to_string(),
        "map" => "a table".to_string(),
        _ => s.replacen("floating point", "float", 1),
    }
}

/// Turns a serde error of the raw structures into a keyed [`SceneError`].
pub(super) fn classify(
    text: &str,
    err: &toml::de::Error,
    doc: &Spanned<DeTable<'_>>,
) -> SceneError {
    let message = one_line(err.message());
    // A missing field points at its table (a header, or the document start): only an exact match
    // is that table, anything merely containing the span is not.
    let exact_only = message.starts_with("missing field ");
    let (path, type_name) = match err.span() {
        Some(span) => {
            let at = locate(doc, &span, exact_only);
            (at.path, at.type_name)
        }
        None => (String::new(), None),
    };
    // What the value is, in words: toml hands a date-time to serde as a table, so serde's own
    // description ("a table") would mislead.
    let describe = |serde_found: &str| match type_name {
        Some("datetime") => {
            let written = err
                .span()
                .and_then(|s| text.get(s))
                .map_or(String::new(), one_line);
            format!("a date-time `{written}`")
        }
        _ => pretty_found(serde_found),
    };
    let kind = if let Some(rest) = message.strip_prefix("unknown field ") {
        let names = backticked(rest);
        let field = names.first().cloned().unwrap_or_default();
        let last = path.rsplit('.').next().unwrap_or("");
        let key = if last == segment(&field) {
            path
        } else {
            join(&path, &segment(&field))
        };
        SceneErrorKind::UnknownKey {
            key,
            expected: names.into_iter().skip(1).collect(),
        }
    } else if let Some(rest) = message.strip_prefix("missing field ") {
        let field = backticked(rest).into_iter().next().unwrap_or_default();
        SceneErrorKind::MissingKey {
            key: join(&path, &segment(&field)),
            note: None,
        }
    } else if let Some(rest) = message.strip_prefix("invalid type: ") {
        let (found, expected) = rest.rsplit_once(", expected ").unwrap_or((rest, "?"));
        if let Some(digits) = found
            .strip_suffix(" as i128")
            .and_then(|f| backticked(f).pop())
        {
            // toml reads integers beyond 64 bits as i128, which serde cannot narrow.
            SceneErrorKind::InvalidValue {
                key: path,
                reason: format!(
                    "the integer {digits} does not fit in 64 bits (TOML integers lie within \
                     ±{}); expected {}",
                    i64::MAX,
                    pretty_expected(expected)
                ),
            }
        } else {
            SceneErrorKind::WrongType {
                key: path,
                expected: pretty_expected(expected),
                found: describe(found),
            }
        }
    } else if let Some(rest) = message.strip_prefix("invalid value: ") {
        let (found, expected) = rest.rsplit_once(", expected ").unwrap_or((rest, "?"));
        SceneErrorKind::InvalidValue {
            key: path,
            reason: format!(
                "expected {}, got {}",
                pretty_expected(expected),
                found.trim()
            ),
        }
    } else if let Some(rest) = message.strip_prefix("unknown variant ") {
        SceneErrorKind::InvalidValue {
            key: path,
            reason: format!("unknown value {rest}"),
        }
    } else if message == "wanted string or table" {
        // toml's message for an enum (support, kind) given as another type
        SceneErrorKind::WrongType {
            key: path,
            expected: "a string".to_string(),
            found: describe(type_name.unwrap_or("another type")),
        }
    } else {
        SceneErrorKind::InvalidValue {
            key: path,
            reason: message,
        }
    };
    kind.into()
}

//! Writing results: stdout or an atomically replaced file, and number formatting.

use std::fs::{self, File, OpenOptions};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::process;
use std::time::{SystemTime, UNIX_EPOCH};

use crate::CliError;

/// Where a result goes: standard output, or a file written atomically (a temporary file in the
/// same directory, flushed to disk, then renamed over the target), so that an interrupted or failed
/// run never leaves a half-written result at `--output`.
pub enum Sink {
    /// Standard output.
    Stdout(BufWriter<io::Stdout>),
    /// A temporary file that becomes `target` on [`Sink::finish`].
    File {
        /// The temporary file (same directory as `target`).
        tmp: PathBuf,
        /// The writer on `tmp`.
        writer: BufWriter<File>,
        /// The final path.
        target: PathBuf,
    },
}

impl Sink {
    /// Opens the sink: stdout when `output` is `None`, else a fresh temporary file beside it.
    pub fn open(output: Option<&Path>) -> Result<Sink, CliError> {
        let Some(target) = output else {
            return Ok(Sink::Stdout(BufWriter::new(io::stdout())));
        };
        if target.as_os_str().is_empty() {
            return Err(CliError::msg("--output: the file name is empty"));
        }
        if target.is_dir() {
            return Err(CliError::msg(format!(
                "{}: cannot write the output: it is a directory",
                target.display()
            )));
        }
        let file_name = target.file_name().ok_or_else(|| {
            CliError::msg(format!(
                "{}: cannot write the output: not a file name",
                target.display()
            ))
        })?;
        let dir = match target.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let nanos = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map(|d| d.subsec_nanos())
            .unwrap_or(0);
        let mut last_err = None;
        for attempt in 0..16u32 {
            let tmp = dir.join(format!(
                ".{}.{}.{}.{}.tmp",
                file_name.to_string_lossy(),
                process::id(),
                nanos,
                attempt
            ));
            match OpenOptions::new().write(true).create_new(true).open(&tmp) {
                Ok(file) => {
                    return Ok(Sink::File {
                        tmp,
                        writer: BufWriter::new(file),
                        target: target.to_path_buf(),
                    })
                }
                Err(e) if e.kind() == io::ErrorKind::AlreadyExists => last_err = Some(e),
                Err(e) => return Err(write_error(target, &e)),
            }
        }
        Err(write_error(
            target,
            &last_err.unwrap_or_else(|| io::Error::other("no free temporary file name")),
        ))
    }

    /// The writer.
    pub fn writer(&mut self) -> &mut dyn Write {
        match self {
            Sink::Stdout(w) => w,
            Sink::File { writer, .. } => writer,
        }
    }

    /// Turns an I/O error of this sink into a message naming the output.
    pub fn error(&self, e: &io::Error) -> CliError {
        match self {
            Sink::Stdout(_) if e.kind() == io::ErrorKind::BrokenPipe => CliError::BrokenPipe,
            Sink::Stdout(_) => CliError::msg(format!("cannot write to standard output: {e}")),
            Sink::File { target, .. } => write_error(target, e),
        }
    }

    /// Flushes; for a file, syncs it to disk and renames it over the target.
    pub fn finish(mut self) -> Result<(), CliError> {
        if let Err(e) = self.writer().flush() {
            return Err(self.fail(&e));
        }
        match self {
            Sink::Stdout(_) => Ok(()),
            Sink::File {
                tmp,
                writer,
                target,
            } => {
                let file = match writer.into_inner() {
                    Ok(f) => f,
                    Err(e) => {
                        let _ = fs::remove_file(&tmp);
                        return Err(write_error(&target, e.error()));
                    }
                };
                let done = file.sync_all().and_then(|()| {
                    drop(file);
                    fs::rename(&tmp, &target)
                });
                done.map_err(|e| {
                    let _ = fs::remove_file(&tmp);
                    write_error(&target, &e)
                })
            }
        }
    }

    /// Abandons the output (removes the temporary file) and returns the error for `e`.
    pub fn fail(self, e: &io::Error) -> CliError {
        let err = self.error(e);
        self.discard();
        err
    }

    /// Abandons the output: the temporary file is removed, the target is left untouched.
    pub fn discard(self) {
        if let Sink::File { tmp, writer, .. } = self {
            drop(writer);
            let _ = fs::remove_file(tmp);
        }
    }
}

fn write_error(target: &Path, e: &io::Error) -> CliError {
    CliError::msg(format!(
        "{}: cannot write the output: {e}",
        target.display()
    ))
}

/// Writes `text` to the sink and finishes it (for the small JSON results).
pub fn write_all(output: Option<&Path>, text: &str) -> Result<(), CliError> {
    let mut sink = Sink::open(output)?;
    if let Err(e) = sink.writer().write_all(text.as_bytes()) {
        return Err(sink.fail(&e));
    }
    sink.finish()
}

/// A finite number as the shortest text that reads back to the same `f64`: plain decimal for
/// moderate magnitudes (`0.25`, `-1000`), exponent notation otherwise (`1.5e-12`).
pub fn fmt_f64(x: f64) -> String {
    let a = x.abs();
    if a == 0.0 || (1e-4..1e16).contains(&a) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

#[cfg(test)]
mod tests {
    use super::fmt_f64;

    #[test]
    fn numbers_round_trip() {
        for x in [
            0.0, -0.0, 1.0, -2.5, 0.1, 1e-5, 1e-300, 123456.789, 1e16, 5e300,
        ] {
            let s = fmt_f64(x);
            assert_eq!(s.parse::<f64>().unwrap().to_bits(), x.to_bits(), "{s}");
        }
        assert_eq!(fmt_f64(0.25), "0.25");
        assert_eq!(fmt_f64(-1000.0), "-1000");
        assert_eq!(fmt_f64(1.5e-12), "1.5e-12");
    }
}

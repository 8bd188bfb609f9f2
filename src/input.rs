//! The one bounded reader of input files (docs/scene-format.md, "Size limits"): scene files,
//! load series, and in the command line the `--controls` and `--model` files all go through
//! [`read_text_file`], so that a mistyped name (`/dev/zero`, a directory, a huge log) fails at
//! once with a message naming the file and the limit instead of exhausting memory.
//!
//! - A **regular file** larger than the limit is refused from its size, before any byte is read;
//!   one that grows while it is read is cut off at the limit and refused.
//! - A **non-regular file** (a pipe, a FIFO, a character device, `/dev/stdin`) is read as a
//!   stream with the same limit. A FIFO keeps its POSIX semantics: opening it blocks until a
//!   writer opens the other end, and reading ends when the last writer closes it.
//! - A **directory** is refused.
//! - The text must be UTF-8 without NUL bytes (every input format is text: TOML, JSON, CSV). The
//!   check runs on each block as it arrives, so binary data (`/dev/zero`, `/dev/urandom`, an
//!   image) fails within its first block, naming the line of the first offending byte.

use std::fmt;
use std::io::{self, Read};
use std::path::{Path, PathBuf};

/// The largest input file read (1 GiB): a scene, a series, a controls or a model file, a
/// regular file or a stream. Far above any valid input (a per-step control of
/// [`MAX_STEPS`](crate::scene::MAX_STEPS) values is about 250 MB of text).
pub const MAX_INPUT_BYTES: u64 = 1 << 30;

/// Bytes read per block (and checked for text before the next block is read).
const BLOCK: usize = 1 << 16;

/// Why an input file could not be read ([`ReadError`]).
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum ReadErrorKind {
    /// Opening or reading failed (it does not exist, no permission, an I/O error).
    Io {
        /// The operating system's error class.
        kind: io::ErrorKind,
        /// The operating system's message.
        message: String,
    },
    /// The name is a directory.
    Directory,
    /// The file holds more than `limit` bytes (a regular file by its size, a stream once it
    /// passed the limit).
    TooLarge {
        /// The limit in bytes.
        limit: u64,
        /// The regular file's size, `None` for a stream (read up to the limit).
        size: Option<u64>,
    },
    /// A NUL byte: binary data, not text.
    NulByte {
        /// 1-based line of the byte.
        line: usize,
        /// 0-based offset of the byte in the file.
        offset: u64,
    },
    /// Bytes that are not UTF-8.
    NotUtf8 {
        /// 1-based line of the first invalid byte.
        line: usize,
        /// 0-based offset of that byte in the file.
        offset: u64,
    },
}

impl fmt::Display for ReadErrorKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Io { message, .. } => write!(f, "cannot read it: {message}"),
            Self::Directory => f.write_str("cannot read it: it is a directory"),
            Self::TooLarge { limit, size } => {
                match size {
                    Some(s) => write!(f, "the file has {s} bytes")?,
                    None => write!(f, "the stream gave more than {limit} bytes")?,
                }
                write!(
                    f,
                    ", over the limit of {} ({limit} bytes) for an input file",
                    human_bytes(*limit)
                )
            }
            Self::NulByte { line, offset } => write!(
                f,
                "line {line}: a NUL byte (byte {offset}): binary data, not a text file"
            ),
            Self::NotUtf8 { line, offset } => write!(
                f,
                "line {line}: invalid UTF-8 (byte {offset}): the file must be UTF-8 text"
            ),
        }
    }
}

/// An input file that could not be read: the file (as named) and why. Displayed as
/// `FILE: REASON`, e.g. `/dev/zero: line 1: a NUL byte (byte 0): binary data, not a text file`.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{}: {kind}", file.display())]
pub struct ReadError {
    /// The file, as named by the caller.
    pub file: PathBuf,
    /// What went wrong.
    pub kind: ReadErrorKind,
}

impl ReadError {
    /// The line of the offending byte, for [`ReadErrorKind::NulByte`] and
    /// [`ReadErrorKind::NotUtf8`].
    pub fn line(&self) -> Option<usize> {
        match self.kind {
            ReadErrorKind::NulByte { line, .. } | ReadErrorKind::NotUtf8 { line, .. } => Some(line),
            _ => None,
        }
    }
}

/// Reads the text file `path` with the limit [`MAX_INPUT_BYTES`] (module docs: regular files by
/// their size, streams as they are read, UTF-8 without NUL bytes).
///
/// # Errors
/// [`ReadError`] naming `path` and the [`ReadErrorKind`].
pub fn read_text_file(path: impl AsRef<Path>) -> Result<String, ReadError> {
    read_text_file_limited(path, MAX_INPUT_BYTES)
}

/// [`read_text_file`] with another limit of `limit` bytes.
///
/// # Errors
/// As [`read_text_file`].
pub fn read_text_file_limited(path: impl AsRef<Path>, limit: u64) -> Result<String, ReadError> {
    let path = path.as_ref();
    let fail = |kind| ReadError {
        file: path.to_path_buf(),
        kind,
    };
    let io_fail = |e: io::Error| {
        fail(ReadErrorKind::Io {
            kind: e.kind(),
            message: e.to_string(),
        })
    };
    // Opening a FIFO blocks until a writer comes (POSIX); a directory opens on Unix.
    let mut file = std::fs::File::open(path).map_err(io_fail)?;
    let meta = file.metadata().map_err(io_fail)?;
    if meta.is_dir() {
        return Err(fail(ReadErrorKind::Directory));
    }
    let regular = meta.is_file();
    if regular && meta.len() > limit {
        return Err(fail(ReadErrorKind::TooLarge {
            limit,
            size: Some(meta.len()),
        }));
    }
    let capacity = if regular { meta.len() } else { BLOCK as u64 };
    let mut bytes = Vec::with_capacity(usize::try_from(capacity.min(limit)).unwrap_or(BLOCK));
    let mut checker = TextCheck::default();
    let mut block = vec![0u8; BLOCK];
    loop {
        let got = match file.read(&mut block) {
            Ok(0) => break,
            Ok(got) => got,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(io_fail(e)),
        };
        if (bytes.len() + got) as u64 > limit {
            return Err(fail(ReadErrorKind::TooLarge { limit, size: None }));
        }
        bytes.extend_from_slice(&block[..got]);
        checker.advance(&bytes, false).map_err(fail)?;
    }
    checker.advance(&bytes, true).map_err(fail)?;
    // Checked block by block above; the conversion checks once more and cannot fail.
    String::from_utf8(bytes).map_err(|e| {
        let offset = e.utf8_error().valid_up_to();
        fail(ReadErrorKind::NotUtf8 {
            line: 1 + e.as_bytes()[..offset]
                .iter()
                .filter(|&&b| b == b'\n')
                .count(),
            offset: offset as u64,
        })
    })
}

/// The text check of the bytes read so far: `checked` bytes are valid UTF-8 without NUL and
/// hold `lines` newlines.
#[derive(Default)]
struct TextCheck {
    checked: usize,
    lines: usize,
}

impl TextCheck {
    /// Checks the bytes after `checked`; a character cut at the end of `bytes` waits for the
    /// next block unless `at_end`.
    fn advance(&mut self, bytes: &[u8], at_end: bool) -> Result<(), ReadErrorKind> {
        let fresh = &bytes[self.checked..];
        let (valid, bad) = match std::str::from_utf8(fresh) {
            Ok(_) => (fresh.len(), None),
            Err(e) if e.error_len().is_none() && !at_end => (e.valid_up_to(), None),
            Err(e) => (e.valid_up_to(), Some(e.valid_up_to())),
        };
        let good = &fresh[..valid];
        if let Some(nul) = good.iter().position(|&b| b == 0) {
            return Err(ReadErrorKind::NulByte {
                line: 1 + self.lines + newlines(&good[..nul]),
                offset: (self.checked + nul) as u64,
            });
        }
        if let Some(bad) = bad {
            return Err(ReadErrorKind::NotUtf8 {
                line: 1 + self.lines + newlines(good),
                offset: (self.checked + bad) as u64,
            });
        }
        self.lines += newlines(good);
        self.checked += valid;
        Ok(())
    }
}

fn newlines(b: &[u8]) -> usize {
    b.iter().filter(|&&c| c == b'\n').count()
}

/// `bytes` for people, in binary units: `512 bytes`, `8.0 GiB`, `894.1 GiB`.
pub fn human_bytes(bytes: u64) -> String {
    const UNITS: [&str; 7] = ["bytes", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"];
    let mut x = bytes as f64;
    let mut unit = 0;
    while x >= 1024.0 && unit + 1 < UNITS.len() {
        x /= 1024.0;
        unit += 1;
    }
    if unit == 0 {
        format!("{bytes} bytes")
    } else {
        format!("{x:.1} {}", UNITS[unit])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp(name: &str, bytes: &[u8]) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("chainbeam-input-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    }

    /// The line and offset of invalid UTF-8 and of a NUL byte are those of the byte written
    /// there (counted by hand in the test data), also when the character is cut by a block.
    #[test]
    fn binary_bytes_are_located() {
        let p = temp("bad_utf8.csv", b"t,fx,fz\n0,0,1\n1,\xff,2\n");
        let e = read_text_file(&p).unwrap_err();
        assert_eq!(
            e.kind,
            ReadErrorKind::NotUtf8 {
                line: 3,
                offset: 16
            }
        );
        let p = temp("nul.csv", b"a\nb\nc\0");
        let e = read_text_file(&p).unwrap_err();
        assert_eq!(e.kind, ReadErrorKind::NulByte { line: 3, offset: 5 });
        // A 3-byte character (€) across the block boundary is valid.
        let mut text = vec![b'x'; BLOCK - 1];
        text.extend("€\n".as_bytes());
        let p = temp("split.csv", &text);
        assert_eq!(read_text_file(&p).unwrap().len(), BLOCK + 3);
        // A truncated character at the end is not.
        let p = temp("cut.csv", b"ok\n\xe2\x82");
        let e = read_text_file(&p).unwrap_err();
        assert_eq!(e.kind, ReadErrorKind::NotUtf8 { line: 2, offset: 3 });
        assert!(
            e.to_string().contains("cut.csv: line 2: invalid UTF-8"),
            "{e}"
        );
    }

    /// A regular file over the limit is refused by its size; a directory is refused.
    #[test]
    fn limits_of_regular_files() {
        let p = temp("big.txt", &[b'1'; 100]);
        let e = read_text_file_limited(&p, 99).unwrap_err();
        assert_eq!(
            e.kind,
            ReadErrorKind::TooLarge {
                limit: 99,
                size: Some(100)
            }
        );
        assert_eq!(read_text_file_limited(&p, 100).unwrap().len(), 100);
        let e = read_text_file(p.parent().unwrap()).unwrap_err();
        assert_eq!(e.kind, ReadErrorKind::Directory);
    }

    /// A stream (a pipe's reading end, opened by name through /proc) is read up to the limit
    /// and refused beyond it: `yes` writes forever, so only the limit ends the read.
    #[cfg(target_os = "linux")]
    #[test]
    fn streams_obey_the_limit() {
        use std::os::fd::AsRawFd;
        use std::process::{Command, Stdio};
        let mut child = Command::new("yes")
            .stdout(Stdio::piped())
            .spawn()
            .expect("`yes` (coreutils) writes the endless stream");
        let stdout = child.stdout.take().unwrap();
        let name = PathBuf::from(format!("/proc/self/fd/{}", stdout.as_raw_fd()));
        let result = read_text_file_limited(&name, 1 << 16);
        drop(stdout);
        let _ = child.kill();
        let _ = child.wait();
        assert_eq!(
            result.unwrap_err().kind,
            ReadErrorKind::TooLarge {
                limit: 1 << 16,
                size: None
            }
        );
    }
}

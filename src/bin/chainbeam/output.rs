//! Writing results the way careful Unix tools do.
//!
//! `--output FILE` is resolved once, before any work ([`Output::prepare`]), so an unwritable or
//! forbidden output fails at once instead of after a long computation:
//!
//! | what FILE is                      | how it is written                                         |
//! |-----------------------------------|-----------------------------------------------------------|
//! | does not exist                    | temporary file beside it, renamed to FILE at the end; the new file gets the usual mode (0666 less the umask) |
//! | a regular file with one link      | temporary file beside it, created with FILE's mode (and, where allowed, owner and group), renamed over FILE at the end |
//! | a regular file with several links | in place (truncated, rewritten), so every link sees the new contents; not atomic |
//! | a FIFO, a character or block device | in place, opened for writing without truncation (a FIFO waits for its reader); never replaced by a regular file |
//! | a symbolic link                   | followed: the rules above apply to the file it points to (a dangling link is written through, creating its target) |
//! | a directory                       | refused                                                   |
//! | an input of the run, through any name | refused ([`refuse_overwrite`])                |
//!
//! The inputs of a run are the scene, its load series files, the `--controls` file, the
//! `--model` scene and its series files; every subcommand checks all its outputs (`--output`,
//! `--summary`) against all of them with the one function [`refuse_overwrite`], by identity
//! (device and inode after following links), after the inputs are read and before anything is
//! written. Two outputs of one run must be different files too.
//!
//! The temporary file is named `.FILE.PID.I.tmp` (FILE cut to its first 200 bytes, so the name
//! fits the 255-byte limit of a file name whatever FILE is) and is removed on every error and, on Unix, on
//! SIGINT, SIGTERM and SIGHUP ([`remove_temporary_files_on_signal`]); a SIGKILL cannot be caught
//! and leaves it behind (the PID in its name tells which run it was).

use std::fs::{self, File, OpenOptions};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::process;
use std::sync::Mutex;

use crate::CliError;

/// Temporary files not yet renamed into place, removed by the signal handler.
static PENDING: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn pending() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    PENDING.lock().unwrap_or_else(|e| e.into_inner())
}

/// Installs the SIGINT/SIGTERM/SIGHUP handling (Unix): a thread waits for the signal, removes the
/// pending temporary files, then ends the process by the same signal (default action), so the
/// parent sees the usual "killed by signal" status. Without the `signal-hook` handler (or when it
/// cannot be installed) the signals keep their default action.
pub fn remove_temporary_files_on_signal() {
    #[cfg(unix)]
    {
        use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
        use signal_hook::iterator::Signals;
        let Ok(mut signals) = Signals::new([SIGINT, SIGTERM, SIGHUP]) else {
            return;
        };
        let spawned = std::thread::Builder::new()
            .name("signals".into())
            .spawn(move || {
                if let Some(sig) = signals.forever().next() {
                    // Holding the lock while removing: a rename in progress completes first
                    // (then the file is the finished output, no longer pending).
                    let mut files = pending();
                    for f in files.drain(..) {
                        let _ = fs::remove_file(f);
                    }
                    let _ = signal_hook::low_level::emulate_default_handler(sig);
                    // Only reached if the default action could not be emulated.
                    process::exit(128 + sig);
                }
            });
        drop(spawned);
    }
}

/// The longest part of the output's name kept in its temporary name: `.` + 200 bytes +
/// `.PID.I.tmp` (at most 1 + 10 + 1 + 2 + 4 bytes) stays under the 255-byte limit of a file name.
const TEMP_STEM_BYTES: usize = 200;

/// The output's file name, cut to [`TEMP_STEM_BYTES`] at a character boundary.
fn temp_stem(target: &Path) -> String {
    let mut name = target
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "output".into());
    let mut end = name.len().min(TEMP_STEM_BYTES);
    while !name.is_char_boundary(end) {
        end -= 1;
    }
    name.truncate(end);
    name
}

/// A temporary file that is removed unless [`TempFile::persist`]ed.
pub struct TempFile {
    path: PathBuf,
    armed: bool,
}

impl TempFile {
    /// Creates a fresh temporary file beside `target` (in `dir`), mode `mode` (exactly, not
    /// reduced by the umask) or the usual 0666 less the umask when `None`.
    fn create(dir: &Path, target: &Path, mode: Option<u32>) -> io::Result<(TempFile, File)> {
        let name = temp_stem(target);
        let mut last = None;
        for attempt in 0..100u32 {
            let path = dir.join(format!(".{name}.{}.{attempt}.tmp", process::id()));
            // Registered before it exists: a signal between creation and registration would
            // otherwise leave it behind.
            pending().push(path.clone());
            let mut tmp = TempFile { path, armed: true };
            let mut opts = OpenOptions::new();
            opts.write(true).create_new(true);
            #[cfg(unix)]
            {
                use std::os::unix::fs::OpenOptionsExt;
                opts.mode(mode.unwrap_or(0o666));
            }
            match opts.open(&tmp.path) {
                Ok(file) => {
                    #[cfg(unix)]
                    if let Some(m) = mode {
                        use std::os::unix::fs::PermissionsExt;
                        // The umask may have removed bits at creation.
                        file.set_permissions(fs::Permissions::from_mode(m))?;
                    }
                    #[cfg(not(unix))]
                    let _ = mode;
                    return Ok((tmp, file));
                }
                Err(e) if e.kind() == io::ErrorKind::AlreadyExists => {
                    // Not ours: forget it without removing it.
                    tmp.disarm();
                    last = Some(e);
                }
                Err(e) => {
                    tmp.disarm();
                    return Err(e);
                }
            }
        }
        Err(last.unwrap_or_else(|| io::Error::other("no free temporary file name")))
    }

    fn disarm(&mut self) {
        self.armed = false;
        pending().retain(|p| p != &self.path);
    }

    /// Renames the file to `target` (under the signal lock, so a signal either sees it pending
    /// and removes it, or sees the rename done).
    fn persist(mut self, target: &Path) -> io::Result<()> {
        let mut files = pending();
        fs::rename(&self.path, target)?;
        files.retain(|p| p != &self.path);
        self.armed = false;
        Ok(())
    }
}

impl Drop for TempFile {
    fn drop(&mut self) {
        if self.armed {
            let mut files = pending();
            let _ = fs::remove_file(&self.path);
            files.retain(|p| p != &self.path);
        }
    }
}

/// Where a result goes, decided before the work starts (module docs).
pub enum Output {
    /// Standard output.
    Stdout,
    /// A temporary file renamed over `target` at the end.
    Replace {
        /// The temporary file (created by [`Output::prepare`]).
        tmp: TempFile,
        /// Its open handle.
        file: File,
        /// The real target (a symbolic link resolved).
        target: PathBuf,
        /// The path as the user gave it (for messages).
        shown: PathBuf,
    },
    /// The file itself, opened at [`Output::open`].
    InPlace {
        /// The file (a symbolic link resolved, unless dangling).
        target: PathBuf,
        /// The path as the user gave it.
        shown: PathBuf,
        /// Truncate (regular files) or not (FIFOs, devices).
        truncate: bool,
    },
}

fn write_error(target: &Path, e: &io::Error) -> CliError {
    CliError::msg(format!(
        "{}: cannot write the output: {e}",
        target.display()
    ))
}

/// What makes two names the same file: device and inode (Unix), else the canonical path; for a
/// file that does not exist yet, its canonical directory and its name.
#[derive(Debug, PartialEq, Eq)]
enum Identity {
    #[cfg(unix)]
    Inode(u64, u64),
    Path(PathBuf),
}

/// The identity of the existing file `path` (links followed), `None` if it cannot be seen.
fn identity(path: &Path) -> Option<Identity> {
    let meta = fs::metadata(path).ok()?;
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        Some(Identity::Inode(meta.dev(), meta.ino()))
    }
    #[cfg(not(unix))]
    {
        let _ = meta;
        fs::canonicalize(path).ok().map(Identity::Path)
    }
}

/// The identity of an output's target: the file if it exists, else where it will be created.
fn future_identity(target: &Path) -> Option<Identity> {
    identity(target).or_else(|| {
        let dir = match target.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        let real = fs::canonicalize(dir).ok()?;
        Some(Identity::Path(real.join(target.file_name()?)))
    })
}

/// Every file a run reads: what its outputs must never land on.
#[derive(Default)]
pub struct Inputs {
    files: Vec<PathBuf>,
}

impl Inputs {
    /// No inputs yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// An input file (`--controls`, ...), as named on the command line.
    pub fn file(&mut self, path: &Path) -> &mut Self {
        self.files.push(path.to_path_buf());
        self
    }

    /// A scene file read from `path` and the time-series files its loads read.
    pub fn scene(&mut self, path: &Path, scene: &chainbeam::Scene) -> &mut Self {
        self.file(path);
        self.files.extend(crate::series_files(path, scene));
        self
    }

    /// Reads and validates the scene file `path` ([`crate::load_scene`]) and records it and the
    /// time-series files its loads read as inputs.
    pub fn load_scene(&mut self, path: &Path) -> Result<chainbeam::ValidScene, CliError> {
        let scene = crate::load_scene(path)?;
        self.scene(path, &scene);
        Ok(scene)
    }
}

/// The one check every subcommand makes before it writes: no output (`--output`, `--summary`;
/// each given with its flag) is any of the run's `inputs`, through any name (a symbolic link,
/// `./`, a hard link: files are compared by identity), and no two outputs are the same file.
/// The error is one line naming the output, the flag and the input.
pub fn refuse_overwrite(outputs: &[(&str, &Output)], inputs: &Inputs) -> Result<(), CliError> {
    let mut seen: Vec<(&str, &Path, Identity)> = Vec::new();
    for &(flag, out) in outputs {
        let (target, shown) = match out {
            Output::Stdout => continue,
            Output::InPlace { target, shown, .. } | Output::Replace { target, shown, .. } => {
                (target, shown)
            }
        };
        let Some(id) = future_identity(target) else {
            continue;
        };
        for input in &inputs.files {
            if identity(input).as_ref() == Some(&id) {
                return Err(CliError::msg(format!(
                    "{}: refusing to write the output ({flag}) onto the input file {}; choose \
                     another {flag}",
                    shown.display(),
                    input.display()
                )));
            }
        }
        if let Some((other, other_shown, _)) = seen.iter().find(|(_, _, i)| *i == id) {
            return Err(CliError::msg(format!(
                "{}: {flag} and {other} name the same file ({}); give two different files",
                shown.display(),
                other_shown.display()
            )));
        }
        seen.push((flag, shown, id));
    }
    Ok(())
}

#[cfg(unix)]
fn links(m: &fs::Metadata) -> u64 {
    use std::os::unix::fs::MetadataExt;
    m.nlink()
}

#[cfg(unix)]
fn mode(m: &fs::Metadata) -> Option<u32> {
    use std::os::unix::fs::MetadataExt;
    Some(m.mode() & 0o7777)
}

#[cfg(not(unix))]
fn links(_: &fs::Metadata) -> u64 {
    1
}

#[cfg(not(unix))]
fn mode(_: &fs::Metadata) -> Option<u32> {
    None
}

impl Output {
    /// Resolves `output` (module docs); `None` is standard output. Whether it is an input is
    /// checked by [`refuse_overwrite`] once the inputs are known.
    pub fn prepare(output: Option<&Path>) -> Result<Output, CliError> {
        let Some(shown) = output else {
            return Ok(Output::Stdout);
        };
        if shown.as_os_str().is_empty() {
            return Err(CliError::msg("--output: the file name is empty"));
        }
        let in_place = |target: PathBuf, truncate: bool| {
            Ok(Output::InPlace {
                target,
                shown: shown.to_path_buf(),
                truncate,
            })
        };
        let target = match fs::symlink_metadata(shown) {
            Err(e) if e.kind() == io::ErrorKind::NotFound => {
                return Self::replace(shown, shown.to_path_buf(), None);
            }
            Err(e) => return Err(write_error(shown, &e)),
            Ok(m) if m.file_type().is_symlink() => match fs::canonicalize(shown) {
                Ok(real) => real,
                // A dangling link: writing through it creates its target.
                Err(e) if e.kind() == io::ErrorKind::NotFound => {
                    return in_place(shown.to_path_buf(), true)
                }
                Err(e) => return Err(write_error(shown, &e)),
            },
            Ok(_) => shown.to_path_buf(),
        };
        let meta = fs::metadata(&target).map_err(|e| write_error(shown, &e))?;
        if meta.is_dir() {
            return Err(CliError::msg(format!(
                "{}: cannot write the output: it is a directory",
                shown.display()
            )));
        }
        if !meta.is_file() {
            // FIFO, character or block device, socket: never replaced by a regular file.
            return in_place(target, false);
        }
        if links(&meta) > 1 {
            // Replacing would detach this name from the other links.
            return in_place(target, true);
        }
        Self::replace(shown, target, Some(meta))
    }

    fn replace(
        shown: &Path,
        target: PathBuf,
        meta: Option<fs::Metadata>,
    ) -> Result<Output, CliError> {
        let dir = match target.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        if !dir.is_dir() {
            return Err(CliError::msg(format!(
                "{}: cannot write the output: the directory {} does not exist",
                shown.display(),
                dir.display()
            )));
        }
        let (tmp, file) = TempFile::create(&dir, &target, meta.as_ref().and_then(mode))
            .map_err(|e| write_error(shown, &e))?;
        #[cfg(unix)]
        if let Some(m) = &meta {
            use std::os::unix::fs::MetadataExt;
            // Keep the owner and group where allowed (root; or one's own group), then the mode
            // again, since a change of owner clears set-user-ID bits.
            if std::os::unix::fs::fchown(&file, Some(m.uid()), Some(m.gid())).is_ok() {
                use std::os::unix::fs::PermissionsExt;
                let _ = file.set_permissions(fs::Permissions::from_mode(m.mode() & 0o7777));
            }
        }
        Ok(Output::Replace {
            tmp,
            file,
            target,
            shown: shown.to_path_buf(),
        })
    }

    /// Whether the output is standard output.
    pub fn is_stdout(&self) -> bool {
        matches!(self, Output::Stdout)
    }

    /// Opens the output for writing (a FIFO target waits here for its reader).
    pub fn open(self) -> Result<Sink, CliError> {
        const CAPACITY: usize = 1 << 20;
        match self {
            Output::Stdout => Ok(Sink::Stdout(BufWriter::with_capacity(
                CAPACITY,
                io::stdout(),
            ))),
            Output::Replace {
                tmp,
                file,
                target,
                shown,
            } => Ok(Sink::Replace {
                tmp,
                writer: BufWriter::with_capacity(CAPACITY, file),
                target,
                shown,
            }),
            Output::InPlace {
                target,
                shown,
                truncate,
            } => {
                let file = OpenOptions::new()
                    .write(true)
                    .create(truncate)
                    .truncate(truncate)
                    .open(&target)
                    .map_err(|e| write_error(&shown, &e))?;
                Ok(Sink::InPlace {
                    writer: BufWriter::with_capacity(CAPACITY, file),
                    shown,
                })
            }
        }
    }

    /// Writes `text` and finishes (for the small JSON results).
    pub fn write_all(self, text: &str) -> Result<(), CliError> {
        let mut sink = self.open()?;
        if let Err(e) = sink.writer().write_all(text.as_bytes()) {
            return Err(sink.error(&e));
        }
        sink.finish()
    }
}

/// An open output.
pub enum Sink {
    /// Standard output.
    Stdout(BufWriter<io::Stdout>),
    /// The temporary file of an atomic replacement.
    Replace {
        /// Removed on drop unless persisted.
        tmp: TempFile,
        /// The writer on it.
        writer: BufWriter<File>,
        /// The final path.
        target: PathBuf,
        /// The path as the user gave it.
        shown: PathBuf,
    },
    /// The target itself.
    InPlace {
        /// The writer on it.
        writer: BufWriter<File>,
        /// The path as the user gave it.
        shown: PathBuf,
    },
}

impl Sink {
    /// The writer.
    pub fn writer(&mut self) -> &mut dyn Write {
        match self {
            Sink::Stdout(w) => w,
            Sink::Replace { writer, .. } | Sink::InPlace { writer, .. } => writer,
        }
    }

    /// Turns an I/O error of this sink into a message naming the output.
    pub fn error(&self, e: &io::Error) -> CliError {
        match self {
            Sink::Stdout(_) if e.kind() == io::ErrorKind::BrokenPipe => CliError::BrokenPipe,
            Sink::Stdout(_) => CliError::msg(format!("cannot write to standard output: {e}")),
            Sink::Replace { shown, .. } | Sink::InPlace { shown, .. } => write_error(shown, e),
        }
    }

    /// Flushes; an atomic replacement is synced to disk and renamed over its target.
    pub fn finish(mut self) -> Result<(), CliError> {
        if let Err(e) = self.writer().flush() {
            return Err(self.error(&e));
        }
        match self {
            Sink::Stdout(_) | Sink::InPlace { .. } => Ok(()),
            Sink::Replace {
                tmp,
                writer,
                target,
                shown,
            } => {
                let file = writer
                    .into_inner()
                    .map_err(|e| write_error(&shown, e.error()))?;
                file.sync_all().map_err(|e| write_error(&shown, &e))?;
                drop(file);
                tmp.persist(&target).map_err(|e| write_error(&shown, &e))
            }
        }
    }
}

/// Appends the shortest decimal text that reads back to the same `f64` (zmij: Schubfach/yy,
/// e.g. `0.25`, `-1000.0`, `1.5e-12`, `3.2e+35`) to `out`.
pub fn push_f64(out: &mut Vec<u8>, buf: &mut zmij::Buffer, x: f64) {
    out.extend_from_slice(buf.format(x).as_bytes());
}

#[cfg(test)]
mod tests {
    use super::push_f64;

    /// Round-trip exactness of the CSV numbers: parsing the text gives the same bits (the
    /// reference is `str::parse`, an independent correctly rounded decimal reader).
    #[test]
    fn numbers_round_trip() {
        let mut buf = zmij::Buffer::new();
        let mut values = vec![0.0, -0.0, 1.0, -2.5, 1e-5, 1e-300, 123456.789, 1e16, 5e300];
        // Bit patterns from a 64-bit LCG (Knuth's MMIX constants): every exponent range.
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        while values.len() < 20_000 {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            let v = f64::from_bits(state);
            if v.is_finite() {
                values.push(v);
            }
        }
        for v in values {
            let mut out = Vec::new();
            push_f64(&mut out, &mut buf, v);
            let s = String::from_utf8(out).unwrap();
            assert_eq!(s.parse::<f64>().unwrap().to_bits(), v.to_bits(), "{s}");
        }
        let mut text = |v: f64| {
            let mut out = Vec::new();
            push_f64(&mut out, &mut buf, v);
            String::from_utf8(out).unwrap()
        };
        assert_eq!(text(0.25), "0.25");
        assert_eq!(text(-1000.0), "-1000.0");
        assert_eq!(text(1.5e-12), "1.5e-12");
    }
}

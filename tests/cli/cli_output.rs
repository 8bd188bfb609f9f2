//! `--output` writes like careful Unix tools (docs/cli.md, "Output files"): regular files are
//! replaced atomically and keep their mode, hard links stay linked, FIFOs and symbolic links are
//! written through (never replaced by a regular file), inputs are never overwritten, and a
//! signal leaves no temporary file behind.
//!
//! Everything happens inside a fresh temporary directory; no device path is ever touched (the
//! tests may run as root).

use crate::common;

use std::fs;

use common::*;

const SMALL: &str = "riser_5.toml";

/// The JSON that `gradient` writes for the shipped riser_5 scene, on stdout (the reference for
/// what a file output must contain).
fn reference_gradient() -> String {
    let o = run(&["gradient".as_ref(), scene(SMALL).as_os_str()]);
    assert_success(&o);
    stdout(&o)
}

fn gradient_to(out: &std::path::Path) -> std::process::Output {
    run(&[
        "gradient".as_ref(),
        scene(SMALL).as_os_str(),
        "--output".as_ref(),
        out.as_os_str(),
    ])
}

#[test]
fn a_new_file_is_created_and_no_temporary_file_is_left() {
    let dir = Dir::new();
    let out = dir.join("g.json");
    let o = gradient_to(&out);
    assert_success(&o);
    assert!(o.stdout.is_empty());
    assert_eq!(fs::read_to_string(&out).unwrap(), reference_gradient());
    assert_eq!(dir.files(), ["g.json"]);
}

#[test]
fn output_onto_an_input_is_refused() {
    let dir = Dir::new();
    let text = fs::read_to_string(scene(SMALL)).unwrap();
    let sc = dir.write("scene.toml", &text);
    for sub in ["simulate", "gradient", "optimize", "explore"] {
        let o = run(&[sub, sc.to_str().unwrap(), "-o", sc.to_str().unwrap()]);
        assert_one_error(&o, &["scene.toml", "refusing", "input"]);
        assert_eq!(fs::read_to_string(&sc).unwrap(), text, "{sub}");
    }
    // The --controls file is an input too.
    let controls = dir.write("u.json", "{\"controls\": [1.5]}");
    let o = run(&[
        "simulate",
        sc.to_str().unwrap(),
        "--controls",
        controls.to_str().unwrap(),
        "-o",
        controls.to_str().unwrap(),
    ]);
    assert_one_error(&o, &["u.json", "refusing", "input"]);
    assert_eq!(
        fs::read_to_string(&controls).unwrap(),
        "{\"controls\": [1.5]}"
    );
    assert_eq!(dir.files(), ["scene.toml", "u.json"]);
}

#[test]
fn a_directory_is_refused() {
    let dir = Dir::new();
    let o = gradient_to(dir.path());
    assert_one_error(&o, &["directory"]);
}

#[cfg(unix)]
mod unix {
    use super::*;
    use std::os::unix::fs::{FileTypeExt, MetadataExt, PermissionsExt};
    use std::path::Path;
    use std::process::{Command, Stdio};
    use std::time::{Duration, Instant};

    fn mode(p: &Path) -> u32 {
        fs::metadata(p).unwrap().mode() & 0o7777
    }

    #[test]
    fn a_replaced_file_keeps_its_mode() {
        let dir = Dir::new();
        for m in [0o600, 0o640, 0o604, 0o755] {
            let out = dir.write("g.json", "old contents");
            fs::set_permissions(&out, fs::Permissions::from_mode(m)).unwrap();
            let ino = fs::metadata(&out).unwrap().ino();
            let o = gradient_to(&out);
            assert_success(&o);
            assert_eq!(fs::read_to_string(&out).unwrap(), reference_gradient());
            assert_eq!(mode(&out), m, "mode {m:o} not kept");
            // Replaced by rename (a new inode), not rewritten in place.
            assert_ne!(fs::metadata(&out).unwrap().ino(), ino);
            assert_eq!(dir.files(), ["g.json"]);
        }
    }

    #[test]
    fn a_hard_linked_file_is_written_in_place_and_stays_linked() {
        let dir = Dir::new();
        let a = dir.write("a.json", "old contents, longer than nothing");
        let b = dir.join("b.json");
        fs::hard_link(&a, &b).unwrap();
        let o = gradient_to(&a);
        assert_success(&o);
        let want = reference_gradient();
        assert_eq!(fs::read_to_string(&a).unwrap(), want);
        assert_eq!(
            fs::read_to_string(&b).unwrap(),
            want,
            "the other link sees it"
        );
        assert_eq!(fs::metadata(&a).unwrap().nlink(), 2);
        assert_eq!(
            fs::metadata(&a).unwrap().ino(),
            fs::metadata(&b).unwrap().ino()
        );
        assert_eq!(dir.files(), ["a.json", "b.json"]);
    }

    #[test]
    fn a_symbolic_link_is_followed_and_stays_a_link() {
        let dir = Dir::new();
        let real = dir.write("real.json", "old");
        fs::set_permissions(&real, fs::Permissions::from_mode(0o600)).unwrap();
        let link = dir.join("link.json");
        std::os::unix::fs::symlink("real.json", &link).unwrap();
        let o = gradient_to(&link);
        assert_success(&o);
        assert!(fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink());
        assert_eq!(fs::read_to_string(&real).unwrap(), reference_gradient());
        assert_eq!(mode(&real), 0o600);
        assert_eq!(dir.files(), ["link.json", "real.json"]);

        // A dangling link is written through: its target is created.
        let dangling = dir.join("dangling.json");
        std::os::unix::fs::symlink("made.json", &dangling).unwrap();
        assert_success(&gradient_to(&dangling));
        assert!(fs::symlink_metadata(&dangling)
            .unwrap()
            .file_type()
            .is_symlink());
        assert_eq!(
            fs::read_to_string(dir.join("made.json")).unwrap(),
            reference_gradient()
        );

        // A link to the scene is the scene: refused.
        let sc = dir.write("scene.toml", &fs::read_to_string(scene(SMALL)).unwrap());
        let to_scene = dir.join("to_scene.csv");
        std::os::unix::fs::symlink(&sc, &to_scene).unwrap();
        let o = run(&[
            "simulate",
            sc.to_str().unwrap(),
            "-o",
            to_scene.to_str().unwrap(),
        ]);
        assert_one_error(&o, &["to_scene.csv", "refusing", "scene.toml"]);
        // So is a hard link to it.
        let hard = dir.join("hard.csv");
        fs::hard_link(&sc, &hard).unwrap();
        let o = run(&[
            "simulate",
            sc.to_str().unwrap(),
            "-o",
            hard.to_str().unwrap(),
        ]);
        assert_one_error(&o, &["hard.csv", "refusing", "scene.toml"]);
        assert_eq!(
            fs::read_to_string(&sc).unwrap(),
            fs::read_to_string(scene(SMALL)).unwrap()
        );
    }

    #[test]
    fn a_fifo_is_written_in_place_and_stays_a_fifo() {
        let dir = Dir::new();
        let fifo = dir.join("pipe");
        let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
        // SAFETY: a valid NUL-terminated path inside our temporary directory.
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o644) }, 0, "mkfifo");
        let reader = {
            let fifo = fifo.clone();
            std::thread::spawn(move || fs::read_to_string(fifo).unwrap())
        };
        let o = gradient_to(&fifo);
        assert_success(&o);
        assert_eq!(reader.join().unwrap(), reference_gradient());
        assert!(fs::symlink_metadata(&fifo).unwrap().file_type().is_fifo());
        assert_eq!(dir.files(), ["pipe"]);
    }

    /// Starts a long optimisation writing into `dir`, waits until its temporary file exists,
    /// sends `signal`, and checks that the process died of it and left nothing behind.
    fn interrupted_run_leaves_nothing(signal: i32) {
        let dir = Dir::new();
        // long_horizon: 1001 per-step parameters, N = 1000; seconds of work (it ends at the
        // iteration limit), so the signal arrives mid-run.
        let sc = dir.write(
            "scene.toml",
            &fs::read_to_string(scene("long_horizon.toml")).unwrap(),
        );
        let out = dir.join("u.json");
        let mut child = Command::new(assert_cmd::cargo::cargo_bin!("chainbeam"))
            .args([
                "optimize",
                "-q",
                sc.to_str().unwrap(),
                "-o",
                out.to_str().unwrap(),
            ])
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let clock = Instant::now();
        loop {
            if dir.files().iter().any(|f| f.ends_with(".tmp")) {
                break;
            }
            assert!(
                child.try_wait().unwrap().is_none(),
                "the run ended before its temporary file was seen"
            );
            assert!(
                clock.elapsed() < Duration::from_secs(60),
                "no temporary file"
            );
            std::thread::sleep(Duration::from_millis(2));
        }
        // SAFETY: signalling our own child process.
        assert_eq!(unsafe { libc::kill(child.id() as libc::pid_t, signal) }, 0);
        let status = child.wait().unwrap();
        use std::os::unix::process::ExitStatusExt;
        assert_eq!(status.signal(), Some(signal), "{status:?}");
        assert_eq!(dir.files(), ["scene.toml"], "temporary file left behind");
    }

    #[test]
    fn sigterm_removes_the_temporary_file() {
        interrupted_run_leaves_nothing(libc::SIGTERM);
    }

    #[test]
    fn sigint_removes_the_temporary_file() {
        interrupted_run_leaves_nothing(libc::SIGINT);
    }
}

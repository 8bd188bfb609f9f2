//! Running a computation the way Python expects: the GIL released, Ctrl-C honoured, and rayon
//! pools that survive `fork`.
//!
//! [`interruptible`] runs the computation on a worker thread and waits for it with the GIL
//! released, waking every [`POLL`] to run Python's signal handlers (`Python::check_signals`): a
//! Ctrl-C (SIGINT → `KeyboardInterrupt`) then returns control to Python at once. The library
//! has no cancellation points, so the abandoned computation finishes on its worker thread in the
//! background and its result is dropped (it holds no Python object and no lock; at interpreter
//! exit the thread ends with the process). A panic on the worker thread (a bug) is reported as
//! `chainbeam.ChainbeamError`, never a crash of the interpreter.
//!
//! [`with_pool`] runs rayon work (multistart, the structured solvers' stage Jacobians, MPC) on
//! a rayon pool built for the call instead of rayon's global pool: the global pool's threads do
//! not survive `fork` (a child process forked after the parent used it would wait forever on
//! threads that exist only in the parent), a pool built in the child does. Results do not
//! depend on the number of threads (the library's multistart and Riccati docs).

use std::sync::mpsc::{sync_channel, RecvTimeoutError};
use std::time::Duration;

use pyo3::prelude::*;

use crate::errors;

/// How often the waiting thread checks for signals.
pub const POLL: Duration = Duration::from_millis(50);

/// The worker thread's stack: the size of a main thread's on Linux (the command line runs the
/// same computations on its main thread).
const STACK: usize = 8 << 20;

/// Runs `f` on a worker thread with the GIL released and returns its result; a signal handler
/// that raises (Ctrl-C: `KeyboardInterrupt`) ends the wait with its exception.
pub fn interruptible<T, F>(py: Python<'_>, f: F) -> PyResult<T>
where
    T: Send + 'static,
    F: FnOnce() -> T + Send + 'static,
{
    let (tx, rx) = sync_channel(1);
    std::thread::Builder::new()
        .name("chainbeam".into())
        .stack_size(STACK)
        .spawn(move || {
            // The receiver is gone only after an interrupt: the result is not wanted.
            let _ = tx.send(f());
        })
        .map_err(|e| errors::internal(py, &format!("cannot start a worker thread: {e}")))?;
    let mut rx = rx;
    loop {
        // The receiver travels into the GIL-free closure and back (it is Send, not Sync).
        let (received, back) = py.detach(move || (rx.recv_timeout(POLL), rx));
        rx = back;
        match received {
            Ok(v) => return Ok(v),
            Err(RecvTimeoutError::Timeout) => py.check_signals()?,
            Err(RecvTimeoutError::Disconnected) => {
                return Err(errors::internal(
                    py,
                    "internal error in chainbeam (please report this bug): the computation \
                     panicked",
                ))
            }
        }
    }
}

/// Runs `f` inside a rayon pool of one thread per core built for this call (module docs: the
/// global pool does not survive `fork`).
pub fn with_pool<T: Send>(f: impl FnOnce() -> T + Send) -> Result<T, String> {
    let threads = std::thread::available_parallelism().map_or(1, usize::from);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .thread_name(|i| format!("chainbeam-rayon-{i}"))
        .build()
        .map_err(|e| format!("cannot start a thread pool: {e}"))?;
    Ok(pool.install(f))
}

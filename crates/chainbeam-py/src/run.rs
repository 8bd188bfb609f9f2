//! Running a computation the way Python expects: the GIL released, Ctrl-C honoured (and the
//! work stopped), progress reported, and rayon pools that survive `fork`.
//!
//! [`interruptible`] (and [`watched`], which also reports progress) runs the computation on a
//! worker thread and waits for it with the GIL released, waking every [`POLL`] to run Python's
//! signal handlers (`Python::check_signals`) and the progress callback. A Ctrl-C (SIGINT →
//! `KeyboardInterrupt`), or a progress callback that raises, returns control to Python at once
//! and cancels the computation through the worker's [`CancelToken`]
//! ([`chainbeam::cancel`]): the library checks the token once per batch of
//! [`chainbeam::cancel::CHECK_EVERY`] steps of every simulation and closed loop, before every
//! run of a fatigue study, and (here) at every iteration of an optimiser, so the abandoned
//! work stops within a batch instead of running to its end in the background
//! (python/tests/test_cancel.py measures the CPU time it uses after the interrupt). A panic on
//! the worker thread (a bug) is reported as `chainbeam.ChainbeamError`, never a crash of the
//! interpreter.
//!
//! Progress: the worker counts what it has done on a [`Ticker`] (runs of a fatigue study,
//! decisions of a closed loop, iterations of an optimiser) and the waiting thread, which holds
//! the GIL between waits, hands `(done, total)` to the Python callback when the count has
//! changed: the callback runs on the calling thread, never on the worker.
//!
//! [`with_pool`] runs rayon work (multistart, the structured solvers' stage Jacobians, MPC,
//! fatigue studies) on a rayon pool built for the call instead of rayon's global pool: the
//! global pool's threads do not survive `fork` (a child process forked after the parent used it
//! would wait forever on threads that exist only in the parent), a pool built in the child does.
//! The pool's threads take the calling thread's cancellation token. Results do not depend on the
//! number of threads (the library's multistart and Riccati docs).

use std::collections::HashMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{sync_channel, RecvTimeoutError};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use chainbeam::cancel::{self, CancelToken};
use pyo3::prelude::*;

use crate::errors;

/// How often the waiting thread checks for signals and reports progress.
pub const POLL: Duration = Duration::from_millis(50);

/// The worker thread's stack: the size of a main thread's on Linux (the command line runs the
/// same computations on its main thread).
const STACK: usize = 8 << 20;

/// What a computation has done out of how much (shared between the worker, which counts, and
/// the waiting thread, which reports).
#[derive(Debug, Default)]
pub struct Ticker {
    done: AtomicU64,
    total: AtomicU64,
}

impl Ticker {
    /// Sets how many units the whole computation has.
    pub fn set_total(&self, total: u64) {
        self.total.store(total, Ordering::Relaxed);
    }

    /// One more unit done.
    pub fn tick(&self) {
        self.done.fetch_add(1, Ordering::Relaxed);
    }

    /// (done, total) now.
    fn get(&self) -> (u64, u64) {
        (
            self.done.load(Ordering::Relaxed),
            self.total.load(Ordering::Relaxed),
        )
    }
}

/// The tokens of the computations running in this process, by a serial number: what
/// [`_cancel_running`] cancels.
static RUNNING: Mutex<Option<HashMap<u64, CancelToken>>> = Mutex::new(None);

/// The serial number of the next computation.
static SERIAL: AtomicU64 = AtomicU64::new(0);

/// A computation's entry in [`RUNNING`], removed when dropped (at the end of its wait).
struct Registered(u64);

impl Registered {
    fn new(token: &CancelToken) -> Self {
        let id = SERIAL.fetch_add(1, Ordering::Relaxed);
        let mut running = RUNNING.lock().unwrap_or_else(|e| e.into_inner());
        running
            .get_or_insert_with(HashMap::new)
            .insert(id, token.clone());
        Registered(id)
    }
}

impl Drop for Registered {
    fn drop(&mut self) {
        let mut running = RUNNING.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(m) = running.as_mut() {
            m.remove(&self.0);
        }
    }
}

/// Cancels every chainbeam computation running in this process, on any thread (each raises
/// `ChainbeamError` with `kind == "Cancelled"` to its caller within a batch of steps); returns
/// how many there were. `chainbeam.fatigue` and `chainbeam.sweep` call it when a Ctrl-C
/// interrupts their wait for an executor that runs tasks on this process's threads (a
/// `ThreadPoolExecutor`: its threads receive no signal).
#[pyfunction]
pub fn _cancel_running() -> usize {
    let running = RUNNING.lock().unwrap_or_else(|e| e.into_inner());
    let tokens = running.as_ref().map_or(0, |m| {
        m.values().for_each(CancelToken::cancel);
        m.len()
    });
    tokens
}

/// Runs `f` on a worker thread with the GIL released and returns its result; a signal handler
/// that raises (Ctrl-C: `KeyboardInterrupt`) ends the wait with its exception and cancels `f`.
pub fn interruptible<T, F>(py: Python<'_>, f: F) -> PyResult<T>
where
    T: Send + 'static,
    F: FnOnce() -> T + Send + 'static,
{
    watched(py, None, move |_| f())
}

/// [`interruptible`] with progress: `f` counts on the [`Ticker`] it is given, and `progress`
/// (a Python callable, or None) is called as `progress(done, total)` on this thread whenever
/// the count changed, and once at the end. An exception of the callback cancels the
/// computation and is raised.
pub fn watched<T, F>(py: Python<'_>, progress: Option<&Bound<'_, PyAny>>, f: F) -> PyResult<T>
where
    T: Send + 'static,
    F: FnOnce(&Arc<Ticker>) -> T + Send + 'static,
{
    let (tx, rx) = sync_channel(1);
    let token = CancelToken::new();
    let ticker = Arc::new(Ticker::default());
    let _registered = Registered::new(&token);
    let (worker_token, worker_ticker) = (token.clone(), ticker.clone());
    std::thread::Builder::new()
        .name("chainbeam".into())
        .stack_size(STACK)
        .spawn(move || {
            let _guard = worker_token.install();
            // The receiver is gone only after an interrupt: the result is not wanted.
            let _ = tx.send(f(&worker_ticker));
        })
        .map_err(|e| errors::internal(py, &format!("cannot start a worker thread: {e}")))?;
    let mut reported = (u64::MAX, u64::MAX);
    let mut report = || -> PyResult<()> {
        let Some(cb) = progress else { return Ok(()) };
        let now = ticker.get();
        if now != reported {
            reported = now;
            cb.call1(now)?;
        }
        Ok(())
    };
    let mut rx = rx;
    loop {
        // The receiver travels into the GIL-free closure and back (it is Send, not Sync).
        let (received, back) = py.detach(move || (rx.recv_timeout(POLL), rx));
        rx = back;
        match received {
            Ok(v) => {
                report()?;
                return Ok(v);
            }
            Err(RecvTimeoutError::Timeout) => {
                if let Err(e) = py.check_signals().and_then(|()| report()) {
                    token.cancel();
                    return Err(e);
                }
            }
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
/// global pool does not survive `fork`); its threads take the calling thread's cancellation
/// token.
pub fn with_pool<T: Send>(f: impl FnOnce() -> T + Send) -> Result<T, String> {
    let threads = std::thread::available_parallelism().map_or(1, usize::from);
    let token = cancel::current();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .thread_name(|i| format!("chainbeam-rayon-{i}"))
        .start_handler(move |_| cancel::set_thread_token(token.clone()))
        .build()
        .map_err(|e| format!("cannot start a thread pool: {e}"))?;
    Ok(pool.install(f))
}

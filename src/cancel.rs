//! Cooperative cancellation: a front end (the Python bindings on Ctrl-C, a service ending a job)
//! asks a running computation to stop, and the computation returns [`Error::Cancelled`] at its
//! next check instead of running to the end with nobody waiting for its result.
//!
//! A [`CancelToken`] is a shared flag. [`CancelToken::install`] makes it the current thread's
//! token for the life of the returned guard; the long loops of the library call [`check`] once
//! per batch of [`CHECK_EVERY`] steps (the stored and streamed simulations, the plant of
//! [`crate::mpc`] that every closed loop and PD tuning steps) and at each decision of a closed
//! loop and before each run of a fatigue study. A thread without a token (the
//! default: the command line, a plain library call) never stops: [`check`] is then one
//! thread-local read. Threads that a computation starts (a rayon pool) see a token only if the
//! front end installs it on them too (e.g. in the pool's start handler).
//!
//! The checks read the flag only: the results of a computation that is not cancelled are the
//! same bit for bit, and no check allocates.

use std::cell::RefCell;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use crate::{Error, Result};

/// How many steps a loop runs between two [`check`]s: the batch after which a cancellation is
/// seen (at most 256 steps of the largest chain: milliseconds to tens of milliseconds).
pub const CHECK_EVERY: usize = 256;

/// A shared cancellation flag (cheap to clone: the clones share the flag).
#[derive(Clone, Debug, Default)]
pub struct CancelToken(Arc<AtomicBool>);

impl CancelToken {
    /// A token that is not cancelled.
    pub fn new() -> Self {
        Self::default()
    }

    /// Asks every computation that checks this token to stop.
    pub fn cancel(&self) {
        self.0.store(true, Ordering::Relaxed);
    }

    /// Whether [`cancel`](Self::cancel) was called.
    pub fn is_cancelled(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }

    /// Makes this token the current thread's until the guard is dropped (the previous one, if
    /// any, is restored then).
    pub fn install(&self) -> TokenGuard {
        let previous = CURRENT.with(|c| c.replace(Some(self.clone())));
        TokenGuard { previous }
    }
}

/// Restores the thread's previous token when dropped ([`CancelToken::install`]).
#[derive(Debug)]
#[must_use = "the token is the thread's only while the guard lives"]
pub struct TokenGuard {
    previous: Option<CancelToken>,
}

impl Drop for TokenGuard {
    fn drop(&mut self) {
        let previous = self.previous.take();
        CURRENT.with(|c| *c.borrow_mut() = previous);
    }
}

thread_local! {
    static CURRENT: RefCell<Option<CancelToken>> = const { RefCell::new(None) };
}

/// The current thread's token, if one is installed (to hand on to threads the computation
/// starts, [`set_thread_token`]).
pub fn current() -> Option<CancelToken> {
    CURRENT.with(|c| c.borrow().clone())
}

/// Makes `token` the current thread's token for the rest of the thread's life (a rayon pool's
/// start handler: the pool's threads then see the token of the computation that built it).
pub fn set_thread_token(token: Option<CancelToken>) {
    CURRENT.with(|c| *c.borrow_mut() = token);
}

/// Whether the current thread's token (if any) was cancelled.
pub fn is_cancelled() -> bool {
    CURRENT.with(|c| c.borrow().as_ref().is_some_and(CancelToken::is_cancelled))
}

/// `Err(Error::Cancelled)` when the current thread's token was cancelled, else `Ok(())`.
///
/// # Errors
/// [`Error::Cancelled`].
pub fn check() -> Result<()> {
    if is_cancelled() {
        Err(Error::Cancelled)
    } else {
        Ok(())
    }
}

/// [`check`] at the steps k that start a batch of [`CHECK_EVERY`] steps.
///
/// # Errors
/// [`Error::Cancelled`].
#[inline]
pub fn check_at(k: usize) -> Result<()> {
    if k.is_multiple_of(CHECK_EVERY) {
        check()
    } else {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Without a token nothing is cancelled; an installed token is seen until its guard drops,
    /// and only on its own thread.
    #[test]
    fn token_is_per_thread_and_scoped() {
        assert!(check().is_ok());
        let token = CancelToken::new();
        {
            let _guard = token.install();
            assert!(check().is_ok());
            token.cancel();
            assert!(matches!(check(), Err(Error::Cancelled)));
            assert!(check_at(1).is_ok(), "only the batch's first step checks");
            assert!(matches!(check_at(CHECK_EVERY), Err(Error::Cancelled)));
            let other = std::thread::spawn(|| check().is_ok()).join().unwrap();
            assert!(other, "another thread has no token");
        }
        assert!(check().is_ok(), "the guard restored the thread's state");
    }
}

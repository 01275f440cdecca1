//! Stopping a long call from outside: Ctrl-C in Python, a caller's deadline.
//!
//! A front end that wants a call to be stoppable runs it inside [`Cancel::run`] on the
//! thread that does the work, and calls [`Cancel::cancel`] from another thread. The core
//! calls [`check`] between its stages and inside its long loops (the order scan, the
//! automatic order's candidates, every refinement round and iteration, the truncated
//! SVD's restarts, OKID's QR blocks, Welch's frame batches); once the token is cancelled,
//! the next check returns [`EraError::Interrupted`] and the call unwinds through its
//! ordinary error path, freeing what it holds. Nothing is left half-changed: the core
//! never mutates its caller's data.
//!
//! The token lives in a thread-local of the calling thread. rayon's workers do not see
//! it, so a loop run across the pool captures [`current`] first and checks that. The CLI
//! does not use this: a signal there ends the process (see era-io's `atomic::abandon`),
//! which is immediate and needs no check points.
//!
//! Why our own and not a crate: what is needed is one atomic flag and a thread-local, and
//! the contract (where the checks are) is the core's.

use crate::error::{EraError, Result};
use std::cell::RefCell;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// A flag a caller raises to stop a call that runs under it.
#[derive(Debug, Clone, Default)]
pub struct Cancel(Arc<AtomicBool>);

thread_local! {
    static CURRENT: RefCell<Option<Cancel>> = const { RefCell::new(None) };
}

impl Cancel {
    /// A token not yet cancelled.
    pub fn new() -> Self {
        Cancel::default()
    }

    /// Asks the call running under this token to stop at its next check.
    pub fn cancel(&self) {
        self.0.store(true, Ordering::Relaxed);
    }

    /// Whether [`Cancel::cancel`] was called.
    pub fn is_cancelled(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }

    /// [`EraError::Interrupted`] once cancelled.
    ///
    /// # Errors
    /// [`EraError::Interrupted`] when the token was cancelled.
    pub fn check(&self) -> Result<()> {
        if self.is_cancelled() {
            Err(EraError::Interrupted)
        } else {
            Ok(())
        }
    }

    /// Runs `work` on this thread with this token as the current one (the previous one
    /// is restored afterwards, also when `work` panics).
    pub fn run<R>(&self, work: impl FnOnce() -> R) -> R {
        struct Restore(Option<Cancel>);
        impl Drop for Restore {
            fn drop(&mut self) {
                let previous = self.0.take();
                CURRENT.with(|c| *c.borrow_mut() = previous);
            }
        }
        let previous = CURRENT.with(|c| c.borrow_mut().replace(self.clone()));
        let _restore = Restore(previous);
        work()
    }
}

/// The token of the call running on this thread, if any (to hand to a parallel loop).
pub fn current() -> Option<Cancel> {
    CURRENT.with(|c| c.borrow().clone())
}

/// [`EraError::Interrupted`] when the call running on this thread was cancelled.
///
/// # Errors
/// [`EraError::Interrupted`] when the current token was cancelled.
pub fn check() -> Result<()> {
    CURRENT.with(|c| match &*c.borrow() {
        Some(token) => token.check(),
        None => Ok(()),
    })
}

/// Runs `work` under `token` (captured with [`current`] before the work left its
/// thread), so that the checks inside it see the caller's token on any worker.
pub(crate) fn under<R>(token: &Option<Cancel>, work: impl FnOnce() -> R) -> R {
    match token {
        Some(t) => t.run(work),
        None => work(),
    }
}

/// [`check`] for a token captured before a parallel loop.
///
/// # Errors
/// [`EraError::Interrupted`] when `token` was cancelled.
pub(crate) fn check_token(token: &Option<Cancel>) -> Result<()> {
    match token {
        Some(t) => t.check(),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_check_fails_only_under_a_cancelled_token() {
        assert!(check().is_ok());
        let token = Cancel::new();
        token.run(|| assert!(check().is_ok()));
        token.cancel();
        assert_eq!(token.run(check), Err(EraError::Interrupted));
        // Outside the run the thread has no token again.
        assert!(check().is_ok());
        assert!(current().is_none());
    }

    #[test]
    fn runs_nest_and_restore() {
        let outer = Cancel::new();
        let inner = Cancel::new();
        inner.cancel();
        outer.run(|| {
            assert_eq!(inner.run(check), Err(EraError::Interrupted));
            assert!(check().is_ok());
        });
    }

    #[test]
    fn a_token_is_restored_after_a_panic() {
        let token = Cancel::new();
        token.cancel();
        let caught = std::panic::catch_unwind(|| token.run(|| panic!("inside")));
        assert!(caught.is_err());
        assert!(check().is_ok());
    }

    #[test]
    fn another_thread_cancels() {
        let token = Cancel::new();
        let remote = token.clone();
        let seen = token.run(|| {
            std::thread::scope(|s| {
                s.spawn(move || remote.cancel());
            });
            check()
        });
        assert_eq!(seen, Err(EraError::Interrupted));
    }

    #[test]
    fn work_handed_to_another_thread_sees_the_token_under_it() {
        let token = Cancel::new();
        token.cancel();
        let (bare, carried) = token.run(|| {
            let captured = current();
            std::thread::scope(|s| {
                let bare = s.spawn(check).join().unwrap();
                let carried = s.spawn(|| under(&captured, check)).join().unwrap();
                (bare, carried)
            })
        });
        // A thread of its own has no token; `under` brings the caller's.
        assert!(bare.is_ok());
        assert_eq!(carried, Err(EraError::Interrupted));
        assert!(under(&None, check).is_ok());
    }
}

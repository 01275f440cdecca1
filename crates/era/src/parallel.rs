//! One setting for the threads of a run: rayon's and faer's together.
//!
//! era's parallel loops are rayon's (the model FRF across lines, the Welch estimate across
//! frames, the stabilization scan across orders, the CSV reader across rows), and faer's
//! dense kernels (SVD, QR, Hessenberg reduction, products) take their parallelism from
//! `faer::get_global_parallelism()`, whose default `Par::rayon(0)` means "as many threads
//! as the current rayon pool has". So a run placed inside a rayon pool of `n` threads
//! ([`with_threads`]) uses `n` threads in both, and a batch of runs, or a bootstrap, can
//! give each run one thread without oversubscribing the machine. Without a setting the
//! global pool is used (all cores, or `RAYON_NUM_THREADS`).
//!
//! The CLI's `--threads N` and Python's `threads=N` call [`with_threads`].

use crate::error::{EraError, Result};
use crate::params::Naming;

/// Most threads a run may ask for (a pool is a few kB of stack and a thread each; more
/// threads than this are never useful on one machine, and a huge count would exhaust
/// the process's threads before any work began).
pub const MAX_THREADS: usize = 1024;

/// Stack of a pool's threads: a main thread's usual 8 MB, as the work would have outside
/// a pool (a spawned thread's default is 2 MB).
const STACK: usize = 8 << 20;

/// Checks a thread count under its front end's name: 1 ..= [`MAX_THREADS`].
///
/// # Errors
/// [`EraError::Invalid`] for 0 or more than [`MAX_THREADS`].
pub fn check_threads(naming: Naming, threads: usize) -> Result<()> {
    if threads == 0 || threads > MAX_THREADS {
        return crate::params::invalid(format!(
            "{} {threads}: must be between 1 and {MAX_THREADS}",
            naming.name("threads")
        ));
    }
    Ok(())
}

/// Runs `work` with `threads` threads for rayon and faer (the global pool when `None`).
///
/// # Errors
/// [`check_threads`]'s, and [`EraError::Numerical`] when the operating system refuses
/// to start the threads.
pub fn with_threads<R: Send>(
    naming: Naming,
    threads: Option<usize>,
    work: impl FnOnce() -> R + Send,
) -> Result<R> {
    let Some(n) = threads else {
        return Ok(work());
    };
    check_threads(naming, n)?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .stack_size(STACK)
        .build()
        .map_err(|e| EraError::Numerical(format!("cannot start {n} threads: {e}")))?;
    // The call's cancel token follows it into the pool's thread.
    let token = crate::cancel::current();
    Ok(pool.install(|| crate::cancel::under(&token, work)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_pool_sets_rayon_and_faer_alike() {
        for n in [1, 3] {
            let (rayon_threads, faer_threads) = with_threads(Naming::Flag, Some(n), || {
                (
                    rayon::current_num_threads(),
                    faer::get_global_parallelism().degree(),
                )
            })
            .unwrap();
            assert_eq!(rayon_threads, n);
            // faer's `Par::rayon(0)` resolves to the current pool; one thread is `Seq`-like.
            assert_eq!(faer_threads, n);
        }
        assert_eq!(with_threads(Naming::Flag, None, || 7).unwrap(), 7);
    }

    #[test]
    fn counts_are_checked_under_the_front_ends_name() {
        let e = with_threads(Naming::Flag, Some(0), || ()).unwrap_err();
        assert_eq!(e.to_string(), "--threads 0: must be between 1 and 1024");
        assert!(e.is_input_error());
        let e = with_threads(Naming::Keyword, Some(5000), || ()).unwrap_err();
        assert!(e.to_string().starts_with("threads 5000:"), "{e}");
    }
}

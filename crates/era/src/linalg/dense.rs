//! The dense thin SVD of a Hankel matrix, stoppable at once.
//!
//! faer's SVD has no way to stop half way, and on the automatic path it is the one step
//! that can take a second or more. When the call runs under a cancel token
//! ([`crate::cancel`], Python), the SVD runs on a thread of its own that owns the matrix,
//! and the caller waits for it while watching the token: a cancelled call returns at
//! once and the abandoned SVD finishes in the background, owning everything it touches.
//! Without a token (the CLI, Rust callers) it runs right here, as `Mat::thin_svd` does.
//!
//! Either way the SVD is faer's `linalg::svd::svd` with the parallelism the caller's
//! thread resolves (`get_global_parallelism`, the size of the caller's rayon pool), so
//! the factors are bit for bit those of `Mat::thin_svd` on the caller's thread.

use crate::cancel;
use crate::error::{EraError, Result};
use faer::diag::Diag;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::svd::{self, ComputeSvdVectors};
use faer::{Mat, Par};

/// A thin SVD `H = U diag(s) Vᵀ`, `s` descending.
#[derive(Debug)]
pub(crate) struct ThinSvd {
    /// Left singular vectors, rows × min(rows, cols).
    pub u: Mat<f64>,
    /// Singular values, descending.
    pub s: Vec<f64>,
    /// Right singular vectors, cols × min(rows, cols).
    pub v: Mat<f64>,
}

/// How often a waiting caller looks at its cancel token.
const POLL: std::time::Duration = std::time::Duration::from_millis(20);

/// The thin SVD of `h` (consumed), `what` naming the matrix in a failure.
///
/// # Errors
/// [`EraError::Numerical`] when faer's SVD does not converge; [`EraError::Interrupted`]
/// when the call's token is cancelled while it runs.
pub(crate) fn thin_svd(h: Mat<f64>, what: &str) -> Result<ThinSvd> {
    let par = faer::get_global_parallelism();
    let failed = |e: svd::SvdError| EraError::Numerical(format!("SVD of {what}: {e:?}"));
    let Some(token) = cancel::current() else {
        return compute(&h, par).map_err(failed);
    };
    token.check()?;
    let (send, receive) = std::sync::mpsc::channel();
    let spawned = std::thread::Builder::new()
        .name("era-svd".into())
        .stack_size(8 << 20)
        .spawn(move || {
            // The receiver is gone when the call was cancelled: the result is dropped.
            let _ = send.send(compute(&h, par));
        });
    if spawned.is_err() {
        return Err(EraError::Numerical(format!(
            "SVD of {what}: cannot start a thread"
        )));
    }
    loop {
        match receive.recv_timeout(POLL) {
            Ok(result) => return result.map_err(failed),
            Err(std::sync::mpsc::RecvTimeoutError::Timeout) => token.check()?,
            Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => {
                return Err(EraError::Numerical(format!(
                    "SVD of {what}: its thread ended without a result"
                )))
            }
        }
    }
}

/// faer's thin SVD of `h` at parallelism `par` (what `Mat::thin_svd` runs).
fn compute(h: &Mat<f64>, par: Par) -> std::result::Result<ThinSvd, svd::SvdError> {
    let (m, n) = h.shape();
    let size = m.min(n);
    let mut u = Mat::zeros(m, size);
    let mut v = Mat::zeros(n, size);
    let mut s = Diag::zeros(size);
    let thin = ComputeSvdVectors::Thin;
    svd::svd(
        h.as_ref(),
        s.as_mut(),
        Some(u.as_mut()),
        Some(v.as_mut()),
        par,
        MemStack::new(&mut MemBuffer::new(svd::svd_scratch::<f64>(
            m,
            n,
            thin,
            thin,
            par,
            Default::default(),
        ))),
        Default::default(),
    )?;
    let s = (0..size).map(|k| s[k]).collect();
    Ok(ThinSvd { u, s, v })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn matrix() -> Mat<f64> {
        Mat::from_fn(60, 40, |i, j| {
            ((i * 7 + j * 13) % 17) as f64 - 0.3 * (i as f64 - j as f64).sin()
        })
    }

    #[test]
    fn equals_faers_thin_svd_bit_for_bit_with_and_without_a_token() {
        let h = matrix();
        let reference = h.thin_svd().unwrap();
        let here = thin_svd(h.clone(), "H").unwrap();
        let token = cancel::Cancel::new();
        let apart = token.run(|| thin_svd(h.clone(), "H")).unwrap();
        for found in [&here, &apart] {
            assert_eq!(found.u, reference.U().to_owned());
            assert_eq!(found.v, reference.V().to_owned());
            for k in 0..found.s.len() {
                assert_eq!(found.s[k].to_bits(), reference.S()[k].to_bits());
            }
        }
    }

    #[test]
    fn a_cancelled_call_returns_without_the_svd() {
        let token = cancel::Cancel::new();
        token.cancel();
        let r = token.run(|| thin_svd(matrix(), "H"));
        assert_eq!(r.unwrap_err(), EraError::Interrupted);
    }

    #[test]
    fn a_call_cancelled_while_its_svd_runs_returns_interrupted() {
        // A 1200 x 1200 SVD takes a good fraction of a second on any machine; the call is
        // cancelled a millisecond in, and returns while the abandoned SVD still runs.
        let h = Mat::from_fn(1200, 1200, |i, j| {
            ((i * 31 + j * 17) % 101) as f64 + f64::from(u8::from(i == j))
        });
        let token = cancel::Cancel::new();
        let remote = token.clone();
        let result = std::thread::scope(|s| {
            s.spawn(move || {
                std::thread::sleep(std::time::Duration::from_millis(1));
                remote.cancel();
            });
            token.run(|| thin_svd(h, "H"))
        });
        assert_eq!(result.unwrap_err(), EraError::Interrupted);
    }
}

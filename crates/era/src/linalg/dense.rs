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
//!
//! A realization needs only the leading singular vectors. For a tall or wide Hankel
//! (OKID's many outputs and few inputs), faer's SVD is a QR, the SVD of the small
//! triangle, and the QR's reflectors applied to the whole thin `U`; [`thin_svd_leading`]
//! takes the same steps with faer's own kernels and parameters but applies the
//! reflectors to the leading columns only (faer has no way to ask for part of `U`). The
//! singular values and the small side's vectors are bit for bit faer's; on DaISy's
//! 4172 x 298 Hankel at 60 states it saves a fifth of the SVD.

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

/// Matrices of fewer entries are decomposed on the caller's thread even under a cancel
/// token: their SVD takes milliseconds, while a thread and a pool of their own for each
/// (two threads started and ended, their stacks mapped and unmapped) cost a Python
/// worker a fifth of its time once another process ran beside it.
const INLINE_ENTRIES: usize = 1 << 18;

/// The thin SVD of `h` (consumed), `what` naming the matrix in a failure.
///
/// # Errors
/// [`EraError::Numerical`] when faer's SVD does not converge; [`EraError::Interrupted`]
/// when the call's token is cancelled while it runs.
pub(crate) fn thin_svd(h: Mat<f64>, what: &str) -> Result<ThinSvd> {
    let par = faer::get_global_parallelism();
    let entries = h.nrows() * h.ncols();
    stoppable(what, entries, move || compute(&h, par))
}

/// Runs the decomposition `work` under the calling thread's cancel token: right here when
/// there is none, on a thread of its own ([`on_own_thread`]) when there is; a failure of
/// faer's is an [`EraError::Numerical`] naming `what`.
fn stoppable<T: Send + 'static>(
    what: &str,
    entries: usize,
    work: impl FnOnce() -> std::result::Result<T, svd::SvdError> + Send + 'static,
) -> Result<T> {
    let failed = |e: svd::SvdError| EraError::Numerical(format!("SVD of {what}: {e:?}"));
    match cancel::current() {
        Some(token) if entries >= INLINE_ENTRIES => {
            on_own_thread(token, work, what)?.map_err(failed)
        }
        Some(token) => {
            token.check()?;
            work().map_err(failed)
        }
        None => work().map_err(failed),
    }
}

/// Runs `work` on a thread of its own while the caller watches `token`: the work's result,
/// or [`EraError::Interrupted`] at once when the token is cancelled (the work finishes in
/// the background and its result is dropped).
///
/// The work runs in a pool as large as the caller's ([`crate::parallel::with_threads`]):
/// a spawned thread belongs to no pool, and rayon's global one would both ignore the
/// call's thread count and, in a process forked after it started, have no threads at
/// all (the SVD would wait for ever).
fn on_own_thread<T: Send + 'static>(
    token: cancel::Cancel,
    work: impl FnOnce() -> T + Send + 'static,
    what: &str,
) -> Result<T> {
    token.check()?;
    let threads = rayon::current_num_threads();
    let (send, receive) = std::sync::mpsc::channel();
    let spawned = std::thread::Builder::new()
        .name("era-svd".into())
        .stack_size(8 << 20)
        .spawn(move || {
            // No pool (the system refused the threads): the sender is dropped, and the
            // caller reports the SVD's thread ended without a result.
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .stack_size(8 << 20)
                .build();
            let Ok(pool) = pool else { return };
            // The receiver is gone when the call was cancelled: the result is dropped.
            let _ = send.send(pool.install(work));
        });
    if spawned.is_err() {
        return Err(EraError::Numerical(format!(
            "SVD of {what}: cannot start a thread"
        )));
    }
    loop {
        match receive.recv_timeout(POLL) {
            Ok(result) => return Ok(result),
            Err(std::sync::mpsc::RecvTimeoutError::Timeout) => token.check()?,
            Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => {
                return Err(EraError::Numerical(format!(
                    "SVD of {what}: its thread ended without a result"
                )))
            }
        }
    }
}

/// [`thin_svd`] with only the leading `keep` columns of `U` and `V` (all the singular
/// values): on a tall or wide matrix (a ratio of sides above faer's QR threshold), the
/// long side's reflectors are applied to `keep` columns instead of all of them. Square
/// matrices take [`thin_svd`] unchanged.
///
/// # Errors
/// As [`thin_svd`].
pub(crate) fn thin_svd_leading(h: Mat<f64>, keep: usize, what: &str) -> Result<ThinSvd> {
    let (m, n) = h.shape();
    let (long, short) = (m.max(n), m.min(n));
    let keep = keep.min(short);
    if short == 0 || (long as f64) <= QR_RATIO * short as f64 || keep == short {
        let mut svd = thin_svd(h, what)?;
        svd.u = svd.u.subcols(0, keep).to_owned();
        svd.v = svd.v.subcols(0, keep).to_owned();
        return Ok(svd);
    }
    let par = faer::get_global_parallelism();
    stoppable(what, m * n, move || {
        if m >= n {
            tall_leading(h, keep, par)
        } else {
            // Hᵀ = V S Uᵀ: the tall route on the transpose, the factors swapped back.
            tall_leading(h.transpose().to_owned(), keep, par).map(|t| ThinSvd {
                u: t.v,
                s: t.s,
                v: t.u,
            })
        }
    })
}

/// The singular values of `h` (consumed), descending: faer's, stoppable as
/// [`thin_svd`].
///
/// # Errors
/// As [`thin_svd`].
pub(crate) fn singular_values(h: Mat<f64>, what: &str) -> Result<Vec<f64>> {
    let entries = h.nrows() * h.ncols();
    stoppable(what, entries, move || h.singular_values())
}

/// The singular values of `h`, descending, from the eigenvalues of the Gram matrix of
/// its short side (`h hᵀ` or `hᵀ h`, lower triangle by one GEMM). Each eigenvalue
/// carries an error of about `m ε σ₁²`, `m` the long side (the Gram product's inner
/// dimension), so a value `σ` is known to a relative `m ε (σ₁/σ)² / 2`: to about 4e-5
/// at `1e-4 σ₁` for the probe's `m = 3184`, and not at all below `√ε σ₁`. For a caller that needs no smaller ones (the order probe on noisy data) it
/// costs about half the SVD's flops.
pub(crate) fn gram_singular_values(h: Mat<f64>, what: &str) -> Result<Vec<f64>> {
    use faer::linalg::matmul::triangular::{matmul, BlockStructure};
    let entries = h.nrows() * h.ncols();
    stoppable(what, entries, move || {
        let short = h.nrows().min(h.ncols());
        let (left, right) = if h.nrows() <= h.ncols() {
            (h.as_ref(), h.transpose())
        } else {
            (h.transpose(), h.as_ref())
        };
        let mut gram = Mat::<f64>::zeros(short, short);
        matmul(
            gram.as_mut(),
            BlockStructure::TriangularLower,
            faer::Accum::Replace,
            left,
            BlockStructure::Rectangular,
            right,
            BlockStructure::Rectangular,
            1.0,
            faer::get_global_parallelism(),
        );
        let eigenvalues = gram
            .self_adjoint_eigenvalues(faer::Side::Lower)
            .map_err(|_| svd::SvdError::NoConvergence)?;
        Ok(eigenvalues
            .into_iter()
            .rev()
            .map(|l| l.max(0.0).sqrt())
            .collect())
    })
}

/// faer's ratio of sides above which its SVD starts with a QR (`SvdParams`'s default).
const QR_RATIO: f64 = 11.0 / 6.0;

/// The SVD of a tall `qr` (rows > cols, factored in place) with `keep` leading columns
/// of `U` and `V`: the steps of faer's tall SVD (QR, the triangle's SVD, the reflectors
/// on `U`) with the reflectors applied to `keep` columns only.
fn tall_leading(
    mut qr: Mat<f64>,
    keep: usize,
    par: Par,
) -> std::result::Result<ThinSvd, svd::SvdError> {
    use faer::linalg::{householder, qr::no_pivoting::factor};
    let (m, n) = qr.shape();
    let block = factor::recommended_block_size::<f64>(m, n);
    let mut coeff = Mat::<f64>::zeros(block, n);
    factor::qr_in_place(
        qr.as_mut(),
        coeff.as_mut(),
        par,
        MemStack::new(&mut MemBuffer::new(factor::qr_in_place_scratch::<f64>(
            m,
            n,
            block,
            par,
            Default::default(),
        ))),
        // faer's SVD passes its QR parameters, whose default is this default.
        Default::default(),
    );
    let r = Mat::from_fn(n, n, |i, j| if i <= j { qr[(i, j)] } else { 0.0 });
    let small = compute(&r, par)?;
    let mut u = Mat::<f64>::zeros(m, keep);
    u.as_mut()
        .submatrix_mut(0, 0, n, keep)
        .copy_from(small.u.subcols(0, keep));
    householder::apply_block_householder_sequence_on_the_left_in_place_with_conj(
        qr.as_ref(),
        coeff.as_ref(),
        faer::Conj::No,
        u.as_mut(),
        par,
        MemStack::new(&mut MemBuffer::new(
            householder::apply_block_householder_sequence_on_the_left_in_place_scratch::<f64>(
                m, block, keep,
            ),
        )),
    );
    Ok(ThinSvd {
        u,
        s: small.s,
        v: small.v.subcols(0, keep).to_owned(),
    })
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

    /// The Gram route against the SVD, wide and tall, on a spectrum from 1 down to 1e-3:
    /// each value to `m ε (σ₁/σ)²` of itself, `m` the long side (the doc's bound, times 10).
    #[test]
    fn gram_singular_values_match_the_svd_down_to_a_thousandth_of_sigma1() {
        let (m, n) = (50, 140);
        let mut rng = crate::linalg::rng::Minstd::new(17);
        let left = Mat::from_fn(m, m, |_, _| rng.normal())
            .qr()
            .compute_thin_Q();
        let right = Mat::from_fn(n, m, |_, _| rng.normal())
            .qr()
            .compute_thin_Q();
        let known: Vec<f64> = (0..m)
            .map(|i| 10f64.powf(-3.0 * i as f64 / (m - 1) as f64))
            .collect();
        let wide = &left
            * Mat::from_fn(m, m, |i, j| if i == j { known[i] } else { 0.0 })
            * right.transpose();
        for h in [wide.clone(), wide.transpose().to_owned()] {
            let gram = gram_singular_values(h.clone(), "a test matrix").unwrap();
            let svd = singular_values(h, "a test matrix").unwrap();
            assert_eq!(gram.len(), m);
            for (i, (g, s)) in gram.iter().zip(&svd).enumerate() {
                let bound = 10.0 * n as f64 * f64::EPSILON * (svd[0] / s).powi(2);
                assert!((g - s).abs() <= bound * s, "σ_{i}: {g:e} against {s:e}");
                assert!(
                    (s - known[i]).abs() <= 1e-12,
                    "the SVD itself: {s:e} against {:e}",
                    known[i]
                );
            }
        }
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
    fn an_svd_on_its_own_thread_keeps_the_callers_thread_count() {
        // Under a token the work leaves the caller's pool for a thread of its own; it
        // runs in a pool as large as the caller's, not in rayon's global one.
        for n in [1, 3] {
            let token = cancel::Cancel::new();
            let inside = token
                .run(|| {
                    crate::parallel::with_threads(crate::params::Naming::Flag, Some(n), || {
                        on_own_thread(cancel::current().unwrap(), rayon::current_num_threads, "H")
                    })
                })
                .unwrap()
                .unwrap();
            assert_eq!(inside, n);
        }
    }

    #[test]
    fn the_leading_columns_are_faers_on_tall_wide_and_square_matrices() {
        let tall = Mat::from_fn(300, 40, |i, j| {
            ((i * 7 + j * 13) % 17) as f64 - 0.3 * ((i * j) as f64).sin()
        });
        for h in [tall.clone(), tall.transpose().to_owned(), matrix()] {
            let reference = h.thin_svd().unwrap();
            let keep = 9;
            let token = cancel::Cancel::new();
            let here = thin_svd_leading(h.clone(), keep, "H").unwrap();
            let apart = token
                .run(|| thin_svd_leading(h.clone(), keep, "H"))
                .unwrap();
            for found in [&here, &apart] {
                assert_eq!((found.u.ncols(), found.v.ncols()), (keep, keep));
                for k in 0..found.s.len() {
                    assert_eq!(found.s[k].to_bits(), reference.S()[k].to_bits());
                }
                let lead = |m: faer::MatRef<f64>| m.subcols(0, keep).to_owned();
                let du = (&found.u - lead(reference.U())).norm_max();
                let dv = (&found.v - lead(reference.V())).norm_max();
                assert!(du < 1e-13 && dv < 1e-13, "U off by {du:e}, V by {dv:e}");
            }
        }
        // More columns than the short side: all of them.
        let all = thin_svd_leading(tall.clone(), 100, "H").unwrap();
        assert_eq!((all.u.ncols(), all.v.ncols()), (40, 40));
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

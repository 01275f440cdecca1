//! One FFT plan cache for the process: every real FFT of the core (the FRF's inverse
//! transform, the matrix-free Hankel operator, Welch's spectra) takes its plans from one
//! `realfft` planner, so a length is planned once however many stages use it.

use realfft::{ComplexToReal, RealFftPlanner, RealToComplex};
use std::sync::{Arc, Mutex, OnceLock};

/// Smallest `n ≥ min` whose prime factors are 2, 3, 5 and 7 (fast FFT sizes).
pub(crate) fn fast_fft_len(min: usize) -> usize {
    let mut n = min.max(1);
    loop {
        let mut m = n;
        for f in [2, 3, 5, 7] {
            while m.is_multiple_of(f) {
                m /= f;
            }
        }
        if m == 1 {
            return n;
        }
        n += 1;
    }
}

/// Forward and inverse real FFT plans of length `len`, from a planner shared by the
/// process: `realfft` caches plans per planner, so each length is planned once.
pub(crate) fn real_fft_plans(
    len: usize,
) -> (Arc<dyn RealToComplex<f64>>, Arc<dyn ComplexToReal<f64>>) {
    static PLANNER: OnceLock<Mutex<RealFftPlanner<f64>>> = OnceLock::new();
    let mut planner = PLANNER
        .get_or_init(|| Mutex::new(RealFftPlanner::new()))
        .lock()
        // A panic elsewhere while planning leaves a usable planner (plans are immutable).
        .unwrap_or_else(|poisoned| poisoned.into_inner());
    (planner.plan_fft_forward(len), planner.plan_fft_inverse(len))
}

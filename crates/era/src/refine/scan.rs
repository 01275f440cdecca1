//! Modes the start missed, found in the residual of a fit.
//!
//! A start without a mode leaves that mode's resonance in the residual, and the fit
//! then does one of two wrong things: a neighbouring pole with a free (or rank-one)
//! residue stands in for two modes, or a pole leaves the mode it started on for the
//! larger unfitted resonance, and the mode it left is missed in turn. Both leave a
//! resonance-shaped residual. This module looks for one.
//!
//! # The test
//!
//! For a candidate pole `s_c` at each line `f_c` of the band (damping: the median of
//! the fitted modes'), the residual `e_ij` of every pair over a window of `±3ζ f_c`
//! (1.5 half-power bandwidths each side, at least 4 lines) is projected on the candidate's two real
//! columns `g(s_c) + g(s̄_c)` and `j(g(s_c) − g(s̄_c))` (the model's own mode columns,
//! [`super::model`]), each pair whitened by its residual's RMS over the band. The
//! statistic is the F ratio of the explained to the unexplained residual per degree of
//! freedom:
//!
//! ```text
//! F = (Δ/ν) / ((E − Δ)/(n − ν)),   ν = 2·pairs,  n = 2·lines·pairs
//! ```
//!
//! with `E` the window's residual energy and `Δ` the part the candidate explains. Noise
//! alone gives `F ≈ 1` (white noise of any level: the ratio is local, so noise that
//! varies over the band does not set it off); an unfitted resonance gives tens to
//! thousands. The bar is [`F_MINIMUM`], or for few pairs the F ratio that noise alone
//! exceeds anywhere in the band with a chance of 1e-3, whichever is higher. Candidates
//! above it and above half the largest F are returned, largest first, at most
//! [`MAX_ADDED`], each only if its window does not overlap a stronger one's: an
//! unfitted resonance also bends the fit of its neighbours, and their lesser peaks,
//! within a window or two of it, go once it is fitted (a pole added on such a peak
//! costs the refit dozens of iterations, wandering as a weak spurious mode); a real
//! one that close is found by the next scan.
//!
//! An exact fit (`fit_after` below 1e-9) has no residual to read and returns nothing.
//!
//! # Why hand-written
//!
//! The projection is two columns per candidate; no crate does this particular scan.

use super::model::{mode_columns, order};
use super::Refinement;
use crate::data::frf::FrfData;
use num_complex::Complex64;
use std::f64::consts::PI;

/// The F ratio above which a candidate may be a missed mode (with fewer pairs the bar is
/// higher: see `noise_quantile`). Noise alone stays below about 1.8 for the 64 pairs of
/// an 8 × 8 set; a resonance the fit left out is far above it. The margin covers
/// non-Gaussian noise and the fit's own small errors near its modes.
pub(crate) const F_MINIMUM: f64 = 4.0;

/// Candidates returned at most per scan.
pub(crate) const MAX_ADDED: usize = 8;

/// The chance that noise alone sets off a scan of the whole band.
const FALSE_ALARM: f64 = 1e-3;

/// `x > 1` with `P(χ²_ν/ν ≥ x) ≤ tail`, from the Chernoff bound
/// `P(χ²_ν ≥ νx) ≤ (x e^(1−x))^(ν/2)` (bisection). For `ν = 2` and a tail of 1e-6 it
/// gives 17.7 where the exact value is 13.8; for `ν = 128`, 1.8.
fn chi2_upper(nu: f64, tail: f64) -> f64 {
    let target = tail.ln() / (0.5 * nu);
    let g = |x: f64| x.ln() + 1.0 - x - target;
    let (mut lo, mut hi) = (1.0, 2.0);
    while g(hi) > 0.0 {
        hi *= 2.0;
    }
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if g(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi
}

/// `c < 1` with `P(χ²_d/d ≤ c) ≤ tail`, from the lower Chernoff bound
/// `P(χ²_d ≤ dc) ≤ (c e^(1−c))^(d/2)` (bisection).
fn chi2_lower(d: f64, tail: f64) -> f64 {
    let target = tail.ln() / (0.5 * d);
    let g = |c: f64| c.ln() + 1.0 - c - target;
    let (mut lo, mut hi) = (0.0_f64, 1.0_f64);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if g(mid) > 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    lo
}

/// An upper bound on the `1 − tail` quantile of `F(ν, d)`, the F ratio of noise alone:
/// `P(F ≥ x/c) ≤ P(χ²_ν/ν ≥ x) + P(χ²_d/d ≤ c)`, each term bounded by `tail/2`.
fn noise_quantile(nu: f64, d: f64, tail: f64) -> f64 {
    chi2_upper(nu, 0.5 * tail) / chi2_lower(d, 0.5 * tail)
}

/// Candidates within this fraction of the largest F are returned; the rest wait for
/// the next scan.
const STRONGEST_FRACTION: f64 = 0.5;

/// Half-width of the window in units of `ζ f` (half a half-power bandwidth): ±3ζf is
/// ±1.5 bandwidths.
const WINDOW_BANDWIDTHS: f64 = 3.0;

/// Lines at least on each side of the candidate.
const WINDOW_MIN_LINES: usize = 4;

/// One candidate: its pole and F ratio.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Missed {
    pub pole: Complex64,
    pub f_ratio: f64,
}

/// The missed modes in the residual of `fit` against `frf` (module doc), largest F
/// first.
pub(crate) fn missed_modes(frf: &FrfData, fit: &Refinement) -> Vec<Missed> {
    if fit.fit_after.is_nan() || fit.fit_after < 1e-9 || fit.modes.is_empty() {
        return Vec::new();
    }
    let (a, b) = fit.band;
    let freq = &frf.frequency_hz()[a..b];
    let lines = b - a;
    let pairs = fit.outputs * fit.inputs;
    // Whitened residual, pair by pair.
    let (mut residual, mean_square) = fit.residual(frf);
    let mut used = 0usize;
    for (e, &power) in residual.chunks_mut(lines).zip(&mean_square) {
        if power > 0.0 && power.is_finite() {
            let scale = 1.0 / power.sqrt();
            e.iter_mut().for_each(|v| *v *= scale);
            used += 1;
        } else {
            e.iter_mut().for_each(|v| *v = Complex64::new(0.0, 0.0));
        }
    }
    if used == 0 {
        return Vec::new();
    }
    let mut zetas: Vec<f64> = fit.modes.iter().map(|m| m.damping_ratio).collect();
    zetas.sort_by(f64::total_cmp);
    let zeta = zetas[zetas.len() / 2].clamp(1e-3, 0.2);
    let kappa = order(fit.quantity);
    let nu = 2.0 * used as f64;
    let window = |k: usize| {
        let half = WINDOW_BANDWIDTHS * zeta * freq[k];
        let mut lo = k;
        while lo > 0 && (freq[k] - freq[lo - 1] <= half || k - lo < WINDOW_MIN_LINES) {
            lo -= 1;
        }
        let mut hi = k + 1;
        while hi < lines && (freq[hi] - freq[k] <= half || hi - k <= WINDOW_MIN_LINES) {
            hi += 1;
        }
        (lo, hi)
    };
    let tail = FALSE_ALARM / lines as f64;
    let scores: Vec<(f64, (usize, usize), Complex64, f64)> = (0..lines)
        .map(|k| {
            let (lo, hi) = window(k);
            let wc = 2.0 * PI * freq[k];
            let n = 2.0 * (hi - lo) as f64 * used as f64;
            if wc <= 0.0 || n <= 2.0 * nu {
                return (0.0, (lo, hi), Complex64::new(0.0, 0.0), f64::INFINITY);
            }
            let s = Complex64::new(-zeta * wc, wc * (1.0 - zeta * zeta).sqrt());
            let columns: Vec<[Complex64; 2]> = (lo..hi)
                .map(|l| mode_columns(s, 2.0 * PI * freq[l], kappa, fit.sample_time_s))
                .collect();
            let dot = |x: Complex64, y: Complex64| x.re * y.re + x.im * y.im;
            let (mut g11, mut g12, mut g22) = (0.0, 0.0, 0.0);
            for c in &columns {
                g11 += dot(c[0], c[0]);
                g12 += dot(c[0], c[1]);
                g22 += dot(c[1], c[1]);
            }
            let det = g11 * g22 - g12 * g12;
            if det.is_nan() || det <= 1e-14 * g11 * g22 {
                return (0.0, (lo, hi), s, f64::INFINITY);
            }
            let (mut explained, mut energy) = (0.0, 0.0);
            for pair in 0..pairs {
                let e = &residual[pair * lines + lo..pair * lines + hi];
                let (mut t1, mut t2) = (0.0, 0.0);
                for (c, v) in columns.iter().zip(e) {
                    t1 += dot(c[0], *v);
                    t2 += dot(c[1], *v);
                    energy += v.norm_sqr();
                }
                explained += (g22 * t1 * t1 - 2.0 * g12 * t1 * t2 + g11 * t2 * t2) / det;
            }
            let rest = (energy - explained).max(1e-300);
            let bar = F_MINIMUM.max(noise_quantile(nu, n - nu, tail));
            ((explained / nu) / (rest / (n - nu)), (lo, hi), s, bar)
        })
        .collect();
    // Local maxima above the threshold, no two with overlapping windows.
    // Only the strongest: an unfitted resonance also bends the fit of its neighbours,
    // whose residuals, lesser peaks, go once it is fitted.
    let top = scores
        .iter()
        .map(|s| s.0)
        .filter(|f| f.is_finite())
        .fold(0.0, f64::max);
    // A candidate whose window reaches the band's edge has no lines on one side: its
    // peak cannot be told from the residual terms' misfit at the edge (on estimated FRFs
    // it lands on the last line, the Nyquist line or the first), and is not added.
    let mut order_by: Vec<usize> = (0..lines)
        .filter(|&k| {
            let f = scores[k].0;
            let (lo, hi) = scores[k].1;
            f.is_finite()
                && f >= scores[k].3
                && f >= top * STRONGEST_FRACTION
                && lo > 0
                && hi < lines
        })
        .collect();
    order_by.sort_by(|&x, &y| scores[y].0.total_cmp(&scores[x].0));
    let mut chosen: Vec<usize> = Vec::new();
    for k in order_by {
        let (lo, hi) = scores[k].1;
        if chosen.iter().any(|&c| {
            let (clo, chi) = scores[c].1;
            lo < chi && clo < hi
        }) {
            continue;
        }
        chosen.push(k);
        if chosen.len() == MAX_ADDED {
            break;
        }
    }
    chosen
        .into_iter()
        .map(|k| Missed {
            pole: scores[k].2,
            f_ratio: scores[k].0,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::noise_quantile;

    #[test]
    fn the_noise_quantile_bounds_the_exact_one() {
        use super::{chi2_lower, chi2_upper};
        // χ²₂/2 is exponential: its 1 − p quantile is ln(1/p).
        for p in [1e-2_f64, 1e-4, 1e-6] {
            let exact = (1.0 / p).ln();
            let bound = chi2_upper(2.0, p);
            assert!(
                bound >= exact && bound <= 1.7 * exact,
                "{p}: {bound} vs {exact}"
            );
            // And its p quantile is −ln(1 − p) ≈ p; χ²₂/2 ≤ c has probability 1 − e^(−c).
            let c = chi2_lower(2.0, p);
            assert!(1.0 - (-c).exp() <= p && c > 0.1 * p, "{p}: {c}");
        }
        // Many degrees of freedom: close to 1 + z√(2/ν).
        let q = chi2_upper(128.0, 1e-6);
        assert!(q > 1.5 && q < 2.0, "{q}");
        // F(2, 16): P(F > x) = (1 + x/8)^(−8) exactly; the bound must not be below
        // the exact quantile.
        let tail = 1e-6_f64;
        let exact = 8.0 * (tail.powf(-1.0 / 8.0) - 1.0);
        let bound = noise_quantile(2.0, 16.0, tail);
        assert!(bound >= exact, "{bound} vs {exact}");
        // The 8 × 8 case: far below the floor F_MINIMUM.
        assert!(noise_quantile(128.0, 2.0 * 9.0 * 64.0 - 128.0, 1e-6) < 4.0);
    }
}

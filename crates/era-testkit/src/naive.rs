//! One assertion for every fast path that has a naive reference.
//!
//! A fast path (an FFT instead of a sum, a truncated SVD instead of a dense one, a
//! Hessenberg solve instead of an LU per line, ...) is checked against its reference
//! with [`assert_matches_naive`], which reports the worst difference, where it is, the
//! two values there, how it was scaled and the tolerance used.
//!
//! Where the two paths differ only by rounding, the tolerance is [`tol`]: a small
//! constant times ε, the size over which rounding errors accumulate, and the condition
//! number that amplifies them. The bound of a backward-stable computation has that form
//! (Higham, *Accuracy and Stability of Numerical Algorithms*, §1.6 and §3.1).
//!
//! With `ERA_SHOW_NAIVE=1` in the environment every comparison prints its worst
//! difference and tolerance on stderr (with `--nocapture`): the margin a tolerance keeps.

use faer::{Mat, MatRef};
use num_complex::Complex64;
use std::fmt;

/// `c · ε · n · cond`: the rounding tolerance of a computation over `n` terms whose
/// result has condition number `cond` (1 for a product of well-scaled data), with `c`
/// the constant of the algorithm's error bound.
pub fn tol(c: f64, n: usize, cond: f64) -> f64 {
    c * f64::EPSILON * n as f64 * cond
}

/// How a difference `|fast − naive|` is made relative.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Scale {
    /// Each difference over the largest `|naive|`: the norm-wise error of a stable
    /// algorithm, which small entries share with the large ones.
    Largest,
    /// Each difference over its own `|naive|` (an entry that is 0 must be 0).
    Entry,
    /// `‖fast − naive‖₂ / ‖naive‖₂` over all entries (Frobenius norms); the worst entry
    /// is reported with it.
    Norm,
    /// The differences as they are.
    Absolute,
    /// Each difference over `max(|naive|, floor)`: relative for the entries above the
    /// floor, absolute below it (eigenvalues, some of which may be near 0).
    Mixed(f64),
}

/// Values compared entry by entry, with a name for an entry's place.
pub trait Values {
    /// The entries, in the order [`Values::locate`] names them.
    fn values(&self) -> Vec<Complex64>;
    /// Where entry `k` of [`Values::values`] is.
    fn locate(&self, k: usize) -> String {
        format!("[{k}]")
    }
}

impl Values for [f64] {
    fn values(&self) -> Vec<Complex64> {
        self.iter().map(|&x| Complex64::new(x, 0.0)).collect()
    }
}

impl Values for [Complex64] {
    fn values(&self) -> Vec<Complex64> {
        self.to_vec()
    }
}

impl<T: Values + ?Sized> Values for &T {
    fn values(&self) -> Vec<Complex64> {
        (**self).values()
    }
    fn locate(&self, k: usize) -> String {
        (**self).locate(k)
    }
}

impl<T> Values for Vec<T>
where
    [T]: Values,
{
    fn values(&self) -> Vec<Complex64> {
        self.as_slice().values()
    }
    fn locate(&self, k: usize) -> String {
        self.as_slice().locate(k)
    }
}

impl<const N: usize> Values for [f64; N] {
    fn values(&self) -> Vec<Complex64> {
        self.as_slice().values()
    }
}

/// Rows of possibly different lengths, located as `[row][k]`.
impl Values for [Vec<f64>] {
    fn values(&self) -> Vec<Complex64> {
        self.iter().flat_map(|r| r.values()).collect()
    }
    fn locate(&self, mut k: usize) -> String {
        for (i, r) in self.iter().enumerate() {
            if k < r.len() {
                return format!("[{i}][{k}]");
            }
            k -= r.len();
        }
        format!("[past the end: {k}]")
    }
}

/// A matrix, column by column, located as `(row, column)`.
impl Values for MatRef<'_, f64> {
    fn values(&self) -> Vec<Complex64> {
        let mut v = Vec::with_capacity(self.nrows() * self.ncols());
        for j in 0..self.ncols() {
            for i in 0..self.nrows() {
                v.push(Complex64::new(self[(i, j)], 0.0));
            }
        }
        v
    }
    fn locate(&self, k: usize) -> String {
        let rows = self.nrows().max(1);
        format!("({}, {})", k % rows, k / rows)
    }
}

impl Values for Mat<f64> {
    fn values(&self) -> Vec<Complex64> {
        self.as_ref().values()
    }
    fn locate(&self, k: usize) -> String {
        self.as_ref().locate(k)
    }
}

/// The outcome of a comparison: the worst relative difference and where it is.
#[derive(Clone, Debug)]
pub struct Difference {
    /// The measure of [`Scale`] (NaN when either side has a NaN).
    pub worst: f64,
    /// Where the largest entry difference is.
    pub at: String,
    /// The fast path's value there.
    pub fast: Complex64,
    /// The reference's value there.
    pub naive: Complex64,
    /// How the difference was made relative.
    pub scale: Scale,
}

impl Difference {
    /// True when the difference is within `tol` (never for a NaN).
    pub fn within(&self, tol: f64) -> bool {
        self.worst <= tol
    }
}

impl fmt::Display for Difference {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "worst {:?} difference {:.3e} at {} (fast {}, naive {})",
            self.scale, self.worst, self.at, self.fast, self.naive
        )
    }
}

/// Compares `fast` with `naive` entry by entry under `scale`. Panics when the two have
/// different numbers of entries.
#[track_caller]
pub fn difference<A: Values + ?Sized, B: Values + ?Sized>(
    fast: &A,
    naive: &B,
    scale: Scale,
) -> Difference {
    let (f, n) = (fast.values(), naive.values());
    assert_eq!(
        f.len(),
        n.len(),
        "the fast path and its reference differ in size"
    );
    let d: Vec<f64> = f.iter().zip(&n).map(|(a, b)| (a - b).norm()).collect();
    // The worst entry: a NaN difference first, then the largest under the scale.
    let rel = |k: usize| match scale {
        Scale::Entry if d[k] == 0.0 => 0.0,
        Scale::Entry => d[k] / n[k].norm(),
        Scale::Mixed(floor) => d[k] / n[k].norm().max(floor),
        _ => d[k],
    };
    let k = (0..d.len())
        .max_by(|&a, &b| {
            let (x, y) = (rel(a), rel(b));
            x.is_nan().cmp(&y.is_nan()).then(x.total_cmp(&y))
        })
        .unwrap_or(0);
    let worst = if d.is_empty() {
        0.0
    } else if d.iter().any(|x| x.is_nan()) {
        f64::NAN
    } else {
        match scale {
            Scale::Absolute | Scale::Entry | Scale::Mixed(_) => rel(k),
            Scale::Largest => d[k] / n.iter().map(|x| x.norm()).fold(0.0, f64::max),
            Scale::Norm => {
                let norm = |v: &mut dyn Iterator<Item = f64>| v.map(|x| x * x).sum::<f64>().sqrt();
                norm(&mut d.iter().copied()) / norm(&mut n.iter().map(|x| x.norm()))
            }
        }
    };
    let worst = if worst.is_nan() && d.iter().all(|&x| x == 0.0) {
        0.0 // both sides zero: equal
    } else {
        worst
    };
    Difference {
        worst,
        at: fast.locate(k),
        fast: f.get(k).copied().unwrap_or_default(),
        naive: n.get(k).copied().unwrap_or_default(),
        scale,
    }
}

/// Asserts that the fast path `fast` matches its naive reference `naive` within `tol`
/// under `scale`; the message names `what`, the worst difference, where it is, the two
/// values there and the tolerance.
#[track_caller]
pub fn assert_matches_naive<A: Values + ?Sized, B: Values + ?Sized>(
    what: &str,
    fast: &A,
    naive: &B,
    scale: Scale,
    tol: f64,
) {
    let diff = difference(fast, naive, scale);
    if std::env::var_os("ERA_SHOW_NAIVE").is_some() {
        eprintln!("SHOW {what}: {diff}, tolerance {tol:.3e}");
    }
    assert!(
        diff.within(tol),
        "{what}: the fast path differs from its naive reference: {diff}, tolerance {tol:.3e}"
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_worst_entry_is_found_and_named() {
        let naive = [1.0, 10.0, 100.0];
        let fast = [1.0 + 1e-12, 10.0, 100.0 + 1e-11];
        let d = difference(&fast, &naive, Scale::Entry);
        assert_eq!(d.at, "[0]");
        assert!((d.worst - 1e-12).abs() < 1e-16);
        let d = difference(&fast, &naive, Scale::Largest);
        assert_eq!(d.at, "[2]");
        assert!((d.worst - 1e-13).abs() < 1e-16);
        let d = difference(&fast, &naive, Scale::Absolute);
        assert!((d.worst - 1e-11).abs() < 1e-14);
        let m = Mat::from_fn(2, 3, |i, j| (i + j) as f64);
        let mut n = m.clone();
        n[(1, 2)] += 1.0;
        let d = difference(&m, &n, Scale::Norm);
        assert_eq!(d.at, "(1, 2)");
        // ‖d‖ = 1 over ‖n‖ = √(0 + 1 + 4 + 1 + 4 + 16).
        assert!((d.worst - 1.0 / 26f64.sqrt()).abs() < 1e-15);
        let d = difference(&[0.5 + 1e-9, 10.0 + 1e-9], &[0.5, 10.0], Scale::Mixed(1.0));
        assert_eq!(d.at, "[0]");
        assert!((d.worst - 1e-9).abs() < 1e-15);
        let rows = vec![vec![1.0], vec![2.0, 3.0]];
        let mut other = rows.clone();
        other[1][1] = 4.0;
        assert_eq!(difference(&rows, &other, Scale::Absolute).at, "[1][1]");
    }

    #[test]
    fn equal_values_and_zeros_pass() {
        let z = [0.0, 0.0];
        assert_matches_naive("zeros", &z, &z, Scale::Entry, 0.0);
        assert_matches_naive("zeros", &z, &z, Scale::Largest, 0.0);
        assert_matches_naive("zeros", &z, &z, Scale::Norm, 0.0);
        let c = vec![Complex64::new(1.0, -2.0)];
        assert_matches_naive("complex", &c, &c, Scale::Entry, 0.0);
    }

    #[test]
    #[should_panic(expected = "tolerance")]
    fn a_difference_past_the_tolerance_fails() {
        assert_matches_naive("x", &[1.0, 2.0 + 1e-9], &[1.0, 2.0], Scale::Entry, 1e-12);
    }

    #[test]
    #[should_panic(expected = "NaN")]
    fn a_nan_fails() {
        assert_matches_naive("x", &[f64::NAN], &[1.0], Scale::Absolute, 1.0);
    }

    #[test]
    #[should_panic(expected = "differ in size")]
    fn a_size_mismatch_fails() {
        assert_matches_naive("x", &[1.0], &[1.0, 2.0], Scale::Absolute, 1.0);
    }

    #[test]
    fn an_entry_that_should_be_zero_must_be() {
        let d = difference(&[1e-300], &[0.0], Scale::Entry);
        assert!(!d.within(1e10));
    }

    #[test]
    fn tol_grows_with_size_and_conditioning() {
        assert_eq!(tol(1.0, 1, 1.0), f64::EPSILON);
        assert_eq!(tol(2.0, 10, 100.0), 2000.0 * f64::EPSILON);
    }
}

//! A change in a fleet: the point in time where the tracked frequencies step, as they do
//! when a monitored structure loses stiffness.
//!
//! **Per track**, a step at a split `s` is the coefficient `c` of the least-squares fit
//! `f(x) = a + b·x + c·[x > s]`: a common trend (a temperature drift goes on across the
//! change) plus a step. When the records have times and span a day or more, the fit
//! also holds a daily cycle, `d·cos 2πx + e·sin 2πx` (x in days): a structure's
//! temperature follows the sun. The step's t statistic is `c / se(c)`, with the
//! residuals' own scatter inflated by their lag-one autocorrelation `ρ` by
//! `(1 + ρ)/(1 − ρ)`: residuals that follow each other (weather, traffic) carry less
//! information than as many independent ones.
//!
//! **Over the fleet**, every split between two consecutive records with at least
//! [`MIN_SIDE`] records of a track on each side is scored by `Σ t²` over the tracks that
//! have it. Without a change, each `t²` is about χ²(1), so the sum about χ²(T) for T
//! tracks. The split with the largest sum is the fleet's change, **significant** when that
//! sum exceeds the χ²(T) quantile at `1 − α/S` for `S` splits tried (Bonferroni over the
//! splits, α = [`ALPHA`]). A daily temperature cycle left in the residuals widens them,
//! which makes the test cautious rather than eager.
//!
//! The least squares are faer's QR; the χ² quantile is `statrs`'s.

use statrs::distribution::{ChiSquared, ContinuousCDF};

/// Records a track needs on each side of a split to have a step there.
pub(crate) const MIN_SIDE: usize = 3;

/// The false-alarm rate of the fleet's test, over all the splits tried.
pub(crate) const ALPHA: f64 = 0.001;

/// A step in one track's frequency at a split.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Step {
    /// The step, Hz (after minus before, beyond the trend).
    pub step_hz: f64,
    /// The step relative to the mean frequency before it.
    pub relative: f64,
    /// Its t statistic.
    pub t: f64,
    /// The fitted model, to draw.
    pub model: StepModel,
}

/// The model fitted at a split: `ȳ + c₀ + c₁ (x − x̄) [+ c₂ cos 2πx + c₃ sin 2πx] + c_step [x > split]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepModel {
    /// `x̄`.
    pub mean_x: f64,
    /// `ȳ`.
    pub mean_y: f64,
    /// The split.
    pub split: f64,
    /// Whether the daily terms are in.
    pub daily: bool,
    /// `c₀, c₁, c₂, c₃, c_step` (`c₂ = c₃ = 0` without the daily terms).
    pub coef: [f64; 5],
}

impl StepModel {
    /// The model's value at `x`.
    pub fn at(&self, x: f64) -> f64 {
        let c = &self.coef;
        let tau = std::f64::consts::TAU;
        let mut v = self.mean_y + c[0] + c[1] * (x - self.mean_x);
        if self.daily {
            v += c[2] * (tau * x).cos() + c[3] * (tau * x).sin();
        }
        if x > self.split {
            v += c[4];
        }
        v
    }
}

/// The fleet's change.
#[derive(Debug, Clone, PartialEq)]
pub struct Change {
    /// The split: records with abscissa above it are after the change.
    pub split: f64,
    /// `Σ t²` over the tracks with a step there.
    pub score: f64,
    /// The χ²(T) threshold `score` is compared with.
    pub threshold: f64,
    /// Whether `score > threshold`.
    pub significant: bool,
    /// Each track's step at the split (`None` for a track without [`MIN_SIDE`] records
    /// on each side), in the order the tracks were given.
    pub steps: Vec<Option<Step>>,
}

/// The step of `(x, y)` at `split` with a common trend (and, with `daily`, a daily
/// cycle: `x` in days); `None` without [`MIN_SIDE`] points on each side, too few points
/// for the fit, or a singular fit.
pub(crate) fn step_at(x: &[f64], y: &[f64], split: f64, daily: bool) -> Option<Step> {
    let n = x.len();
    let after = x.iter().filter(|&&v| v > split).count();
    if after < MIN_SIDE || n - after < MIN_SIDE || y.len() != n {
        return None;
    }
    let mx = x.iter().sum::<f64>() / n as f64;
    let my = y.iter().sum::<f64>() / n as f64;
    let tau = std::f64::consts::TAU;
    // Columns: 1, x, [cos 2πx, sin 2πx,] and the step last, so that its variance is
    // σ² / R[p-1, p-1]² of the QR factor.
    let p = if daily { 5 } else { 3 };
    let column = |i: usize, j: usize| -> f64 {
        let xi = x[i];
        match (j, daily) {
            (0, _) => 1.0,
            (1, _) => xi - mx,
            (2, true) => (tau * xi).cos(),
            (3, true) => (tau * xi).sin(),
            _ => f64::from(u8::from(xi > split)),
        }
    };
    if n < p + 2 {
        return None;
    }
    let design = faer::Mat::<f64>::from_fn(n, p, column);
    let qr = design.qr();
    let (q, r) = (qr.compute_thin_Q(), qr.thin_R().to_owned());
    let z: Vec<f64> = (0..p)
        .map(|j| (0..n).map(|i| q[(i, j)] * (y[i] - my)).sum())
        .collect();
    let scale = (0..p).fold(0.0f64, |m, j| m.max(r[(j, j)].abs()));
    if (0..p).any(|j| r[(j, j)].abs() <= 1e-10 * scale || r[(j, j)].is_nan()) {
        return None;
    }
    let mut coef = vec![0.0; p];
    for j in (0..p).rev() {
        let tail: f64 = (j + 1..p).map(|k| r[(j, k)] * coef[k]).sum();
        coef[j] = (z[j] - tail) / r[(j, j)];
    }
    let residuals: Vec<f64> = (0..n)
        .map(|i| y[i] - my - (0..p).map(|j| column(i, j) * coef[j]).sum::<f64>())
        .collect();
    let ssr: f64 = residuals.iter().map(|e| e * e).sum();
    // Residuals that follow each other (a slow environmental effect the model does not
    // hold) make the records count for less: the variance is inflated by the lag-one
    // autocorrelation's (1 + ρ) / (1 − ρ).
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| x[a].total_cmp(&x[b]));
    let lag: f64 = order
        .windows(2)
        .map(|w| residuals[w[0]] * residuals[w[1]])
        .sum();
    let rho = if ssr > 0.0 {
        (lag / ssr).clamp(0.0, 0.9)
    } else {
        0.0
    };
    let sigma2 = ssr / (n - p) as f64 * (1.0 + rho) / (1.0 - rho);
    let rpp = r[(p - 1, p - 1)];
    let se = (sigma2 / (rpp * rpp)).sqrt();
    let step = coef[p - 1];
    let before: Vec<f64> = x
        .iter()
        .zip(y)
        .filter(|(&xi, _)| xi <= split)
        .map(|(_, &yi)| yi)
        .collect();
    let mean_before = before.iter().sum::<f64>() / before.len() as f64;
    if !(se > 0.0 && se.is_finite() && mean_before != 0.0) {
        return None;
    }
    let mut all = [0.0; 5];
    all[..2].copy_from_slice(&coef[..2]);
    if daily {
        all[2..4].copy_from_slice(&coef[2..4]);
    }
    all[4] = step;
    Some(Step {
        step_hz: step,
        relative: step / mean_before,
        t: step / se,
        model: StepModel {
            mean_x: mx,
            mean_y: my,
            split,
            daily,
            coef: all,
        },
    })
}

/// The fleet's change over `tracks` (each `(x, y)`: abscissae and frequencies of one
/// track), tried at every midpoint between consecutive distinct abscissae of all the
/// tracks; `None` when no split has a track with [`MIN_SIDE`] records on each side.
/// `daily`: the abscissae are days, and each track's fit holds a daily cycle when its
/// records span at least a day.
pub(crate) fn fleet_change(tracks: &[(Vec<f64>, Vec<f64>)], daily: bool) -> Option<Change> {
    let mut xs: Vec<f64> = tracks.iter().flat_map(|t| t.0.iter().copied()).collect();
    xs.sort_by(f64::total_cmp);
    xs.dedup();
    let splits: Vec<f64> = xs.windows(2).map(|w| 0.5 * (w[0] + w[1])).collect();
    // Whether each track's fit holds the daily cycle: its records span a day.
    let cycles: Vec<bool> = tracks
        .iter()
        .map(|(x, _)| {
            let span = x.iter().copied().fold(f64::NEG_INFINITY, f64::max)
                - x.iter().copied().fold(f64::INFINITY, f64::min);
            daily && span >= 1.0
        })
        .collect();
    let mut best: Option<(f64, f64, Vec<Option<Step>>)> = None;
    let mut tried = 0usize;
    for &s in &splits {
        let steps: Vec<Option<Step>> = tracks
            .iter()
            .zip(&cycles)
            .map(|((x, y), &cycle)| step_at(x, y, s, cycle))
            .collect();
        if steps.iter().all(Option::is_none) {
            continue;
        }
        tried += 1;
        let score: f64 = steps.iter().flatten().map(|st| st.t * st.t).sum();
        if best.as_ref().is_none_or(|b| score > b.1) {
            best = Some((s, score, steps));
        }
    }
    let (split, score, steps) = best?;
    let dof = steps.iter().flatten().count() as f64;
    let level = 1.0 - ALPHA / tried.max(1) as f64;
    let threshold = ChiSquared::new(dof).ok()?.inverse_cdf(level);
    Some(Change {
        split,
        score,
        threshold,
        significant: score > threshold,
        steps,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fleet of `n` records: frequencies with a trend, a deterministic scatter and, from
    /// record `at` on, a step of `step` (relative).
    fn fleet(n: usize, at: usize, step: f64) -> Vec<(Vec<f64>, Vec<f64>)> {
        [1.0, 4.0, 9.0]
            .iter()
            .enumerate()
            .map(|(k, &f0)| {
                let x: Vec<f64> = (0..n).map(|i| i as f64).collect();
                let y = x
                    .iter()
                    .map(|&xi| {
                        let wobble = 0.001 * ((xi * 2.3 + k as f64).sin());
                        let s = if (xi as usize) >= at { step } else { 0.0 };
                        f0 * (1.0 - 0.0005 * xi + wobble + s)
                    })
                    .collect();
                (x, y)
            })
            .collect()
    }

    #[test]
    fn a_step_is_found_where_it_is_and_none_without_one() {
        let c = fleet_change(&fleet(40, 25, -0.01), false).unwrap();
        assert!(c.significant, "{c:?}");
        assert!((c.split - 24.5).abs() < 1e-12, "{c:?}");
        for s in c.steps.iter().flatten() {
            assert!((s.relative + 0.01).abs() < 0.002, "{s:?}");
        }
        let none = fleet_change(&fleet(40, 100, 0.0), false).unwrap();
        assert!(!none.significant, "{none:?}");
    }

    /// Hourly records over two days with a daily cycle of ±0.5 % in every frequency and
    /// a small scatter: no step is called a change; a 1 % step from record 30 is, there.
    #[test]
    fn a_daily_cycle_is_not_a_change_and_a_step_on_it_is_found() {
        let tracks = |step: f64| -> Vec<(Vec<f64>, Vec<f64>)> {
            [2.0, 7.0, 13.0]
                .iter()
                .enumerate()
                .map(|(k, &f0)| {
                    let x: Vec<f64> = (0..48).map(|i| f64::from(i) / 24.0).collect();
                    let y = x
                        .iter()
                        .enumerate()
                        .map(|(i, &d)| {
                            let cycle = 0.005 * (std::f64::consts::TAU * d).sin();
                            let scatter = 0.0005 * ((i * 7 + k * 3) as f64).sin();
                            let s = if i >= 30 { step } else { 0.0 };
                            f0 * (1.0 - 0.004 * d + cycle + scatter + s)
                        })
                        .collect();
                    (x, y)
                })
                .collect()
        };
        let quiet = fleet_change(&tracks(0.0), true).unwrap();
        assert!(!quiet.significant, "{quiet:?}");
        // Without the daily terms the cycle reads as steps.
        let naive = fleet_change(&tracks(0.0), false).unwrap();
        assert!(naive.score > quiet.score, "{naive:?}");
        let c = fleet_change(&tracks(-0.01), true).unwrap();
        assert!(c.significant, "{c:?}");
        assert!((c.split - 29.5 / 24.0).abs() < 1e-9, "{c:?}");
        for s in c.steps.iter().flatten() {
            assert!((s.relative + 0.01).abs() < 0.001, "{s:?}");
        }
    }

    #[test]
    fn too_few_records_on_a_side_give_no_step() {
        let x = [0.0, 1.0, 2.0, 3.0, 4.0];
        let y = [1.0, 1.0, 1.0, 0.9, 0.9];
        assert!(step_at(&x, &y, 2.5, false).is_none());
        assert!(fleet_change(&[(x.to_vec(), y.to_vec())], false).is_none());
    }
}

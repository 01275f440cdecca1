//! ERA/DC, the Eigensystem Realization Algorithm with data correlations (Juang, Cooper &
//! Wright 1988): ERA on the correlations of the Hankel matrices rather than on the
//! Hankel matrix itself, which averages the noise over every column before the
//! factorization and so lowers the bias of lightly damped poles on noisy data. It takes
//! any Markov sequence (FRF, OKID).
//!
//! With the Hankel blocks `H(k)[i][j] = Y_(k+1+i+j)`, `α` block rows and `β` block
//! columns, `H(k) = P_α A^k Q_β` (`P_α` the observability matrix of `α` blocks, `Q_β` the
//! controllability matrix of `β`). Its correlations, shifted by `s` blocks,
//!
//! ```text
//! R(k) = H(s + k) H(0)ᵀ = P_α A^k G,      G = A^s Q_β H(0)ᵀ,
//! 𝓗(k)[i][j] = R(k + τ(i + j)),  i, j = 0..ξ,   𝓗(k) = 𝓟 A^k 𝓖,
//! 𝓟 = [P_α; P_α A^τ; …; P_α A^(ξτ)],
//! ```
//!
//! have the same `A`: `𝓗(0) = U Σ Vᵀ` truncated to `n`, `A = Σ^(−½) Uᵀ 𝓗(1) V Σ^(−½)`,
//! `P_α` the first `αq` rows of `U Σ^(½)`, `C` its first `q` rows, and `B` the first `p`
//! columns of `Q_β = P_α⁺ H(0)`.
//!
//! The default sizes (`DcShape::new`): `α = β` the block rows and columns of ERA's
//! Hankel at the same order and Hankel factor (`n·lh/2 − 1`), `ξ = 0` (the correlation
//! `R` itself), `τ = 1`, and the shift `s = 1`: the product of `H(0)` with itself would
//! put the variance of white noise on the sequence on its diagonal, and with the shift
//! no sample meets itself on the diagonal. Larger `ξ` and `β ≫ α` (few rows, long
//! sums) are the paper's other choices; on decaying responses with white noise the
//! columns past the signal add only noise to the sums, so they are not the default.
//! The products and the SVD are faer's.

use crate::error::{EraError, Result};
use crate::pipeline::factor::{check_dense_svd, check_room, FactorParts, Factorization};
use crate::pipeline::realize::{DirectTerm, Realization};
use crate::sources::MarkovSequence;
use faer::Mat;
use std::time::Instant;

/// The sizes of ERA/DC (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub struct DcShape {
    /// Block rows `α` of the Hankel blocks.
    pub alpha: usize,
    /// Block columns `β`.
    pub beta: usize,
    /// Block rows and columns of the correlation Hankel, less one (`ξ = ζ`).
    pub xi: usize,
    /// Lag spacing `τ`.
    pub tau: usize,
    /// Shift `s` of the correlated Hankel blocks.
    pub shift: usize,
}

impl DcShape {
    /// The default sizes for `states` at `hankel_factor` with `outputs` outputs.
    pub fn new(states: usize, hankel_factor: usize, outputs: usize) -> Self {
        let q = outputs.max(1);
        let era_blocks = (states * hankel_factor.max(1) / 2).saturating_sub(1);
        let alpha = era_blocks.max((states + q).div_ceil(q)).max(2);
        DcShape {
            alpha,
            beta: alpha,
            xi: 0,
            tau: 1,
            shift: 1,
        }
    }

    /// The last Markov index it reads: `H(s + k)` for `k ≤ 2ξτ + 1` reaches
    /// `Y_(s + k + α + β − 1)`.
    pub fn reach(&self) -> usize {
        self.shift + 2 * self.xi * self.tau + self.alpha + self.beta
    }

    fn check(&self, markov: &MarkovSequence, states: usize, hankel_factor: usize) -> Result<()> {
        if self.alpha == 0 || self.beta == 0 || self.tau == 0 {
            return Err(EraError::InvalidParameter {
                name: "states",
                value: states.to_string(),
                reason: format!("ERA/DC needs blocks and a lag spacing of at least 1 ({self:?})")
                    .into(),
            });
        }
        if self.reach() >= markov.samples() {
            return Err(EraError::NotEnoughMarkovSamples {
                needed: self.reach() + 1,
                available: markov.samples(),
                states,
                hankel_factor,
            });
        }
        Ok(())
    }
}

/// `H(k)` with `alpha` block rows and `beta` block columns.
fn hankel_at(markov: &MarkovSequence, k: usize, alpha: usize, beta: usize) -> Mat<f64> {
    let (q, p) = (markov.outputs(), markov.inputs());
    Mat::from_fn(alpha * q, beta * p, |row, col| {
        markov.get(k + 1 + row / q + col / p, row % q, col % p)
    })
}

/// The factorization of ERA/DC's correlation `R(0) = H(s) H(0)ᵀ` at a shape with `ξ = 0`
/// (the default's), kept so that realizations of every order up to `max_states` cost
/// small products: the stabilization scan and the automatic order run on it as on ERA's
/// ([`Factorization::realize`]).
///
/// `R(0)` (`αq × αq`) is never formed. With the thin SVD `H(0) = U₀ S₀ V₀ᵀ`,
/// `R(0) = (H(s) V₀ S₀) U₀ᵀ`, and the thin SVD `H(s) V₀ S₀ = U Σ Zᵀ` gives
/// `R(0) = U Σ (U₀ Z)ᵀ`: two SVDs of the size of ERA's Hankel. Then
/// `U_Nᵀ R(1) V_N = U_Nᵀ H(s+1) V₀ S₀ Z_N`, and `Q_β = Σ^(−½) U_nᵀ H(0)` gives `B`.
///
/// # Errors
/// [`EraError::InvalidParameter`] for `ξ ≠ 0` (the tests' reference `realize_dc_with` takes any shape);
/// as [`realize_dc`] otherwise, and [`EraError::HankelTooSmall`] when `R(0)` has fewer
/// singular values than `max_states`.
pub fn factor_dc(
    markov: &MarkovSequence,
    sample_time_s: f64,
    shape: &DcShape,
    max_states: usize,
    hankel_factor: usize,
) -> Result<Factorization> {
    if shape.xi != 0 {
        return Err(EraError::InvalidParameter {
            name: "states",
            value: max_states.to_string(),
            reason: format!(
                "the factorization of ERA/DC takes the correlation itself (xi = 0), not {}",
                shape.xi
            )
            .into(),
        });
    }
    shape.check(markov, max_states, hankel_factor)?;
    let clock = Instant::now();
    let (q, p) = (markov.outputs(), markov.inputs());
    let (alpha, beta, shift) = (shape.alpha, shape.beta, shape.shift);
    let (rows, cols) = (alpha * q, beta * p);
    check_room(rows, cols, max_states)?;
    check_dense_svd(rows, cols)?;
    let numerical = |what: &str, e: faer::linalg::svd::SvdError| {
        EraError::Numerical(format!("SVD of {what} (ERA/DC): {e:?}"))
    };
    let h0 = hankel_at(markov, 0, alpha, beta);
    let svd0 = h0.thin_svd().map_err(|e| numerical("H(0)", e))?;
    let k = rows.min(cols);
    let v0s0 = Mat::from_fn(cols, k, |i, j| svd0.V()[(i, j)] * svd0.S()[j]);
    let w = hankel_at(markov, shift, alpha, beta) * &v0s0;
    let svdw = w.thin_svd().map_err(|e| numerical("H(s) V0 S0", e))?;
    drop(w);
    let singular_values: Vec<f64> = (0..k).map(|i| svdw.S()[i]).collect();
    let u = svdw.U().to_owned();
    let v = svd0.U() * svdw.V();
    let un = u.subcols(0, max_states);
    let zn = svdw.V().subcols(0, max_states);
    let ut_h1_v = un.transpose() * (hankel_at(markov, shift + 1, alpha, beta) * (&v0s0 * zn));
    let ut_h0 = un.transpose() * &h0;
    let parts = FactorParts {
        u,
        v,
        ut_h1_v,
        singular_values,
        max_states,
        hankel_size: (rows, rows),
        ut_h0: Some(ut_h0),
    };
    Ok(Factorization::from_parts(
        markov,
        sample_time_s,
        parts,
        clock.elapsed().as_secs_f64(),
    ))
}

/// ERA/DC at `states` and `hankel_factor` on `markov` (samples `sample_time_s` apart).
///
/// # Errors
/// [`EraError::InvalidParameter`] for zero states; [`EraError::NotEnoughMarkovSamples`] when the sequence is shorter than
/// [`DcShape::reach`];
/// [`EraError::RankDeficient`] when the correlations have rank below `states`;
/// [`EraError::Numerical`] when the SVD fails.
pub fn realize_dc(
    markov: &MarkovSequence,
    sample_time_s: f64,
    states: usize,
    hankel_factor: usize,
    direct: DirectTerm,
) -> Result<Realization> {
    if states == 0 {
        return Err(EraError::InvalidParameter {
            name: "states",
            value: "0".into(),
            reason: "ERA/DC needs at least one state".into(),
        });
    }
    let shape = DcShape::new(states, hankel_factor, markov.outputs());
    factor_dc(markov, sample_time_s, &shape, states, hankel_factor)?.realize(states, direct)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::statespace::{StateSpace, TimeDomain};
    use crate::linalg::rng::Minstd;
    use crate::pipeline::factor::SvdPath;
    use crate::pipeline::modes::modal_parameters;
    use crate::pipeline::realize::HankelTails;
    use crate::sim::{ModalSpec, ModalStructure};
    use era_testkit::{assert_matches_naive, Scale};
    use faer::linalg::solvers::SolveLstsq;

    /// [`realize_dc`] with the sizes given, any of the paper's shapes: the correlations
    /// formed and factored as they are (the reference of [`factor_dc`]).
    ///
    /// # Errors
    /// As [`realize_dc`].
    fn realize_dc_with(
        markov: &MarkovSequence,
        sample_time_s: f64,
        states: usize,
        hankel_factor: usize,
        shape: &DcShape,
        direct: DirectTerm,
    ) -> Result<Realization> {
        if states == 0 {
            return Err(EraError::InvalidParameter {
                name: "states",
                value: "0".into(),
                reason: "ERA/DC needs at least one state".into(),
            });
        }
        shape.check(markov, states, hankel_factor)?;
        let clock = Instant::now();
        let (q, p) = (markov.outputs(), markov.inputs());
        let DcShape {
            alpha,
            beta,
            xi,
            tau,
            shift,
        } = *shape;
        check_dense_svd((xi + 1) * alpha * q, (xi + 1) * alpha * q)?;
        let h0 = hankel_at(markov, 0, alpha, beta);
        let h0t = h0.transpose();
        // R(k) = H(s + k) H(0)ᵀ for the lags 𝓗(0) and 𝓗(1) read: k = τm and τm + 1.
        let lag_of = |k: usize| hankel_at(markov, shift + k, alpha, beta) * h0t;
        let lags: Vec<(Mat<f64>, Mat<f64>)> = (0..=2 * xi)
            .map(|m| (lag_of(tau * m), lag_of(tau * m + 1)))
            .collect();
        let block = alpha * q;
        let corr = |shifted: bool| {
            Mat::from_fn((xi + 1) * block, (xi + 1) * block, |row, col| {
                let (at, next) = &lags[row / block + col / block];
                let r = if shifted { next } else { at };
                r[(row % block, col % block)]
            })
        };
        let (c0, c1) = (corr(false), corr(true));
        let svd = c0
            .svd()
            .map_err(|e| EraError::Numerical(format!("SVD of the ERA/DC correlations: {e:?}")))?;
        let size = c0.nrows();
        let sv: Vec<f64> = (0..size).map(|i| svd.S()[i]).collect();
        let top = sv.first().copied().unwrap_or(0.0);
        let threshold = top * size as f64 * f64::EPSILON;
        let rank = sv.iter().take_while(|&&v| v > threshold).count();
        if rank < states {
            return Err(EraError::RankDeficient {
                rank,
                states,
                threshold,
            });
        }
        let hankel_svd_seconds = clock.elapsed().as_secs_f64();
        let products = Instant::now();
        let un = svd.U().get(.., ..states);
        let vn = svd.V().get(.., ..states);
        let inv_root: Vec<f64> = sv[..states].iter().map(|s| 1.0 / s.sqrt()).collect();
        let middle = un.transpose() * &c1 * vn;
        let a = Mat::from_fn(states, states, |i, j| {
            middle[(i, j)] * inv_root[i] * inv_root[j]
        });
        let p_alpha = Mat::from_fn(block, states, |i, j| un[(i, j)] / inv_root[j]);
        let c = p_alpha.get(..q, ..).to_owned();
        let q_beta = p_alpha.qr().solve_lstsq(&h0);
        let b = q_beta.get(.., ..p).to_owned();
        let d = match direct {
            DirectTerm::Zero => Mat::zeros(q, p),
            DirectTerm::FirstMarkov => Mat::from_fn(q, p, |i, j| markov.get(0, i, j)),
        };
        let model = StateSpace::new(a, b, c, d, TimeDomain::Discrete { sample_time_s });
        Ok(Realization {
            model,
            singular_values: sv,
            hankel_size: (size, size),
            warnings: Vec::new(),
            hankel_svd_seconds,
            products_seconds: products.elapsed().as_secs_f64(),
            svd_path: SvdPath::Dense,
            svd_iterations: None,
            tails: HankelTails {
                observability: p_alpha,
                controllability: q_beta,
                outputs: q,
                inputs: p,
            },
        })
    }

    fn markov_of(model: &StateSpace, samples: usize) -> MarkovSequence {
        let mut seq = MarkovSequence::zeros(model.outputs(), model.inputs(), samples);
        let mut x = model.b.clone();
        for k in 1..samples {
            let y = &model.c * &x;
            for i in 0..model.outputs() {
                for j in 0..model.inputs() {
                    seq.set(k, i, j, y[(i, j)]);
                }
            }
            x = &model.a * &x;
        }
        seq
    }

    fn structure(q: usize, p: usize, modes: usize, seed: u64) -> (ModalStructure, StateSpace) {
        let spec = ModalSpec {
            fmin_hz: 1.0,
            fmax_hz: 20.0,
            collocated: false,
            seed,
            ..ModalSpec::new(q, p, modes)
        };
        let s = ModalStructure::random(&spec).unwrap();
        let m = s
            .state_space(crate::data::frf::Quantity::Displacement)
            .c2d(1.0 / 64.0)
            .unwrap();
        (s, m)
    }

    #[test]
    fn exact_markov_gives_the_poles() {
        for (q, p, modes) in [(3, 2, 5), (1, 1, 3), (8, 2, 10)] {
            let (truth, model) = structure(q, p, modes, 11);
            let markov = markov_of(&model, 600);
            let found = realize_dc(&markov, 1.0 / 64.0, 2 * modes, 5, DirectTerm::Zero).unwrap();
            let m = modal_parameters(&found.model).unwrap();
            for f in &truth.frequencies_hz {
                let best = m
                    .modes
                    .iter()
                    .map(|x| (x.frequency_hz - f).abs() / f)
                    .fold(f64::INFINITY, f64::min);
                assert!(best < 1e-8, "{q}x{p}: {f} Hz off by {best:e}");
            }
            // The realization reproduces the Markov parameters.
            let mut x = found.model.b.clone();
            let mut worst = 0.0f64;
            for k in 1..50 {
                let y = &found.model.c * &x;
                for i in 0..q {
                    for j in 0..p {
                        worst = worst.max((y[(i, j)] - markov.get(k, i, j)).abs());
                    }
                }
                x = &found.model.a * &x;
            }
            let scale = (1..50)
                .flat_map(|k| (0..q).flat_map(move |i| (0..p).map(move |j| (k, i, j))))
                .map(|(k, i, j)| markov.get(k, i, j).abs())
                .fold(0.0, f64::max);
            assert!(worst < 1e-8 * scale, "{q}x{p}: Markov error {worst:e}");
        }
    }

    /// On noisy Markov parameters ERA/DC finds every mode: frequencies within 0.5 % and
    /// damping within a factor of two (median within 25 %). It is not better than ERA on
    /// this noise (white, on the Markov blocks): the route table of the benches says
    /// where each is the better choice.
    #[test]
    fn noisy_markov_gives_every_mode() {
        let mut damping = Vec::new();
        for seed in 1..=4u64 {
            let (truth, model) = structure(4, 2, 6, seed);
            let mut markov = markov_of(&model, 1024);
            let peak = (0..1024)
                .map(|k| markov.get(k, 0, 0).abs())
                .fold(0.0, f64::max);
            let mut rng = Minstd::new(seed + 100);
            for k in 1..1024 {
                for i in 0..4 {
                    for j in 0..2 {
                        let v = markov.get(k, i, j) + 0.02 * peak * rng.normal();
                        markov.set(k, i, j, v);
                    }
                }
            }
            let dc = realize_dc(&markov, 1.0 / 64.0, 12, 20, DirectTerm::Zero).unwrap();
            let m = modal_parameters(&dc.model).unwrap();
            for (f, z) in truth.frequencies_hz.iter().zip(&truth.damping_ratios) {
                let best = m
                    .modes
                    .iter()
                    .min_by(|a, b| {
                        (a.frequency_hz - f)
                            .abs()
                            .total_cmp(&(b.frequency_hz - f).abs())
                    })
                    .unwrap();
                assert!(
                    (best.frequency_hz - f).abs() < 5e-3 * f,
                    "seed {seed}: {f} Hz"
                );
                let ratio = best.damping_ratio / z;
                assert!(
                    (0.5..2.0).contains(&ratio),
                    "seed {seed}: ζ {ratio} × truth at {f} Hz"
                );
                damping.push((ratio - 1.0).abs());
            }
        }
        damping.sort_by(f64::total_cmp);
        assert!(
            damping[damping.len() / 2] < 0.25,
            "median {:.3}",
            damping[damping.len() / 2]
        );
    }

    /// The factorization (two thin SVDs, `R(0)` never formed) realizes what the
    /// correlations formed and factored whole do, at every order it keeps, on noisy data:
    /// the same transfer function (Markov blocks) and the same singular values.
    #[test]
    fn the_factorization_matches_the_formed_correlations() {
        let (_, model) = structure(4, 2, 6, 7);
        let mut markov = markov_of(&model, 400);
        let mut rng = Minstd::new(77);
        for k in 1..400 {
            for i in 0..4 {
                for j in 0..2 {
                    let v = markov.get(k, i, j) + 1e-3 * rng.normal();
                    markov.set(k, i, j, v);
                }
            }
        }
        let shape = DcShape::new(24, 5, 4);
        let factored = factor_dc(&markov, 1.0 / 64.0, &shape, 24, 5).unwrap();
        for states in [8, 12, 24] {
            let fast = factored.realize(states, DirectTerm::Zero).unwrap();
            let reference =
                realize_dc_with(&markov, 1.0 / 64.0, states, 5, &shape, DirectTerm::Zero).unwrap();
            // Two routes to the factors (the formed correlations square the data's
            // conditioning): a fixed bound, not a rounding one.
            let (sv, reference_sv) = (&fast.singular_values, &reference.singular_values);
            let k = sv.len().min(reference_sv.len()).min(30);
            let what = format!("{states} states, singular values");
            assert_matches_naive(&what, &sv[..k], &reference_sv[..k], Scale::Largest, 1e-10);
            // Realizations differ by a state basis (signs): compare C A^k B.
            let block = |m: &StateSpace, k: usize| {
                let mut x = m.b.clone();
                for _ in 0..k {
                    x = &m.a * &x;
                }
                &m.c * &x
            };
            for k in [0, 1, 5, 40] {
                let (f, r) = (block(&fast.model, k), block(&reference.model, k));
                let what = format!("{states} states, block {k}");
                assert_matches_naive(&what, &f, &r, Scale::Norm, 1e-8);
            }
        }
        assert!(factor_dc(&markov, 1.0, &DcShape { xi: 1, ..shape }, 8, 5).is_err());
    }

    /// The paper's other sizes (few rows, long sums, a correlation Hankel of several
    /// lags) realize exact data exactly too.
    #[test]
    fn every_shape_is_exact_on_exact_data() {
        let (truth, model) = structure(3, 2, 4, 5);
        let markov = markov_of(&model, 800);
        let shape = DcShape {
            alpha: 4,
            beta: 300,
            xi: 2,
            tau: 3,
            shift: 4,
        };
        let found = realize_dc_with(&markov, 1.0 / 64.0, 8, 5, &shape, DirectTerm::Zero).unwrap();
        let m = modal_parameters(&found.model).unwrap();
        for f in &truth.frequencies_hz {
            let best = m
                .modes
                .iter()
                .map(|x| (x.frequency_hz - f).abs() / f)
                .fold(f64::INFINITY, f64::min);
            assert!(best < 1e-8, "{f} Hz off by {best:e}");
        }
    }

    #[test]
    fn a_short_sequence_is_refused() {
        let (_, model) = structure(2, 1, 3, 2);
        let markov = markov_of(&model, 12);
        assert!(matches!(
            realize_dc(&markov, 1.0, 6, 5, DirectTerm::Zero),
            Err(EraError::NotEnoughMarkovSamples { .. })
        ));
    }
}

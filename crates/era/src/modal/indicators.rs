//! Quality indicators of identified modes: which poles describe the structure and which
//! only fit noise or truncation error (docs/src/design.md §10).
//!
//! Each indicator is a pure function of the mode and, for EMAC, of what the Hankel
//! matrix said about it. None depends on the state basis: a similarity transform
//! `A' = T⁻¹AT`, `B' = T⁻¹B`, `C' = CT` changes the eigenvectors to `T⁻¹φ` and `ψT`,
//! and every quantity below is a product in which `T` cancels.
//!
//! **MPC**, modal phase collinearity (Pappa, Elliott & Schenk 1993). A lightly damped
//! structure with proportional damping has real normal modes: every entry of the shape
//! `Cφ` has the same phase, up to sign. With `x = Re(Cφ)`, `y = Im(Cφ)` and the 2 × 2
//! scatter matrix `S = [[xᵀx, xᵀy], [xᵀy, yᵀy]]` of eigenvalues `λ₁ ≥ λ₂`,
//!
//! ```text
//! MPC = ((λ₁ − λ₂)/(λ₁ + λ₂))² = ((xᵀx − yᵀy)² + 4 (xᵀy)²) / (xᵀx + yᵀy)²
//! ```
//!
//! 1 when the entries lie on a line through 0 of the complex plane (any common phase), 0
//! when they spread evenly in all directions. Invariant to the complex scale of `φ`.
//!
//! **EMAC**, extended modal amplitude coherence (Juang & Pappa 1985's modal amplitude
//! coherence, extended by Pappa, Elliott & Schenk 1993). The Hankel's SVD gives the data's
//! own estimate of the observability matrix, `U_n S_n^(½)`, whose block row `k` stands
//! for `C A^k`. The model *predicts* that block for mode `i` from its eigenvalue:
//! `C A^k φ_i = λ_i^k C φ_i`. A real mode is consistent over the record, so the
//! identified `(U_n S_n^(½))_k φ_i` and the predicted `λ_i^k C φ_i` agree; a computational
//! mode that fits one stretch of noise does not. Pappa et al. compare at the last block
//! row `k = R − 1`. With the long Hankels a scan uses, a well-damped real mode has
//! decayed into rounding error long before that, and would score 0; era compares at the
//! last block row or at the block where the mode's envelope `|λ|^k` has fallen to
//! [`EMAC_DECAY`] of its start, whichever comes first. Per output `j`, with identified
//! `a_j` and predicted `b_j`,
//!
//! ```text
//! R_j = min(|a_j|/|b_j|, |b_j|/|a_j|)            (amplitude agreement)
//! W_j = max(0, 1 − |arg(a_j/b_j)| / (π/4))        (phase agreement, 0 past 45°)
//! EMAC_out = Σ_j R_j W_j |b_j|² / Σ_j |b_j|²
//! ```
//!
//! and the same on the input side with the controllability matrix `S_n^(½) V_nᵀ`,
//! `ψ_i (…)_k` against `λ_i^k ψ_i B`. `EMAC = EMAC_out · EMAC_in`.
//!
//! **CMI**, consistent-mode indicator: `CMI = EMAC · MPC` (same paper).
//!
//! **Contribution**: the mode's share of the FRF, `‖G_k‖_F / ‖G‖_F` over the fitted lines
//! and all pairs, where `G_k` is the mode's pole pair's term of the model's FRF and `G`
//! the measured FRF.
//!
//! Everything here is a few lines of complex arithmetic per mode; no crate provides these
//! modal-analysis indicators, so they are written here.

use crate::data::statespace::TimeDomain;
use crate::pipeline::modes::ModalForm;
use crate::pipeline::realize::{HankelTails, Tails};
use num_complex::Complex64;

/// Modal phase collinearity of a shape, in [0, 1] (0 for a zero shape).
pub fn mpc(shape: &[Complex64]) -> f64 {
    let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
    for v in shape {
        sxx += v.re * v.re;
        syy += v.im * v.im;
        sxy += v.re * v.im;
    }
    let total = sxx + syy;
    if total <= 0.0 {
        return 0.0;
    }
    let spread = (sxx - syy).powi(2) + 4.0 * sxy * sxy;
    (spread / (total * total)).clamp(0.0, 1.0)
}

/// Amplitude coherence of an identified vector with a predicted one: `Σ R_j W_j |b_j|² /
/// Σ |b_j|²` (module doc). 0 when the prediction is zero.
pub(crate) fn amplitude_coherence(identified: &[Complex64], predicted: &[Complex64]) -> f64 {
    let mut weighted = 0.0;
    let mut total = 0.0;
    for (a, b) in identified.iter().zip(predicted) {
        let w = b.norm_sqr();
        total += w;
        let (na, nb) = (a.norm(), b.norm());
        if na == 0.0 || nb == 0.0 {
            continue;
        }
        let ratio = (na / nb).min(nb / na);
        let phase = (a / b).arg().abs();
        let agreement = (1.0 - phase / std::f64::consts::FRAC_PI_4).max(0.0);
        weighted += ratio * agreement * w;
    }
    if total > 0.0 && total.is_finite() {
        weighted / total
    } else {
        0.0
    }
}

/// Where EMAC compares identified and predicted blocks: the last block of the Hankel, or
/// earlier, the block at which the mode's envelope `|λ|^k` has decayed to this fraction
/// of its start.
pub const EMAC_DECAY: f64 = 0.05;

/// The block index EMAC uses for eigenvalue `lambda` among `blocks` (module doc).
pub(crate) fn emac_block(lambda: Complex64, blocks: usize) -> usize {
    let last = blocks.saturating_sub(1);
    let r = lambda.norm();
    if !(r > 0.0 && r < 1.0) {
        return last;
    }
    let k = (EMAC_DECAY.ln() / r.ln()).ceil();
    if k.is_finite() && k >= 1.0 {
        (k as usize).min(last)
    } else {
        last.min(1)
    }
}

/// Output and input EMAC of every eigenvalue of `form`, from the identified
/// observability and controllability matrices (module doc). The model must be the
/// discrete one whose basis they are in.
pub fn emac(form: &ModalForm, tails: &HankelTails) -> Vec<(f64, f64)> {
    emac_of(form, tails)
}

/// [`emac`] of tails formed or read in place. Each block row (column) an eigenvalue
/// compares at is gathered once, contiguous in the states, for every eigenvalue that
/// compares there (lightly damped poles mostly share the last).
pub(crate) fn emac_of(form: &ModalForm, tails: &impl Tails) -> Vec<(f64, f64)> {
    emac_at(form, tails, 0..form.eigenvalues.len())
}

/// [`emac_of`] of the eigenvalues `which` only, in that order (the order scan keeps one
/// of each conjugate pair).
pub(crate) fn emac_at(
    form: &ModalForm,
    tails: &impl Tails,
    which: impl Iterator<Item = usize>,
) -> Vec<(f64, f64)> {
    let n = form.eigenvalues.len();
    let (q, p) = (tails.outputs(), tails.inputs());
    // Block `k` of the observability matrix as `q` runs of `n`, and of the
    // controllability matrix as `p` runs of `n` (one per column); at least one of each,
    // empty, for tails without outputs or inputs (whose block index is 0).
    let mut out_blocks: Vec<Option<Vec<f64>>> = vec![None; tails.block_rows().max(1)];
    let mut in_blocks: Vec<Option<Vec<f64>>> = vec![None; tails.block_cols().max(1)];
    which
        .map(|k| {
            let lambda = form.eigenvalues[k];
            let ko = emac_block(lambda, tails.block_rows());
            let ki = emac_block(lambda, tails.block_cols());
            let rise_out = power(lambda, ko);
            let rise_in = power(lambda, ki);
            let right = form.right.col(k);
            let out_block = out_blocks[ko].get_or_insert_with(|| {
                (0..q)
                    .flat_map(|i| (0..n).map(move |r| (i, r)))
                    .map(|(i, r)| tails.observability(ko * q + i, r))
                    .collect()
            });
            let identified_out: Vec<Complex64> = out_block
                .chunks_exact(n.max(1))
                .take(q)
                .map(|row| row.iter().enumerate().map(|(r, o)| right[r] * o).sum())
                .collect();
            let predicted_out: Vec<Complex64> =
                form.shapes[k].iter().map(|c| c * rise_out).collect();
            let in_block = in_blocks[ki].get_or_insert_with(|| {
                (0..p)
                    .flat_map(|j| (0..n).map(move |r| (j, r)))
                    .map(|(j, r)| tails.controllability(r, ki * p + j))
                    .collect()
            });
            let identified_in: Vec<Complex64> = in_block
                .chunks_exact(n.max(1))
                .take(p)
                .map(|col| {
                    col.iter()
                        .enumerate()
                        .map(|(r, c)| form.left[(k, r)] * c)
                        .sum()
                })
                .collect();
            let predicted_in: Vec<Complex64> =
                form.participations[k].iter().map(|b| b * rise_in).collect();
            (
                amplitude_coherence(&identified_out, &predicted_out),
                amplitude_coherence(&identified_in, &predicted_in),
            )
        })
        .collect()
}

/// `λ^k` by repeated squaring (exact powers of the eigenvalue; underflows to 0 cleanly).
fn power(lambda: Complex64, k: usize) -> Complex64 {
    let mut result = Complex64::new(1.0, 0.0);
    let mut base = lambda;
    let mut e = k;
    while e > 0 {
        if e & 1 == 1 {
            result *= base;
        }
        base *= base;
        e >>= 1;
    }
    result
}

/// `Σ_lines ‖G_k‖_F²` of one pole's term `c bᵀ/(z − λ)` (and its conjugate's, for a
/// complex pole) at the evaluation `points` (`z = e^(jωTs)` or `jω`).
///
/// With `r_ij = c_i b_j`, `w = 1/(z − λ)` and `w' = 1/(z − λ̄)` (0 for a real pole),
/// `Σ_ij |r_ij w + r̄_ij w'|² = S₁(|w|² + |w'|²) + 2 Re(S₂ w w̄')`, where
/// `S₁ = Σ_ij |r_ij|² = Σ|c_i|² Σ|b_j|²` and `S₂ = Σ_ij r_ij² = Σc_i² Σb_j²`: O(1) per
/// line instead of O(q·p).
pub(crate) fn term_energy(
    shape: &[Complex64],
    participation: &[Complex64],
    lambda: Complex64,
    points: &[Complex64],
) -> f64 {
    let pair = lambda.im != 0.0;
    let s1 = shape.iter().map(|c| c.norm_sqr()).sum::<f64>()
        * participation.iter().map(|b| b.norm_sqr()).sum::<f64>();
    let s2 = shape.iter().map(|c| c * c).sum::<Complex64>()
        * participation.iter().map(|b| b * b).sum::<Complex64>();
    let mut sum = 0.0;
    for z in points {
        let w = 1.0 / (z - lambda);
        if pair {
            let wc = 1.0 / (z - lambda.conj());
            sum += s1 * (w.norm_sqr() + wc.norm_sqr()) + 2.0 * (s2 * w * wc.conj()).re;
        } else {
            sum += s1 * w.norm_sqr();
        }
    }
    sum
}

/// `‖G_k‖_F / ‖G‖_F` of every eigenvalue of `form` (its conjugate's term included for a
/// complex pole) over the lines `frequency_hz`; `measured` is the FRF `[out][in][line]`
/// on those lines. 0 for all when the measurement is zero.
pub(crate) fn contributions(
    form: &ModalForm,
    domain: TimeDomain,
    frequency_hz: &[f64],
    measured: &[Complex64],
) -> Vec<f64> {
    let reference: f64 = measured.iter().map(|v| v.norm_sqr()).sum::<f64>().sqrt();
    let points: Vec<Complex64> = frequency_hz
        .iter()
        .map(|f| crate::pipeline::fit::evaluation_point(domain, *f))
        .collect();
    form.eigenvalues
        .iter()
        .enumerate()
        .map(|(k, lambda)| {
            if reference <= 0.0 || !reference.is_finite() {
                return 0.0;
            }
            term_energy(&form.shapes[k], &form.participations[k], *lambda, &points).sqrt()
                / reference
        })
        .collect()
}

/// The indicators of one mode.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModeIndicators {
    /// Modal phase collinearity of the shape.
    pub mpc: f64,
    /// Extended modal amplitude coherence, output side times input side (`None` when the
    /// model did not come with Hankel factors, e.g. a refined model).
    pub emac: Option<f64>,
    /// `EMAC · MPC` (`None` with EMAC).
    pub cmi: Option<f64>,
    /// The mode's share of the measured FRF (`None` when not computed).
    pub contribution: Option<f64>,
}

/// Modal assurance criterion of two complex shapes (0 when either is zero).
pub fn mac(a: &[Complex64], b: &[Complex64]) -> f64 {
    let cross: Complex64 = a.iter().zip(b).map(|(x, y)| x.conj() * y).sum();
    let na: f64 = a.iter().map(|x| x.norm_sqr()).sum();
    let nb: f64 = b.iter().map(|x| x.norm_sqr()).sum();
    if na > 0.0 && nb > 0.0 {
        cross.norm_sqr() / (na * nb)
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::statespace::StateSpace;
    use crate::pipeline::realize::{realize, RealizeOptions};
    use crate::sources::frf::MarkovSequence;
    use faer::Mat;

    #[test]
    fn mac_is_one_for_scaled_shapes_and_zero_for_orthogonal() {
        let a = [Complex64::new(1.0, 1.0), Complex64::new(2.0, -1.0)];
        let b: Vec<Complex64> = a.iter().map(|v| v * Complex64::new(0.0, -3.0)).collect();
        assert!((mac(&a, &b) - 1.0).abs() < 1e-15);
        assert_eq!(
            mac(
                &[Complex64::new(1.0, 0.0), Complex64::new(0.0, 0.0)],
                &[Complex64::new(0.0, 0.0), Complex64::new(1.0, 0.0)]
            ),
            0.0
        );
    }

    fn c(re: f64, im: f64) -> Complex64 {
        Complex64::new(re, im)
    }

    #[test]
    fn mpc_is_one_for_collinear_and_zero_for_circular_shapes() {
        let phase = Complex64::from_polar(1.0, 0.7);
        let real: Vec<Complex64> = [1.0, -0.5, 0.25, 2.0].iter().map(|v| phase * v).collect();
        assert!((mpc(&real) - 1.0).abs() < 1e-14);
        // Four points at 90° steps: no preferred direction.
        let round = [c(1.0, 0.0), c(0.0, 1.0), c(-1.0, 0.0), c(0.0, -1.0)];
        assert!(mpc(&round) < 1e-14);
        assert_eq!(mpc(&[c(0.0, 0.0)]), 0.0);
    }

    #[test]
    fn amplitude_coherence_penalises_amplitude_and_phase() {
        let a = [c(1.0, 0.0), c(0.0, 2.0)];
        assert!((amplitude_coherence(&a, &a) - 1.0).abs() < 1e-15);
        let half: Vec<Complex64> = a.iter().map(|v| v * 0.5).collect();
        assert!((amplitude_coherence(&half, &a) - 0.5).abs() < 1e-15);
        let turned: Vec<Complex64> = a
            .iter()
            .map(|v| v * Complex64::from_polar(1.0, std::f64::consts::FRAC_PI_8))
            .collect();
        assert!((amplitude_coherence(&turned, &a) - 0.5).abs() < 1e-12);
        let opposite: Vec<Complex64> = a.iter().map(|v| -v).collect();
        assert_eq!(amplitude_coherence(&opposite, &a), 0.0);
    }

    /// Exact Markov blocks of a discrete model with real normal modes (proportional
    /// damping): the modes of `y(k) = Σ φ φᵀ … ` with real shapes.
    fn real_mode_model() -> StateSpace {
        let ts = 0.01;
        let modes = [(3.0, 0.02), (7.5, 0.01), (12.0, 0.03)];
        let shapes = [[1.0, 0.4, -0.3], [0.5, -1.0, 0.8], [-0.2, 0.6, 1.0]];
        let n = 2 * modes.len();
        let mut a = Mat::<f64>::zeros(n, n);
        let mut b = Mat::<f64>::zeros(n, 3);
        let mut cm = Mat::<f64>::zeros(3, n);
        for (k, (f, z)) in modes.iter().enumerate() {
            let w = 2.0 * std::f64::consts::PI * f;
            a[(2 * k, 2 * k + 1)] = 1.0;
            a[(2 * k + 1, 2 * k)] = -w * w;
            a[(2 * k + 1, 2 * k + 1)] = -2.0 * z * w;
            for i in 0..3 {
                b[(2 * k + 1, i)] = shapes[k][i];
                cm[(i, 2 * k)] = shapes[k][i];
            }
        }
        StateSpace::new(a, b, cm, Mat::zeros(3, 3), TimeDomain::Continuous)
            .c2d(ts)
            .unwrap()
    }

    fn markov_of(model: &StateSpace, samples: usize) -> MarkovSequence {
        let mut seq = MarkovSequence::zeros(model.outputs(), model.inputs(), samples);
        let mut ak_b = model.b.clone();
        for k in 1..samples {
            let y = &model.c * &ak_b;
            for i in 0..model.outputs() {
                for j in 0..model.inputs() {
                    seq.set(k, i, j, y[(i, j)]);
                }
            }
            ak_b = &model.a * &ak_b;
        }
        seq
    }

    #[test]
    fn real_normal_modes_on_exact_data_score_one() {
        let truth = real_mode_model();
        let markov = markov_of(&truth, 200);
        let r = realize(&markov, 0.01, &RealizeOptions::new(6, 20)).unwrap();
        let form = ModalForm::new(&r.model).unwrap();
        let e = emac(&form, &r.tails);
        for (k, lambda) in form.eigenvalues.iter().enumerate() {
            assert!((mpc(&form.shapes[k]) - 1.0).abs() < 1e-8, "MPC of {lambda}");
            assert!(
                (e[k].0 - 1.0).abs() < 1e-8,
                "EMAC out of {lambda}: {}",
                e[k].0
            );
            assert!(
                (e[k].1 - 1.0).abs() < 1e-8,
                "EMAC in of {lambda}: {}",
                e[k].1
            );
        }
    }

    /// EMAC as it was computed before the tails could be read in place: entry by entry
    /// from the formed tails (the reference of `emac_of`'s gathered blocks).
    fn emac_reference(form: &ModalForm, tails: &HankelTails) -> Vec<(f64, f64)> {
        let n = form.eigenvalues.len();
        let (q, p) = (tails.outputs, tails.inputs);
        (0..n)
            .map(|k| {
                let lambda = form.eigenvalues[k];
                let ko = emac_block(lambda, tails.block_rows());
                let ki = emac_block(lambda, tails.block_cols());
                let identified_out: Vec<Complex64> = (0..q)
                    .map(|i| {
                        (0..n)
                            .map(|r| form.right[(r, k)] * tails.observability[(ko * q + i, r)])
                            .sum()
                    })
                    .collect();
                let identified_in: Vec<Complex64> = (0..p)
                    .map(|j| {
                        (0..n)
                            .map(|r| form.left[(k, r)] * tails.controllability[(r, ki * p + j)])
                            .sum()
                    })
                    .collect();
                let out: Vec<Complex64> = form.shapes[k]
                    .iter()
                    .map(|c| c * power(lambda, ko))
                    .collect();
                let inp: Vec<Complex64> = form.participations[k]
                    .iter()
                    .map(|b| b * power(lambda, ki))
                    .collect();
                (
                    amplitude_coherence(&identified_out, &out),
                    amplitude_coherence(&identified_in, &inp),
                )
            })
            .collect()
    }

    #[test]
    fn emac_read_in_place_is_the_entry_by_entry_emac_bit_for_bit() {
        // A scan reads each order's tails from the factors and EMAC gathers each block it
        // compares at once: the same numbers as the sums entry by entry over the formed
        // tails (which `pipeline::realize`'s tests hold to the factors' products), for ERA
        // and for ERA/DC (whose controllability tail comes from U_nᵀ H(0)).
        use crate::pipeline::factor::{FactorOptions, Factorization};
        use crate::pipeline::realize::DirectTerm;
        use crate::pipeline::realize_dc::{factor_dc, DcShape};
        let truth = real_mode_model();
        let mut markov = markov_of(&truth, 400);
        let mut rng = crate::linalg::rng::Minstd::new(7);
        for k in 1..400 {
            for i in 0..3 {
                for j in 0..3 {
                    let v = markov.get(k, i, j);
                    markov.set(k, i, j, v + 1e-4 * rng.normal());
                }
            }
        }
        let era = Factorization::thesis(&markov, 0.01, &FactorOptions::new(20, 10)).unwrap();
        let dc = factor_dc(&markov, 0.01, &DcShape::new(20, 10, 3), 20, 10).unwrap();
        for f in [&era, &dc] {
            for n in [6, 12, 20] {
                let formed = f.realize(n, DirectTerm::Zero).unwrap();
                let (model, view) = f.realize_in_place(n, DirectTerm::Zero).unwrap();
                assert_eq!(model.a, formed.model.a);
                assert_eq!(model.b, formed.model.b);
                assert_eq!(model.c, formed.model.c);
                let form = ModalForm::new(&model).unwrap();
                let reference = emac_reference(&form, &formed.tails);
                assert_eq!(emac_of(&form, &view), reference, "EMAC at {n} states");
                // The scan's: one of each conjugate pair, the same numbers.
                let upper: Vec<usize> = (0..n).filter(|&k| form.eigenvalues[k].im > 0.0).collect();
                let some = emac_at(&form, &view, upper.iter().copied());
                let expected: Vec<(f64, f64)> = upper.iter().map(|&k| reference[k]).collect();
                assert!(!upper.is_empty());
                assert_eq!(some, expected, "EMAC of the upper poles at {n} states");
                assert_eq!(emac(&form, &formed.tails), reference);
                assert!(reference.iter().any(|&(o, i)| o > 0.5 && i > 0.5));
            }
        }
    }

    #[test]
    fn emac_of_tails_without_outputs_or_inputs_is_zero_not_a_panic() {
        let truth = real_mode_model();
        let form = ModalForm::new(&truth).unwrap();
        let n = truth.states();
        let tails = HankelTails {
            observability: Mat::zeros(0, n),
            controllability: Mat::zeros(n, 0),
            outputs: 0,
            inputs: 0,
        };
        let e = emac(&form, &tails);
        assert_eq!(e.len(), n);
    }

    #[test]
    fn a_mode_fitted_to_noise_scores_low() {
        // The exact data plus a little noise, identified with many more states than the
        // 6 it has: the extra poles fit the noise and are not consistent over the record.
        let truth = real_mode_model();
        let mut markov = markov_of(&truth, 400);
        let mut rng = crate::linalg::rng::Minstd::new(4);
        let peak = (1..400)
            .map(|k| markov.get(k, 0, 0).abs())
            .fold(0.0, f64::max);
        for k in 1..400 {
            for i in 0..3 {
                for j in 0..3 {
                    let v = markov.get(k, i, j);
                    markov.set(k, i, j, v + 1e-3 * peak * rng.normal());
                }
            }
        }
        let r = realize(&markov, 0.01, &RealizeOptions::new(20, 10)).unwrap();
        let form = ModalForm::new(&r.model).unwrap();
        let e = emac(&form, &r.tails);
        let truth_poles: Vec<Complex64> = ModalForm::new(&truth).unwrap().eigenvalues;
        let mut real_scores = Vec::new();
        let mut computational = Vec::new();
        for (k, lambda) in form.eigenvalues.iter().enumerate() {
            let near = truth_poles.iter().any(|t| (t - lambda).norm() < 1e-3);
            let score = e[k].0 * e[k].1 * mpc(&form.shapes[k]);
            if near {
                real_scores.push(score);
            } else {
                computational.push(score);
            }
        }
        assert_eq!(
            real_scores.len(),
            6,
            "the six true poles are found: {:?}",
            form.eigenvalues
        );
        assert!(real_scores.iter().all(|s| *s > 0.9), "{real_scores:?}");
        let worst_real = real_scores.iter().copied().fold(1.0, f64::min);
        let median = {
            let mut c = computational.clone();
            c.sort_by(f64::total_cmp);
            c[c.len() / 2]
        };
        assert!(
            median < 0.5 && median < worst_real,
            "computational CMI {computational:?}"
        );
    }

    #[test]
    fn contributions_of_a_single_mode_model_cover_its_response() {
        let truth = real_mode_model();
        let form = ModalForm::new(&truth).unwrap();
        let f: Vec<f64> = (1..400).map(|k| k as f64 * 0.05).collect();
        let g = crate::pipeline::fit::frequency_response_modal(&truth, &form, &f);
        let share = contributions(&form, truth.domain, &f, &g);
        // Each pole and its conjugate give the same share (their pair's); the three
        // shares lie in (0, 1), and by the triangle inequality they sum to at least 1.
        let total: f64 = share.iter().sum::<f64>() / 2.0;
        assert!(share.iter().all(|s| *s > 0.01 && *s < 1.0), "{share:?}");
        for pair in share.chunks(2) {
            assert!((pair[0] - pair[1]).abs() < 1e-12 * pair[0], "{share:?}");
        }
        assert!(total >= 1.0 - 1e-12, "{total}");
        // A model of one of the modes alone has that mode's share.
        let one = ModalForm {
            eigenvalues: form.eigenvalues[..2].to_vec(),
            shapes: form.shapes[..2].to_vec(),
            participations: form.participations[..2].to_vec(),
            ..form.clone()
        };
        let g1 = crate::pipeline::fit::frequency_response_modal(&truth, &one, &f);
        let alone: f64 = g1.iter().map(|v| v.norm_sqr()).sum::<f64>().sqrt()
            / g.iter().map(|v| v.norm_sqr()).sum::<f64>().sqrt();
        assert!(
            (alone - share[0]).abs() < 1e-9 * alone,
            "{alone} vs {}",
            share[0]
        );
    }
}

//! Which identified modes to trust: a mode is *stable* when models of other orders have
//! a mode close to it in frequency, damping and shape (the stabilisation-diagram test).
//!
//! A mode of the reference model matches a mode of another model when
//! - the frequencies differ by at most `frequency_tolerance` (relative),
//! - the damping ratios differ by at most `damping_tolerance` (relative to the
//!   reference's),
//! - the output shapes agree: modal assurance criterion
//!   `MAC = |φ₁ᴴφ₂|² / (φ₁ᴴφ₁ · φ₂ᴴφ₂) ≥ mac_minimum`.
//!
//! The closest match in frequency among those is taken. A mode is stable when it matches
//! in every other model and its damping ratio is below `damping_maximum` (noise and
//! computational modes are often heavily damped).

use crate::modal::Mode;
use num_complex::Complex64;

/// Thresholds of the match.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StabilityCriteria {
    /// Largest relative frequency difference.
    pub frequency_tolerance: f64,
    /// Largest damping difference relative to the reference's damping ratio.
    pub damping_tolerance: f64,
    /// Smallest MAC of the output shapes.
    pub mac_minimum: f64,
    /// Largest damping ratio of a stable mode.
    pub damping_maximum: f64,
}

impl Default for StabilityCriteria {
    /// 0.5 % in frequency, 30 % in damping, MAC 0.9, ζ below 10 %.
    fn default() -> Self {
        StabilityCriteria {
            frequency_tolerance: 0.005,
            damping_tolerance: 0.3,
            mac_minimum: 0.9,
            damping_maximum: 0.1,
        }
    }
}

/// One reference mode's matches.
#[derive(Debug, Clone, PartialEq)]
pub struct ModeStability {
    /// Index of the mode in the reference list.
    pub mode: usize,
    /// Per other model: the index of the matching mode and its MAC, if any.
    pub matches: Vec<Option<(usize, f64)>>,
    /// Matched in every other model, and damped below the maximum.
    pub stable: bool,
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

/// Matches each mode of `reference` in each of `others`.
pub fn stability(
    reference: &[Mode],
    others: &[&[Mode]],
    criteria: &StabilityCriteria,
) -> Vec<ModeStability> {
    reference
        .iter()
        .enumerate()
        .map(|(k, m)| {
            let matches: Vec<Option<(usize, f64)>> = others
                .iter()
                .map(|list| {
                    list.iter()
                        .enumerate()
                        .filter(|(_, o)| {
                            (o.frequency_hz - m.frequency_hz).abs()
                                <= criteria.frequency_tolerance * m.frequency_hz
                                && (o.damping_ratio - m.damping_ratio).abs()
                                    <= criteria.damping_tolerance * m.damping_ratio.abs()
                        })
                        .map(|(j, o)| (j, mac(&m.shape, &o.shape), o.frequency_hz))
                        .filter(|(_, mac, _)| *mac >= criteria.mac_minimum)
                        .min_by(|a, b| {
                            (a.2 - m.frequency_hz)
                                .abs()
                                .total_cmp(&(b.2 - m.frequency_hz).abs())
                        })
                        .map(|(j, mac, _)| (j, mac))
                })
                .collect();
            let stable =
                matches.iter().all(Option::is_some) && m.damping_ratio < criteria.damping_maximum;
            ModeStability {
                mode: k,
                matches,
                stable,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mode(f: f64, z: f64, shape: &[f64]) -> Mode {
        Mode {
            frequency_hz: f,
            damping_ratio: z,
            eigenvalue: Complex64::new(0.0, 0.0),
            continuous_pole: Complex64::new(0.0, 0.0),
            shape: shape.iter().map(|&v| Complex64::new(v, 0.0)).collect(),
            participation: vec![],
        }
    }

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

    #[test]
    fn stable_only_when_every_model_matches() {
        let reference = [
            mode(10.0, 0.01, &[1.0, 0.5]),
            mode(20.0, 0.02, &[1.0, -1.0]),
            mode(30.0, 0.5, &[1.0, 1.0]),
        ];
        let a = [
            mode(10.02, 0.011, &[2.0, 1.0]),
            mode(20.5, 0.02, &[1.0, -1.0]),
            mode(30.0, 0.5, &[1.0, 1.0]),
        ];
        let b = [
            mode(9.99, 0.009, &[1.0, 0.45]),
            mode(20.0, 0.02, &[1.0, 1.0]),
            mode(30.0, 0.5, &[1.0, 1.0]),
        ];
        let s = stability(&reference, &[&a, &b], &StabilityCriteria::default());
        assert!(s[0].stable);
        assert_eq!(s[0].matches[0].unwrap().0, 0);
        // 20 Hz: too far in a (2.5 %), wrong shape in b (MAC 0).
        assert!(!s[1].stable && s[1].matches[0].is_none() && s[1].matches[1].is_none());
        // 30 Hz matches everywhere but is 50 % damped.
        assert!(!s[2].stable && s[2].matches.iter().all(Option::is_some));
    }
}

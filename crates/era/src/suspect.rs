//! Suspect results: checks on a finished identification that do not stop the run but
//! say when its numbers should not be trusted as they are.
//!
//! A realization can succeed and still be wrong in ways the singular values do not show.
//! Three cases are common enough, and cheap enough to detect, to be checked on every
//! run:
//!
//! - **A Hankel too short for the lowest mode.** The Hankel matrices of docs/design.md
//!   §1.7 see the impulse response over the Markov samples `Y_1 … Y_{r+c}` (`r` block
//!   rows, `c` block columns), a window of `T_H = (r + c)·Ts` seconds. A mode whose
//!   period `1/f` is longer than `T_H` is seen over less than one cycle: its frequency and
//!   above all its damping are then set by the Hankel's edges, not by the data. On a
//!   clean one-mode FRF (0.3 Hz, ζ 2 %, lines to 12.5 Hz) the damping found is 2.39 % at
//!   0.22 of a period, 2.02 % at 0.46 and 1.99993 % at 1.2 (`cargo run --release -p era
//!   --example short_hankel -- 0.3 0.02 12.5 513 0` prints the curve).
//!   Padding (`pad_to`) shortens `Ts`, so it shortens `T_H` at the same `hankel_factor`;
//!   that is how a padded run ends with a negative damping. The check is
//!   `T_H < 1/f_min`, with `f_min` the lowest mode judged physical (the lowest mode when
//!   none is), and the remedy a larger `hankel_factor` (or less padding).
//! - **Negative damping.** A mode with `ζ < 0` (`Re s > 0`) grows: the model is unstable
//!   and its time response diverges, whatever its FRF fit says.
//! - **A pole outside the unit circle.** The same for a real pole: `|z| > 1` in discrete
//!   time, `s > 0` in continuous time (a real pole at exactly `s = 0`, the integrator of a
//!   refinement's lower residual, is not unstable in this sense and is not reported).
//!
//! Each warning is worded for the calling front end ([`Naming`]): the CLI names flags,
//! Python keywords.

use crate::identify::{Identification, ModeQuality};
use crate::modal::ModalParameters;
use crate::params::Naming;

/// A result to treat with care.
#[derive(Debug, Clone, PartialEq)]
pub enum SuspectResult {
    /// The Hankel's window is shorter than the period of the lowest mode.
    ShortHankel {
        /// The window `(r + c)·Ts`, s.
        window_s: f64,
        /// The lowest mode's frequency, Hz.
        lowest_hz: f64,
    },
    /// Modes with negative damping, as (frequency in Hz, damping ratio).
    NegativeDamping(Vec<(f64, f64)>),
    /// Real poles outside the unit circle: their continuous `Re s > 0`, rad/s.
    UnstableRealPoles(Vec<f64>),
}

impl SuspectResult {
    /// The warning in the words of `naming`'s front end.
    pub fn message(&self, naming: Naming) -> String {
        match self {
            SuspectResult::ShortHankel {
                window_s,
                lowest_hz,
            } => format!(
                "the Hankel matrix spans {window_s:.3} s of impulse response, less than one period of the lowest mode ({lowest_hz:.4} Hz, {:.3} s): its frequency and damping are poorly determined; raise {} (or pad less with {})",
                1.0 / lowest_hz,
                naming.name("hankel_factor"),
                naming.name("pad_to"),
            ),
            SuspectResult::NegativeDamping(modes) => {
                let list: Vec<String> = modes
                    .iter()
                    .take(5)
                    .map(|(f, z)| format!("{f:.4} Hz (damping {:.2} %)", z * 100.0))
                    .collect();
                let more = if modes.len() > 5 {
                    format!(" and {} more", modes.len() - 5)
                } else {
                    String::new()
                };
                format!(
                    "{} mode(s) with negative damping: {}{more}; the model is unstable (its time response grows): such modes are usually computational; try {} auto, or fewer {}",
                    modes.len(),
                    list.join(", "),
                    naming.name("states"),
                    naming.name("states"),
                )
            }
            SuspectResult::UnstableRealPoles(poles) => {
                let list: Vec<String> = poles.iter().take(5).map(|s| format!("{s:.4e}")).collect();
                format!(
                    "{} real pole(s) outside the unit circle (growth rate Re s = {}{} 1/s): the model is unstable; try fewer {}",
                    poles.len(),
                    list.join(", "),
                    if poles.len() > 5 { ", ..." } else { "" },
                    naming.name("states"),
                )
            }
        }
    }
}

impl std::fmt::Display for SuspectResult {
    /// Worded with the option fields' names ([`Naming::Keyword`]).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message(Naming::Keyword))
    }
}

/// The checks of this module on a model's modes. `hankel_window` is the realization's
/// `(block rows + block columns, Ts)`, when a Hankel was built.
pub fn check(
    modal: &ModalParameters,
    quality: &[ModeQuality],
    hankel_window: Option<(usize, f64)>,
) -> Vec<SuspectResult> {
    let mut found = Vec::new();
    if let Some((samples, ts)) = hankel_window {
        // The lowest physical mode; every mode counts when none is judged physical.
        let any_physical = quality.iter().any(|q| q.physical);
        let lowest = modal
            .modes
            .iter()
            .enumerate()
            .filter(|(k, _)| !any_physical || quality.get(*k).is_some_and(|q| q.physical))
            .map(|(_, m)| m.frequency_hz)
            .filter(|f| f.is_finite() && *f > 0.0)
            .min_by(f64::total_cmp);
        let window_s = samples as f64 * ts;
        if let Some(lowest_hz) = lowest {
            if samples > 0 && window_s * lowest_hz < 1.0 {
                found.push(SuspectResult::ShortHankel {
                    window_s,
                    lowest_hz,
                });
            }
        }
    }
    let negative: Vec<(f64, f64)> = modal
        .modes
        .iter()
        .filter(|m| m.damping_ratio < 0.0)
        .map(|m| (m.frequency_hz, m.damping_ratio))
        .collect();
    if !negative.is_empty() {
        found.push(SuspectResult::NegativeDamping(negative));
    }
    let outside: Vec<f64> = modal
        .real_poles
        .iter()
        .map(|p| p.continuous_pole.re)
        .filter(|re| *re > 0.0)
        .collect();
    if !outside.is_empty() {
        found.push(SuspectResult::UnstableRealPoles(outside));
    }
    found
}

/// The checks on an identification: its modes, and its Hankel's window when the
/// realization has one.
pub fn check_identification(found: &Identification) -> Vec<SuspectResult> {
    let (rows, cols) = found.realization.hankel_size;
    let (q, p) = (found.model.outputs().max(1), found.model.inputs().max(1));
    let window = (rows > 0 && cols > 0).then_some((rows / q + cols / p, found.sample_time_s));
    check(&found.modal, &found.quality, window)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::identify::{identify, EraOptions};
    use crate::{Complex64, FrfData, Quantity};

    /// Receptance of one mode, `1/(ωn² − ω² + 2iζωnω)`, on `lines` lines to `fmax`.
    fn one_mode(fn_hz: f64, zeta: f64, fmax: f64, lines: usize) -> FrfData {
        let f: Vec<f64> = (0..lines)
            .map(|k| k as f64 * fmax / (lines - 1) as f64)
            .collect();
        let wn = 2.0 * std::f64::consts::PI * fn_hz;
        let v = f
            .iter()
            .map(|&h| {
                let w = 2.0 * std::f64::consts::PI * h;
                Complex64::new(1.0, 0.0) / Complex64::new(wn * wn - w * w, 2.0 * zeta * wn * w)
            })
            .collect();
        FrfData::new(f, 1, 1, v, Quantity::Displacement).unwrap()
    }

    fn short(found: &Identification) -> bool {
        found
            .suspects
            .iter()
            .any(|s| matches!(s, SuspectResult::ShortHankel { .. }))
    }

    #[test]
    fn a_hankel_shorter_than_the_lowest_period_is_flagged() {
        let frf = one_mode(0.3, 0.02, 12.5, 513);
        // 9 + 9 samples at 0.04 s: 0.22 of the 3.3 s period. The damping is 20 % off.
        let found = identify(&frf, &EraOptions::new(2, 10)).unwrap();
        let z = found.modal.modes[0].damping_ratio;
        assert!((z - 0.02).abs() > 0.003, "damping {z}");
        assert!(short(&found), "{:?}", found.suspects);
        let message = found.warnings(Naming::Flag).join("\n");
        assert!(
            message.contains("--hankel-factor") && message.contains("0.2995"),
            "{message}"
        );
        // 49 + 49 samples: 1.2 periods, the damping right to 1e-6, no warning.
        let found = identify(&frf, &EraOptions::new(2, 50)).unwrap();
        assert!((found.modal.modes[0].damping_ratio - 0.02).abs() < 1e-6);
        assert!(found.suspects.is_empty(), "{:?}", found.suspects);
    }

    #[test]
    fn padding_that_leaves_the_hankel_short_warns_of_the_unstable_result() {
        // Padded to 2048 lines the samples are four times shorter: the same Hankel
        // sees 0.06 s of a 1 s period, and the pole found grows.
        let frf = one_mode(1.0, 0.02, 12.5, 513);
        let mut options = EraOptions::new(2, 5);
        options.pad_to = 2048;
        let found = identify(&frf, &options).unwrap();
        assert!(found.modal.modes.iter().any(|m| m.damping_ratio < 0.0));
        assert!(short(&found));
        assert!(found
            .suspects
            .iter()
            .any(|s| matches!(s, SuspectResult::NegativeDamping(m) if m[0].1 < 0.0)));
        let text = found.warnings(Naming::Keyword).join("\n");
        assert!(
            text.contains("negative damping") && text.contains("pad_to"),
            "{text}"
        );
        assert!(!text.contains("--"), "{text}");
    }

    #[test]
    fn unstable_poles_are_named_and_stable_ones_are_not() {
        let mode = |f: f64, z: f64| crate::modal::Mode {
            frequency_hz: f,
            damping_ratio: z,
            eigenvalue: Complex64::new(0.0, 0.0),
            continuous_pole: Complex64::new(0.0, 0.0),
            shape: vec![],
            participation: vec![],
        };
        let real = |re: f64| crate::modal::RealPole {
            eigenvalue: re.exp(),
            continuous_pole: Complex64::new(re, 0.0),
            frequency_hz: re.abs() / (2.0 * std::f64::consts::PI),
        };
        let modal = ModalParameters {
            modes: vec![mode(2.0, 0.01), mode(3.0, -0.004)],
            // An integrator (s = 0) is not outside the unit circle.
            real_poles: vec![real(0.0), real(-3.0), real(0.5)],
        };
        let found = check(&modal, &[], None);
        assert_eq!(
            found,
            vec![
                SuspectResult::NegativeDamping(vec![(3.0, -0.004)]),
                SuspectResult::UnstableRealPoles(vec![0.5]),
            ]
        );
        assert!(found[0].to_string().contains("3.0000 Hz (damping -0.40 %)"));
        assert!(found[1].to_string().contains("outside the unit circle"));
        // With a window: 1 s is less than the 2 Hz mode's period of 0.5 s? No: no warning.
        assert_eq!(check(&modal, &[], Some((100, 0.01))).len(), 2);
        assert_eq!(check(&modal, &[], Some((10, 0.01))).len(), 3);
    }
}

//! Suspect results: checks on a finished identification that do not stop the run but
//! say when its numbers should not be trusted as they are.
//!
//! A realization can succeed and still be wrong in ways the singular values do not show.
//! Three cases are common enough, and cheap enough to detect, to be checked on every
//! run:
//!
//! - **A Hankel too short for the lowest mode.** The Hankel matrices of docs/src/design.md
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
//!
//! Two more checks need what the front end knows about the data, and run when it asks
//! ([`crate::identify::zero_start`], [`band_edges`]):
//!
//! - **Zeroed leading lines.** An FRF that starts above 0 Hz is padded with zero lines
//!   (ERA's inverse FFT needs every line from 0 Hz), and `zero_lines` zeroes lines on
//!   purpose. ERA then fits an impulse response whose low-frequency content is missing,
//!   and the lowest modes' damping comes out biased (38 % low on a mode just above a
//!   5 Hz start). The size of the effect on this very model is measured: the model's
//!   own FRF is identified twice, on every line and with the same lines zeroed, and the
//!   largest shift of a physical mode's damping and frequency is reported. A refinement
//!   fits only the measured lines and is free of it.
//! - **A mode at the edge of the band.** A mode whose half-power band (three half-widths
//!   `ζ f` each side, at least two lines) reaches past an edge of the band identified
//!   over has one flank missing: its damping rests on one side of its peak. At the low
//!   edge this is a band too short for the lowest mode.
//!
//! Each warning is worded for the calling front end ([`Naming`]): the CLI names flags,
//! Python keywords.

use crate::data::identification::{Identification, ModeQuality, SuspectResult};
use crate::params::Naming;
use crate::pipeline::modes::ModalParameters;

impl SuspectResult {
    /// The warning in the words of `naming`'s front end.
    pub(crate) fn message(&self, naming: Naming) -> String {
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
            SuspectResult::ZeroStart {
                first_hz,
                mode_hz,
                damping_shift,
                frequency_shift,
                refined,
            } => format!(
                "the lines below {first_hz} Hz are zero (padded, or zeroed with {}): on this model's own FRF that shifts ERA's {mode_hz:.4} Hz mode by {:+.1} % in damping and {:+.3} % in frequency; {}",
                naming.name("zero_lines"),
                damping_shift * 100.0,
                frequency_shift * 100.0,
                if *refined {
                    "the refinement fitted only the measured lines, so the values reported are free of it"
                } else {
                    "a refinement fits only the measured lines and is free of it; or export the FRFs from 0 Hz"
                }
            ),
            SuspectResult::BandEdge {
                mode_hz,
                damping_ratio,
                edge_hz,
                lowest,
            } => {
                let which = if *lowest {
                    "the band is too short for the lowest mode:"
                } else {
                    "a mode at the edge of the band:"
                };
                format!(
                    "{which} the {mode_hz:.4} Hz mode (damping {:.2} %) is within three half-power widths of the band's edge at {edge_hz} Hz, so one flank of its peak is missing and its damping is poorly determined; widen the band ({}) if the data allow",
                    damping_ratio * 100.0,
                    naming.name("band"),
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
pub(crate) fn check(
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
pub(crate) fn check_identification(found: &Identification) -> Vec<SuspectResult> {
    let (rows, cols) = found.realization.hankel_size;
    let (q, p) = (found.model.outputs().max(1), found.model.inputs().max(1));
    let window = (rows > 0 && cols > 0).then_some((rows / q + cols / p, found.sample_time_s));
    check(&found.modal, &found.quality, window)
}

/// Physical modes of `found` whose half-power band (three half-widths `ζ f` each side,
/// at least two lines) reaches past an edge of `band_hz`, the band identified over. An
/// edge where the data's lines end (0 Hz, the last line) is not checked: there is no
/// data beyond it to leave out.
pub fn band_edges(found: &Identification, band_hz: (f64, f64)) -> Vec<SuspectResult> {
    let freq = found.processed.frequency_hz();
    let (Some(&first), Some(&last)) = (freq.first(), freq.last()) else {
        return Vec::new();
    };
    let spacing = found.processed.spacing_hz();
    let (lo, hi) = band_hz;
    let check_lo = lo > first + spacing / 2.0;
    let check_hi = hi < last - spacing / 2.0;
    let mut lowest = true;
    let mut out = Vec::new();
    for (m, q) in found.modal.modes.iter().zip(&found.quality) {
        if !(q.physical && m.frequency_hz.is_finite() && m.damping_ratio.is_finite()) {
            continue;
        }
        let reach = (3.0 * m.damping_ratio.abs() * m.frequency_hz).max(2.0 * spacing);
        let edge = if check_lo && m.frequency_hz - reach < lo {
            Some(lo)
        } else if check_hi && m.frequency_hz + reach > hi {
            Some(hi)
        } else {
            None
        };
        if let Some(edge_hz) = edge {
            out.push(SuspectResult::BandEdge {
                mode_hz: m.frequency_hz,
                damping_ratio: m.damping_ratio,
                edge_hz,
                lowest: lowest && edge_hz == lo,
            });
        }
        lowest = false;
    }
    out
}

impl Identification {
    /// `self` with [`Identification::suspects`] found anew from its modes.
    pub(crate) fn with_suspects(mut self) -> Self {
        self.suspects = check_identification(&self);
        self
    }

    /// Every warning of the run, worded for `naming`'s front end: the realization's
    /// (docs/src/design.md §1.8), then the suspect results.
    pub fn warnings(&self, naming: Naming) -> Vec<String> {
        self.realization
            .warnings
            .iter()
            .map(|w| w.message(naming))
            .chain(self.suspects.iter().map(|s| s.message(naming)))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::frf::leading_zero_lines;
    use crate::identify::{identify, zero_start, EraOptions};
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
        let mode = |f: f64, z: f64| crate::pipeline::modes::Mode {
            frequency_hz: f,
            damping_ratio: z,
            eigenvalue: Complex64::new(0.0, 0.0),
            continuous_pole: Complex64::new(0.0, 0.0),
            shape: vec![],
            participation: vec![],
        };
        let real = |re: f64| crate::pipeline::modes::RealPole {
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

    use crate::test_support::receptance as modes;

    #[test]
    fn zeroed_leading_lines_report_the_damping_they_cost() {
        let frf = modes(&[(6.0, 0.02), (13.0, 0.01)], 0.1, 401);
        let options = EraOptions::new(4, 20);
        let clean = identify(&frf, &options).unwrap();
        assert_eq!(leading_zero_lines(&clean.processed), 0);
        assert_eq!(zero_start(&clean, &options, false), None);
        // The lines below 5 Hz zeroed, as a padded late start would be.
        let zeroed = crate::sources::frf::preprocess::zero_leading_lines(&frf, 50);
        assert_eq!(leading_zero_lines(&zeroed), 50);
        let found = identify(&zeroed, &options).unwrap();
        let z = found.modal.modes[0].damping_ratio;
        let Some(SuspectResult::ZeroStart {
            first_hz,
            mode_hz,
            damping_shift,
            refined,
            ..
        }) = zero_start(&found, &options, false)
        else {
            panic!("no warning; damping {z}");
        };
        assert!((first_hz - 5.0).abs() < 1e-9);
        assert!((mode_hz - 6.0).abs() < 0.3, "{mode_hz}");
        // The shift measured on the model's own FRF has the sign and size of the
        // bias the zeroed lines put on the data's own estimate.
        let actual = z / 0.02 - 1.0;
        assert!(actual.abs() > 0.05, "actual {actual}");
        assert!(
            damping_shift.signum() == actual.signum(),
            "{damping_shift} vs {actual}"
        );
        assert!(!refined);
        let text = zero_start(&found, &options, true)
            .unwrap()
            .message(Naming::Flag);
        assert!(
            text.contains("--zero-lines") && text.contains("free of it"),
            "{text}"
        );
    }

    #[test]
    fn modes_near_a_band_edge_are_named_and_the_lowest_at_the_low_edge_says_so() {
        let frf = modes(&[(6.0, 0.02), (13.0, 0.01), (30.0, 0.01)], 0.1, 401);
        let found = identify(&frf, &EraOptions::new(6, 20)).unwrap();
        assert!(found.quality.iter().all(|q| q.physical));
        // Every line: no edge is checked.
        assert!(band_edges(&found, (0.0, 40.0)).is_empty());
        // A band from 5.8 Hz cuts the 6 Hz mode's lower flank; one to 30.5 Hz the
        // 30 Hz mode's upper one; 13 Hz is well inside.
        let edges = band_edges(&found, (5.8, 30.5));
        assert_eq!(edges.len(), 2, "{edges:?}");
        assert!(
            matches!(edges[0], SuspectResult::BandEdge { lowest: true, edge_hz, .. } if edge_hz == 5.8)
        );
        assert!(
            matches!(edges[1], SuspectResult::BandEdge { lowest: false, edge_hz, .. } if edge_hz == 30.5)
        );
        assert!(edges[0]
            .to_string()
            .contains("too short for the lowest mode"));
        assert!(edges[1].to_string().contains("edge of the band"));
        assert!(band_edges(&found, (3.0, 36.0)).is_empty());
    }
}

//! How the length of the Hankel window sets the damping ERA finds for a lightly damped
//! mode, and when `era::identify::suspect` warns (docs/src/design.md §1.8).
//!
//! `cargo run --release -p era --example short_hankel -- FN_HZ ZETA FMAX_HZ LINES PAD_TO`
//! e.g. `-- 0.3 0.02 12.5 513 0`: a clean receptance of one mode on `LINES` lines from 0
//! to `FMAX_HZ`, identified with 2 states at growing `hankel_factor`. Each row gives the
//! Hankel's window in seconds and in periods of the mode, the frequency and damping
//! found, and the run's warnings.

use era::identify::{identify, EraOptions};
use era::params::Naming;
use era::{Complex64, FrfData, Quantity};

fn main() {
    let args: Vec<f64> = std::env::args()
        .skip(1)
        .map(|a| a.parse().expect("numbers: FN_HZ ZETA FMAX_HZ LINES PAD_TO"))
        .collect();
    let [fn_hz, zeta, fmax, lines, pad] = args[..] else {
        eprintln!("usage: short_hankel FN_HZ ZETA FMAX_HZ LINES PAD_TO");
        std::process::exit(2);
    };
    let lines = lines as usize;
    let f: Vec<f64> = (0..lines)
        .map(|k| k as f64 * fmax / (lines - 1) as f64)
        .collect();
    let wn = 2.0 * std::f64::consts::PI * fn_hz;
    let v: Vec<Complex64> = f
        .iter()
        .map(|&h| {
            let w = 2.0 * std::f64::consts::PI * h;
            Complex64::new(1.0, 0.0) / Complex64::new(wn * wn - w * w, 2.0 * zeta * wn * w)
        })
        .collect();
    let frf = FrfData::new(f, 1, 1, v, Quantity::Displacement).expect("a valid FRF");
    println!("hankel_factor  window_s  periods  frequency_hz  damping_%  warnings");
    for hf in [5usize, 10, 20, 50, 100] {
        let mut options = EraOptions::new(2, hf);
        options.pad_to = pad as usize;
        match identify(&frf, &options) {
            Ok(found) => {
                let (rows, cols) = found.realization.hankel_size;
                let window = (rows + cols) as f64 * found.sample_time_s;
                let (f, z) = found
                    .modal
                    .modes
                    .first()
                    .map_or((f64::NAN, f64::NAN), |m| (m.frequency_hz, m.damping_ratio));
                println!(
                    "{hf:>13}  {window:>8.3}  {:>7.2}  {f:>12.6}  {:>9.5}  {}",
                    window * fn_hz,
                    z * 100.0,
                    found.warnings(Naming::Flag).join(" | ")
                );
            }
            Err(e) => println!("{hf:>13}  {e}"),
        }
    }
}

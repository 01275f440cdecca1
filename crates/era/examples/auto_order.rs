//! How `--states auto` does on DTA-like sets (docs/src/design.md §10): for each seed and noise
//! level, the modes found within 0.5 % of the truth and the spurious modes marked
//! physical.
//!
//! `cargo run --release -p era --example auto_order -- [SEEDS] [NOISE,...] [ORDERS]`,
//! e.g. `-- 1,2,3 0,0.05 40..200:4`.

use era::identify::{identify, EraOptions, Order, ScanOptions};
use era::modal::stabilization::OrderRange;
use era::sim::{add_noise, ModalSpec, ModalStructure};
use era::Quantity;
use std::time::Instant;

#[path = "../benches/support/sets.rs"]
mod sets;

fn main() -> era::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let seeds: Vec<u64> = args
        .first()
        .map(|s| s.split(',').map(|v| v.parse().unwrap()).collect())
        .unwrap_or(vec![1, 2, 3]);
    let noises: Vec<f64> = args
        .get(1)
        .map(|s| s.split(',').map(|v| v.parse().unwrap()).collect())
        .unwrap_or(vec![0.0, 0.05]);
    let orders = args.get(2).map(|s| OrderRange::parse(s)).transpose()?;
    for &seed in &seeds {
        for &noise in &noises {
            let spec = ModalSpec {
                seed,
                // The DTA-like set: 8×8, 40 modes in 0.5–14 Hz, ζ 0.5–2 %, collocated.
                ..ModalSpec::default()
            };
            let structure = ModalStructure::random(&spec)?;
            let mut frf = structure.frf(801, 0.025, Quantity::Acceleration)?;
            if noise > 0.0 {
                frf = add_noise(&frf, noise, seed)?;
            }
            // PRESET=measured: what `era identify` does on a measured-FRF file.
            let mut options = if std::env::var("PRESET").as_deref() == Ok("measured") {
                sets::measured_auto()
            } else {
                EraOptions::thesis_dta()
            };
            options.order = Order::Auto;
            let mut scan = {
                let mut o = ScanOptions::default();
                o.orders = orders.clone();
                o
            };
            if let Ok(v) = std::env::var("TOL") {
                scan.svd_tolerance = v.parse().unwrap();
            }
            if let Ok(v) = std::env::var("FLOOR") {
                scan.svd_floor_fraction = v.parse().unwrap();
            }
            if let Ok(v) = std::env::var("CMI") {
                scan.selection.cmi_minimum = v.parse().unwrap();
            }
            let clock = Instant::now();
            options.scan = scan;
            let found = identify(&frf, &options)?;
            let seconds = clock.elapsed().as_secs_f64();
            let physical = sets::physical(&found);
            // One-to-one matching, nearest first.
            let mut pairs: Vec<(f64, usize, usize)> = Vec::new();
            for (i, f) in structure.frequencies_hz.iter().enumerate() {
                for (j, (g, _)) in physical.iter().enumerate() {
                    let rel = (g - f).abs() / f;
                    if rel <= 0.005 {
                        pairs.push((rel, i, j));
                    }
                }
            }
            pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
            let (mut ti, mut pj) = (vec![false; 40], vec![false; physical.len()]);
            let mut ferr = Vec::new();
            let mut zerr = Vec::new();
            for (rel, i, j) in pairs {
                if !ti[i] && !pj[j] {
                    ti[i] = true;
                    pj[j] = true;
                    ferr.push(rel);
                    zerr.push(
                        (physical[j].1 - structure.damping_ratios[i]).abs()
                            / structure.damping_ratios[i],
                    );
                }
            }
            ferr.sort_by(f64::total_cmp);
            zerr.sort_by(f64::total_cmp);
            let missed: Vec<String> = (0..40)
                .filter(|&i| !ti[i])
                .map(|i| format!("{:.3}", structure.frequencies_hz[i]))
                .collect();
            let spurious: Vec<String> = (0..physical.len())
                .filter(|&j| !pj[j])
                .map(|j| format!("{:.3}/{:.3}", physical[j].0, physical[j].1))
                .collect();
            let st = found.stabilization.as_ref().unwrap();
            if std::env::var("CLUSTERS").is_ok() {
                for c in st.selection.clusters.iter().filter(|c| c.physical) {
                    let rep = &st.scan.poles[c.representative];
                    let t = structure
                        .frequencies_hz
                        .iter()
                        .map(|f| (f - rep.frequency_hz).abs() / f)
                        .fold(f64::INFINITY, f64::min);
                    let mut cmis: Vec<f64> =
                        c.members.iter().map(|&i| st.scan.poles[i].cmi()).collect();
                    cmis.sort_by(f64::total_cmp);
                    let orders: Vec<usize> =
                        c.members.iter().map(|&i| st.scan.poles[i].order).collect();
                    println!("  {} f {:.4} z {:.4} members {} upper {} rep cmi {:.2} median cmi {:.2} mpc {:.2} median mpc {:.2} truth-dist {:.1e} orders {}..{}", if t < 0.005 {"  "} else {"!!"}, rep.frequency_hz, rep.damping_ratio, c.members.len(), c.upper_count, rep.cmi(), cmis[cmis.len()/2], rep.mpc, c.median_mpc, t, orders[0], orders[orders.len()-1]);
                    if std::env::var("MACS").is_ok() {
                        for d in st.selection.clusters.iter().filter(|d| {
                            d.physical
                                && (st.scan.poles[d.representative].frequency_hz - rep.frequency_hz)
                                    .abs()
                                    < 0.03 * rep.frequency_hz
                                && d.representative != c.representative
                        }) {
                            println!(
                                "      vs {:.4}: mac {:.3}",
                                st.scan.poles[d.representative].frequency_hz,
                                era::modal::indicators::mac(
                                    &rep.shape,
                                    &st.scan.poles[d.representative].shape
                                )
                            );
                        }
                    }
                }
            }
            if std::env::var("DEBUG").is_ok() {
                for i in (0..40).filter(|&i| !ti[i]) {
                    let f = structure.frequencies_hz[i];
                    let near: Vec<String> = st
                        .scan
                        .poles
                        .iter()
                        .enumerate()
                        .filter(|(_, p)| (p.frequency_hz - f).abs() < 0.005 * f)
                        .map(|(k, p)| {
                            let why = st
                                .selection
                                .rejected
                                .iter()
                                .find(|(r, _)| *r == k)
                                .map(|(_, w)| format!("{w}").chars().take(14).collect::<String>())
                                .unwrap_or_default();
                            format!(
                                "{}:{:.4}/{:.4}/m{:.2}/e{:.2}{}",
                                p.order,
                                p.frequency_hz,
                                p.damping_ratio,
                                p.mpc,
                                p.emac,
                                if why.is_empty() {
                                    String::new()
                                } else {
                                    format!("[{why}]")
                                }
                            )
                        })
                        .collect();
                    println!(
                        "  missed {f:.4} z {:.4}: {} poles: {}",
                        structure.damping_ratios[i],
                        near.len(),
                        near.join(" ")
                    );
                    for c in st
                        .selection
                        .clusters
                        .iter()
                        .filter(|c| (c.median_frequency_hz - f).abs() < 0.005 * f)
                    {
                        println!(
                            "    cluster f {:.4} members {} upper {} physical {}",
                            c.median_frequency_hz,
                            c.members.len(),
                            c.upper_count,
                            c.physical
                        );
                    }
                }
            }
            println!(
                "seed {seed} noise {noise}: found {}/40, spurious {} {:?}, missed {:?}, median df {:.1e}, dz {:.1e}, orders {}, {:.2} s (scan {:.2} s, factor {:.2} s, {:?} it), fit {:.3e}",
                ti.iter().filter(|t| **t).count(),
                spurious.len(),
                spurious,
                missed,
                ferr.get(ferr.len() / 2).copied().unwrap_or(f64::NAN),
                zerr.get(zerr.len() / 2).copied().unwrap_or(f64::NAN),
                st.range,
                seconds,
                st.seconds,
                st.factor_seconds,
                st.svd_iterations,
                found.fit.collocated_mean_relative_error.unwrap_or(f64::NAN),
            );
        }
    }
    Ok(())
}

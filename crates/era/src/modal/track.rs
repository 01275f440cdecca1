//! Modes followed over a fleet of records: the modes each record's identification found,
//! clustered into **tracks**, one per physical mode of the structure, so that a drift
//! with temperature or a drop after damage shows as a line over time.
//!
//! **Why not just sort by frequency.** Over months a monitored structure's frequencies
//! move by a few percent; some records miss a mode (too little excitation, a channel
//! missing) and two modes can cross in frequency. Matching "the k-th mode of each
//! record" or a fixed frequency band mixes modes up at every gap and crossing. Here the
//! shapes decide where the frequencies cannot.
//!
//! **How** ([`track`]), record by record in time order (ties and records without a time
//! by id, digit runs compared as numbers, so the result does not depend on the order
//! the records are given in):
//!
//! 1. Each *live track* has a reference: the mean frequency of its last
//!    [`TrackOptions::memory`] members (a running mean, so a slow drift is followed) and
//!    the shapes of those members.
//! 2. Each mode of the record (physical modes only unless [`TrackOptions::all_modes`])
//!    is compared with each track. The relative frequency distance `d = |f − f_ref| /
//!    (tol·f_ref)` (the gate widened to three standard deviations of the mode's frequency
//!    when that is larger) must be at most 1, and the MAC with the most recent member
//!    that shares at least two channels with the mode (the MAC is taken on the shared
//!    channels, matched by name, since records may miss channels) at least
//!    [`TrackOptions::mac_min`]. The cost of a pair is `½ d + ½ (1 − MAC)/(1 − mac_min)`,
//!    each half in `0 … ½`; with no shared channels the MAC half is ¼ (neither for nor
//!    against).
//! 3. The modes are assigned to tracks one to one at the least total cost (the Hungarian
//!    algorithm on the modes × candidate tracks matrix, pairs outside the gates
//!    forbidden). Two crossing modes have nearly equal frequency distances to both
//!    tracks; their shapes keep them apart. A mode left unassigned starts a new track.
//! 4. A track never closes: a mode missing from some records is picked up again when it
//!    returns (a gap is bridged), at the reference it had.
//!
//! Then each track gets its mean and standard deviation of frequency and damping, the
//! number of records it appears in, and a **trend**: the least-squares slope of its
//! frequency against time, relative to its mean frequency, per day when every record has
//! a time and per record (the record's position in the fleet) otherwise, with the
//! slope's standard error. Tracks seen in fewer than [`TrackOptions::min_records`]
//! records are flagged *sparse* (kept, so that nothing is hidden). Tracks are numbered
//! from 1 by mean frequency.
//!
//! The tracking is era's own: no crate we know of does mode tracking (ARTeMIS's SHM
//! plugin and OWI-Lab's clustering scripts, which show what monitoring users build, are
//! neither Rust nor libraries). The algorithm is the usual one of the automated
//! monitoring literature (frequency and MAC distances against a reference, as in
//! Magalhães, Cunha & Caetano 2009), with an optimal rather than greedy assignment.

use crate::error::{EraError, Result};
use crate::modal::indicators::mac;
use num_complex::Complex64;
use std::cmp::Ordering;

/// One mode of one record, as the record's identification gave it.
#[derive(Debug, Clone, PartialEq)]
pub struct TrackMode {
    /// Natural frequency, Hz.
    pub frequency_hz: f64,
    /// Damping ratio.
    pub damping_ratio: f64,
    /// Standard deviation of the frequency, Hz, when estimated.
    pub frequency_std_hz: Option<f64>,
    /// Standard deviation of the damping ratio, when estimated.
    pub damping_ratio_std: Option<f64>,
    /// Whether the identification called the mode physical.
    pub physical: bool,
    /// The shape, one entry per channel.
    pub shape: Vec<Complex64>,
    /// The channel of each shape entry (compared by name across records).
    pub channels: Vec<String>,
}

/// One record: its id, its time and its modes.
#[derive(Debug, Clone, PartialEq)]
pub struct TrackRecord {
    /// The record's id (unique in the fleet).
    pub id: String,
    /// The record's start, seconds from any fixed origin (Unix time, say).
    pub time_s: Option<f64>,
    /// Its modes.
    pub modes: Vec<TrackMode>,
}

/// The fewest records a track must appear in not to be sparse.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MinRecords {
    /// A number of records.
    Count(usize),
    /// A fraction of the fleet's records (0 < f ≤ 1), rounded up.
    Fraction(f64),
}

impl MinRecords {
    /// The count for a fleet of `records` records.
    pub fn count(self, records: usize) -> usize {
        match self {
            MinRecords::Count(n) => n,
            MinRecords::Fraction(f) => (f * records as f64 - 1e-9).ceil().max(1.0) as usize,
        }
    }
}

/// How to track.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct TrackOptions {
    /// Track every mode, not only the physical ones.
    pub all_modes: bool,
    /// Relative frequency gate: a mode joins a track only within this fraction of the
    /// track's reference frequency (or three of the mode's standard deviations, if
    /// wider). Default 0.05.
    pub frequency_tolerance: f64,
    /// Least MAC with the track's recent shape. Default 0.6.
    pub mac_min: f64,
    /// Tracks in fewer records are sparse. Default: half the records.
    pub min_records: MinRecords,
    /// Members the running reference (frequency mean, shapes) is taken over. Default 5.
    pub memory: usize,
}

impl Default for TrackOptions {
    fn default() -> Self {
        TrackOptions {
            all_modes: false,
            frequency_tolerance: 0.05,
            mac_min: 0.6,
            min_records: MinRecords::Fraction(0.5),
            memory: 5,
        }
    }
}

/// What a trend's slope is per.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TrendUnit {
    /// Per day (every record has a time).
    Day,
    /// Per record (the record's position in the fleet's time order).
    Record,
}

impl TrendUnit {
    /// `day` or `record`.
    pub fn name(self) -> &'static str {
        match self {
            TrendUnit::Day => "day",
            TrendUnit::Record => "record",
        }
    }
}

/// A least-squares line of a track's frequency.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Trend {
    /// Slope, Hz per unit.
    pub slope_hz: f64,
    /// Slope relative to the track's mean frequency, per unit (0.001 = 0.1 %).
    pub relative: f64,
    /// Standard error of `relative` (`None` with fewer than three points).
    pub relative_std_error: Option<f64>,
    /// Frequency of the line at abscissa 0, Hz.
    pub intercept_hz: f64,
}

/// One mode of one record in a track.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Member {
    /// The record's index in the input.
    pub record: usize,
    /// The mode's index in that record's modes.
    pub mode: usize,
    /// The track's id.
    pub track: usize,
    /// The MAC with the track's recent shape when the mode joined (`None` for the
    /// track's first member or no shared channels).
    pub mac_to_track: Option<f64>,
    /// The record's abscissa: days from the first record, or its position.
    pub x: f64,
}

/// One track.
#[derive(Debug, Clone, PartialEq)]
pub struct Track {
    /// 1-based, by mean frequency.
    pub id: usize,
    /// Records it appears in (one mode each).
    pub records: usize,
    /// Mean frequency, Hz.
    pub frequency_mean_hz: f64,
    /// Standard deviation of the frequency over the records, Hz (0 for one record).
    pub frequency_std_hz: f64,
    /// Mean damping ratio.
    pub damping_mean: f64,
    /// Standard deviation of the damping ratio over the records.
    pub damping_std: f64,
    /// The frequency's trend (`None` with fewer than two records at distinct abscissae).
    pub trend: Option<Trend>,
    /// Seen in fewer than the minimum records.
    pub sparse: bool,
}

/// The tracks of a fleet.
#[derive(Debug, Clone, PartialEq)]
pub struct Tracking {
    /// The tracks, by id (`tracks[k].id == k + 1`).
    pub tracks: Vec<Track>,
    /// Every tracked mode, in time order of its record, then by frequency.
    pub members: Vec<Member>,
    /// What the abscissae and trends are in.
    pub unit: TrendUnit,
    /// Time of the first record, s (the origin of the days), when there are times.
    pub origin_s: Option<f64>,
    /// The records' indices in time order.
    pub order: Vec<usize>,
    /// The minimum records of a non-sparse track, as counted.
    pub min_records: usize,
    /// The change in the fleet: where the non-sparse tracks' frequencies step together
    /// (`super::change::fleet_change`), its steps in the order of `tracks` (`None`
    /// for a sparse track); `None` when no split has enough records on each side.
    pub change: Option<super::change::Change>,
}

/// A pair outside the gates: larger than any sum of allowed costs.
const FORBIDDEN: f64 = 1.0e9;

/// A live track during the pass.
struct Live {
    /// `(frequency, record, mode)` of its members, oldest first.
    members: Vec<(f64, usize, usize)>,
}

/// `a` and `b` with runs of digits compared as numbers (`r2` before `r10`).
pub(crate) fn natural_order(a: &str, b: &str) -> Ordering {
    let (mut x, mut y) = (a.as_bytes(), b.as_bytes());
    loop {
        match (x.first(), y.first()) {
            (None, None) => return a.cmp(b),
            (None, _) => return Ordering::Less,
            (_, None) => return Ordering::Greater,
            (Some(p), Some(q)) if p.is_ascii_digit() && q.is_ascii_digit() => {
                let run = |s: &[u8]| s.iter().take_while(|c| c.is_ascii_digit()).count();
                let (m, n) = (run(x), run(y));
                let strip = |s: &[u8]| {
                    let k = s.iter().take_while(|c| **c == b'0').count();
                    s[k..].to_vec()
                };
                let (dx, dy) = (strip(&x[..m]), strip(&y[..n]));
                let c = dx.len().cmp(&dy.len()).then_with(|| dx.cmp(&dy));
                if c != Ordering::Equal {
                    return c;
                }
                x = &x[m..];
                y = &y[n..];
            }
            (Some(p), Some(q)) => {
                if p != q {
                    return p.cmp(q);
                }
                x = &x[1..];
                y = &y[1..];
            }
        }
    }
}

/// MAC of two shapes on the channels they share (by name); `None` with fewer than two.
pub(crate) fn shared_mac(a: &TrackMode, b: &TrackMode) -> Option<f64> {
    let mut x = Vec::new();
    let mut y = Vec::new();
    for (k, name) in a.channels.iter().enumerate() {
        if let Some(j) = b.channels.iter().position(|c| c == name) {
            if let (Some(&u), Some(&v)) = (a.shape.get(k), b.shape.get(j)) {
                x.push(u);
                y.push(v);
            }
        }
    }
    (x.len() >= 2).then(|| mac(&x, &y))
}

/// Minimum-cost assignment of each row to a distinct column (rows ≤ columns), by the
/// Hungarian algorithm with potentials (O(rows² · columns)): `out[i]` is row i's column.
fn assign_rows(cost: &[Vec<f64>]) -> Vec<usize> {
    let n = cost.len();
    let m = cost.first().map_or(0, Vec::len);
    debug_assert!(n <= m);
    let mut u = vec![0.0; n + 1];
    let mut v = vec![0.0; m + 1];
    let mut p = vec![0usize; m + 1];
    let mut way = vec![0usize; m + 1];
    for i in 1..=n {
        p[0] = i;
        let mut j0 = 0;
        let mut minv = vec![f64::INFINITY; m + 1];
        let mut used = vec![false; m + 1];
        loop {
            used[j0] = true;
            let i0 = p[j0];
            let mut delta = f64::INFINITY;
            let mut j1 = 0;
            for j in 1..=m {
                if !used[j] {
                    let cur = cost[i0 - 1][j - 1] - u[i0] - v[j];
                    if cur < minv[j] {
                        minv[j] = cur;
                        way[j] = j0;
                    }
                    if minv[j] < delta {
                        delta = minv[j];
                        j1 = j;
                    }
                }
            }
            for j in 0..=m {
                if used[j] {
                    u[p[j]] += delta;
                    v[j] -= delta;
                } else {
                    minv[j] -= delta;
                }
            }
            j0 = j1;
            if p[j0] == 0 {
                break;
            }
        }
        loop {
            let j1 = way[j0];
            p[j0] = p[j1];
            j0 = j1;
            if j0 == 0 {
                break;
            }
        }
    }
    let mut out = vec![0; n];
    for j in 1..=m {
        if p[j] != 0 {
            out[p[j] - 1] = j - 1;
        }
    }
    out
}

/// Minimum-cost one-to-one assignment of a rectangular matrix: `out[i]` is row i's
/// column, `None` for the rows left over when there are more rows than columns.
pub(crate) fn assign(cost: &[Vec<f64>]) -> Vec<Option<usize>> {
    let n = cost.len();
    let m = cost.first().map_or(0, Vec::len);
    if n == 0 || m == 0 {
        return vec![None; n];
    }
    if n <= m {
        return assign_rows(cost).into_iter().map(Some).collect();
    }
    let transposed: Vec<Vec<f64>> = (0..m)
        .map(|j| (0..n).map(|i| cost[i][j]).collect())
        .collect();
    let mut out = vec![None; n];
    for (j, i) in assign_rows(&transposed).into_iter().enumerate() {
        out[i] = Some(j);
    }
    out
}

fn check(records: &[TrackRecord], o: &TrackOptions) -> Result<()> {
    let bad = |name: &'static str, value: String, reason: &str| {
        Err(EraError::InvalidParameter {
            name,
            value,
            reason: reason.to_string().into(),
        })
    };
    if !(o.frequency_tolerance.is_finite()
        && o.frequency_tolerance > 0.0
        && o.frequency_tolerance < 1.0)
    {
        return bad(
            "frequency_tolerance",
            o.frequency_tolerance.to_string(),
            "must be a fraction between 0 and 1 (0.05 is 5 %)",
        );
    }
    if !(0.0..1.0).contains(&o.mac_min) {
        return bad(
            "mac_min",
            o.mac_min.to_string(),
            "must be from 0 to below 1",
        );
    }
    match o.min_records {
        MinRecords::Fraction(f) if !(f > 0.0 && f <= 1.0) => {
            return bad(
                "min_records",
                f.to_string(),
                "a fraction must be above 0 and at most 1",
            )
        }
        _ => {}
    }
    if o.memory == 0 {
        return bad("memory", "0".into(), "must be at least 1 member");
    }
    let mut ids: Vec<&str> = records.iter().map(|r| r.id.as_str()).collect();
    ids.sort_unstable();
    if let Some(w) = ids.windows(2).find(|w| w[0] == w[1]) {
        return bad("records", w[0].to_string(), "the record id is given twice");
    }
    for r in records {
        if r.time_s.is_some_and(|t| !t.is_finite()) {
            return bad("time", r.id.clone(), "the record's time is not finite");
        }
        for (k, m) in r.modes.iter().enumerate() {
            let finite = m.frequency_hz.is_finite() && m.damping_ratio.is_finite();
            if !(finite && m.frequency_hz > 0.0) || m.shape.len() != m.channels.len() {
                return bad(
                    "modes",
                    format!("{} mode {}", r.id, k + 1),
                    "needs a positive finite frequency, a finite damping ratio and one channel per shape entry",
                );
            }
        }
    }
    Ok(())
}

/// The records' indices in time order (then by id), and whether all have times.
fn time_order(records: &[TrackRecord]) -> (Vec<usize>, bool) {
    let timed = !records.is_empty() && records.iter().all(|r| r.time_s.is_some());
    let mut order: Vec<usize> = (0..records.len()).collect();
    order.sort_by(|&a, &b| {
        let (ra, rb) = (&records[a], &records[b]);
        let by_time = if timed {
            ra.time_s
                .unwrap_or(0.0)
                .total_cmp(&rb.time_s.unwrap_or(0.0))
        } else {
            Ordering::Equal
        };
        by_time.then_with(|| natural_order(&ra.id, &rb.id))
    });
    (order, timed)
}

/// The cost of `mode` joining `live` (`FORBIDDEN` outside the gates) and the MAC.
fn pair_cost(
    mode: &TrackMode,
    live: &Live,
    records: &[TrackRecord],
    o: &TrackOptions,
) -> (f64, Option<f64>) {
    let recent = &live.members[live.members.len().saturating_sub(o.memory)..];
    let reference = recent.iter().map(|m| m.0).sum::<f64>() / recent.len() as f64;
    let gate = (o.frequency_tolerance * reference).max(3.0 * mode.frequency_std_hz.unwrap_or(0.0));
    let d = (mode.frequency_hz - reference).abs() / gate;
    if d > 1.0 {
        return (FORBIDDEN, None);
    }
    let shape = recent
        .iter()
        .rev()
        .find_map(|&(_, r, k)| shared_mac(mode, &records[r].modes[k]));
    let shape_cost = match shape {
        Some(m) if m < o.mac_min => return (FORBIDDEN, Some(m)),
        Some(m) => 0.5 * (1.0 - m) / (1.0 - o.mac_min),
        None => 0.25,
    };
    (0.5 * d + shape_cost, shape)
}

/// Clusters the modes of `records` into tracks (see the module's text).
///
/// # Errors
/// [`EraError::InvalidParameter`] for options out of range, a record id given twice, a
/// non-finite time, or a mode without a positive finite frequency, a finite damping
/// ratio or one channel name per shape entry.
pub fn track(records: &[TrackRecord], options: &TrackOptions) -> Result<Tracking> {
    check(records, options)?;
    let (order, timed) = time_order(records);
    let origin_s = if timed {
        order.first().and_then(|&r| records[r].time_s)
    } else {
        None
    };
    let abscissa = |position: usize, r: usize| match (origin_s, records[r].time_s) {
        (Some(t0), Some(t)) => (t - t0) / 86_400.0,
        _ => position as f64,
    };
    let mut live: Vec<Live> = Vec::new();
    // (record, mode, live track, mac, x)
    let mut joined: Vec<(usize, usize, usize, Option<f64>, f64)> = Vec::new();
    for (position, &r) in order.iter().enumerate() {
        let mut modes: Vec<usize> = (0..records[r].modes.len())
            .filter(|&k| options.all_modes || records[r].modes[k].physical)
            .collect();
        modes.sort_by(|&a, &b| {
            let m = &records[r].modes;
            m[a].frequency_hz
                .total_cmp(&m[b].frequency_hz)
                .then(a.cmp(&b))
        });
        let x = abscissa(position, r);
        let pairs: Vec<Vec<(f64, Option<f64>)>> = modes
            .iter()
            .map(|&k| {
                live.iter()
                    .map(|t| pair_cost(&records[r].modes[k], t, records, options))
                    .collect()
            })
            .collect();
        // Only the tracks some mode may join take part.
        let candidates: Vec<usize> = (0..live.len())
            .filter(|&t| pairs.iter().any(|row| row[t].0 < FORBIDDEN))
            .collect();
        let cost: Vec<Vec<f64>> = pairs
            .iter()
            .map(|row| candidates.iter().map(|&t| row[t].0).collect())
            .collect();
        let chosen = assign(&cost);
        for (i, &k) in modes.iter().enumerate() {
            let f = records[r].modes[k].frequency_hz;
            match chosen[i].map(|c| candidates[c]) {
                Some(t) if pairs[i][t].0 < FORBIDDEN => {
                    live[t].members.push((f, r, k));
                    joined.push((r, k, t, pairs[i][t].1, x));
                }
                _ => {
                    live.push(Live {
                        members: vec![(f, r, k)],
                    });
                    joined.push((r, k, live.len() - 1, None, x));
                }
            }
        }
    }
    let min_records = options.min_records.count(records.len());
    Ok(summarize(
        records,
        &live,
        joined,
        (timed, origin_s, order, min_records),
    ))
}

/// Mean and sample standard deviation.
fn mean_std(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    if values.len() < 2 {
        return (mean, 0.0);
    }
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, var.sqrt())
}

/// The least-squares line of `y` against `x`, relative to `mean_y`.
pub fn trend(x: &[f64], y: &[f64], mean_y: f64) -> Option<Trend> {
    let n = x.len();
    if n < 2 || y.len() != n {
        return None;
    }
    let mx = x.iter().sum::<f64>() / n as f64;
    let my = y.iter().sum::<f64>() / n as f64;
    let sxx: f64 = x.iter().map(|v| (v - mx).powi(2)).sum();
    if sxx <= 0.0 || mean_y == 0.0 || !mean_y.is_finite() {
        return None;
    }
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let slope = sxy / sxx;
    let intercept = my - slope * mx;
    let error = (n > 2).then(|| {
        let ssr: f64 = x
            .iter()
            .zip(y)
            .map(|(a, b)| (b - intercept - slope * a).powi(2))
            .sum();
        (ssr / (n - 2) as f64 / sxx).sqrt() / mean_y.abs()
    });
    Some(Trend {
        slope_hz: slope,
        relative: slope / mean_y,
        relative_std_error: error,
        intercept_hz: intercept,
    })
}

/// The fleet's change over the non-sparse tracks; sparse tracks get no step.
fn fleet_change(
    tracks: &[Track],
    members: &[Member],
    records: &[TrackRecord],
    timed: bool,
) -> Option<super::change::Change> {
    let series: Vec<(Vec<f64>, Vec<f64>)> = tracks
        .iter()
        .filter(|t| !t.sparse)
        .map(|t| {
            members
                .iter()
                .filter(|m| m.track == t.id)
                .map(|m| (m.x, records[m.record].modes[m.mode].frequency_hz))
                .unzip()
        })
        .collect();
    let mut change = super::change::fleet_change(&series, timed)?;
    let mut steps = change.steps.into_iter();
    change.steps = tracks
        .iter()
        .map(|t| {
            if t.sparse {
                None
            } else {
                steps.next().flatten()
            }
        })
        .collect();
    Some(change)
}

/// The tracks' statistics and ids (by mean frequency) from the pass's results.
fn summarize(
    records: &[TrackRecord],
    live: &[Live],
    joined: Vec<(usize, usize, usize, Option<f64>, f64)>,
    (timed, origin_s, order, min_records): (bool, Option<f64>, Vec<usize>, usize),
) -> Tracking {
    let mut stats: Vec<Track> = Vec::with_capacity(live.len());
    for (t, _) in live.iter().enumerate() {
        let mine: Vec<&(usize, usize, usize, Option<f64>, f64)> =
            joined.iter().filter(|j| j.2 == t).collect();
        let f: Vec<f64> = mine
            .iter()
            .map(|j| records[j.0].modes[j.1].frequency_hz)
            .collect();
        let z: Vec<f64> = mine
            .iter()
            .map(|j| records[j.0].modes[j.1].damping_ratio)
            .collect();
        let x: Vec<f64> = mine.iter().map(|j| j.4).collect();
        let (fm, fs) = mean_std(&f);
        let (zm, zs) = mean_std(&z);
        stats.push(Track {
            id: 0,
            records: mine.len(),
            frequency_mean_hz: fm,
            frequency_std_hz: fs,
            damping_mean: zm,
            damping_std: zs,
            trend: trend(&x, &f, fm),
            sparse: mine.len() < min_records,
        });
    }
    // Ids by mean frequency (ties by creation order, which is deterministic).
    let mut by_frequency: Vec<usize> = (0..stats.len()).collect();
    by_frequency.sort_by(|&a, &b| {
        stats[a]
            .frequency_mean_hz
            .total_cmp(&stats[b].frequency_mean_hz)
            .then(a.cmp(&b))
    });
    let mut id_of = vec![0; stats.len()];
    for (k, &t) in by_frequency.iter().enumerate() {
        id_of[t] = k + 1;
    }
    let tracks: Vec<Track> = by_frequency
        .iter()
        .map(|&t| Track {
            id: id_of[t],
            ..stats[t].clone()
        })
        .collect();
    let members: Vec<Member> = joined
        .into_iter()
        .map(|(record, mode, t, mac_to_track, x)| Member {
            record,
            mode,
            track: id_of[t],
            mac_to_track,
            x,
        })
        .collect();
    let change = fleet_change(&tracks, &members, records, timed);
    Tracking {
        change,
        tracks,
        members,
        unit: if timed {
            TrendUnit::Day
        } else {
            TrendUnit::Record
        },
        origin_s,
        order,
        min_records,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn brute(cost: &[Vec<f64>]) -> f64 {
        fn go(cost: &[Vec<f64>], i: usize, used: &mut Vec<bool>) -> f64 {
            if i == cost.len() {
                return 0.0;
            }
            let mut best = f64::INFINITY;
            for j in 0..used.len() {
                if !used[j] {
                    used[j] = true;
                    best = best.min(cost[i][j] + go(cost, i + 1, used));
                    used[j] = false;
                }
            }
            best
        }
        go(cost, 0, &mut vec![false; cost[0].len()])
    }

    proptest! {
        #[test]
        fn the_assignment_is_optimal_and_one_to_one(
            rows in 1usize..5, cols in 1usize..6, seed in proptest::collection::vec(0.0f64..10.0, 30)
        ) {
            let cost: Vec<Vec<f64>> = (0..rows)
                .map(|i| (0..cols).map(|j| seed[(i * cols + j) % 30] + (i * j) as f64 * 0.01).collect())
                .collect();
            let out = assign(&cost);
            let used: Vec<usize> = out.iter().flatten().copied().collect();
            let mut unique = used.clone();
            unique.sort_unstable();
            unique.dedup();
            prop_assert_eq!(unique.len(), used.len());
            prop_assert_eq!(used.len(), rows.min(cols));
            if rows <= cols {
                let total: f64 = out.iter().enumerate().map(|(i, j)| cost[i][j.unwrap()]).sum();
                prop_assert!((total - brute(&cost)).abs() < 1e-9, "{} vs {}", total, brute(&cost));
            }
        }
    }

    #[test]
    fn ids_in_natural_order() {
        let mut ids = vec!["r10", "r2", "r1", "r02x", "a"];
        ids.sort_by(|a, b| natural_order(a, b));
        assert_eq!(ids, vec!["a", "r1", "r2", "r02x", "r10"]);
        assert_eq!(natural_order("r2", "r02"), "r2".cmp("r02"));
    }

    #[test]
    fn a_line_has_its_slope_and_no_error() {
        let x = [0.0, 1.0, 2.0, 3.0];
        let y: Vec<f64> = x.iter().map(|v| 10.0 - 0.1 * v).collect();
        let t = trend(&x, &y, 10.0).unwrap();
        assert!((t.slope_hz + 0.1).abs() < 1e-12 && (t.relative + 0.01).abs() < 1e-12);
        assert!(t.relative_std_error.unwrap() < 1e-12);
        assert!(trend(&[1.0, 1.0], &[2.0, 3.0], 2.5).is_none());
    }

    #[test]
    fn min_records_counts() {
        assert_eq!(MinRecords::Fraction(0.5).count(12), 6);
        assert_eq!(MinRecords::Fraction(0.5).count(13), 7);
        assert_eq!(MinRecords::Fraction(1.0).count(12), 12);
        assert_eq!(MinRecords::Count(3).count(12), 3);
    }
}

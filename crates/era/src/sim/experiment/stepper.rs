//! One run of the experiment as a sequence of small steps. At each grid point (an
//! excitation knot or an LVT sample, whichever comes first) the run samples the
//! compensator, sets the inputs `f = f₀ + f₁τ` up to the next grid point, frees or stops
//! the masses whose forces say so, records the analyzer's sample and the probes; it then
//! advances to the next grid point event by event ([`super::events`]).

use super::{
    Actuator, CompensatorTrace, Config, EventCounts, ExperimentSpec, Mode, RunOptions, RunOutput,
    RunRecord, SharedConfigs, StepCoeffs, System, GRAZING_SPEED, KNOTS_PER_SAMPLE,
};
use crate::error::{EraError, Result};
use crate::friction::compensator::{ChannelConfig, FrictionCompensator};
use crate::linalg::rng::Minstd;
use num_complex::Complex64;
use std::collections::HashMap;
use std::f64::consts::PI;
use std::sync::Arc;

/// FIR low-pass, windowed sinc (Blackman), `taps` odd, cutoff `fc/fs`.
fn lowpass(taps: usize, cutoff: f64) -> Vec<f64> {
    let mid = (taps / 2) as f64;
    let mut h: Vec<f64> = (0..taps)
        .map(|k| {
            let x = k as f64 - mid;
            let sinc = if x == 0.0 {
                2.0 * cutoff
            } else {
                (2.0 * PI * cutoff * x).sin() / (PI * x)
            };
            let t = k as f64 / (taps - 1) as f64;
            let w = 0.42 - 0.5 * (2.0 * PI * t).cos() + 0.08 * (4.0 * PI * t).cos();
            sinc * w
        })
        .collect();
    let dc: f64 = h.iter().sum();
    h.iter_mut().for_each(|v| *v /= dc);
    h
}

/// Band-limited Gaussian noise of RMS `rms` (in theory), `n` samples at `fs`.
fn band_noise(rng: &mut Minstd, n: usize, fs: f64, band_hz: f64, rms: f64) -> Vec<f64> {
    let taps = 129;
    // The cutoff sits a little above the band so the band edge is flat.
    let h = lowpass(taps, (band_hz * 1.08 / fs).min(0.49));
    let gain = h.iter().map(|x| x * x).sum::<f64>().sqrt();
    let white: Vec<f64> = (0..n + taps).map(|_| rng.normal()).collect();
    (0..n)
        .map(|k| {
            let s: f64 = h.iter().zip(&white[k..k + taps]).map(|(a, b)| a * b).sum();
            s * rms / gain
        })
        .collect()
}

/// The run's time base, in ticks of the common grid.
pub(super) struct Grid {
    pub ticks_per_knot: usize,
    pub ticks_per_lvt: usize,
    /// Excitation samples per second.
    pub knot_rate: f64,
    /// One tick, s.
    pub tick: f64,
    /// Analyzer samples recorded.
    pub samples: usize,
    /// Ticks before the first recorded sample.
    pub settle_ticks: usize,
    pub total_knots: usize,
    pub total_ticks: usize,
}

impl Grid {
    fn new(spec: &ExperimentSpec) -> Result<Self> {
        let (_tick_rate, ticks_per_knot, ticks_per_lvt) = spec.grid()?;
        let knot_rate = KNOTS_PER_SAMPLE as f64 * spec.analyzer_rate_hz;
        let samples = spec.averages * spec.frame;
        let settle_knots = (spec.settle_s * knot_rate).ceil() as usize;
        let total_knots = settle_knots + samples * KNOTS_PER_SAMPLE;
        Ok(Grid {
            ticks_per_knot,
            ticks_per_lvt,
            knot_rate,
            tick: 1.0 / (knot_rate * ticks_per_knot as f64),
            samples,
            settle_ticks: settle_knots * ticks_per_knot,
            total_knots,
            total_ticks: total_knots * ticks_per_knot,
        })
    }

    /// The grid point after `t`: the next excitation knot or LVT sample.
    fn next_point(&self, t: usize) -> usize {
        let knot_end = (t / self.ticks_per_knot + 1) * self.ticks_per_knot;
        let lvt_end = (t / self.ticks_per_lvt + 1) * self.ticks_per_lvt;
        knot_end.min(lvt_end)
    }

    /// Whether the analyzer samples at tick `t`.
    fn is_sample(&self, t: usize) -> bool {
        t >= self.settle_ticks
            && (t - self.settle_ticks).is_multiple_of(self.ticks_per_knot * KNOTS_PER_SAMPLE)
    }
}

/// The physical state outside the modal coordinates: structure states, and every
/// actuator's stroke and relative velocity.
pub(super) struct Physical {
    pub xs: Vec<f64>,
    pub z: Vec<f64>,
    pub zd: Vec<f64>,
}

/// A run in progress: its inputs, its mechanical state and what it has recorded.
pub(super) struct Stepper<'a> {
    pub spec: &'a ExperimentSpec,
    pub sys: &'a System,
    shared: &'a SharedConfigs,
    pub grid: Grid,
    /// Actuators.
    pub a: usize,
    /// Structure states.
    pub ns: usize,
    /// Excitation voltages at the knots per actuator (empty when not excited).
    voltage_knots: Vec<Vec<f64>>,
    gains: Vec<f64>,
    /// Coulomb forces.
    pub fc: Vec<f64>,
    pub any_friction: bool,
    compensator: Option<FrictionCompensator>,
    noise_rng: Minstd,
    lvt_rng: Minstd,
    /// Whether the compensator's samples are traced.
    keep_trace: bool,
    probe_times_s: Vec<f64>,
    next_probe: usize,
    pub modes: Vec<Mode>,
    /// The stuck set, one bit per actuator.
    pub mask: u64,
    configs: HashMap<u64, Arc<Config>>,
    pub steps: HashMap<(u64, usize), StepCoeffs>,
    pub phys: Physical,
    /// Modal coordinates in the current configuration.
    pub xi: Vec<Complex64>,
    /// The compensator's output, held until its next sample.
    comp_v: Vec<f64>,
    /// Inputs over the current interval, `f₀ + f₁τ`.
    pub f0: Vec<f64>,
    pub f1: Vec<f64>,
    /// `w f₀`, `w f₁` and the state at the end of the step, reused.
    pub b0: Vec<Complex64>,
    pub b1: Vec<Complex64>,
    pub next: Vec<Complex64>,
    pub record: RunRecord,
    trace: CompensatorTrace,
    probes: Vec<Vec<(f64, f64)>>,
    /// The current grid point.
    pub t_ticks: usize,
}

/// The stuck set of `modes`, one bit per actuator.
pub(super) fn mask_of(modes: &[Mode]) -> u64 {
    modes
        .iter()
        .enumerate()
        .filter(|(_, m)| matches!(m, Mode::Stuck { .. }))
        .fold(0u64, |acc, (j, _)| acc | 1 << j)
}

/// One run: the actuators in `excited` driven, everything recorded; `run` selects the
/// random streams. Configurations are shared with the other runs through `shared`.
pub(super) fn simulate_run_shared(
    spec: &ExperimentSpec,
    sys: &System,
    shared: &SharedConfigs,
    excited: &[usize],
    run: u64,
    opts: RunOptions,
) -> Result<RunOutput> {
    let mut s = Stepper::new(spec, sys, shared, excited, run, opts)?;
    while s.t_ticks <= s.grid.total_ticks {
        s.sample_compensator()?;
        let t_next = s.grid.next_point(s.t_ticks);
        s.set_inputs();
        s.release()?;
        s.record_sample();
        s.record_probes();
        if s.t_ticks == s.grid.total_ticks {
            break;
        }
        s.advance_to(t_next)?;
        if s.xi.iter().any(|v| !(v.re.is_finite() && v.im.is_finite())) {
            return Err(EraError::Numerical(format!(
                "the simulation diverged at t = {:.3} s",
                s.t_ticks as f64 * s.grid.tick
            )));
        }
        s.t_ticks = t_next;
    }
    Ok(RunOutput {
        record: s.record,
        compensator: s.trace,
        probes: s.probes,
    })
}

/// Every mass at rest: stuck where it is released when there is friction or a stroke,
/// else sliding.
fn initial_modes(init: &[f64], any_friction: bool) -> Vec<Mode> {
    init.iter()
        .map(|&z| {
            if any_friction || z != 0.0 {
                Mode::Stuck { z, stop: 0.0 }
            } else {
                Mode::Sliding(1.0)
            }
        })
        .collect()
}

/// The compensator of `spec`, one channel per actuator, if there is one.
fn compensator(spec: &ExperimentSpec) -> Result<Option<FrictionCompensator>> {
    let Some(c) = &spec.compensation else {
        return Ok(None);
    };
    FrictionCompensator::new(
        c.coefficients
            .iter()
            .zip(&spec.actuators)
            .map(|(&coef, act)| ChannelConfig {
                coefficient: coef,
                dead_zone: c.dead_zone,
                fraction: c.fraction,
                gain: 1.0 / act.motor_force_per_volt,
                output_min: f64::NEG_INFINITY,
                output_max: f64::INFINITY,
            })
            .collect(),
    )
    .map(Some)
    .map_err(|e| EraError::InvalidParameter {
        name: "compensation",
        value: String::new(),
        reason: e.to_string().into(),
    })
}

impl<'a> Stepper<'a> {
    /// The run at rest before its first grid point: the excitation drawn, every mass
    /// stuck where it is released (the first grid point frees those the forces move).
    fn new(
        spec: &'a ExperimentSpec,
        sys: &'a System,
        shared: &'a SharedConfigs,
        excited: &[usize],
        run: u64,
        opts: RunOptions,
    ) -> Result<Self> {
        let a = spec.actuators.len();
        let q = spec.structure.sensors();
        let grid = Grid::new(spec)?;
        let stream = |k: u64| {
            spec.seed
                .wrapping_mul(1_000_003)
                .wrapping_add(run.wrapping_mul(7919))
                .wrapping_add(k)
        };
        let voltage_knots = excite(spec, &grid, excited, Minstd::new(stream(1)));
        let compensator = compensator(spec)?;
        let fc: Vec<f64> = spec.actuators.iter().map(|x| x.coulomb_force).collect();
        let any_friction = fc.iter().any(|&f| f > 0.0);
        // Initial state: at rest; masses released at their initial strokes.
        let init = opts.initial_stroke.clone().unwrap_or_else(|| vec![0.0; a]);
        let modes = initial_modes(&init[..a], any_friction);
        let samples = grid.samples;
        let mut s = Stepper {
            spec,
            sys,
            shared,
            a,
            ns: sys.n_s(),
            voltage_knots,
            gains: spec
                .actuators
                .iter()
                .map(|x| x.motor_force_per_volt)
                .collect(),
            fc,
            any_friction,
            compensator,
            noise_rng: Minstd::new(stream(2)),
            lvt_rng: Minstd::new(stream(3)),
            keep_trace: opts.initial_stroke.is_some() || !opts.probe_times_s.is_empty(),
            probe_times_s: opts.probe_times_s,
            next_probe: 0,
            mask: mask_of(&modes),
            modes,
            configs: HashMap::new(),
            steps: HashMap::new(),
            phys: Physical {
                xs: vec![0.0; sys.n_s()],
                z: init,
                zd: vec![0.0; a],
            },
            xi: Vec::new(),
            comp_v: vec![0.0; a],
            f0: vec![0.0; a],
            f1: vec![0.0; a],
            b0: Vec::new(),
            b1: Vec::new(),
            next: Vec::new(),
            record: RunRecord::empty(excited, a, q, samples),
            trace: CompensatorTrace::default(),
            probes: Vec::new(),
            grid,
            t_ticks: 0,
        };
        s.enter(s.mask)?;
        Ok(s)
    }

    /// The configuration of stuck set `mask`, diagonalised once per experiment.
    pub(super) fn config(&mut self, mask: u64) -> Result<Arc<Config>> {
        if let Some(c) = self.configs.get(&mask) {
            return Ok(c.clone());
        }
        let found = self
            .shared
            .lock()
            .map(|m| m.get(&mask).cloned())
            .unwrap_or(None);
        let cfg = match found {
            Some(c) => c,
            None => {
                let c = Arc::new(Config::new(self.sys, mask)?);
                if let Ok(mut m) = self.shared.lock() {
                    m.entry(mask).or_insert_with(|| c.clone());
                }
                c
            }
        };
        self.configs.insert(mask, cfg.clone());
        Ok(cfg)
    }

    /// The current configuration.
    pub(super) fn current(&self) -> Arc<Config> {
        self.configs
            .get(&self.mask)
            .expect("config present")
            .clone()
    }

    /// The dynamic state of `cfg` from the physical state.
    pub(super) fn pack(&self, cfg: &Config) -> Vec<f64> {
        let mut x = self.phys.xs.clone();
        x.resize(cfg.n(), 0.0);
        for j in 0..self.a {
            if let Some(k) = cfg.slot[j] {
                x[self.ns + k] = self.phys.z[j];
                x[self.ns + cfg.nf + k] = self.phys.zd[j];
            }
        }
        x
    }

    /// Enters the configuration `mask` from the physical state.
    pub(super) fn enter(&mut self, mask: u64) -> Result<()> {
        self.mask = mask;
        let cfg = self.config(mask)?;
        self.xi = cfg.modal_of(&self.pack(&cfg));
        Ok(())
    }

    /// Sets the physical state from modal coordinates `xi` of the current configuration.
    pub(super) fn unpack_from(&mut self, cfg: &Config, xi: &[Complex64]) {
        let x = cfg.full_state(xi);
        let (xs, z, zd) = unpack(cfg, &x, &self.modes, &self.phys.z, self.ns, self.a);
        self.phys = Physical { xs, z, zd };
    }

    /// Voltage and slope (V/s) of the excitation of `j` at tick `t` (+ `frac` s).
    fn volt_at(&self, j: usize, t: usize, frac: f64) -> (f64, f64) {
        let v = &self.voltage_knots[j];
        if v.is_empty() {
            return (0.0, 0.0);
        }
        let k = t / self.grid.ticks_per_knot;
        let within = (t % self.grid.ticks_per_knot) as f64 * self.grid.tick + frac;
        let k1 = (k + 1).min(v.len() - 1);
        let slope = (v[k1] - v[k]) * self.grid.knot_rate;
        (v[k] + slope * within, slope)
    }

    /// Motor force of `j` and its slope at tick `t`: excitation plus compensation.
    fn motor(&self, j: usize, t: usize, frac: f64) -> (f64, f64) {
        let (v, s) = self.volt_at(j, t, frac);
        (self.gains[j] * (v + self.comp_v[j]), self.gains[j] * s)
    }

    /// The force that holds stuck mass `j` at `z` (motor force `motor`), under state `xi`
    /// and inputs `f` of `cfg`.
    pub(super) fn stick_force(
        &self,
        cfg: &Config,
        xi: &[Complex64],
        f: &[f64],
        j: usize,
        z: f64,
        motor: f64,
    ) -> f64 {
        let m = self.sys.mass[j];
        m * Config::row_value(&cfg.mount_x, &cfg.mount_f, j, xi, f) + self.sys.act[j].stiffness * z
            - motor
    }

    /// At an LVT sample: the compensator reads the velocities (with noise) and sets its
    /// output.
    fn sample_compensator(&mut self) -> Result<()> {
        if !self.t_ticks.is_multiple_of(self.grid.ticks_per_lvt) {
            return Ok(());
        }
        let cfg = self.current();
        let ns = self.ns;
        let noise = self.spec.lvt_noise_rms;
        let rng = &mut self.lvt_rng;
        let read: Vec<f64> = cfg
            .slot
            .iter()
            .map(|slot| {
                let v = slot.map_or(0.0, |k| cfg.state(&self.xi, ns + cfg.nf + k));
                v + noise * rng.normal()
            })
            .collect();
        if let Some(c) = &self.compensator {
            c.step(&read, &mut self.comp_v)
                .map_err(|e| EraError::Numerical(e.to_string()))?;
            if self.keep_trace {
                self.trace.time_s.push(self.t_ticks as f64 * self.grid.tick);
                self.trace.velocity.push(read.clone());
                self.trace.output_v.push(self.comp_v.clone());
            }
        }
        Ok(())
    }

    /// Inputs from here to the next grid point: motor force and friction.
    fn set_inputs(&mut self) {
        for j in 0..self.a {
            let (fm, fs) = self.motor(j, self.t_ticks, 0.0);
            let fric = match self.modes[j] {
                Mode::Sliding(s) => -self.fc[j] * s,
                Mode::Stuck { .. } => 0.0,
            };
            self.f0[j] = fm + fric;
            self.f1[j] = fs;
        }
    }

    /// Stops the sliding masses whose velocity has the wrong sign and frees the stuck
    /// ones whose holding force exceeds `F_C` right now (start, release), one at a time
    /// until none is left.
    fn release(&mut self) -> Result<()> {
        loop {
            let cfg = self.current();
            if let Some(j) = self.wrong_way(&cfg) {
                self.stop_wrong_way(&cfg, j)?;
                continue;
            }
            let Some((j, dir)) = self.breaking_away(&cfg) else {
                return Ok(());
            };
            self.unpack_from(&cfg, &self.xi.clone());
            self.phys.zd[j] = 0.0;
            self.modes[j] = Mode::Sliding(dir);
            self.f0[j] += -self.fc[j] * dir;
            self.enter(mask_of(&self.modes))?;
            if self.any_friction {
                self.record.counts.breakaways += 1;
            }
        }
    }

    /// A sliding mass whose velocity has the wrong sign (a grazing stop missed within
    /// the last step).
    fn wrong_way(&self, cfg: &Config) -> Option<usize> {
        (0..self.a).find(|&j| match (self.modes[j], cfg.slot[j]) {
            (Mode::Sliding(s), Some(k)) => {
                self.fc[j] > 0.0 && s * cfg.state(&self.xi, self.ns + cfg.nf + k) < -GRAZING_SPEED
            }
            _ => false,
        })
    }

    /// Stops sliding mass `j`; [`Stepper::release`] frees it again if the forces move it,
    /// in their direction.
    fn stop_wrong_way(&mut self, cfg: &Config, j: usize) -> Result<()> {
        self.unpack_from(cfg, &self.xi.clone());
        self.phys.zd[j] = 0.0;
        let Mode::Sliding(s) = self.modes[j] else {
            unreachable!()
        };
        self.f0[j] += self.fc[j] * s;
        self.modes[j] = Mode::Stuck {
            z: self.phys.z[j],
            stop: 0.0,
        };
        self.enter(mask_of(&self.modes))?;
        self.record.counts.sticks += 1;
        Ok(())
    }

    /// The first stuck mass whose holding force exceeds `F_C` (unless it pushes into
    /// the end stop it rests on), with the direction it slides in.
    fn breaking_away(&self, cfg: &Config) -> Option<(usize, f64)> {
        for j in 0..self.a {
            if let Mode::Stuck { z, stop } = self.modes[j] {
                let (fm, _) = self.motor(j, self.t_ticks, 0.0);
                let ff = self.stick_force(cfg, &self.xi, &self.f0, j, z, fm);
                let dir = -ff.signum();
                if ff.abs() > self.fc[j] && !(stop != 0.0 && dir == stop) {
                    return Some((j, dir));
                }
            }
        }
        None
    }

    /// At an analyzer sample (after the settling time): voltages, compensation,
    /// strokes, velocities, and the accelerations with noise.
    fn record_sample(&mut self) {
        if !(self.grid.is_sample(self.t_ticks)
            && self.record.acceleration[0].len() < self.grid.samples)
        {
            return;
        }
        let cfg = self.current();
        for j in 0..self.a {
            let (v, _) = self.volt_at(j, self.t_ticks, 0.0);
            self.record.voltage[j].push(v);
            self.record.compensation_v[j].push(self.comp_v[j]);
            let (z, zd) = self.stroke_and_velocity(&cfg, j);
            self.record.stroke[j].push(z);
            self.record.relative_velocity[j].push(zd);
        }
        for i in 0..self.record.acceleration.len() {
            let acc = Config::row_value(&cfg.acc_x, &cfg.acc_f, i, &self.xi, &self.f0);
            self.record.acceleration[i]
                .push(acc + self.spec.accel_noise_rms * self.noise_rng.normal());
        }
    }

    /// `(z_j, ż_j)` now.
    fn stroke_and_velocity(&self, cfg: &Config, j: usize) -> (f64, f64) {
        match (self.modes[j], cfg.slot[j]) {
            (_, Some(k)) => (
                cfg.state(&self.xi, self.ns + k),
                cfg.state(&self.xi, self.ns + cfg.nf + k),
            ),
            (Mode::Stuck { z, .. }, None) => (z, 0.0),
            _ => (0.0, 0.0),
        }
    }

    /// Every actuator's `(z, ż)` for the probe times reached.
    fn record_probes(&mut self) {
        let cfg = self.current();
        while let Some(&pt) = self.probe_times_s.get(self.next_probe) {
            if pt <= self.t_ticks as f64 * self.grid.tick + 1e-12 {
                self.next_probe += 1;
                let probe = (0..self.a)
                    .map(|j| self.stroke_and_velocity(&cfg, j))
                    .collect();
                self.probes.push(probe);
            } else {
                break;
            }
        }
    }

    /// The actuator of index `j`.
    pub(super) fn actuator(&self, j: usize) -> Actuator {
        self.spec.actuators[j]
    }
}

impl RunRecord {
    /// A record of `a` actuators and `q` sensors, with room for `samples` samples.
    fn empty(excited: &[usize], a: usize, q: usize, samples: usize) -> Self {
        RunRecord {
            excited: excited.to_vec(),
            voltage: vec![Vec::with_capacity(samples); a],
            acceleration: vec![Vec::with_capacity(samples); q],
            stroke: vec![Vec::with_capacity(samples); a],
            relative_velocity: vec![Vec::with_capacity(samples); a],
            compensation_v: vec![Vec::with_capacity(samples); a],
            counts: EventCounts::default(),
        }
    }
}

/// The excitation voltages at the knots (one extra for the last interval), for the
/// actuators in `excited`, drawn from `rng` in their order.
fn excite(spec: &ExperimentSpec, grid: &Grid, excited: &[usize], mut rng: Minstd) -> Vec<Vec<f64>> {
    let mut voltage_knots = vec![Vec::new(); spec.actuators.len()];
    for &j in excited {
        voltage_knots[j] = band_noise(
            &mut rng,
            grid.total_knots + 1,
            grid.knot_rate,
            spec.band_hz,
            spec.excitation_rms_v,
        );
    }
    voltage_knots
}

/// Splits a dynamic state into structure states, strokes and velocities of all
/// actuators (stuck ones from their mode).
pub(super) fn unpack(
    cfg: &Config,
    x: &[f64],
    modes: &[Mode],
    old_z: &[f64],
    ns: usize,
    a: usize,
) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let xs = x[..ns].to_vec();
    let mut z = old_z.to_vec();
    let mut zd = vec![0.0; a];
    for j in 0..a {
        match (cfg.slot[j], modes[j]) {
            (Some(k), _) => {
                z[j] = x[ns + k];
                zd[j] = x[ns + cfg.nf + k];
            }
            (None, Mode::Stuck { z: zs, .. }) => z[j] = zs,
            _ => {}
        }
    }
    (xs, z, zd)
}

//! From one grid point to the next, event by event: the exact modal step, the event
//! functions `g(τ) = Re Σ r_k ξ_k(τ) + d·f(τ) + c₀` (positive while nothing happens),
//! the earliest crossing by safeguarded Newton in a sign-change bracket, and what each
//! event does (stick or reverse, end-stop impact, break-away).

use super::stepper::{mask_of, unpack, Stepper};
use super::{phi_coeffs, Config, ExperimentSpec, Mode, MAX_EVENTS_PER_STEP, REST_SPEED};
use crate::error::{EraError, Result};
use num_complex::Complex64;

/// What happens to an actuator: its velocity reaches zero (kind 0), it reaches an end
/// stop (1), or its holding force reaches `F_C` (2).
type Event = (usize, u8);

/// Where an event function changes sign within the step.
enum Crossing {
    /// No positive value just after the actuator's last event: it grazes.
    Grazing,
    /// Not before `cap`.
    Beyond,
    /// The crossing's upper bracket end.
    At(f64),
}

/// What the step from the current point has reached so far.
struct Interval {
    /// Time left to the next grid point, s.
    remaining: f64,
    /// Time since the grid point, s.
    elapsed: f64,
    /// Ticks of the whole step while no event has shortened it (its step coefficients
    /// are cached).
    full_step: Option<usize>,
    /// Actuators whose event function has no positive value just after their last
    /// event (a grazing contact): left as they are until the next grid point.
    grazing: u64,
}

impl Stepper<'_> {
    /// Advances from the current grid point to `t_next`, event by event.
    pub(super) fn advance_to(&mut self, t_next: usize) -> Result<()> {
        let mut step = Interval {
            remaining: (t_next - self.t_ticks) as f64 * self.grid.tick,
            elapsed: 0.0,
            full_step: Some(t_next - self.t_ticks),
            grazing: 0,
        };
        let mut events_this_step = 0;
        loop {
            let cfg = self.current();
            self.step_to_end(&cfg, &step);
            if !self.any_friction && self.spec.actuators.iter().all(|x| x.stroke.is_infinite()) {
                std::mem::swap(&mut self.xi, &mut self.next);
                return Ok(());
            }
            let fend: Vec<f64> = self
                .f0
                .iter()
                .zip(&self.f1)
                .map(|(x, s)| x + s * step.remaining)
                .collect();
            let candidates = self.candidates(&cfg, &fend, step.grazing);
            if candidates.is_empty() {
                std::mem::swap(&mut self.xi, &mut self.next);
                return Ok(());
            }
            events_this_step += 1;
            if events_this_step > MAX_EVENTS_PER_STEP {
                return Err(EraError::Numerical(format!(
                    "stick-slip events did not resolve near t = {:.6} s",
                    self.t_ticks as f64 * self.grid.tick + step.elapsed
                )));
            }
            let Some((tau, event)) = self.earliest(&cfg, &candidates, &fend, &mut step) else {
                // Every candidate grazes, or its crossing lies beyond the step (end-point
                // roundoff): the step stands.
                std::mem::swap(&mut self.xi, &mut self.next);
                return Ok(());
            };
            self.advance_to_event(&cfg, tau, event, &mut step)?;
            if step.remaining <= 0.0 {
                return Ok(());
            }
        }
    }

    /// `next`: the state at the end of the step, from `xi` under the current inputs.
    fn step_to_end(&mut self, cfg: &Config, step: &Interval) {
        let mm = cfg.m();
        if self.b0.len() != mm {
            self.b0.resize(mm, Complex64::new(0.0, 0.0));
            self.b1.resize(mm, Complex64::new(0.0, 0.0));
            self.next.resize(mm, Complex64::new(0.0, 0.0));
        }
        cfg.input(&self.f0, &mut self.b0);
        cfg.input(&self.f1, &mut self.b1);
        let mask = self.mask;
        let remaining = step.remaining;
        let coeffs = step.full_step.map(|t| {
            &*self
                .steps
                .entry((mask, t))
                .or_insert_with(|| cfg.step_coeffs(remaining))
        });
        cfg.advance_into(
            &self.xi,
            &self.b0,
            &self.b1,
            remaining,
            coeffs,
            &mut self.next,
        );
    }

    /// Event function `kind` of actuator `j` at state `xi_t` under inputs `f_t`, positive
    /// while nothing happens.
    fn event_value(&self, cfg: &Config, xi_t: &[Complex64], f_t: &[f64], (j, kind): Event) -> f64 {
        let ns = self.ns;
        match (kind, self.modes[j], cfg.slot[j]) {
            (0, Mode::Sliding(s), Some(k)) => s * cfg.state(xi_t, ns + cfg.nf + k),
            (1, Mode::Sliding(_), Some(k)) => {
                self.spec.actuators[j].stroke - cfg.state(xi_t, ns + k).abs()
            }
            (2, Mode::Stuck { z, stop }, None) => {
                // f_t[j] holds the motor force of a stuck actuator.
                let ff = self.stick_force(cfg, xi_t, f_t, j, z, f_t[j]);
                let dir = -ff.signum();
                if stop != 0.0 && dir == stop {
                    1.0
                } else {
                    self.fc[j] - ff.abs()
                }
            }
            _ => 1.0,
        }
    }

    /// The events whose function is negative at the end of the step.
    fn candidates(&self, cfg: &Config, fend: &[f64], grazing: u64) -> Vec<Event> {
        let mut candidates = Vec::new();
        for j in 0..self.a {
            if grazing >> j & 1 == 1 {
                continue;
            }
            for kind in 0..3u8 {
                if kind == 0 && self.fc[j] == 0.0 {
                    continue;
                }
                if kind == 1 && self.spec.actuators[j].stroke.is_infinite() {
                    continue;
                }
                if self.event_value(cfg, &self.next, fend, (j, kind)) < 0.0 {
                    candidates.push((j, kind));
                }
            }
        }
        candidates
    }

    /// The earliest crossing among `candidates`, marking those that graze in `step`.
    fn earliest(
        &self,
        cfg: &Config,
        candidates: &[Event],
        fend: &[f64],
        step: &mut Interval,
    ) -> Option<(f64, Event)> {
        let mut best: Option<(f64, Event)> = None;
        for &event in candidates {
            let cap = best.map_or(step.remaining, |b| b.0);
            match self.crossing(cfg, event, fend, step.remaining, cap) {
                Crossing::Grazing => step.grazing |= 1 << event.0,
                Crossing::Beyond => {}
                Crossing::At(hi) => {
                    if hi <= cap {
                        best = Some((hi, event));
                    }
                }
            }
        }
        best
    }

    /// Where `event`'s function crosses zero before `cap`: safeguarded Newton in a
    /// sign-change bracket.
    fn crossing(
        &self,
        cfg: &Config,
        (j, kind): Event,
        fend: &[f64],
        remaining: f64,
        cap: f64,
    ) -> Crossing {
        let (r, d, c0) = event_row(
            cfg,
            &self.modes,
            &self.next,
            fend,
            j,
            kind,
            self.spec,
            &self.sys.mass,
            &self.fc,
            self.ns,
        );
        let g = EventFunction::new(cfg, self, &r, &d, c0);
        let mut lo = 0.0;
        let (mut g_lo, _) = g.at(0.0);
        if g_lo <= 0.0 {
            // Just after an event at this actuator: find where it is positive.
            let mut found = false;
            for p in (1..=30).rev() {
                let tau = remaining * 0.5f64.powi(p);
                if tau >= cap {
                    break;
                }
                let (gv, _) = g.at(tau);
                if gv > 0.0 {
                    lo = tau;
                    g_lo = gv;
                    found = true;
                    break;
                }
            }
            if !found {
                return Crossing::Grazing;
            }
        }
        let hi = cap;
        let (g_hi, _) = g.at(hi);
        if g_hi > 0.0 {
            return Crossing::Beyond; // crosses after the best so far (or not at all)
        }
        Crossing::At(g.root((lo, g_lo), (hi, g_hi), remaining))
    }

    /// Advances to the event at `tau` and lets it happen; the state continues in the
    /// configuration the event leaves.
    fn advance_to_event(
        &mut self,
        cfg: &Config,
        tau: f64,
        (j, kind): Event,
        step: &mut Interval,
    ) -> Result<()> {
        let lam = &cfg.lam;
        let buf: Vec<Complex64> = (0..cfg.m())
            .map(|k| {
                let (e, p1, p2) = phi_coeffs(lam[k], tau);
                e * self.xi[k] + p1 * self.b0[k] + p2 * self.b1[k]
            })
            .collect();
        self.unpack_from(cfg, &buf);
        for jj in 0..self.a {
            self.f0[jj] += self.f1[jj] * tau;
        }
        step.elapsed += tau;
        step.remaining -= tau;
        step.full_step = None;
        match kind {
            0 => self.velocity_zero(j)?,
            1 => self.impact(cfg, j),
            _ => self.break_away(cfg, &buf, j),
        }
        let new_mask = mask_of(&self.modes);
        if new_mask == self.mask && kind == 0 {
            // A reversal keeps the configuration: continue from the modal state.
            self.xi.clone_from(&buf);
        } else {
            self.enter(new_mask)?;
        }
        Ok(())
    }

    /// A sliding mass's velocity reaches zero: it sticks when the holding force is within
    /// `F_C`, else it reverses.
    fn velocity_zero(&mut self, j: usize) -> Result<()> {
        let Mode::Sliding(s) = self.modes[j] else {
            unreachable!()
        };
        self.phys.zd[j] = 0.0;
        let motor_j = self.f0[j] + self.fc[j] * s;
        let stuck_mask = self.mask | 1 << j;
        let sc = self.config(stuck_mask)?;
        let xi_s = sc.modal_of(&self.pack(&sc));
        let mut fs = self.f0.clone();
        fs[j] = motor_j;
        let ff = self.stick_force(&sc, &xi_s, &fs, j, self.phys.z[j], motor_j);
        if ff.abs() <= self.fc[j] {
            self.modes[j] = Mode::Stuck {
                z: self.phys.z[j],
                stop: 0.0,
            };
            self.f0[j] = motor_j;
            self.record.counts.sticks += 1;
        } else {
            let dir = -ff.signum();
            self.modes[j] = Mode::Sliding(dir);
            self.f0[j] = motor_j - self.fc[j] * dir;
            self.record.counts.reversals += 1;
        }
        Ok(())
    }

    /// A sliding mass reaches its end stop: a rigid impact with restitution `e`; a
    /// rebound slower than [`REST_SPEED`] leaves it resting on the stop.
    fn impact(&mut self, cfg: &Config, j: usize) {
        let act = self.actuator(j);
        let Mode::Sliding(sliding) = self.modes[j] else {
            unreachable!()
        };
        let s = self.phys.z[j].signum();
        self.record.counts.impacts += 1;
        self.phys.z[j] = s * act.stroke;
        let bz = cfg.bz[j];
        let v_in = self.phys.zd[j];
        let impulse = -(1.0 + act.restitution) * v_in / bz;
        // Δx = B_S[:, j]·P, through the modal form: Δξ = w_j P.
        let mut xi_new = cfg.modal_of(&self.pack(cfg));
        let am = self.f0.len();
        for (r, v) in xi_new.iter_mut().enumerate() {
            *v += cfg.w[r * am + j] * impulse;
        }
        let x = cfg.full_state(&xi_new);
        let (xs, z, zd) = unpack(cfg, &x, &self.modes, &self.phys.z, self.ns, self.a);
        self.phys.xs = xs;
        self.phys.zd = zd;
        self.phys.z[j] = z[j].clamp(-act.stroke, act.stroke);
        let motor_j = self.f0[j] + self.fc[j] * sliding;
        if self.phys.zd[j].abs() < REST_SPEED {
            self.phys.zd[j] = 0.0;
            self.modes[j] = Mode::Stuck {
                z: self.phys.z[j],
                stop: s,
            };
            self.f0[j] = motor_j;
        } else {
            self.modes[j] = Mode::Sliding(-s);
            self.f0[j] = motor_j + self.fc[j] * s;
        }
    }

    /// A stuck mass's holding force leaves `[−F_C, F_C]`: it breaks away, sliding
    /// against it.
    fn break_away(&mut self, cfg: &Config, buf: &[Complex64], j: usize) {
        let Mode::Stuck { z, .. } = self.modes[j] else {
            unreachable!()
        };
        let ff = self.stick_force(cfg, buf, &self.f0, j, z, self.f0[j]);
        let dir = -ff.signum();
        self.phys.zd[j] = 0.0;
        self.modes[j] = Mode::Sliding(dir);
        self.f0[j] += -self.fc[j] * dir;
        self.record.counts.breakaways += 1;
    }
}

/// An event function along the step, `g(τ) = Re Σ r_k ξ_k(τ) + d·f(τ) + c₀`: affine in
/// the modal coordinates and the inputs, so value and slope cost one pass over the modes.
struct EventFunction<'c> {
    lam: &'c [Complex64],
    /// Per mode `(r_k ξ_k, r_k b0_k, r_k b1_k)`.
    coef: Vec<(Complex64, Complex64, Complex64)>,
    df0: f64,
    df1: f64,
    c0: f64,
}

impl<'c> EventFunction<'c> {
    fn new(cfg: &'c Config, s: &Stepper<'_>, r: &[Complex64], d: &[f64], c0: f64) -> Self {
        let (xi, b0, b1) = (&s.xi, &s.b0, &s.b1);
        EventFunction {
            lam: &cfg.lam,
            coef: (0..cfg.m())
                .map(|k| (r[k] * xi[k], r[k] * b0[k], r[k] * b1[k]))
                .collect(),
            df0: d.iter().zip(&s.f0).map(|(x, y)| x * y).sum(),
            df1: d.iter().zip(&s.f1).map(|(x, y)| x * y).sum(),
            c0,
        }
    }

    /// `(g(τ), g'(τ))`.
    fn at(&self, tau: f64) -> (f64, f64) {
        let (mut v, mut dv) = (0.0, 0.0);
        for (k, &(ca, cb, cc)) in self.coef.iter().enumerate() {
            let (e, p1, p2) = phi_coeffs(self.lam[k], tau);
            let y = e * ca + p1 * cb + p2 * cc;
            v += y.re;
            dv += (self.lam[k] * y + e * cb + p1 * cc).re;
        }
        (v + self.df0 + self.df1 * tau + self.c0, dv + self.df1)
    }

    /// The upper end of the bracket `(lo, hi)` (`g(lo) > 0 ≥ g(hi)`) narrowed by
    /// safeguarded Newton (regula falsi when Newton leaves it, bisection when that
    /// does) to `1e-13 (1 + remaining)`.
    fn root(
        &self,
        (mut lo, mut g_lo): (f64, f64),
        (mut hi, mut g_hi): (f64, f64),
        remaining: f64,
    ) -> f64 {
        let mut tau = lo - g_lo * (hi - lo) / (g_hi - g_lo);
        for _ in 0..60 {
            if !(tau > lo && tau < hi) {
                tau = 0.5 * (lo + hi);
            }
            let (gv, dg) = self.at(tau);
            if gv > 0.0 {
                lo = tau;
                g_lo = gv;
            } else {
                hi = tau;
                g_hi = gv;
            }
            if hi - lo <= 1e-13 * (1.0 + remaining) {
                break;
            }
            let newton = tau - gv / dg;
            let step_ok = dg != 0.0 && newton > lo && newton < hi;
            tau = if step_ok {
                newton
            } else {
                lo - g_lo * (hi - lo) / (g_hi - g_lo)
            };
            if (newton - tau).abs() < 1e-14 && step_ok && (gv.abs() < 1e-300) {
                break;
            }
        }
        hi
    }
}

/// The event function of actuator `j` as an affine form `(r, d, c₀)`:
/// `g = Re Σ r_k ξ_k + d·f + c₀`, positive while nothing happens. Kind 0: velocity zero of
/// a sliding mass; 1: end stop; 2: a stuck mass's holding force reaching `F_C`. The sign
/// of two-sided functions is fixed from the state at the end of the step (`xi_end`).
#[allow(clippy::too_many_arguments)]
fn event_row(
    cfg: &Config,
    modes: &[Mode],
    xi_end: &[Complex64],
    f_end: &[f64],
    j: usize,
    kind: u8,
    spec: &ExperimentSpec,
    mass: &[f64],
    fc: &[f64],
    ns: usize,
) -> (Vec<Complex64>, Vec<f64>, f64) {
    let m = cfg.m();
    let a = f_end.len();
    let row = |c: usize| cfg.v[c * m..(c + 1) * m].to_vec();
    let scaled = |v: Vec<Complex64>, s: f64| v.into_iter().map(|x| x * s).collect::<Vec<_>>();
    match (kind, modes[j], cfg.slot[j]) {
        (0, Mode::Sliding(s), Some(k)) => (scaled(row(ns + cfg.nf + k), s), vec![0.0; a], 0.0),
        (1, Mode::Sliding(_), Some(k)) => {
            let sigma = cfg.state(xi_end, ns + k).signum();
            (
                scaled(row(ns + k), -sigma),
                vec![0.0; a],
                spec.actuators[j].stroke,
            )
        }
        (2, Mode::Stuck { z, .. }, None) => {
            let mj = mass[j];
            let ff = mj * Config::row_value(&cfg.mount_x, &cfg.mount_f, j, xi_end, f_end)
                + spec.actuators[j].stiffness * z
                - f_end[j];
            let sigma = ff.signum();
            let r = cfg.mount_x[j * m..(j + 1) * m]
                .iter()
                .map(|x| x * (-sigma * mj))
                .collect();
            let mut d: Vec<f64> = cfg.mount_f[j * a..(j + 1) * a]
                .iter()
                .map(|x| -sigma * mj * x)
                .collect();
            d[j] += sigma;
            (r, d, fc[j] - sigma * spec.actuators[j].stiffness * z)
        }
        _ => (vec![Complex64::new(0.0, 0.0); m], vec![0.0; a], 1.0),
    }
}

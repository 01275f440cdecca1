//! The random generator of the core: MINSTD (Park & Miller 1988) with Box–Muller
//! normals. It is a few lines, and portable: the Octave peer draws the same stream in the
//! same order, so a seed gives bit-identical noise, structures and start vectors in both.
//! Ours rather than `rand`'s for that reason.

use num_complex::Complex64;
use std::f64::consts::PI;

/// MINSTD uniform generator (Park & Miller 1988): `x ← 16807·x mod (2³¹ − 1)`,
/// `u = x/(2³¹ − 1)` in (0, 1).
#[derive(Debug, Clone)]
pub struct Minstd {
    pub(crate) state: u64,
}

const MINSTD_MODULUS: u64 = 2_147_483_647;

impl Minstd {
    /// Seeds the generator; a seed that is 0 modulo 2³¹ − 1 becomes 1 (as in the peer).
    pub fn new(seed: u64) -> Self {
        let state = seed % MINSTD_MODULUS;
        Minstd {
            state: if state == 0 { 1 } else { state },
        }
    }
    /// Next uniform in (0, 1).
    pub fn uniform(&mut self) -> f64 {
        self.state = (16807 * self.state) % MINSTD_MODULUS;
        self.state as f64 / MINSTD_MODULUS as f64
    }
    /// Next standard normal: `sqrt(−2 ln u1)·cos(2π u2)` from two uniforms.
    pub fn normal(&mut self) -> f64 {
        let u1 = self.uniform();
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (2.0 * PI * u2).cos()
    }
    /// Next circular complex normal of unit variance:
    /// `sqrt(−2 ln u1)·(cos 2πu2 + j sin 2πu2)/√2`.
    pub fn complex_normal(&mut self) -> Complex64 {
        let u1 = self.uniform();
        let u2 = self.uniform();
        let r = (-2.0 * u1.ln()).sqrt();
        Complex64::from_polar(r, 2.0 * PI * u2) / 2f64.sqrt()
    }
}

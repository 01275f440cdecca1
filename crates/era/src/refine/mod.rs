//! Maximum-likelihood refinement of poles, residues and residual terms against the
//! measured FRFs, starting from ERA's poles (the thesis's closing recommendation, §VI:
//! ERA "fits the poles rather well, but is much more inaccurate in fitting the zeros").
//!
//! # The model
//!
//! The FRFs are modelled in continuous time as a sum of modes, each a pole pair
//! `s_r = −σ_r + jω_r` (`σ_r > 0`, `ω_r > 0`) with a complex residue matrix `R_r` (q × p)
//! of **displacement** per unit force:
//!
//! ```text
//! G(jω) = Σ_r [ s_r^κ R_r/(jω − s_r) + s̄_r^κ R̄_r/(jω − s̄_r) ]  +  L (jω)^(κ−2)  +  U
//! ```
//!
//! where `κ` = 0, 1, 2 for displacement, velocity or acceleration data. The modal sum is
//! the strictly proper part of `(jω)^κ` times the receptance `Σ R_r/(jω − s_r) + c.c.`:
//! since `(jω)^κ/(jω − s) = s^κ/(jω − s) + (a polynomial in jω)`, the two differ by a
//! polynomial, which is zero for a mechanical structure except for the constant
//! (`Σ 2Re(R_r s_r)`, the `D = CB` of acceleration output), and that constant is what `U`
//! carries. Keeping the modal sum strictly proper is what makes the fitted model a
//! proper state-space model for every quantity.
//!
//! The residual terms, real q × p matrices ([`Residuals`]):
//! - **lower**, `L/(jω)²` in displacement, so `L (jω)^(κ−2)` in the data's quantity: the
//!   mass line of modes below the band (rigid-body-like);
//! - **upper**, `U`, a constant in the *data's* quantity: the residual flexibility of
//!   modes above the band for displacement data, and the direct term `D` of velocity and
//!   acceleration data. (The textbook upper residual of acceleration data, `−ω²F`, is not
//!   proper and cannot be part of `(A, B, C, D)`.)
//!
//! For acceleration data both terms are constants: with [`Residuals::Both`] the constant
//! is fitted once and reported as `upper`.
//!
//! # The fit: variable projection
//!
//! For fixed poles the model is linear in the residues and residual matrices, with one
//! real basis `Φ(θ)` (`2L` rows: real parts over imaginary parts) shared by every
//! output/input pair: `Re R_r` multiplies `g(s) + g(s̄)` and `Im R_r` multiplies
//! `j(g(s) − g(s̄))`, `g(s) = s^κ/(jω − s)`. The cost
//!
//! ```text
//! F(θ) = Σ_pairs ‖W(y − Φ(θ) c)‖²,   c = (WΦ)⁺ W y
//! ```
//!
//! depends on the pole parameters `θ = (x_r, ω_r)` alone (Golub & Pereyra 1973, 2003),
//! with `x_r = ln σ_r` when stability is enforced (so `σ_r > 0` always) or `x_r = σ_r`.
//! Levenberg–Marquardt (Marquardt 1963, with his diagonal scaling) minimises it with
//! Kaufman's (1975) simplified Jacobian `J = −P⊥ (∂Φ/∂θ) c`; `varpro` says how one QR
//! per block and a few Gram matrices give `JᵀJ` and `Jᵀr` without forming `J`.
//! [`refine_naive`] is the reference: the same driver with a central-difference Jacobian
//! of the projected residual and a dense solve per pair.
//!
//! Options: reciprocity (`R_r = R_rᵀ`, and `L`, `U` symmetric: the pairs `(i, j)` and
//! `(j, i)` share their coefficients, a linear constraint that keeps the problem
//! separable; the rank-one form `ψψᵀ` is bilinear and is imposed after, see "Rank-one
//! residues"), real normal
//! modes (`R_r = jX_r` with `X_r` real: proportionally damped modes, whose receptance
//! residue is `φφᵀ/(2jω_d)`), and weighting by coherence (`w = γ²`) or by inverse
//! variance (`w = 1/var`) per pair and line.
//!
//! ## Noise per pair
//!
//! Sensors and drive points differ, and noise given as a fraction of each FRF's level
//! (the thesis's 15 %) makes the variance differ from pair to pair by orders of
//! magnitude. The maximum-likelihood cost of independent complex Gaussian noise of
//! variance `σ²_ij` per pair is `Σ_ij ‖y_ij − ŷ_ij‖²/σ²_ij`; uniform weights waste the
//! quiet pairs. [`Weighting::PairNoise`] estimates `σ²_ij` from the residual of a uniform
//! fit (`‖y_ij − ŷ_ij‖²/L`, floored at 1e-12 of the mean) and refits with `1/σ²_ij`
//! from the first fit's poles (one step of iteratively reweighted least squares). With
//! rank-one residues the refit's free stage takes no step: the rank-one stage moves
//! every pole again, with the weights. An
//! exact fit (`fit_after` below 1e-9) has no noise to weight by and is returned as it
//! is. The costs reported are of the second pass's weights; `fit_before` is the
//! unweighted fit at the start poles, as always. On the truth model with 15 % noise this
//! lowers the median frequency error of every mode against the uniform fit
//! (docs/src/refinement.md).
//!
//! A mode is dropped, and the reason recorded in [`Refinement::dropped`], when its
//! share of the band's FRF norm falls below [`MIN_CONTRIBUTION`], when its pole
//! coalesces with another (closer than [`COALESCED`] relative, or its basis columns
//! become a combination of the others'), or when its pole becomes real.
//!
//! Each mode's part of a step is shortened to within `2σ_r` in frequency and a factor
//! `e^0.7` in damping: beyond a resonance's width the cost is far from quadratic, and
//! without the limit one badly predicted mode forces `λ` up for all.
//!
//! ## Stopping
//!
//! The fit has converged when an accepted step lowers the cost by less than
//! [`RefineOptions::tolerance`] of itself, or by less than a hundredth of one noise
//! variance `σ̂² = cost/(observations − unknowns)`. A parameter that moves by `δ`
//! standard deviations changes the cost by about `δ²σ̂²`, so such a step moves every
//! parameter by a tenth of its standard deviation or less: with noise, the rest is
//! noise. An exact fit has `σ̂² ≈ 0` and runs to the relative tolerance (or to
//! round-off). Trial steps are evaluated without their Jacobian; only an accepted
//! one pays for it. The rank-one stage also stops one step sooner where it can tell:
//! after a step that took less than one noise variance off the cost, as its model
//! predicted (gain ratio within 0.1 of 1), it solves for the undamped step from
//! there, and when that step is predicted to take less than the hundredth of a noise
//! variance, the fit has converged without taking it.
//!
//! The weighted pass of [`Weighting::PairNoise`] fits with one weight per pair, so every
//! pair still shares one basis and one QR (see `model::Block::scales`); its uniform first
//! pass stops at a relative decrease of 1e-4, since it only has to estimate the noise.
//! So does the free fit when the rank-one stage follows and will run: it is only that
//! stage's start, and the joint fit moves every pole again to the caller's tolerance.
//!
//! ## Rank-one residues
//!
//! A structure's residue is a mode shape times a participation, `R_r = u_r v_rᵀ`, and
//! with reciprocity `ψ_r ψ_rᵀ`. Variable projection keeps the residues free (that is what
//! keeps it separable), and a free residue can take up more than its mode: near a close
//! pair, or a mode the start missed, one pole with a rank-two residue stands in for two
//! modes, or a pole wanders between modes fitting what their residues leave. So, by
//! default ([`RefineOptions::rank_one`]), the free fit is followed by a joint
//! Levenberg–Marquardt fit of the poles, shapes, participations and residual terms,
//! started from the free fit's poles and each residue's leading singular pair
//! (`rank_one` module). On the DTA-like 8 × 8 set with 5 % noise
//! (`cargo run --release -p era --example refine_targets`, seeds 11–18) it has about half
//! the free fit's median damping error. The model then has two states per mode. Its
//! cost: the joint normal matrix is over every parameter (1344 for 8 × 8 and 40 modes;
//! 640 once each output's shapes are eliminated), so it takes two to four times the
//! free fit's time. It needs weights constant over the band per pair, complex modes and
//! at most `rank_one::MAX_PARAMETERS` (4000) parameters; otherwise the residues stay
//! free and [`Refinement::rank_one`] is false.
//!
//! ## Missed modes
//!
//! Neither stage can find a mode the start lacks. Where the start misses one, a pole
//! with its residue stands in for two modes, or a pole leaves its own mode for the
//! larger unfitted resonance (and its own mode is then missed). Both leave a
//! resonance-shaped residual, and by default ([`RefineOptions::add_missed`]) the fit
//! looks for one: an F test of the residual against one candidate mode at each line
//! (`scan` module). While a scan finds some, their poles join the fitted ones and the
//! fit runs again (at most [`MISSED_ROUNDS`] times); a refit that fails, does not lower
//! the fit error or loses the rank-one stage is discarded. The refit's rank-one stage
//! starts the modes it already had from the earlier fit's rank-one poles and residues,
//! not from the projection of its free fit (whose poles suit free residues): on the
//! DTA-like sets that start's cost is 2–30 % above the optimum, where the projection's
//! was up to ten times above it. The added poles are [`Refinement::added`]. A pole added on
//! noise ends with little weight: [`RefinedMode::significance`], its weighted energy
//! over the noise variance per parameter, tells it (Schwarz's criterion,
//! [`Refinement::significance_minimum`]), and the pipeline marks such a mode not
//! physical. On the DTA-like sets with 5 % noise (seeds 11–18) this took the modes
//! found from 36–40 to 39–40 of 40 and the spurious modes from two to none; each round
//! costs a refit.
//!
//! The scan does not wait for a fit's convergence: the final stage of a fit that a scan
//! follows (the weighted one under [`Weighting::PairNoise`]) stops after [`LOOK_AFTER`]
//! iterations. Where a pole stands for two modes it creeps between them for tens of
//! iterations, each lowering the cost a little, and the mode the scan then adds ends
//! that at once. A fit so cut short runs on from where it stopped, with every iteration
//! the options allow, when the scan finds nothing in it (and the scan then looks at it
//! again), and before it is judged when it was a refit that did not yet beat the fit it
//! would replace. The fit returned has therefore run to its tolerance as before, unless
//! a run-on fails, which [`Refinement::converged`] then says.
//!
//! # Sampled data: the z-domain model
//!
//! FRFs computed from a zero-order-hold discrete model (the truth model's,
//! docs/src/design.md §2) are not those of any continuous pole–residue model: the hold
//! delays and folds them, and a continuous fit is biased (by up to about 100 Hz in a
//! truth-model frequency with 15 % noise, where ERA's error is about 10 Hz). With [`RefineOptions::sample_time_s`] the model
//! is the hold's image instead,
//!
//! ```text
//! G(z) = Σ_r [ R_r/(z − e^(s_r Ts)) + R̄_r/(z − e^(s̄_r Ts)) ]  +  U  +  L·H_(κ−2)(z),   z = e^(jωTs)
//! ```
//!
//! with the same pole parameters (so `σ_r > 0` is still the stability constraint),
//! residues `R_r` of the data's quantity in `z`, and `H_0 = 1`, `H_(−1) = Ts/(z − 1)`,
//! `H_(−2) = Ts²(z + 1)/(2(z − 1)²)`, the hold's images of `1`, `1/s` and `1/s²`.
//!
//! # The model as a state-space model
//!
//! [`Refinement::to_state_space`] realises the fit in real modal block form. A mode with
//! residue `R' = s^κ' R` of the output quantity `κ'` is split by its SVD into rank-one
//! terms `u vᵀ` (singular values below `1e-12` of the largest are left out); each is two
//! states with
//!
//! ```text
//! A = [ Re s  Im s ; −Im s  Re s ],  B = √2 [ Re vᵀ ; −Im vᵀ ],  C = √2 [ Re u  Im u ]
//! ```
//!
//! so that `C (jωI − A)⁻¹ B = u vᵀ/(jω − s) + ū v̄ᵀ/(jω − s̄)`. The SVD leaves each
//! term's phase free (`u e^(iφ)`, `v e^(−iφ)`); the term's largest entry of `u` is made
//! real and positive, so that round-off in the fit cannot turn a mode's states around
//! (a free residue whose singular values are nearly equal can still turn its two terms
//! into each other). Rank-one residues (the
//! default, and any noise-free fit of a structure) give two states per mode; free
//! residues of a noisy fit up to `2 min(q, p)`. The residual terms: a term `K (jω)^0`
//! goes into `D`; a term `K/(jω)^m` (`m` = 1, 2) is `m·p` states at `s = 0`, an
//! integrator chain per input (`ẋ₁ = x₂, …, ẋ_m = u_j`, output `K x₁`). So for
//! displacement data the lower residual is a double integrator and the upper one `D`;
//! for acceleration data both are in `D`.
//!
//! A z-domain fit is realised the same way in `z` (blocks of `e^(sTs)`, `B_d`), and
//! returned as the continuous model whose `c2d(Ts)` it is: per block
//! `B_c = A_c (A_d − I)⁻¹ B_d`, which for the 2 × 2 block of a complex number is the
//! multiplication of `v` by `μ = s/(e^(sTs) − 1)`; the integrator chains are their own
//! continuous originals.
//!
//! # Uncertainty
//!
//! See `uncertainty`: `σ² (JᵀJ)⁻¹` at the optimum, propagated to frequency and damping.
//!
//! # Why hand-written
//!
//! No Rust crate does separable least squares; the structure that makes it fast here
//! (one basis for all q·p pairs, Jacobian columns touching only their mode's columns) is
//! specific to the pole–residue model. Every QR, product and solve is `faer`'s.
//!
//! References: G. H. Golub, V. Pereyra, "The differentiation of pseudo-inverses and
//! nonlinear least squares problems whose variables separate", SIAM J. Numer. Anal. 10,
//! 1973, and "Separable nonlinear least squares: the variable projection method and its
//! applications", Inverse Problems 19, 2003; L. Kaufman, "A variable projection method
//! for solving separable nonlinear least squares problems", BIT 15, 1975;
//! D. W. Marquardt, SIAM J. Appl. Math. 11, 1963; the LSFD estimator of modal analysis
//! (Peeters et al., "The PolyMAX frequency-domain method", Shock Vib. 11, 2004).

mod fit;
pub mod identification;
mod lm;
mod model;
mod naive;
mod rank_one;
mod scan;
pub(crate) mod uncertainty;
pub(crate) mod varpro;

pub use fit::{COALESCED, MIN_CONTRIBUTION};

use crate::data::frf::{FrfData, Quantity};
use crate::data::statespace::{StateSpace, TimeDomain};
use crate::error::{EraError, Result};
use faer::Mat;
use model::{order, partial_fraction, power, residual_factor};
use num_complex::Complex64;
use std::f64::consts::PI;

/// Which residual terms the model has (see the module doc).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Residuals {
    /// Modes only.
    None,
    /// `L/(jω)²` in displacement: modes below the band.
    Lower,
    /// `U`, constant in the data's quantity.
    Upper,
    /// Both (for acceleration data, one constant).
    #[default]
    Both,
}

/// How the pairs and lines are weighted in the cost.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum Weighting {
    /// Every line and pair alike.
    Uniform,
    /// Ordinary (or multiple) coherence `γ²` in [0, 1], `[output][input][line]` like
    /// [`FrfData::values`]: the squared error of a line is weighted by `γ²`.
    Coherence(Vec<f64>),
    /// Variance of each FRF value, `[output][input][line]`: weight `1/var`.
    InverseVariance(Vec<f64>),
    /// Each pair weighted by `1/σ²_pair`, its noise variance estimated from the residual
    /// of a first, uniform fit (module doc, "Noise per pair"); then the fit is repeated
    /// from the first fit's poles with those weights. The default: maximum likelihood
    /// when the pairs' noise levels differ, as they do between sensors.
    #[default]
    PairNoise,
}

/// Options of [`refine`].
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct RefineOptions {
    /// Residual terms (default [`Residuals::Both`]).
    pub residuals: Residuals,
    /// Symmetric residues and residual matrices (square sets; default false).
    pub reciprocal: bool,
    /// Purely imaginary receptance residues (real normal modes; default false).
    pub real_modes: bool,
    /// Keep `Re s < 0` by the parameter `ln σ` (default true).
    pub enforce_stability: bool,
    /// Levenberg–Marquardt iterations at most (default 100).
    pub max_iterations: usize,
    /// Converged when an accepted step lowers the cost by less than this fraction
    /// (default 1e-6: with noise, smaller decreases only move the parameters that the
    /// data does not determine). A free fit that only starts another (the uniform pass
    /// of [`Weighting::PairNoise`], the free fit before the rank-one stage) stops at
    /// 1e-4 or this, whichever is larger.
    pub tolerance: f64,
    /// Lines fitted, `first..end` (0-based, end exclusive); default every line above 0 Hz.
    pub band: Option<(usize, usize)>,
    /// Weighting (default [`Weighting::PairNoise`]).
    pub weighting: Weighting,
    /// `Some(Ts)`: fit the zero-order-hold image of the model, `z = e^(jωTs)` (module
    /// doc), for FRFs of a sampled system such as the truth model's; default `None`
    /// (continuous).
    pub sample_time_s: Option<f64>,
    /// Each residue a shape times a participation, `R_r = u_r v_rᵀ` (`ψ_r ψ_rᵀ` when
    /// reciprocal), fitted jointly with the poles after the free fit (module doc,
    /// "Rank-one residues"): two states per mode in the model. Default true. It needs
    /// weights constant over the band (uniform, per pair) and complex modes; otherwise
    /// the residues stay free and [`Refinement::rank_one`] says so.
    pub rank_one: bool,
    /// Look for modes the start missed in the residual of the fit, add their poles and
    /// fit again (module doc, "Missed modes"); default true.
    pub add_missed: bool,
    /// The poles' standard deviations (default true). Turned off only for a fit of no
    /// iterations read for its cost and significances alone (the automatic order's
    /// judge, [`crate::pipeline`]): with `max_iterations` 0 its Jacobian is then never
    /// formed, and the deviations are NaN. With iterations allowed it has no effect
    /// (the descent needs the Jacobian, and the deviations come with it).
    pub(crate) standard_deviations: bool,
}

impl Default for RefineOptions {
    fn default() -> Self {
        RefineOptions {
            residuals: Residuals::Both,
            reciprocal: false,
            real_modes: false,
            enforce_stability: true,
            max_iterations: 100,
            tolerance: 1e-6,
            band: None,
            weighting: Weighting::default(),
            sample_time_s: None,
            rank_one: true,
            add_missed: true,
            standard_deviations: true,
        }
    }
}

/// One refined mode.
#[derive(Debug, Clone, PartialEq)]
pub struct RefinedMode {
    /// Continuous pole, `Im s > 0`.
    pub pole: Complex64,
    /// `|s|/2π`, Hz.
    pub frequency_hz: f64,
    /// `−Re s/|s|` (a fraction).
    pub damping_ratio: f64,
    /// Receptance residue `R_r`, q × p row-major (`[output][input]`); in a z-domain fit
    /// the residue of the data's quantity in `z`.
    pub residue: Vec<Complex64>,
    /// Standard deviation of the frequency, Hz (NaN when the fit has no spare degrees
    /// of freedom or a singular normal matrix).
    pub frequency_std_hz: f64,
    /// Standard deviation of the damping ratio.
    pub damping_ratio_std: f64,
    /// The mode's share of the band's FRF norm, `‖G_r‖/‖G‖`.
    pub contribution: f64,
    /// The mode's weighted energy over the noise, per parameter of the mode:
    /// `‖W G_r‖²/(σ̂² k_r)` with `k_r` its pole's and residue's parameters. Below
    /// [`Refinement::significance_minimum`] the mode cannot be told from noise. NaN when the weights
    /// vary by line or the fit has no spare degrees of freedom; infinite for an
    /// exact fit.
    pub significance: f64,
    /// The start pole it came from: a 0-based index into the caller's start poles, or,
    /// from their count `n` on, into [`Refinement::added`] (`start − n`).
    pub start: usize,
}

/// The result of [`refine`]: the fitted model and how the fit went.
#[derive(Debug, Clone, PartialEq)]
pub struct Refinement {
    /// Modes, by ascending frequency.
    pub modes: Vec<RefinedMode>,
    /// Lower residual `L` (q × p), when fitted.
    pub lower: Option<Mat<f64>>,
    /// Upper residual `U` (q × p), when fitted.
    pub upper: Option<Mat<f64>>,
    /// Start poles dropped (0-based index into the start poles, then into
    /// [`Refinement::added`] as for [`RefinedMode::start`]) and why.
    pub dropped: Vec<(usize, String)>,
    /// Poles added to the caller's start poles for modes the start missed, found in
    /// the residual (module doc, "Missed modes"), in the order they were added.
    pub added: Vec<Complex64>,
    /// Accepted Levenberg–Marquardt steps (of every fit, when poles were added).
    pub iterations: usize,
    /// Whether the cost stopped decreasing (rather than the iterations running out), in
    /// the last fit.
    pub converged: bool,
    /// Weighted cost `Σ‖W(y − ŷ)‖²` at the start poles, with the weights of
    /// [`Refinement::cost_after`]. When poles were added ([`Refinement::added`]) these
    /// are the last fit's: the earlier fits' poles and the added ones. It is the cost
    /// with free residues: with rank-one residues ([`Refinement::rank_one`]) the cost
    /// after can exceed it, the rank-one model having far fewer parameters; compare
    /// [`Refinement::fit_before`] and [`Refinement::fit_after`] instead.
    pub cost_before: f64,
    /// Weighted cost at the end.
    pub cost_after: f64,
    /// `‖G − Ĝ‖/‖G‖` over the band at the start poles.
    pub fit_before: f64,
    /// `‖G − Ĝ‖/‖G‖` over the band at the end.
    pub fit_after: f64,
    /// `σ²` per real observation, `cost/(observations − unknowns)`.
    pub noise_variance: f64,
    /// The data's quantity.
    pub quantity: Quantity,
    /// Outputs `q`.
    pub outputs: usize,
    /// Inputs `p`.
    pub inputs: usize,
    /// Lines fitted, `first..end`.
    pub band: (usize, usize),
    /// The sample time of a z-domain fit ([`RefineOptions::sample_time_s`]).
    pub sample_time_s: Option<f64>,
    /// Whether the residues are rank one ([`RefineOptions::rank_one`], when the
    /// weights and modes allow it).
    pub rank_one: bool,
}

/// Refines `start_poles` (continuous, one per mode; conjugates, real poles and
/// duplicates are sorted out) against `frf` by variable projection with an analytic
/// Jacobian (module doc). `progress(iteration, cost)` is called after every accepted
/// step (and with 0 at the start).
///
/// # Errors
/// [`EraError::InvalidParameter`] for no or non-finite start poles, a bad band,
/// reciprocity of a non-square set, bad weights, too few lines for the unknowns, or
/// when every start pole is dropped; [`EraError::ShapeMismatch`] for weights of the
/// wrong length; [`EraError::AllZero`]; [`EraError::Limit`].
pub fn refine(
    frf: &FrfData,
    start_poles: &[Complex64],
    options: &RefineOptions,
    progress: &mut dyn FnMut(usize, f64),
) -> Result<Refinement> {
    refine_rounds(frf, start_poles, options, progress).map(|(refinement, _)| refinement)
}

/// [`refine`] with `options` at the same start poles in the continuous domain and in the
/// zero-order-hold domain of `sample_time_s`, side by side (neither reads the other),
/// each under the caller's cancel token on whichever thread runs it: continuous first.
pub(crate) fn refine_in_both_domains(
    frf: &FrfData,
    start_poles: &[Complex64],
    options: &RefineOptions,
    sample_time_s: f64,
) -> (Result<Refinement>, Result<Refinement>) {
    let fit = |ts: Option<f64>| {
        let options = RefineOptions {
            sample_time_s: ts,
            ..options.clone()
        };
        refine(frf, start_poles, &options, &mut |_, _| {})
    };
    let token = crate::cancel::current();
    rayon::join(
        || crate::cancel::under(&token, || fit(None)),
        || crate::cancel::under(&token, || fit(Some(sample_time_s))),
    )
}

/// [`refine`], and the seconds of each of its rounds: the first fit, then each look
/// for modes the start missed with what follows it (a refit, the run-on of a fit stopped
/// for the look, or nothing: the last look, which found none, included).
///
/// # Errors
/// As [`refine`].
pub(crate) fn refine_rounds(
    frf: &FrfData,
    start_poles: &[Complex64],
    options: &RefineOptions,
    progress: &mut dyn FnMut(usize, f64),
) -> Result<(Refinement, Vec<f64>)> {
    let mut rounds = Vec::new();
    let refinement = run(
        frf,
        start_poles,
        options,
        progress,
        varpro::evaluate,
        &mut rounds,
    )?;
    Ok((refinement, rounds))
}

/// The relative decrease that ends a fit that is only the start of another: the uniform
/// first pass of [`Weighting::PairNoise`], and the free fit before the rank-one stage.
const START_TOLERANCE: f64 = 1e-4;

/// Refits with modes the scan for missed modes found, at most.
pub const MISSED_ROUNDS: usize = 6;

/// Iterations of a fit that a scan for missed modes follows (module doc, "Missed
/// modes"): its final stage stops there, and runs on if the scan finds nothing.
pub const LOOK_AFTER: usize = 20;

/// The fit ([`run_once`]), then while the residual shows a mode the start missed, the
/// fit again from its poles and the missed ones; each fit a scan follows stops after
/// [`LOOK_AFTER`] iterations, and runs on ([`run_on`]) when the scan finds nothing in it,
/// or when it stopped there without beating the fit it would replace (module doc,
/// "Missed modes"). `rounds` gets the seconds of the first fit, then of each look with
/// what follows it (a refit, a run-on, or nothing).
fn run(
    frf: &FrfData,
    start_poles: &[Complex64],
    options: &RefineOptions,
    progress: &mut dyn FnMut(usize, f64),
    evaluate: varpro::Evaluator,
    rounds: &mut Vec<f64>,
) -> Result<Refinement> {
    let clock = std::time::Instant::now();
    let full = options.max_iterations;
    let cap = if options.add_missed {
        full.min(LOOK_AFTER)
    } else {
        full
    };
    // Whether a fit stopped at the look's limit before its tolerance.
    let cut_short = |r: &Refinement| !r.converged && cap < full;
    let mut result = run_once(frf, start_poles, &[], options, cap, progress, evaluate)?;
    rounds.push(clock.elapsed().as_secs_f64());
    if !options.add_missed {
        return Ok(result);
    }
    let mut refits_left = MISSED_ROUNDS;
    let n_start = start_poles.len();
    // Each round's seconds, however it ends.
    struct Round<'a>(&'a mut Vec<f64>, std::time::Instant);
    impl Drop for Round<'_> {
        fn drop(&mut self) {
            self.0.push(self.1.elapsed().as_secs_f64());
        }
    }
    loop {
        let _round = Round(rounds, std::time::Instant::now());
        let missed = if refits_left > 0 {
            scan::missed_modes(frf, &result)
        } else {
            Vec::new()
        };
        if missed.is_empty() {
            if !cut_short(&result) {
                break;
            }
            // Nothing missed in a fit cut short: it runs on to its tolerance, and is
            // looked at again (unless the run-on failed, which its `converged` says).
            result = run_on(frf, result, options, progress, evaluate)?;
            if cut_short(&result) || refits_left == 0 {
                break;
            }
            continue;
        }
        refits_left -= 1;
        let kept = result.modes.len();
        let mut poles: Vec<Complex64> = result.modes.iter().map(|m| m.pole).collect();
        poles.extend(missed.iter().map(|m| m.pole));
        let again = RefineOptions {
            band: Some(result.band),
            ..options.clone()
        };
        let warm = warm_modes(&result);
        let refit = match run_once(frf, &poles, &warm, &again, cap, progress, evaluate) {
            Ok(next) => Some(next),
            Err(EraError::Interrupted) => return Err(EraError::Interrupted),
            Err(_) => None,
        };
        // A refit stopped at the look's limit is judged once it has run on, unless it
        // already beats the fit it would replace.
        let refit = match refit {
            Some(next)
                if cut_short(&next)
                    && next.fit_after.partial_cmp(&result.fit_after)
                        != Some(std::cmp::Ordering::Less) =>
            {
                Some(run_on(frf, next, options, progress, evaluate)?)
            }
            other => other,
        };
        // A refit that fails (more poles than a narrow band can fit, a limit), that
        // does not lower the error, or that lost the rank-one stage (too many
        // parameters with the added poles) leaves the fit as it was, and ends the
        // looks; a fit cut short then runs on.
        let Some(mut next) = refit.filter(|next| {
            next.fit_after < result.fit_after && (next.rank_one || !result.rank_one)
        }) else {
            if cut_short(&result) {
                result = run_on(frf, result, options, progress, evaluate)?;
            }
            break;
        };
        // Indices into `poles` → indices into the caller's start poles and `added`.
        let added_before = result.added.len();
        let origin = |k: usize| {
            if k < kept {
                result.modes[k].start
            } else {
                n_start + added_before + (k - kept)
            }
        };
        // The costs stay those of one fit, with one set of weights: this one's.
        continue_from(&mut next, &result, origin);
        next.added = result.added.clone();
        next.added.extend(missed.iter().map(|m| m.pole));
        result = next;
    }
    Ok(result)
}

/// The warm starts of a refit from `fit`'s modes: the rank-one stage starts them where
/// `fit`'s left them (none when `fit`'s residues were free).
fn warm_modes(fit: &Refinement) -> Vec<Option<fit::Warm<'_>>> {
    fit.modes
        .iter()
        .map(|m| {
            fit.rank_one.then_some(fit::Warm {
                pole: m.pole,
                residue: &m.residue,
            })
        })
        .collect()
}

/// `fit`, stopped at the look's limit ([`LOOK_AFTER`]), run on from its own poles (the
/// rank-one ones with their residues) with every iteration `options` allow, in `fit`'s
/// numbering; `fit` as it is when the run-on fails or loses the rank-one stage (its
/// `converged` then says that it stopped short). An interruption is passed on.
fn run_on(
    frf: &FrfData,
    fit: Refinement,
    options: &RefineOptions,
    progress: &mut dyn FnMut(usize, f64),
    evaluate: varpro::Evaluator,
) -> Result<Refinement> {
    let poles: Vec<Complex64> = fit.modes.iter().map(|m| m.pole).collect();
    let warm = warm_modes(&fit);
    let again = RefineOptions {
        band: Some(fit.band),
        ..options.clone()
    };
    let full = options.max_iterations;
    match run_once(frf, &poles, &warm, &again, full, progress, evaluate) {
        Ok(mut next) if !next.fit_after.is_nan() && (next.rank_one || !fit.rank_one) => {
            continue_from(&mut next, &fit, |k| fit.modes[k].start);
            next.added = fit.added.clone();
            Ok(next)
        }
        Err(EraError::Interrupted) => Err(EraError::Interrupted),
        _ => Ok(fit),
    }
}

/// The fit, or for [`Weighting::PairNoise`] a uniform fit and a reweighted one; the
/// fit returned (the reweighted one) takes at most `cap` iterations, the uniform fit
/// that sets its weights every one `options` allow.
#[allow(clippy::too_many_arguments)]
fn run_once(
    frf: &FrfData,
    start_poles: &[Complex64],
    warm: &[Option<fit::Warm>],
    options: &RefineOptions,
    cap: usize,
    progress: &mut dyn FnMut(usize, f64),
    evaluate: varpro::Evaluator,
) -> Result<Refinement> {
    if options.weighting != Weighting::PairNoise {
        let capped = RefineOptions {
            max_iterations: options.max_iterations.min(cap),
            ..options.clone()
        };
        return fit::run(frf, start_poles, warm, false, &capped, progress, evaluate);
    }
    // The first fit only has to be good enough to estimate each pair's noise, which
    // small moves of the poles hardly change: a looser tolerance, and free residues (the
    // rank-one stage runs once, after the weighted pass).
    let uniform = RefineOptions {
        weighting: Weighting::Uniform,
        tolerance: options.tolerance.max(START_TOLERANCE),
        rank_one: false,
        ..options.clone()
    };
    let first = fit::run(frf, start_poles, &[], false, &uniform, progress, evaluate)?;
    // `warm` told in the first fit's numbering.
    let warm: Vec<Option<fit::Warm>> = first
        .modes
        .iter()
        .map(|m| warm.get(m.start).copied().flatten())
        .collect();
    // NaN (no fit measure) is returned as it is, like an exact fit: with the rank-one
    // stage when it was asked for (the first pass ran without it).
    if first.fit_after.is_nan() || first.fit_after < 1e-9 {
        if !options.rank_one {
            return Ok(first);
        }
        let poles: Vec<Complex64> = first.modes.iter().map(|m| m.pole).collect();
        let mut exact = fit::run(
            frf,
            &poles,
            &warm,
            false,
            &RefineOptions {
                band: Some(first.band),
                rank_one: true,
                ..uniform.clone()
            },
            progress,
            evaluate,
        )?;
        for m in &mut exact.modes {
            m.start = first.modes[m.start].start;
        }
        exact.dropped = first.dropped.clone();
        exact.iterations += first.iterations;
        // Before: at the caller's start poles, with the same (uniform) weights.
        exact.fit_before = first.fit_before;
        exact.cost_before = first.cost_before;
        return Ok(exact);
    }
    let weighted = RefineOptions {
        weighting: Weighting::InverseVariance(pair_noise_variance(frf, &first)),
        band: Some(first.band),
        max_iterations: options.max_iterations.min(cap),
        ..options.clone()
    };
    let poles: Vec<Complex64> = first.modes.iter().map(|m| m.pole).collect();
    // The uniform fit placed the poles; the rank-one stage (where it runs) moves them
    // for the weights.
    let mut second = fit::run(frf, &poles, &warm, true, &weighted, progress, evaluate)?;
    // Indices into the first fit's modes → indices into the caller's start poles.
    continue_from(&mut second, &first, |k| first.modes[k].start);
    Ok(second)
}

/// Each pair's noise variance, the mean square of `fit`'s residual over its band (at
/// least 1e-12 of the mean over pairs), for every line of `frf`
/// ([`Weighting::InverseVariance`]).
fn pair_noise_variance(frf: &FrfData, fit: &Refinement) -> Vec<f64> {
    let (q, p, lines) = (frf.outputs(), frf.inputs(), frf.lines());
    let (_, per_pair) = fit.residual(frf);
    let mean = per_pair.iter().sum::<f64>() / per_pair.len() as f64;
    let floor = 1e-12 * mean;
    let mut variance = vec![1.0; q * p * lines];
    for (pair, &v) in per_pair.iter().enumerate() {
        variance[pair * lines..(pair + 1) * lines].fill(v.max(floor));
    }
    variance
}

/// `next`, a fit started from `earlier`'s poles (and maybe more), told in the caller's
/// numbering: `origin(k)` is the caller's index of `next`'s start pole `k`, for its modes
/// and its dropped poles, which join `earlier`'s; the iterations add up, and
/// `fit_before` stays `earlier`'s, at the caller's start.
fn continue_from(next: &mut Refinement, earlier: &Refinement, origin: impl Fn(usize) -> usize) {
    for m in &mut next.modes {
        m.start = origin(m.start);
    }
    let mut dropped = earlier.dropped.clone();
    dropped.extend(
        next.dropped
            .iter()
            .map(|(k, why)| (origin(*k), why.clone())),
    );
    dropped.sort_by_key(|d| d.0);
    next.dropped = dropped;
    next.iterations += earlier.iterations;
    next.fit_before = earlier.fit_before;
}

/// [`refine`] with a central-difference Jacobian and a dense solve per pair: the
/// reference of the fast path. Slow: for small sets and tests.
///
/// # Errors
/// As [`refine`].
pub fn refine_naive(
    frf: &FrfData,
    start_poles: &[Complex64],
    options: &RefineOptions,
    progress: &mut dyn FnMut(usize, f64),
) -> Result<Refinement> {
    run(
        frf,
        start_poles,
        options,
        progress,
        naive::evaluate,
        &mut Vec::new(),
    )
}

/// Singular values of a mode's residue below this fraction of its largest are left out
/// of the state-space model.
pub const RESIDUE_RANK_TOLERANCE: f64 = 1e-12;

impl Refinement {
    /// `frf` minus the model over the band, `[pair][line]`, and each pair's mean square
    /// of it.
    pub(crate) fn residual(&self, frf: &FrfData) -> (Vec<Complex64>, Vec<f64>) {
        let (a, b) = self.band;
        let (lines, all) = (b - a, frf.lines());
        let mut residual = self.response(&frf.frequency_hz()[a..b], frf.quantity());
        let mut mean_square = Vec::with_capacity(self.outputs * self.inputs);
        for (pair, e) in residual.chunks_mut(lines.max(1)).enumerate() {
            let data = &frf.values()[pair * all + a..pair * all + b];
            for (e, y) in e.iter_mut().zip(data) {
                *e = y - *e;
            }
            mean_square.push(e.iter().map(|v| v.norm_sqr()).sum::<f64>() / lines as f64);
        }
        (residual, mean_square)
    }

    /// The [`RefinedMode::significance`] a mode needs to be told from noise: a mode
    /// lowers the cost by about its weighted energy, and by Schwarz's criterion (BIC) a
    /// parameter must lower it by more than `σ̂² ln n`, `n` the real observations
    /// (`2·lines·q·p`).
    pub fn significance_minimum(&self) -> f64 {
        let lines = self.band.1.saturating_sub(self.band.0);
        ((2 * lines * self.outputs * self.inputs).max(1) as f64).ln()
    }

    /// The residue of `mode` in the model's own variable: `s^κ' R` of `quantity` (order
    /// `κ'`) over `(jω − s)` for a continuous fit, the z-domain residue `R` of the data's
    /// quantity over `(z − e^(sTs))` for a sampled one (`quantity` is then the data's,
    /// as in [`Refinement::to_state_space`]). Its rank-one part is the mode's shape
    /// times its participation.
    pub(crate) fn model_residue(&self, mode: &RefinedMode, quantity: Quantity) -> Vec<Complex64> {
        match self.sample_time_s {
            Some(_) => mode.residue.clone(),
            None => {
                let scale = power(mode.pole, order(quantity));
                mode.residue.iter().map(|r| scale * r).collect()
            }
        }
    }

    /// The model's FRF of `quantity` at `frequency_hz`, `[output][input][line]`:
    /// `Σ_r [s^κ' R/(jω − s) + c.c.]` plus [`Refinement::residual_terms`] (in the data's
    /// quantity `L (jω)^(κ−2) + U`), with `κ'` the order of `quantity` and `κ` the
    /// data's (module doc). A negative power at 0 Hz is
    /// infinite. A z-domain fit gives `Σ_r [R/(z − e^(sTs)) + c.c.]` plus the residual
    /// terms' zero-order-hold images, of the data's quantity only.
    ///
    /// # Panics
    /// For a z-domain fit and a `quantity` other than the data's.
    #[track_caller]
    pub fn response(&self, frequency_hz: &[f64], quantity: Quantity) -> Vec<Complex64> {
        let (q, p, nl) = (self.outputs, self.inputs, frequency_hz.len());
        let k_out = order(quantity);
        let ts = self.sample_time_s;
        assert!(
            ts.is_none() || quantity == self.quantity,
            "a z-domain refinement has only the data's quantity"
        );
        let mut out = vec![Complex64::new(0.0, 0.0); q * p * nl];
        let terms = self.residual_terms(quantity);
        // Mode by mode, each pair's lines in one contiguous run; every entry still sums
        // the modes in order, then the residual terms, as line by line would.
        let (mut a, mut b) = (
            vec![Complex64::new(0.0, 0.0); nl],
            vec![Complex64::new(0.0, 0.0); nl],
        );
        for mode in &self.modes {
            let s = mode.pole;
            for (k, f) in frequency_hz.iter().enumerate() {
                let w = 2.0 * PI * f;
                let jw = Complex64::new(0.0, w);
                (a[k], b[k]) = match ts {
                    Some(_) => (
                        partial_fraction(s, w, k_out, ts).0,
                        partial_fraction(s.conj(), w, k_out, ts).0,
                    ),
                    None => (
                        power(s, k_out) / (jw - s),
                        power(s.conj(), k_out) / (jw - s.conj()),
                    ),
                };
            }
            for (pair, row) in out.chunks_exact_mut(nl.max(1)).enumerate().take(q * p) {
                let r = mode.residue[pair];
                for ((o, ak), bk) in row.iter_mut().zip(&a).zip(&b) {
                    *o += r * ak + r.conj() * bk;
                }
            }
        }
        for (e, m) in &terms {
            for (k, f) in frequency_hz.iter().enumerate() {
                let factor = residual_factor(2.0 * PI * f, *e, ts);
                for i in 0..q {
                    for j in 0..p {
                        out[(i * p + j) * nl + k] += factor * m[(i, j)];
                    }
                }
            }
        }
        out
    }

    /// The terms of the model of `quantity` besides the modal sum
    /// `Σ_r [s^κ' R/(jω − s) + c.c.]`, as `(e, K)` for `K (jω)^e`, one per power.
    ///
    /// The fitted receptance is `(jω)^(−κ)` times the data's model, and
    /// `(jω)^κ/(jω − s) = s^κ/(jω − s) + p_κ(jω, s)` with `p_0 = 0`, `p_1 = 1`,
    /// `p_2 = jω + s`: the modal sum of the data's quantity leaves out the polynomial
    /// `P_κ = Σ_r [R p_κ + c.c.]`, which `U` absorbs (for acceleration data
    /// `U = Σ 2Re(s R) +` the residual). In another quantity `κ'` the model is therefore
    /// `Σ [s^κ' R/(jω − s) + c.c.] + L (jω)^(κ'−2) + (jω)^(κ'−κ) (U − P_κ) + P_κ'`:
    /// for acceleration data in velocity `(U − Σ 2Re(sR))/(jω)`, the mass line the modes
    /// do not carry. For an integral (`κ' < κ`) every power is at most 0. For a
    /// derivative only `U (jω)^(κ'−κ)` is kept (the modes' polynomial is then not
    /// proper in general).
    pub fn residual_terms(&self, quantity: Quantity) -> Vec<(i32, Mat<f64>)> {
        let (q, p) = (self.outputs, self.inputs);
        let k_out = order(quantity);
        let k_data = order(self.quantity);
        let mut terms: Vec<(i32, Mat<f64>)> = Vec::new();
        let mut add =
            |e: i32, m: &Mat<f64>, sign: f64| match terms.iter_mut().find(|(f, _)| *f == e) {
                Some((_, acc)) => {
                    for i in 0..q {
                        for j in 0..p {
                            acc[(i, j)] += sign * m[(i, j)];
                        }
                    }
                }
                None => terms.push((e, Mat::from_fn(q, p, |i, j| sign * m[(i, j)]))),
            };
        if let Some(l) = &self.lower {
            add(k_out - 2, l, 1.0);
        }
        if let Some(u) = &self.upper {
            add(k_out - k_data, u, 1.0);
        }
        if k_out < k_data && self.sample_time_s.is_none() {
            // P_κ(jω) = Σ_j c_j (jω)^j: `c_0`, `c_1` of the data's order, and of κ'.
            let polynomial = |k: i32| -> Vec<(i32, Mat<f64>)> {
                let sum = |f: &dyn Fn(&RefinedMode, Complex64) -> Complex64| {
                    Mat::from_fn(q, p, |i, j| {
                        self.modes
                            .iter()
                            .map(|m| 2.0 * f(m, m.residue[i * p + j]).re)
                            .sum::<f64>()
                    })
                };
                match k {
                    1 => vec![(0, sum(&|_, r| r))],
                    2 => vec![(1, sum(&|_, r| r)), (0, sum(&|m, r| m.pole * r))],
                    _ => vec![],
                }
            };
            for (j, c) in polynomial(k_data) {
                add(j + k_out - k_data, &c, -1.0);
            }
            for (j, c) in polynomial(k_out) {
                add(j, &c, 1.0);
            }
        }
        terms.sort_by_key(|t| t.0);
        terms
    }

    /// The fit as a continuous state-space model whose output is `quantity`, in real
    /// modal block form, with the residual terms as `D` and integrator states (module
    /// doc). Its frequency response is [`Refinement::response`] to round-off (and to the
    /// residue rank truncation, [`RESIDUE_RANK_TOLERANCE`]).
    ///
    /// # Errors
    /// [`EraError::InvalidParameter`] when `quantity` is a derivative of the data's and
    /// an upper residual is present (`U (jω)^(κ'−κ)` is not proper);
    /// [`EraError::Numerical`] when an SVD fails.
    pub fn to_state_space(&self, quantity: Quantity) -> Result<StateSpace> {
        let (q, p) = (self.outputs, self.inputs);
        let k_out = order(quantity);
        if self.sample_time_s.is_some() && quantity != self.quantity {
            return Err(EraError::InvalidParameter {
                name: "quantity",
                value: quantity.name().into(),
                reason: format!(
                    "a z-domain refinement models only the data's quantity, {}",
                    self.quantity
                )
                .into(),
            });
        }
        // Rank-one terms (pole, u, v) of every mode.
        let mut terms: Vec<(Complex64, Vec<Complex64>, Vec<Complex64>)> = Vec::new();
        for mode in &self.modes {
            let s = mode.pole;
            // The z-domain residue is of the data's quantity already.
            let scale = match self.sample_time_s {
                Some(_) => Complex64::new(1.0, 0.0),
                None => power(s, k_out),
            };
            let r = Mat::from_fn(q, p, |i, j| scale * mode.residue[i * p + j]);
            let svd = r
                .thin_svd()
                .map_err(|e| EraError::Numerical(format!("SVD of a residue: {e:?}")))?;
            let sv: Vec<f64> = (0..q.min(p)).map(|k| svd.S()[k].re).collect();
            let largest = sv.iter().copied().fold(0.0, f64::max);
            for (k, &sk) in sv.iter().enumerate() {
                if sk.is_nan() || sk <= RESIDUE_RANK_TOLERANCE * largest {
                    continue;
                }
                let root = sk.sqrt();
                // The SVD's phase of a singular pair is arbitrary (round-off can turn
                // it): the term's own phase makes `(A, B, C)` one function of the fit.
                let (top, turn) = canonical_phase((0..q).map(|i| svd.U()[(i, k)]));
                let mut u: Vec<Complex64> = (0..q)
                    .map(|i| svd.U()[(i, k)] * root * turn.conj())
                    .collect();
                // Real to the last bit, not to round-off.
                u[top] = Complex64::new(u[top].norm(), 0.0);
                // z-domain: B_c = A_c (A_d − I)⁻¹ B_d, which for the 2 × 2 block of a
                // complex number is multiplication by μ = s/(e^(sTs) − 1).
                let mu = match self.sample_time_s {
                    Some(ts) => s / ((s * ts).exp() - 1.0),
                    None => Complex64::new(1.0, 0.0),
                } * turn;
                let v = (0..p).map(|j| svd.V()[(j, k)].conj() * root * mu).collect();
                terms.push((s, u, v));
            }
        }
        let mut chains: Vec<(usize, &Mat<f64>)> = Vec::new();
        let mut d = Mat::<f64>::zeros(q, p);
        let residual_terms = self.residual_terms(quantity);
        for (e, m) in &residual_terms {
            match *e {
                0 => d += m,
                e if e < 0 => chains.push(((-e) as usize, m)),
                _ => {
                    return Err(EraError::InvalidParameter {
                        name: "quantity",
                        value: quantity.name().into(),
                        reason: format!(
                            "the upper residual of {} data times (jω)^{e} is not proper: ask for {} or an integral of it",
                            self.quantity, self.quantity
                        ).into(),
                        // (only the upper residual has a positive power: see
                        // `residual_terms`)
                    });
                }
            }
        }
        let n = 2 * terms.len() + chains.iter().map(|(m, _)| m * p).sum::<usize>();
        crate::params::limits::STATES.check("refined model states", n as u64)?;
        let mut a = Mat::<f64>::zeros(n, n);
        let mut b = Mat::<f64>::zeros(n, p);
        let mut c = Mat::<f64>::zeros(q, n);
        let root2 = 2f64.sqrt();
        for (t, (s, u, v)) in terms.iter().enumerate() {
            let x = 2 * t;
            a[(x, x)] = s.re;
            a[(x, x + 1)] = s.im;
            a[(x + 1, x)] = -s.im;
            a[(x + 1, x + 1)] = s.re;
            for j in 0..p {
                b[(x, j)] = root2 * v[j].re;
                b[(x + 1, j)] = -root2 * v[j].im;
            }
            for i in 0..q {
                c[(i, x)] = root2 * u[i].re;
                c[(i, x + 1)] = root2 * u[i].im;
            }
        }
        let mut x = 2 * terms.len();
        for (m, k) in chains {
            for j in 0..p {
                for t in 0..m {
                    if t + 1 < m {
                        a[(x + t, x + t + 1)] = 1.0;
                    } else {
                        b[(x + t, j)] = 1.0;
                    }
                }
                for i in 0..q {
                    c[(i, x)] = k[(i, j)];
                }
                x += m;
            }
        }
        Ok(StateSpace::new(a, b, c, d, TimeDomain::Continuous))
    }
}

/// The largest entry of a state-space term's output vector `u` (the first of those
/// within 1e-9 of the largest, so that a symmetric structure's equal entries do not let
/// round-off choose) and its unit phase `e^(iφ)`: `u e^(−iφ)` has that entry real and
/// positive. `(0, 1)` for a zero vector.
fn canonical_phase(u: impl Iterator<Item = Complex64>) -> (usize, Complex64) {
    let u: Vec<Complex64> = u.collect();
    let largest = u.iter().map(|z| z.norm()).fold(0.0, f64::max);
    u.iter()
        .position(|z| z.norm() >= (1.0 - 1e-9) * largest && largest > 0.0)
        .map_or((0, Complex64::new(1.0, 0.0)), |i| (i, u[i] / u[i].norm()))
}

crate::params::names::named!(display Residuals, "residuals", [
    Residuals::None => "none",
    Residuals::Lower => "lower",
    Residuals::Upper => "upper",
    Residuals::Both => "both",
]);

impl Weighting {
    /// [`Weighting::Coherence`] from an estimate's coherence curves of one length: one per
    /// output (multiple coherence, for every input of that output) or one per pair,
    /// output by output, clamped to [0, 1]. `None` when the curves are neither.
    pub fn coherence_of(curves: &[&[f64]], outputs: usize, inputs: usize) -> Option<Self> {
        let per_output = curves.len() == outputs;
        if !(per_output || curves.len() == outputs * inputs)
            || curves.windows(2).any(|w| w[0].len() != w[1].len())
        {
            return None;
        }
        let mut weights = Vec::with_capacity(outputs * inputs * curves.first()?.len());
        for i in 0..outputs {
            for j in 0..inputs {
                let curve = curves[if per_output { i } else { i * inputs + j }];
                weights.extend(curve.iter().map(|g| g.clamp(0.0, 1.0)));
            }
        }
        Some(Weighting::Coherence(weights))
    }
}

crate::params::names::named!(display Weighting, "weighting", [
    Weighting::PairNoise => "pair-noise",
    Weighting::Uniform => "uniform",
]);

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::{add_noise, ModalSpec, ModalStructure};

    /// A 3 × 4 structure of six modes between 2 and 9 Hz, and its velocity FRFs over
    /// 401 lines with 5 % noise of seed `noise_seed`.
    fn six_modes(noise_seed: u64) -> (ModalStructure, FrfData) {
        let spec = ModalSpec {
            fmin_hz: 2.0,
            fmax_hz: 9.0,
            ..ModalSpec::new(3, 4, 6)
        };
        let s = ModalStructure::random(&spec).unwrap();
        let frf = s.frf(401, 0.025, Quantity::Velocity).unwrap();
        (s, add_noise(&frf, 0.05, noise_seed).unwrap())
    }

    /// The automatic order's judge reads a fit of no iterations for its cost and
    /// significances alone, without forming the Jacobian: everything it reads is the
    /// same as with the Jacobian, and the deviations it does not read are NaN.
    #[test]
    fn a_judged_fit_without_deviations_has_the_same_cost_and_significances() {
        let (s, frf) = six_modes(9);
        let judged = RefineOptions {
            max_iterations: 0,
            add_missed: false,
            rank_one: false,
            weighting: Weighting::Uniform,
            ..RefineOptions::default()
        };
        let start: Vec<Complex64> = s.poles().iter().map(|s| 1.001 * s).collect();
        let with = refine(&frf, &start, &judged, &mut |_, _| {}).unwrap();
        let without = RefineOptions {
            standard_deviations: false,
            ..judged.clone()
        };
        let without = refine(&frf, &start, &without, &mut |_, _| {}).unwrap();
        assert_eq!(with.cost_after, without.cost_after);
        assert_eq!(with.noise_variance, without.noise_variance);
        assert_eq!(with.modes.len(), 6);
        for (a, b) in with.modes.iter().zip(&without.modes) {
            assert_eq!((a.pole, a.start), (b.pole, b.start));
            assert_eq!(a.residue, b.residue);
            assert_eq!(a.significance, b.significance);
            assert!(a.frequency_std_hz.is_finite() && a.frequency_std_hz > 0.0);
            assert!(b.frequency_std_hz.is_nan() && b.damping_ratio_std.is_nan());
        }
    }

    /// A refit handed an earlier rank-one fit's modes as warm starts, in reverse order
    /// after a start pole it drops, from start poles a little off theirs, starts each
    /// mode from its own entry. With no iteration allowed, every mode ends exactly on
    /// the warm pole of the start it names, through the uniform pass (which sorts and
    /// renumbers the modes) and the weighted rank-one stage; without the entries, on
    /// its start pole.
    #[test]
    fn warm_modes_reach_the_refit_under_their_own_numbers() {
        let (s, frf) = six_modes(5);
        let options = RefineOptions {
            weighting: Weighting::PairNoise,
            add_missed: false,
            ..RefineOptions::default()
        };
        let start: Vec<Complex64> = s.poles().iter().map(|s| 1.002 * s).collect();
        let first = refine(&frf, &start, &options, &mut |_, _| {}).unwrap();
        assert!(first.rank_one);
        assert_eq!(first.modes.len(), 6);
        // Start k ≥ 1 is mode 6 − k of the first fit, 0.1 % off in frequency.
        let mut poles = vec![Complex64::new(-3.0, 0.0)];
        let mut warm = vec![None];
        for m in first.modes.iter().rev() {
            poles.push(Complex64::new(m.pole.re, m.pole.im * 1.001));
            warm.push(Some(fit::Warm {
                pole: m.pole,
                residue: &m.residue,
            }));
        }
        let again = RefineOptions {
            band: Some(first.band),
            max_iterations: 0,
            ..options.clone()
        };
        let refit = run_once(
            &frf,
            &poles,
            &warm,
            &again,
            again.max_iterations,
            &mut |_, _| {},
            varpro::evaluate,
        )
        .unwrap();
        assert!(refit.rank_one);
        assert_eq!(refit.dropped.len(), 1);
        assert_eq!(refit.dropped[0].0, 0);
        let mut starts: Vec<usize> = refit.modes.iter().map(|m| m.start).collect();
        starts.sort_unstable();
        assert_eq!(starts, (1..=6).collect::<Vec<_>>());
        for m in &refit.modes {
            let want = first.modes[6 - m.start].pole;
            assert!(
                (m.pole - want).norm() <= 1e-13 * want.norm(),
                "start {}",
                m.start
            );
        }
        // Without the warm entries the same refit stays on its start poles.
        let cold = run_once(
            &frf,
            &poles,
            &[],
            &again,
            again.max_iterations,
            &mut |_, _| {},
            varpro::evaluate,
        )
        .unwrap();
        for m in &cold.modes {
            let want = poles[m.start];
            assert!(
                (m.pole - want).norm() <= 1e-13 * want.norm(),
                "start {}",
                m.start
            );
        }
    }
}

//! The route an identification takes where the caller leaves a choice open.
//!
//! Two presets fill the choices a caller does not make:
//!
//! - [`Preset::Measured`], the default, is the route measured FRFs need: the order from
//!   the stabilization diagram, a maximum-likelihood refinement of poles, residues and
//!   residual terms over the excited band, a continuous-time model (measured FRFs are
//!   continuous-time data), and the direct term the quantity implies.
//! - [`Preset::Thesis`] is plain ERA as the thesis runs it: no refinement, the discrete
//!   model, `D = 0`, every line, the FRFs as given.
//!
//! An explicit choice always wins over the preset. Every choice comes back as a
//! [`Choice`] with the reason it was made, so a front end can echo the route it took.
//! The texts name options in words, not in any front end's spelling.

use crate::data::frf::Quantity;
use crate::identify::ModelDomain;
use crate::pipeline::realize::DirectTerm;

/// Which defaults fill the choices a caller leaves open.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Preset {
    /// The route for measured FRFs (see the module documentation).
    #[default]
    Measured,
    /// Plain ERA with the thesis's settings.
    Thesis,
}

impl Preset {
    /// `measured` or `thesis`.
    pub fn name(self) -> &'static str {
        crate::params::names::Named::name_of(&self)
    }

    /// Parses `measured` or `thesis` (case-insensitive).
    pub fn parse(text: &str) -> Option<Preset> {
        crate::params::names::parse(text).ok()
    }
}

/// What the caller asked for: `None` leaves the choice to the preset.
#[derive(Debug, Clone, Default, PartialEq)]
#[non_exhaustive]
pub struct RouteRequest {
    /// Which defaults fill the open choices.
    pub preset: Preset,
    /// A fixed order (first-order states), or `None` for the order the stabilization
    /// diagram finds.
    pub states: Option<usize>,
    /// Refine the ERA model by maximum likelihood.
    pub refine: Option<bool>,
    /// The domain of the model returned.
    pub domain: Option<ModelDomain>,
    /// The model's `D`.
    pub direct_term: Option<DirectTerm>,
    /// Identify over the band where the coherence says the test carried information.
    pub coherence_band: Option<bool>,
    /// The band the caller gives, Hz: it replaces the coherence's.
    pub band_hz: Option<(f64, f64)>,
    /// Divide a Welch estimate's lag window out of the FRFs when their metadata names it.
    pub window_correction: Option<bool>,
    /// Whether the front end's data can carry a coherence and window metadata (files
    /// and time histories can; a bare array cannot): without, neither is used, and the
    /// echo says why.
    pub without_metadata: bool,
    /// Where the Markov parameters come from: with OKID's, the measured preset does not
    /// refine (the FRFs beside them are Welch estimates, whose bias a refinement
    /// against them would bring back).
    pub markov: crate::sources::MarkovSource,
}

/// One choice of the route: what was chosen and why.
#[derive(Debug, Clone, PartialEq)]
pub struct Choice {
    /// The option, in words ("order", "refinement", "time domain", …).
    pub name: &'static str,
    /// The value chosen, in words.
    pub value: String,
    /// Why: the caller's choice, or the preset's reason.
    pub reason: String,
}

/// The resolved route: every choice made, with its reasons in [`Route::choices`] and
/// the cautions about explicit choices that cost accuracy in [`Route::cautions`].
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct Route {
    /// Which preset filled the open choices.
    pub preset: Preset,
    /// A fixed order, or `None` for the automatic order.
    pub states: Option<usize>,
    /// Whether the ERA model is refined.
    pub refine: bool,
    /// The domain of the model returned.
    pub domain: ModelDomain,
    /// The model's `D`.
    pub direct_term: DirectTerm,
    /// Whether the band comes from the coherence (when there is one).
    pub coherence_band: bool,
    /// Whether a Welch estimate's lag window is divided out.
    pub window_correction: bool,
    /// Every choice with its reason, in the order above.
    pub choices: Vec<Choice>,
    /// Explicit choices that make the result worse than the preset's would.
    pub cautions: Vec<String>,
}

impl RouteRequest {
    /// A request that leaves every choice to `preset`.
    pub fn new(preset: Preset) -> Self {
        RouteRequest {
            preset,
            ..RouteRequest::default()
        }
    }

    /// Resolves the open choices for FRFs of `quantity` after `integrations`
    /// integrations (the quantity ERA sees decides the direct term).
    pub fn resolve(&self, quantity: Quantity, integrations: usize) -> Route {
        let measured = self.preset == Preset::Measured;
        let preset = format!("the {} preset", self.preset.name());
        let given = || "as asked".to_string();
        let mut choices = Vec::new();
        let mut cautions = Vec::new();

        let states = self.states;
        choices.push(Choice {
            name: "order",
            value: states.map_or("automatic".into(), |n| format!("{n} states")),
            reason: match states {
                Some(_) => given(),
                None => "from the stabilization diagram: the orders the data supports are scanned and the modes that stay are kept".into(),
            },
        });

        let okid = self.markov == crate::sources::MarkovSource::Okid;
        let refine = self.refine.unwrap_or(measured && !okid);
        choices.push(Choice {
            name: "refinement",
            value: if refine { "on" } else { "off" }.into(),
            reason: match self.refine {
                Some(_) => given(),
                None if measured && okid => format!("{preset} with OKID: the observer's Markov parameters carry no window and no leakage, and a refinement against the Welch FRFs would bring their bias back (ask for the refinement to refine anyway)"),
                None if measured => format!("{preset}: poles, residues and residual terms by maximum likelihood over the band, with standard deviations"),
                None => format!("{preset}: plain ERA"),
            },
        });

        let domain = self.domain.unwrap_or(if measured && refine {
            ModelDomain::Continuous
        } else {
            ModelDomain::Discrete
        });
        choices.push(Choice {
            name: "time domain",
            value: match domain {
                ModelDomain::Discrete => "discrete",
                ModelDomain::Continuous => "continuous",
            }
            .into(),
            reason: match self.domain {
                Some(_) => given(),
                None if !measured => format!("{preset}: the discrete model ERA realizes"),
                None if refine => format!("{preset}: measured FRFs are continuous-time data, and the refinement fits the model in that domain"),
                None => format!("{preset} without refinement: the discrete model ERA realizes (converted without a refinement it would fit worse)"),
            },
        });
        if self.domain == Some(ModelDomain::Continuous) && !refine {
            cautions.push("a continuous-time model without refinement is the zero-order-hold inverse of ERA's discrete model, which fits sampled-at-lines FRFs worse than the discrete model does; refine to fit it in continuous time".into());
        }

        let seen = (0..integrations).try_fold(quantity, |q, _| q.integrated());
        let direct_term = self.direct_term.unwrap_or(match (measured, seen) {
            (true, Some(Quantity::Acceleration)) => DirectTerm::FirstMarkov,
            _ => DirectTerm::Zero,
        });
        choices.push(Choice {
            name: "direct term",
            value: match direct_term {
                DirectTerm::Zero => "D = 0",
                DirectTerm::FirstMarkov => "D = Y0",
            }
            .into(),
            reason: match (self.direct_term, seen) {
                (Some(_), _) => given(),
                (None, _) if !measured => preset.clone(),
                (None, Some(Quantity::Acceleration)) => format!("{preset}: an accelerance tends to a constant above its modes, which the time-zero Markov block carries{}", if refine { "; the refined model's D is its upper residual" } else { "" }),
                (None, Some(q)) => format!("{preset}: a {} FRF has no direct term", q.name()),
                (None, None) => preset.clone(),
            },
        });
        if self.direct_term == Some(DirectTerm::Zero)
            && seen == Some(Quantity::Acceleration)
            && !refine
        {
            cautions.push("D = 0 on accelerance: the collocated pairs' constant above the modes is left out of the model, and their fit suffers (D = Y0 carries it)".into());
        }

        let bare = "this data carries no coherence or window metadata (an array, not a file)";
        let coherence_band = self.band_hz.is_none()
            && !self.without_metadata
            && self.coherence_band.unwrap_or(measured);
        choices.push(Choice {
            name: "band",
            value: match self.band_hz {
                Some((lo, hi)) => format!("{lo}..{hi} Hz"),
                None if coherence_band => "from the coherence".into(),
                None => "every line".into(),
            },
            reason: match (self.band_hz, self.coherence_band) {
                (Some(_), _) | (None, Some(_)) => given(),
                _ if self.without_metadata => bare.to_string(),
                _ if measured => format!("{preset}: where the coherence shows the test excited the structure, when the data has a coherence"),
                _ => preset.clone(),
            },
        });

        let window_correction =
            !self.without_metadata && self.window_correction.unwrap_or(measured);
        choices.push(Choice {
            name: "window correction",
            value: if window_correction { "on" } else { "off" }.into(),
            reason: match self.window_correction {
                Some(_) => given(),
                None if self.without_metadata => bare.to_string(),
                None if measured => format!("{preset}: a Welch estimate's lag window, when the data's metadata names it, biases damping and adds doublets"),
                None => format!("{preset}: the FRFs as given"),
            },
        });

        Route {
            preset: self.preset,
            states,
            refine,
            domain,
            direct_term,
            coherence_band,
            window_correction,
            choices,
            cautions,
        }
    }
}

impl Route {
    /// The domain ERA realizes in on this route: a refined route realizes in discrete
    /// time, ERA's own, and the refinement returns [`Route::domain`] (a discrete
    /// realization with a negative real pole has no continuous image to start from).
    pub fn realization_domain(&self) -> ModelDomain {
        if self.refine {
            ModelDomain::Discrete
        } else {
            self.domain
        }
    }

    /// The choices as lines `name: value (reason)`, for an echo.
    pub fn echo(&self) -> Vec<String> {
        self.choices
            .iter()
            .map(|c| format!("{}: {} ({})", c.name, c.value, c.reason))
            .collect()
    }
}

crate::params::names::named!(display Preset, "preset", [
    Preset::Measured => "measured",
    Preset::Thesis => "thesis",
]);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_measured_preset_refines_in_continuous_time_with_the_quantitys_direct_term() {
        let r = RouteRequest::default().resolve(Quantity::Acceleration, 0);
        assert_eq!(r.states, None);
        assert!(r.refine && r.coherence_band && r.window_correction);
        assert_eq!(r.domain, ModelDomain::Continuous);
        assert_eq!(r.direct_term, DirectTerm::FirstMarkov);
        assert!(r.cautions.is_empty());
        // One integration: velocity, no direct term.
        let r = RouteRequest::default().resolve(Quantity::Acceleration, 1);
        assert_eq!(r.direct_term, DirectTerm::Zero);
        let r = RouteRequest::default().resolve(Quantity::Displacement, 0);
        assert_eq!(r.direct_term, DirectTerm::Zero);
    }

    #[test]
    fn the_thesis_preset_is_plain_era_and_explicit_choices_win() {
        let r = RouteRequest::new(Preset::Thesis).resolve(Quantity::Acceleration, 0);
        assert!(!r.refine && !r.coherence_band && !r.window_correction);
        assert_eq!(r.domain, ModelDomain::Discrete);
        assert_eq!(r.direct_term, DirectTerm::Zero);
        let mut q = RouteRequest::new(Preset::Thesis);
        q.states = Some(8);
        q.refine = Some(true);
        q.direct_term = Some(DirectTerm::FirstMarkov);
        let r = q.resolve(Quantity::Acceleration, 0);
        assert_eq!(r.states, Some(8));
        assert!(r.refine);
        // The thesis's domain stays unless asked for.
        assert_eq!(r.domain, ModelDomain::Discrete);
        assert_eq!(r.direct_term, DirectTerm::FirstMarkov);
        assert_eq!(r.choices[1].reason, "as asked");
    }

    #[test]
    fn measured_without_refinement_stays_discrete_and_a_continuous_request_is_cautioned() {
        let mut q = RouteRequest {
            refine: Some(false),
            ..RouteRequest::default()
        };
        let r = q.resolve(Quantity::Acceleration, 0);
        assert_eq!(r.domain, ModelDomain::Discrete);
        assert!(r.cautions.is_empty());
        q.domain = Some(ModelDomain::Continuous);
        q.direct_term = Some(DirectTerm::Zero);
        let r = q.resolve(Quantity::Acceleration, 0);
        assert_eq!(r.cautions.len(), 2, "{:?}", r.cautions);
        assert_eq!(r.echo().len(), r.choices.len());
    }

    #[test]
    fn a_given_band_and_bare_data_are_said_as_such() {
        let q = RouteRequest {
            band_hz: Some((60.0, 500.0)),
            ..RouteRequest::default()
        };
        let r = q.resolve(Quantity::Acceleration, 0);
        assert!(!r.coherence_band && r.window_correction);
        assert_eq!(r.choices[4].value, "60..500 Hz");
        assert_eq!(r.choices[4].reason, "as asked");
        let q = RouteRequest {
            without_metadata: true,
            ..RouteRequest::default()
        };
        let r = q.resolve(Quantity::Acceleration, 0);
        assert!(!r.coherence_band && !r.window_correction);
        assert!(r.choices[5]
            .reason
            .contains("no coherence or window metadata"));
    }

    #[test]
    fn presets_parse_by_name() {
        for p in [Preset::Measured, Preset::Thesis] {
            assert_eq!(Preset::parse(p.name()), Some(p));
        }
        assert_eq!(Preset::parse(" Thesis "), Some(Preset::Thesis));
        assert_eq!(Preset::parse("fast"), None);
    }
}

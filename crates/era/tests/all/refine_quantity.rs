//! A refinement fitted in one quantity and realised in an integral of it is the
//! integral of the fit: the modes' polynomial part that the data's upper residual
//! absorbed is carried over (`Refinement::residual_terms`). With acceleration data and
//! its constant term, the velocity and displacement models of an exact structure are
//! that structure's velocity and displacement FRFs.

use era::pipeline::fit::frequency_response;
use era::refine::{refine, RefineOptions, Residuals};
use era::sim::{ModalSpec, ModalStructure};
use era::{Complex64, Quantity};

fn relative(a: &[Complex64], b: &[Complex64]) -> f64 {
    let num: f64 = a.iter().zip(b).map(|(x, y)| (x - y).norm_sqr()).sum();
    let den: f64 = b.iter().map(|y| y.norm_sqr()).sum();
    (num / den).sqrt()
}

#[test]
fn integrals_of_an_acceleration_fit_are_the_structure_s_integrals() {
    let spec = ModalSpec {
        fmin_hz: 2.0,
        fmax_hz: 8.0,
        seed: 5,
        ..ModalSpec::new(3, 2, 4)
    };
    let s = ModalStructure::random(&spec).unwrap();
    let frf = s.frf(401, 0.025, Quantity::Acceleration).unwrap();
    let start: Vec<Complex64> = s
        .poles()
        .iter()
        .map(|p| Complex64::new(p.re * 1.1, p.im * (1.0 + 2e-4)))
        .collect();
    // (Without the constant the acceleration modal sum cannot be the data.)
    for residuals in [Residuals::Upper, Residuals::Both] {
        let mut options = {
            let mut o = RefineOptions::default();
            o.weighting = era::refine::Weighting::Uniform;
            o
        };
        options.residuals = residuals;
        let r = refine(&frf, &start, &options, &mut |_, _| {}).unwrap();
        let freq: Vec<f64> = frf.frequency_hz()[1..].to_vec();
        for out in [Quantity::Velocity, Quantity::Displacement] {
            let truth = s.frf(401, 0.025, out).unwrap();
            let lines = truth.lines();
            let want: Vec<Complex64> = (0..truth.outputs() * truth.inputs())
                .flat_map(|pair| truth.values()[pair * lines + 1..(pair + 1) * lines].to_vec())
                .collect();
            let own = r.response(&freq, out);
            let e = relative(&own, &want);
            assert!(e < 1e-8, "{residuals:?}, {out}: response {e:e}");
            let ss = r.to_state_space(out).unwrap();
            let g = frequency_response(&ss, &freq).unwrap();
            let e = relative(&g, &want);
            assert!(e < 1e-8, "{residuals:?}, {out}: state space {e:e}");
        }
        assert!(r.fit_after < 1e-10, "{residuals:?}: {}", r.fit_after);
    }
}

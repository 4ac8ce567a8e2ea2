//! Paper 004's network learned from trial cuts (issue 32): on forces from the mechanistic model
//! it recovers the model's exponents within the uncertainty it states; on the lab's current-based
//! estimates of the same cuts it moves by a stated amount.
// Test code: unwrapping and panicking on a broken expectation is the point.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use cutlab::estimation::cut_forces::CutGeometry;
use cutlab::estimation::power_law_fit::{
    learn, local_exponent, mechanistic_resultant_n, stepped_specimen, TrialCut,
};
use cutlab::plant::materials::Material;
use cutlab::plant::mechanics::{Cutter, MillingMode};
use cutlab::plant::power_law::{PowerLawInput, PowerLawInputs, PowerLawMaterial, PowerLawReading};

/// The mechanistic mean resultant of a Ø20 mm two-tooth cutter in SM45C, down milling, N.
fn mechanistic_n(p: &PowerLawInputs) -> f64 {
    let cut = CutGeometry {
        cutter: Cutter::new(20.0, 2, 30.0).unwrap(),
        mode: MillingMode::Down,
        coefficients: Material::Sm45c.coefficients(),
    };
    mechanistic_resultant_n(&cut, p)
}

#[test]
fn trial_cuts_on_the_mechanistic_model_give_its_exponents_within_the_stated_uncertainty() {
    let cuts: Vec<TrialCut> = stepped_specimen(20.0, 2)
        .into_iter()
        .map(|inputs| TrialCut {
            inputs,
            force_n: mechanistic_n(&inputs),
        })
        .collect();
    let law = learn(
        &cuts,
        PowerLawReading::Handbook,
        PowerLawMaterial::CarbonSteel,
    )
    .unwrap();
    // The mechanistic model is no power law (the edge forces make the feed's exponent
    // K_c·f / (K_c·f + K_e), the width's depends on the immersion): its exponent is the local
    // d ln F / d ln p, which varies over the specimen. The learned one lies within that range,
    // widened by the uncertainty the fit states.
    let specimen = stepped_specimen(20.0, 2);
    for input in [
        PowerLawInput::RadialWidth,
        PowerLawInput::FeedPerTooth,
        PowerLawInput::AxialDepth,
    ] {
        let learned = law.exponent(input).unwrap();
        let local: Vec<f64> = specimen
            .iter()
            .map(|at| local_exponent(mechanistic_n, at, input))
            .collect();
        let lo = local.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = local.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        assert!(
            learned.exponent >= lo - learned.uncertainty
                && learned.exponent <= hi + learned.uncertainty,
            "{}: learned {} ± {}, the model's {lo}–{hi}",
            input.symbol(),
            learned.exponent,
            learned.uncertainty
        );
        // Physically: force proportional to the depth, less than proportional to the feed
        // (the edge forces), and rising with the width.
        assert!(learned.uncertainty < 0.1, "{learned:?}");
    }
    assert!((law.exponent(PowerLawInput::AxialDepth).unwrap().exponent - 1.0).abs() < 1e-6);
    let feed = law.exponent(PowerLawInput::FeedPerTooth).unwrap().exponent;
    assert!(feed > 0.5 && feed < 1.0, "{feed}");
    // One cutter: its diameter and teeth are held at the published exponents.
    assert_eq!(law.held.len(), 2);
    // The network reproduces the trial cuts within a few percent.
    assert!(
        law.residuals_pct.iter().all(|r| r.abs() < 5.0),
        "{:?}",
        law.residuals_pct
    );
}

#[test]
fn learned_on_the_current_based_estimates_the_weights_move_by_little() {
    use cutlab::closed_loop::trial_cuts::{preset_trial_cuts, DEFAULT_TRIAL_FEEDS_PCT};
    use cutlab::plant::Preset;

    let cuts = preset_trial_cuts(Preset::KimStepDoc, &DEFAULT_TRIAL_FEEDS_PCT)
        .unwrap()
        .unwrap();
    assert_eq!(cuts.material, PowerLawMaterial::CarbonSteel);
    let (truth, estimated) = (&cuts.measured, &cuts.estimated);
    assert!(truth.len() >= 12, "{} sections", truth.len());
    let from_truth = learn(
        truth,
        PowerLawReading::Handbook,
        PowerLawMaterial::CarbonSteel,
    )
    .unwrap();
    let from_estimates = learn(
        estimated,
        PowerLawReading::Handbook,
        PowerLawMaterial::CarbonSteel,
    )
    .unwrap();
    for input in [PowerLawInput::FeedPerTooth, PowerLawInput::AxialDepth] {
        let t = from_truth.exponent(input).unwrap();
        let e = from_estimates.exponent(input).unwrap();
        // The estimate is a calibrated line of the current: its idle offset and noise move the
        // exponents, by less than the published exponents' own uncertainty between machines.
        assert!(
            (t.exponent - e.exponent).abs() < cutlab::plant::power_law::EXPONENT_UNCERTAINTY / 2.0,
            "{}: {} from the force, {} from the estimate",
            input.symbol(),
            t.exponent,
            e.exponent
        );
    }
    assert!(
        (from_estimates.bias_n / from_truth.bias_n - 1.0).abs() < 0.2,
        "bias {} against {}",
        from_estimates.bias_n,
        from_truth.bias_n
    );
}

/// The networks the plant ships for its sensorless estimate are what the mill presets learn
/// today from their current-based estimates (`cutlab learn --shipped-networks`, run by
/// scripts/sample-data, writes them again when the plant, the chain or the learning changes),
/// and kim-step-doc, whose program steps its depth, has one.
#[cfg(not(target_arch = "wasm32"))]
#[test]
fn the_shipped_networks_are_what_the_presets_learn_today() {
    use cutlab::closed_loop::trial_cuts::preset_networks;
    use cutlab::plant::sensorless::shipped_networks;
    use cutlab::plant::Preset;

    let learned = preset_networks().unwrap();
    assert_eq!(
        shipped_networks(),
        learned,
        "www/data/sensorless-networks.json is stale: run scripts/sample-data"
    );
    assert!(learned.iter().any(|(p, _)| *p == Preset::KimStepDoc));
}

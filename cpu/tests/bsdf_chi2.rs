//! Chi-square goodness of fit of every BSDF's `sample` against its `pdf`
//! (plus its delta lobes and rejected samples), and a test that the test
//! itself rejects a wrong density.

mod common;

use common::*;
use glam::Vec3;
use glint_cpu::bsdf::{Bsdf, Shadowing};
use rayon::prelude::*;

const SAMPLES: usize = 1_000_000;
const ALPHA: f64 = 0.01;

fn run_case(case: &Case, seed: u64) -> Result<Chi2Report, String> {
    let bsdf = case.bsdf;
    let wo = case.wo;
    let deltas = delta_lobes(&bsdf, wo);
    chi2_test(
        &|uc, u| bsdf.sample(wo, uc, u).map(|s| (s.wi, s.delta)),
        &|wi| bsdf.pdf(wo, wi) as f64,
        &deltas,
        SAMPLES,
        seed,
        &Grid::for_case(&bsdf, wo),
    )
}

#[test]
fn sampling_matches_pdf() {
    let cases = chi2_cases();
    let level = sidak(ALPHA, cases.len());
    let results: Vec<(String, Result<Chi2Report, String>)> = cases
        .par_iter()
        .enumerate()
        .map(|(i, c)| (c.name.clone(), run_case(c, 1000 + i as u64)))
        .collect();
    let mut failures = Vec::new();
    for (name, r) in &results {
        match r {
            Err(e) => failures.push(format!("{name}: {e}")),
            // The density plus delta masses never integrate above 1 (an
            // error from chi2_test), and with the rejected fraction they
            // account for every sample (the statistic's "lost" bin).
            Ok(r) => {
                if r.p_value < level {
                    failures.push(format!("{name}: rejected, {r:?}"));
                }
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} failed (level {level:.2e}):\n{}",
        failures.len(),
        results.len(),
        failures.join("\n")
    );
}

/// The test has power: a density with alpha 10% too large, and a cos^1.1
/// density for a cosine sampler, are both rejected at the suite's level.
#[test]
fn chi2_rejects_wrong_densities() {
    let level = sidak(ALPHA, chi2_cases().len());
    let wo = dir_cos(0.6, PHI_O);
    let right = Bsdf::Conductor(gold(rough(0.3, 0.3, Shadowing::Correlated)));
    let wrong = Bsdf::Conductor(gold(rough(0.33, 0.33, Shadowing::Correlated)));
    let r = chi2_test(
        &|uc, u| right.sample(wo, uc, u).map(|s| (s.wi, s.delta)),
        &|wi| wrong.pdf(wo, wi) as f64,
        &[],
        SAMPLES,
        7,
        &Grid::new(20, 40),
    );
    // Detected by the normalisation check or by the statistic.
    assert!(
        r.as_ref().map_or(true, |r| r.p_value < level),
        "alpha +10% not detected: {r:?}"
    );

    let diffuse = Bsdf::Diffuse {
        reflectance: Vec3::ONE,
    };
    let r = chi2_test(
        &|uc, u| diffuse.sample(wo, uc, u).map(|s| (s.wi, s.delta)),
        // Normalised cos^1.1 density: (a + 1) / (2 pi) cos^a.
        &|wi| {
            if wi.z > 0.0 {
                2.1 / (2.0 * std::f64::consts::PI) * (wi.z as f64).powf(1.1)
            } else {
                0.0
            }
        },
        &[],
        SAMPLES,
        8,
        &Grid::new(20, 40),
    )
    .unwrap();
    assert!(r.p_value < level, "cos^1.1 not detected: {r:?}");

    // And the right density passes for the same sampler and seed.
    let r = chi2_test(
        &|uc, u| right.sample(wo, uc, u).map(|s| (s.wi, s.delta)),
        &|wi| right.pdf(wo, wi) as f64,
        &[],
        SAMPLES,
        7,
        &Grid::new(20, 40),
    )
    .unwrap();
    assert!(r.p_value >= level, "{r:?}");
}

//! The error of an unbiased estimator falls as 1/spp: the slope of log
//! relMSE against log spp is -1. The check measures it on a scene whose
//! exact image is known, with a tolerance derived from the noise of the
//! relMSE estimates themselves, and shows that a biased image (scaled by a
//! few percent) flattens the slope enough to fail the same check.

mod render_common;

use glam::Vec3;
use glint_cpu::metrics::{ImageRef, relmse};
use glint_cpu::{Film, Material, RenderOptions, SamplerKind};
use render_common::*;

const SIZE: u32 = 48;
const RHO: f32 = 0.5;
const DEPTH: i32 = 4;

/// Inside a closed sphere whose wall is diffuse (albedo RHO) and emits 1
/// on both sides: with paths of at most DEPTH segments the radiance is
/// exactly 1 + RHO + ... + RHO^(DEPTH-1) everywhere (each vertex adds the
/// emission of the next), while MIS between light and BSDF samples makes
/// every sample noisy. A sphere rather than a box: inside it the geometry
/// term between two wall points is bounded, so the noise has light tails
/// and the 1/spp law holds already at a few samples (a box's edges give
/// light samples of unbounded weight).
fn furnace() -> (glint_cpu::Scene, f32) {
    let wall = Material {
        name: "glowing wall".into(),
        emission: Vec3::ONE,
        double_sided: true,
        absorption: glam::Vec3::ZERO,
        ..diffuse("wall", RHO)
    };
    let s = scene(
        uv_sphere(Vec3::ZERO, 1.0, 32, 16, 0),
        vec![wall],
        vec![],
        look_at(
            Vec3::new(0.2, 0.1, 0.5),
            Vec3::new(-0.3, -0.2, -1.0),
            Vec3::Y,
            70.0,
        ),
        Vec3::ZERO,
    );
    let exact = (0..DEPTH).map(|k| RHO.powi(k)).sum();
    (s, exact)
}

/// Per-pixel relative squared errors against the constant `exact`, scaled
/// by `scale` (1: the renderer's image; otherwise a biased one).
fn errors(film: &Film, exact: f32, scale: f32) -> Vec<f64> {
    let reference = vec![Vec3::splat(exact); film.sum.len()];
    let means: Vec<Vec3> = film.means().iter().map(|m| *m * scale).collect();
    (0..means.len())
        .map(|i| {
            let one = ImageRef::new(1, 1, &means[i..i + 1]).unwrap();
            let rr = ImageRef::new(1, 1, &reference[i..i + 1]).unwrap();
            relmse(&one, &rr).unwrap()
        })
        .collect()
}

/// relMSE (the mean of the per-pixel errors) and its standard error:
/// pixels draw independent random streams, so their errors are independent.
fn mean_and_se(e: &[f64]) -> (f64, f64) {
    let n = e.len() as f64;
    let m = e.iter().sum::<f64>() / n;
    let var = e.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1.0);
    (m, (var / n).sqrt())
}

/// The slope between two sample counts and its standard deviation (delta
/// method: sd(ln m) = se / m).
fn slope(lo: (u32, &[f64]), hi: (u32, &[f64])) -> (f64, f64) {
    let (m1, se1) = mean_and_se(lo.1);
    let (m2, se2) = mean_and_se(hi.1);
    let dx = (hi.0 as f64 / lo.0 as f64).ln();
    let s = (m2 / m1).ln() / dx;
    let sd = ((se1 / m1).powi(2) + (se2 / m2).powi(2)).sqrt() / dx;
    (s, sd)
}

#[test]
fn relmse_falls_as_one_over_spp_and_a_biased_image_does_not() {
    let (s, exact) = furnace();
    let (n1, n2) = (4u32, 64u32);
    // Independent seeds, so the two estimates are independent.
    // SEED=n explores other seeds (the check must hold for any).
    let seed: u64 = std::env::var("SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(11);
    // Independent sampling: Monte Carlo's 1/spp law. (Owen-scrambled Sobol
    // points converge faster than 1/spp on smooth integrands: measured
    // slope -1.11 here, which is why they are the default.)
    let mc = |spp, seed| RenderOptions {
        sampler: SamplerKind::Independent,
        ..opts(SIZE, spp, DEPTH, seed)
    };
    let lo = render(&s, &mc(n1, seed));
    let hi = render(&s, &mc(n2, seed + 1));

    let (e1, e2) = (errors(&lo, exact, 1.0), errors(&hi, exact, 1.0));
    let (k, sd) = slope((n1, &e1), (n2, &e2));
    assert!(sd > 0.0 && sd < 0.05, "the test has no power: sd {sd}");
    let z = (k + 1.0) / sd;
    assert!(z.abs() < 4.0, "unbiased slope {k:.4} +- {sd:.4} (z {z:.2})");

    // A 2% scaled image converges to the wrong answer: its error stops
    // falling, and the same check must fail.
    let (b1, b2) = (errors(&lo, exact, 1.02), errors(&hi, exact, 1.02));
    let (kb, sdb) = slope((n1, &b1), (n2, &b2));
    let zb = (kb + 1.0) / sdb;
    assert!(
        zb.abs() > 4.0,
        "biased slope {kb:.4} +- {sdb:.4} passed (z {zb:.2})"
    );
    eprintln!("slope {k:.4} +- {sd:.4}; 2% biased: {kb:.4} +- {sdb:.4}");
}

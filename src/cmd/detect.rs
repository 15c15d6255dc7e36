//! `detect = delta` in a `glint test` suite: the samples per pixel at which
//! `glint diff`'s block test (`glint_cpu::compare`) catches a uniform
//! relative change `delta` of the image with probability at least
//! [`POWER`], from a pilot render's variance.
//!
//! The rule. A block B (8x8 and every coarser level up to the whole image,
//! as `compare` tiles them) and channel c has mean m (the mean of its pixel
//! means) and, for one sample per pixel, variance of the mean
//! s^2 = sum_i (var_i x pilot_spp) / n^2 (var_i: the pilot's variance of
//! pixel i's mean). Scaling the image by (1 + delta) shifts the block's
//! difference by delta x m, so at N spp against a reference whose block
//! variance is V_ref the expected z is delta m / sqrt(s^2 / N + V_ref). The
//! local test rejects when |z| exceeds z_t, the Sidak threshold for the T
//! block-channel tests at alpha / 2 (`compare`'s split); the observed z is
//! normal around its expectation with unit variance, so
//! P(caught) >= Phi(E z - z_t) >= POWER once E z >= z_t + z_POWER, i.e.
//!
//!     N >= s^2 / ((delta m)^2 / (z_t + z_POWER)^2 - V_ref),
//!
//! taking the smallest N over blocks and channels (one block that catches
//! the change suffices; the global count test only adds power). Where the
//! reference does not exist yet (`--update`), V_ref is what a reference of
//! [`REF_FACTOR`] x N spp will hold: s^2 / (REF_FACTOR N).

use glam::DVec3;
use glint::cpu::compare::normal_quantile;
use glint::cpu::exr_file::RadianceImage;

/// The detection probability the chosen spp guarantees.
pub const POWER: f64 = 0.9;
/// References take this many times the tests' samples.
pub const REF_FACTOR: u32 = 4;
/// compare's finest block edge.
const BLOCK: u32 = 8;

/// Per block level, per block: (mean, per-sample variance of the mean).
fn levels(img: &RadianceImage, pilot_spp: u32) -> Vec<Vec<(DVec3, DVec3)>> {
    let var = img.variance.as_deref().unwrap_or(&[]);
    let mut out = Vec::new();
    let mut edge = BLOCK;
    loop {
        let bx = img.width.div_ceil(edge);
        let by = img.height.div_ceil(edge);
        let mut acc = vec![(DVec3::ZERO, DVec3::ZERO, 0u32); (bx * by) as usize];
        for y in 0..img.height {
            for x in 0..img.width {
                let i = (y * img.width + x) as usize;
                let b = &mut acc[((y / edge) * bx + x / edge) as usize];
                b.0 += img.mean[i].as_dvec3();
                b.1 += var.get(i).map_or(DVec3::ZERO, |v| v.as_dvec3());
                b.2 += 1;
            }
        }
        out.push(
            acc.into_iter()
                .filter(|a| a.2 > 0)
                .map(|(s, v, n)| {
                    let n = n as f64;
                    (s / n, v * pilot_spp as f64 / (n * n))
                })
                .collect(),
        );
        if bx * by <= 1 {
            return out;
        }
        edge *= 2;
    }
}

/// The spp at which a relative change `delta` is caught with probability
/// [`POWER`] at `alpha` (module notes), at most `cap`. `pilot` holds
/// variance from a render of `pilot_spp` samples; `reference`, when given,
/// is the reference the test will diff against (same size).
pub fn required_spp(
    pilot: &RadianceImage,
    pilot_spp: u32,
    reference: Option<&RadianceImage>,
    delta: f64,
    alpha: f64,
    cap: u32,
) -> u32 {
    let lv = levels(pilot, pilot_spp);
    let tests: usize = lv.iter().map(|l| 3 * l.len()).sum();
    let a_local = 1.0 - (1.0 - alpha / 2.0).powf(1.0 / tests.max(1) as f64);
    let z = normal_quantile(1.0 - a_local / 2.0) + normal_quantile(POWER);
    let ref_var: Option<Vec<Vec<(DVec3, DVec3)>>> = reference.map(|r| levels(r, 1));
    let mut best = f64::INFINITY;
    for (li, level) in lv.iter().enumerate() {
        for (bi, &(m, s2)) in level.iter().enumerate() {
            for c in 0..3 {
                let shift2 = (delta * m[c]).powi(2) / (z * z);
                let n = match &ref_var {
                    // V_ref known: N >= s^2 / (shift^2 / z^2 - V_ref).
                    Some(r) => {
                        let v_ref = r[li][bi].1[c];
                        let room = shift2 - v_ref;
                        if room > 0.0 {
                            s2[c] / room
                        } else {
                            f64::INFINITY
                        }
                    }
                    // V_ref = s^2 / (REF_FACTOR N).
                    None => s2[c] * (1.0 + 1.0 / REF_FACTOR as f64) / shift2,
                };
                if n.is_finite() && n >= 0.0 {
                    best = best.min(n);
                }
            }
        }
    }
    if best.is_finite() {
        (best.ceil() as u32).clamp(1, cap)
    } else {
        cap
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn image(size: u32, mean: f32, var: f32) -> RadianceImage {
        let n = (size * size) as usize;
        RadianceImage {
            width: size,
            height: size,
            mean: vec![Vec3::splat(mean); n],
            variance: Some(vec![Vec3::splat(var); n]),
            meta: None,
        }
    }

    #[test]
    fn noisier_needs_more_and_smaller_changes_need_more() {
        let quiet = image(16, 1.0, 1e-3);
        let noisy = image(16, 1.0, 4e-3);
        let a = required_spp(&quiet, 16, None, 0.02, 1e-3, 1 << 20);
        let b = required_spp(&noisy, 16, None, 0.02, 1e-3, 1 << 20);
        assert!(b > 3 * a && b < 5 * a, "{a} {b}");
        let c = required_spp(&quiet, 16, None, 0.01, 1e-3, 1 << 20);
        assert!(c > 3 * a && c < 5 * a, "{a} {c}");
        // The cap wins where the rule asks for more.
        assert!(b > 10, "{b}");
        assert_eq!(required_spp(&noisy, 16, None, 0.02, 1e-3, 10), 10);
    }

    #[test]
    fn matches_the_closed_form_for_one_block() {
        // 8x8: a single block; s^2 = var x spp / 64 per channel.
        let img = image(8, 2.0, 0.01);
        let (delta, alpha) = (0.05, 1e-3);
        let a_local = 1.0 - (1.0 - alpha / 2.0f64).powf(1.0 / 3.0);
        let z = normal_quantile(1.0 - a_local / 2.0) + normal_quantile(POWER);
        let s2 = 0.01f32 as f64 * 16.0 / 64.0;
        let want = (s2 * 1.25 * z * z / (delta * 2.0f64).powi(2)).ceil() as u32;
        assert_eq!(required_spp(&img, 16, None, delta, alpha, 1 << 20), want);
        // A reference noisier than the REF_FACTOR x N spp one the rule
        // assumes leaves less room: more samples (its block variance
        // 0.02 / 64 against the assumed s^2 / (4 x 8)).
        let reference = image(8, 2.0, 0.02);
        let with_ref = required_spp(&img, 16, Some(&reference), delta, alpha, 1 << 20);
        assert!(with_ref > want, "{with_ref} {want}");
    }
}

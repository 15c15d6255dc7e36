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
//!
//! One material. A change confined to one material moves only the pixels
//! that see it, so the uniform rule under-sizes it (a 2% change of a floor's
//! dark tiles is a small part of 2% of any block that holds light tiles
//! too). Every non-emitting material that covers at least
//! [`MATERIAL_SHARE`] of the image (by primary hit) is a change of its own
//! ([`material_changes`]): from [`SHARE_SPP`] path samples per pixel, split
//! by the material their camera ray hits first, pixel i moves by delta x
//! L_i,k (the mean over the pixel's samples of the radiance of those whose
//! first hit is material k), so a block's shift is delta times the block
//! mean of L_i,k. That is a lower bound of the true shift when what the
//! material reflects is scaled by 1 +- delta (every such path scales so,
//! paths that meet the material later add more, and a light's material,
//! whose pixels show emission, is left out), so the N it gives is enough.
//! The rule takes, per change, the smallest N over blocks and channels, and
//! the largest over the changes: every one of them is caught with
//! probability at least [`POWER`].

use glam::{DVec3, Vec3};
use glint::cpu::compare::normal_quantile;
use glint::cpu::exr_file::RadianceImage;
use glint::cpu::integrator::PathTracer;
use glint::cpu::sobol::PathSampler;
use glint::cpu::{RenderOptions, Scene};
use rayon::prelude::*;

/// The detection probability the rule aims at: 0.95, above the 0.9 the
/// suite promises, because its inputs (the pilot's variance, the material's
/// radiance L_i,k) are themselves estimates.
pub const POWER: f64 = 0.95;
/// References take this many times the tests' samples.
pub const REF_FACTOR: u32 = 4;
/// compare's finest block edge.
const BLOCK: u32 = 8;
/// A material covering at least this share of the image is sized for.
pub const MATERIAL_SHARE: f64 = 0.1;
/// Path samples per pixel behind the material changes.
pub const SHARE_SPP: u32 = 16;

/// A change `detect` sizes the spp for: one material.
#[derive(Clone, Debug)]
pub struct Change {
    /// Names it in the report: `material NAME (S% of the image)`.
    pub label: String,
    /// Per pixel, L_i,k: the radiance a relative change of the material
    /// moves by that relative amount (module notes).
    pub moved: Vec<Vec3>,
}

/// The non-emitting materials that cover at least [`MATERIAL_SHARE`] of
/// the image `opts` renders, each as a [`Change`] (module notes).
pub fn material_changes(scene: &Scene, opts: &RenderOptions) -> anyhow::Result<Vec<Change>> {
    let opts = RenderOptions {
        spp: SHARE_SPP,
        ..opts.clone()
    };
    let pt = PathTracer::new(scene, &opts)?;
    let (w, h) = (opts.width, opts.height);
    // Per pixel: (material, rays, radiance) of the samples by first hit.
    let pixels: Vec<Vec<(u32, u32, Vec3)>> = (0..w * h)
        .into_par_iter()
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let mut by: Vec<(u32, u32, Vec3)> = Vec::new();
            let mut rays = 0u64;
            for s in 0..SHARE_SPP {
                let sample = opts.sample_start + s;
                // The camera ray `sample` traces first (the sampler's
                // first draw is the pixel position).
                let u = PathSampler::new(pt.sampler, pt.key, i, sample).pixel_2d();
                let Some(hit) = scene.intersect(&pt.camera.ray(x, y, u)) else {
                    continue;
                };
                let m = scene.triangles[hit.tri as usize].material;
                let l = pt.sample(x, y, sample, &mut rays);
                let l = if l.is_finite() { l } else { Vec3::ZERO };
                match by.iter_mut().find(|e| e.0 == m) {
                    Some(e) => {
                        e.1 += 1;
                        e.2 += l;
                    }
                    None => by.push((m, 1, l)),
                }
            }
            by
        })
        .collect();
    // Shares first: at most 1 / MATERIAL_SHARE materials qualify, so only
    // theirs get a per-pixel image (a file may hold thousands).
    let mut rays = vec![0u64; scene.materials.len()];
    for &(m, n, _) in pixels.iter().flatten() {
        if let Some(r) = rays.get_mut(m as usize) {
            *r += n as u64;
        }
    }
    let total = (w as u64 * h as u64 * SHARE_SPP as u64).max(1) as f64;
    let mut changes = Vec::new();
    for (m, material) in scene.materials.iter().enumerate() {
        let share = rays[m] as f64 / total;
        if share < MATERIAL_SHARE || material.emission != Vec3::ZERO {
            continue;
        }
        let moved = pixels
            .iter()
            .map(|by| {
                by.iter()
                    .find(|e| e.0 as usize == m)
                    .map_or(Vec3::ZERO, |e| e.2 / SHARE_SPP as f32)
            })
            .collect();
        let name = if material.name.is_empty() {
            format!("#{m}")
        } else {
            material.name.clone()
        };
        changes.push(Change {
            label: format!("material {name} ({:.0}% of the image)", 100.0 * share),
            moved,
        });
    }
    Ok(changes)
}

/// Per block level (8x8, then doubling up to the whole image, as `compare`
/// tiles it), per non-empty block: the sum of `value(i)` over its pixels
/// and their count.
fn block_sums(w: u32, h: u32, value: impl Fn(usize) -> DVec3) -> Vec<Vec<(DVec3, f64)>> {
    let mut out = Vec::new();
    let mut edge = BLOCK;
    loop {
        let bx = w.div_ceil(edge);
        let by = h.div_ceil(edge);
        let mut acc = vec![(DVec3::ZERO, 0.0); (bx * by) as usize];
        for y in 0..h {
            for x in 0..w {
                let b = &mut acc[((y / edge) * bx + x / edge) as usize];
                b.0 += value((y * w + x) as usize);
                b.1 += 1.0;
            }
        }
        out.push(acc.into_iter().filter(|a| a.1 > 0.0).collect());
        if bx * by <= 1 {
            return out;
        }
        edge *= 2;
    }
}

/// Per block level, per block: the mean of the pixel means, or of a
/// change's L_i,k when `moved` is given.
fn block_means(img: &RadianceImage, moved: Option<&[Vec3]>) -> Vec<Vec<DVec3>> {
    let value = |i: usize| match moved {
        Some(mv) => mv.get(i).copied().unwrap_or(Vec3::ZERO).as_dvec3(),
        None => img.mean[i].as_dvec3(),
    };
    block_sums(img.width, img.height, value)
        .into_iter()
        .map(|l| l.into_iter().map(|(s, n)| s / n).collect())
        .collect()
}

/// Per block level, per block: the variance of the block mean for one
/// sample per pixel, from `img`'s variance of a `spp`-sample render.
fn block_variances(img: &RadianceImage, spp: u32) -> Vec<Vec<DVec3>> {
    let var = img.variance.as_deref().unwrap_or(&[]);
    let value = |i: usize| var.get(i).map_or(DVec3::ZERO, |v| v.as_dvec3());
    block_sums(img.width, img.height, value)
        .into_iter()
        .map(|l| {
            l.into_iter()
                .map(|(v, n)| v * spp as f64 / (n * n))
                .collect()
        })
        .collect()
}

/// The spp at which a relative change `delta` of the whole image, and of
/// each of `changes`, is caught with probability [`POWER`] at `alpha`
/// (module notes), at most `cap`; and the label of the change that set it
/// (`None`: the whole image). `pilot` holds variance from a render of
/// `pilot_spp` samples; `reference`, when given, is the reference the test
/// will diff against (same size).
pub fn required_spp(
    pilot: &RadianceImage,
    pilot_spp: u32,
    reference: Option<&RadianceImage>,
    delta: f64,
    alpha: f64,
    cap: u32,
    changes: &[Change],
) -> (u32, Option<String>) {
    let var = block_variances(pilot, pilot_spp);
    let tests: usize = var.iter().map(|l| 3 * l.len()).sum();
    let a_local = 1.0 - (1.0 - alpha / 2.0).powf(1.0 / tests.max(1) as f64);
    let z = normal_quantile(1.0 - a_local / 2.0) + normal_quantile(POWER);
    let ref_var = reference.map(|r| block_variances(r, 1));
    let uniform = block_means(pilot, None);
    let mut need = needed(&uniform, &var, ref_var.as_deref(), delta, z);
    let mut by = None;
    for c in changes {
        let shifted = block_means(pilot, Some(&c.moved));
        let n = needed(&shifted, &var, ref_var.as_deref(), delta, z);
        if n > need {
            need = n;
            by = Some(c.label.clone());
        }
    }
    let n = if need.is_finite() {
        (need.ceil() as u32).clamp(1, cap)
    } else {
        cap
    };
    (n, by)
}

/// The smallest N over blocks and channels at which a block whose mean
/// moves by delta x `shifted` reaches expected z `z`; `var` gives the
/// blocks' one-sample variances, `ref_var` the reference's.
fn needed(
    shifted: &[Vec<DVec3>],
    var: &[Vec<DVec3>],
    ref_var: Option<&[Vec<DVec3>]>,
    delta: f64,
    z: f64,
) -> f64 {
    let mut best = f64::INFINITY;
    for (li, level) in shifted.iter().enumerate() {
        for (bi, &m) in level.iter().enumerate() {
            let s2 = var[li][bi];
            for c in 0..3 {
                let shift2 = (delta * m[c]).powi(2) / (z * z);
                let n = match ref_var {
                    // V_ref known: N >= s^2 / (shift^2 / z^2 - V_ref).
                    Some(r) => {
                        let room = shift2 - r[li][bi][c];
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
    best
}

#[cfg(test)]
mod tests {
    use super::*;

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
        let a = required_spp(&quiet, 16, None, 0.02, 1e-3, 1 << 20, &[]).0;
        let b = required_spp(&noisy, 16, None, 0.02, 1e-3, 1 << 20, &[]).0;
        assert!(b > 3 * a && b < 5 * a, "{a} {b}");
        let c = required_spp(&quiet, 16, None, 0.01, 1e-3, 1 << 20, &[]).0;
        assert!(c > 3 * a && c < 5 * a, "{a} {c}");
        // The cap wins where the rule asks for more.
        assert!(b > 10, "{b}");
        assert_eq!(required_spp(&noisy, 16, None, 0.02, 1e-3, 10, &[]).0, 10);
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
        assert_eq!(
            required_spp(&img, 16, None, delta, alpha, 1 << 20, &[]).0,
            want
        );
        // A reference noisier than the REF_FACTOR x N spp one the rule
        // assumes leaves less room: more samples (its block variance
        // 0.02 / 64 against the assumed s^2 / (4 x 8)).
        let reference = image(8, 2.0, 0.02);
        let with_ref = required_spp(&img, 16, Some(&reference), delta, alpha, 1 << 20, &[]).0;
        assert!(with_ref > want, "{with_ref} {want}");
    }

    #[test]
    fn a_material_on_one_block_is_sized_for_that_block_alone() {
        // 16x16: four 8x8 blocks and the whole image (5 blocks, 15 tests).
        // A material filling the top-left block moves only it; the rule
        // must size N for that block's variance (4x the whole image's).
        let img = image(16, 1.0, 0.01);
        let (delta, alpha) = (0.05, 1e-3);
        // The pixel means are 1, so what moves is 1 on the block.
        let moved: Vec<Vec3> = (0..256)
            .map(|i| Vec3::splat(if i % 16 < 8 && i / 16 < 8 { 1.0 } else { 0.0 }))
            .collect();
        let change = Change {
            label: "material m".into(),
            moved,
        };
        let (uniform, by) = required_spp(&img, 16, None, delta, alpha, 1 << 20, &[]);
        assert_eq!(by, None);
        let (n, by) = required_spp(&img, 16, None, delta, alpha, 1 << 20, &[change]);
        assert_eq!(by.as_deref(), Some("material m"));
        let a_local = 1.0 - (1.0 - alpha / 2.0f64).powf(1.0 / 15.0);
        let z = normal_quantile(1.0 - a_local / 2.0) + normal_quantile(POWER);
        let s2 = 0.01f32 as f64 * 16.0 / 64.0;
        let want = (s2 * 1.25 * z * z / delta.powi(2)).ceil() as u32;
        assert_eq!(n, want);
        // The whole image (variance s^2 / 4) catches a uniform change at a
        // quarter of that.
        assert_eq!(
            uniform,
            (s2 / 4.0 * 1.25 * z * z / delta.powi(2)).ceil() as u32
        );
    }
}

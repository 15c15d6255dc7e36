//! Statistical comparison of noisy renders (Mitsuba 3's render tests and
//! their variance images, done by blocks so two noisy images can be
//! compared without a reference).
//!
//! The rule, for images A and B (or A against a constant):
//! 1. Tile the image into 8x8 blocks (edge blocks keep what they have;
//!    with a mask, only masked pixels count and empty blocks are skipped).
//!    Per block and channel: the mean of the pixel means, and the variance
//!    of that mean, sum(pixel variance of the mean) / n^2 (pixels are
//!    independent; each pixel's variance comes from the film's own
//!    sum/sum_sq).
//! 2. Welch's z = (mean_A - mean_B) / sqrt(var_A + var_B + floor), the
//!    floor (1e-5 x max(|mean_A|, |mean_B|))^2 standing for the f32
//!    rounding of the sums (a noise-free region must match to 1e-5
//!    relative). When one image has zero variance in a block and the other
//!    not, the other's variance stands in for it (a deterministic region on
//!    one side is compared at the noise level of the other); against an
//!    exact reference (`compare_to_reference`) B's variance is truly zero.
//! 3. Two one-sided tests share the overall significance `alpha` (default
//!    1e-3) equally:
//!    - local: any |z| above the Sidak-corrected two-sided threshold for N
//!      tests at alpha/2 fails (a strongly wrong region). The z's are those
//!      of the 8x8 blocks and of coarser blocks, 16x16, 32x32, ... up to
//!      the whole image (each from the pixels it covers, the same way): a
//!      change spread over k blocks has sqrt(k) times the z in the block
//!      that covers them, while the extra tests cost little (N grows by a
//!      third, the threshold by ~0.1). Sidak's inequality holds for
//!      two-sided tests of jointly normal z's whatever their correlation
//!      (Sidak 1967), so the nested blocks keep the level;
//!    - global: the count of blocks with some channel's |z| above the
//!      two-sided 1% threshold must be consistent with Binomial(blocks,
//!      1 - 0.99^3) at alpha/2 (a mild bias spread over the image, which
//!      no single block shows). Blocks, not block-channels, are counted:
//!      the channels of a block share their paths, far from independent;
//!      1 - 0.99^3 is the exceedance chance for independent channels and
//!      an upper bound for correlated ones, so the test stays valid.
//!
//! With a correct renderer the images pass with probability about
//! 1 - alpha (the z's are only approximately normal at low spp).
//!
//! Quasi-Monte Carlo films (`--sampler sobol`): a pixel's samples are then
//! a scrambled net, not independent, and the sample variance over n
//! overestimates the variance V of the pixel mean (measured 4-15x, growing
//! with n, since QMC converges faster than 1/n). From 32 spp a Sobol film
//! estimates V from batch means instead (`Film::variance_of_mean`: 16 or
//! more batches of L consecutive sample indices, each a scrambled net), an
//! estimate that is conservative as long as the batches are not positively
//! correlated and measured 2-4x V; below 32 spp (too few batches) it falls
//! back to the independent formula, conservative as long as the scrambled
//! points do no worse than independent ones. Pixels stay independent of
//! each other (each has its own scrambles and index shuffles, `sobol`), so
//! block variances still add. Both are measured rather than assumed:
//! `cpu/tests/render_stats.rs`
//! (`the_film_variance_is_calibrated_for_both_samplers`) renders scenes
//! under 40 seeds and compares the estimates with the seed-to-seed
//! variance of the pixel means; `tests/cli_regression.rs` checks the
//! false-positive rate of `glint diff` over 200 pairs for both samplers.

// `!(a <= b)` on floats is meant: it is true for NaN too.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use glam::Vec3;

use crate::film::Film;

/// Block edge in pixels.
pub const BLOCK: u32 = 8;
/// Default overall significance.
pub const ALPHA: f64 = 1e-3;
/// Per-test level of the global (counting) test.
pub const P_GLOBAL: f64 = 0.01;

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum CompareError {
    #[error("image sizes differ: {0}x{1} vs {2}x{3}")]
    Size(u32, u32, u32, u32),
    #[error("no samples to compare")]
    Empty,
    #[error(
        "{0} pixels hold non-finite radiance or variance (overflow near f32's range): no verdict"
    )]
    NonFinite(usize),
    #[error(
        "the test has no power: an 8x8 block needs at least {MIN_BLOCK_SAMPLES} samples \
         (pixels x spp) and the best has {0}; render more samples or a larger image"
    )]
    NoPower(u64),
}

/// The outcome of a comparison, with what explains it.
#[derive(Clone, Debug, PartialEq)]
pub struct CompareReport {
    /// Block-channel tests performed.
    pub tests: usize,
    /// Largest |z| and where: block (x, y) in units of its edge, channel.
    pub z_max: f64,
    pub worst: (u32, u32, usize),
    /// Edge in pixels of the block where |z| is largest.
    pub worst_edge: u32,
    /// Sidak threshold of the local test.
    pub z_local: f64,
    /// Blocks with a channel above the 1% threshold, and how many chance allows.
    pub exceed_global: usize,
    pub allowed_global: usize,
    /// Mean relative difference over the compared pixels (for messages).
    pub mean_a: Vec3,
    pub mean_b: Vec3,
    /// Blocks left out for having under `MIN_BLOCK_SAMPLES` samples.
    pub skipped: usize,
    pub pass: bool,
}

impl std::fmt::Display for CompareReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{}: {} block tests, max |z| {:.2} at {e}x{e} block {:?} (local threshold {:.2}), \
             {} blocks above the 1% level (chance allows {}), means {:?} vs {:?}",
            if self.pass { "pass" } else { "FAIL" },
            self.tests,
            self.z_max,
            self.worst,
            self.z_local,
            self.exceed_global,
            self.allowed_global,
            self.mean_a.to_array(),
            self.mean_b.to_array(),
            e = self.worst_edge,
        )?;
        if self.skipped > 0 {
            write!(
                f,
                ", {} blocks skipped (under {MIN_BLOCK_SAMPLES} samples)",
                self.skipped
            )?;
        }
        Ok(())
    }
}

/// A noisy image as the test sees it: per-pixel means and variances of
/// the mean (a film's, or an EXR's `variance.*` channels), and how many
/// independent values per pixel each variance was estimated from, when
/// known: the samples per pixel, or the variance batches of a Sobol film
/// (`Film::variance_batch`).
#[derive(Clone, Copy, Debug)]
pub struct Estimate<'a> {
    pub width: u32,
    pub height: u32,
    pub mean: &'a [Vec3],
    pub variance: &'a [Vec3],
    pub samples: Option<u32>,
}

/// Fewest samples (pixels x spp) a block needs to be tested: below it the
/// block's variance estimate is too rough for a z-test (a few samples can
/// agree by chance and claim zero variance), so the block is skipped; a
/// comparison with no testable block has no power and says so.
pub const MIN_BLOCK_SAMPLES: u64 = 32;

/// Block means and variances of the mean of one image.
struct Blocks {
    bx: u32,
    by: u32,
    /// Per block: (mean, variance of the mean, pixel count); count 0 = skipped.
    data: Vec<(glam::DVec3, glam::DVec3, u32)>,
}

fn blocks(img: &Estimate, mask: &dyn Fn(u32, u32) -> bool, edge: u32) -> Blocks {
    let bx = img.width.div_ceil(edge);
    let by = img.height.div_ceil(edge);
    let mut acc = vec![(glam::DVec3::ZERO, glam::DVec3::ZERO, 0u32); (bx * by) as usize];
    for y in 0..img.height {
        for x in 0..img.width {
            if !mask(x, y) {
                continue;
            }
            let i = y as usize * img.width as usize + x as usize;
            let b = &mut acc[((y / edge) * bx + x / edge) as usize];
            b.0 += img.mean[i].as_dvec3();
            b.1 += img.variance[i].as_dvec3();
            b.2 += 1;
        }
    }
    // Kept in f64 until the z: radiance near f32's range must not
    // overflow the block sums (non-finite pixels are refused before).
    let data = acc
        .into_iter()
        .map(|(s, v, n)| {
            if n == 0 {
                (glam::DVec3::ZERO, glam::DVec3::ZERO, 0)
            } else {
                let n2 = n as f64 * n as f64;
                (s / n as f64, v / n2, n)
            }
        })
        .collect();
    Blocks { bx, by, data }
}

/// Relative noise floor standing for the f32 rounding of the films' sums:
/// means closer than this (relative) are never told apart.
pub const ROUNDING_FLOOR: f64 = 1e-5;

/// Welch's z with the zero-variance rules of the module notes. `b_exact`:
/// B is a reference value, not a noisy image (its variance is truly zero).
fn welch_z(ma: f64, va: f64, mb: f64, vb: f64, b_exact: bool) -> f64 {
    let d = ma - mb;
    let (va, vb) = match (va > 0.0, vb > 0.0 || b_exact) {
        (false, true) if !b_exact => (vb, vb),
        (true, false) => (va, va),
        _ => (va, vb),
    };
    let floor = (ROUNDING_FLOOR * ma.abs().max(mb.abs())).powi(2);
    let var = va + vb + floor;
    if var > 0.0 {
        d / var.sqrt()
    } else if d == 0.0 {
        0.0
    } else {
        f64::INFINITY
    }
}

/// The inverse of the standard normal CDF (Acklam's rational
/// approximation, relative error < 1.2e-9, one Halley step refining it).
pub fn normal_quantile(p: f64) -> f64 {
    assert!(p > 0.0 && p < 1.0);
    const A: [f64; 6] = [
        -3.969683028665376e+01,
        2.209460984245205e+02,
        -2.759285104469687e+02,
        1.383_577_518_672_69e2,
        -3.066479806614716e+01,
        2.506628277459239e+00,
    ];
    const B: [f64; 5] = [
        -5.447609879822406e+01,
        1.615858368580409e+02,
        -1.556989798598866e+02,
        6.680131188771972e+01,
        -1.328068155288572e+01,
    ];
    const C: [f64; 6] = [
        -7.784894002430293e-03,
        -3.223964580411365e-01,
        -2.400758277161838e+00,
        -2.549732539343734e+00,
        4.374664141464968e+00,
        2.938163982698783e+00,
    ];
    const D: [f64; 4] = [
        7.784695709041462e-03,
        3.224671290700398e-01,
        2.445134137142996e+00,
        3.754408661907416e+00,
    ];
    let p_low = 0.02425;
    let tail = |q: f64| {
        (((((C[0] * q + C[1]) * q + C[2]) * q + C[3]) * q + C[4]) * q + C[5])
            / ((((D[0] * q + D[1]) * q + D[2]) * q + D[3]) * q + 1.0)
    };
    let x = if p < p_low {
        tail((-2.0 * p.ln()).sqrt())
    } else if p <= 1.0 - p_low {
        let q = p - 0.5;
        let r = q * q;
        (((((A[0] * r + A[1]) * r + A[2]) * r + A[3]) * r + A[4]) * r + A[5]) * q
            / (((((B[0] * r + B[1]) * r + B[2]) * r + B[3]) * r + B[4]) * r + 1.0)
    } else {
        -tail((-2.0 * (1.0 - p).ln()).sqrt())
    };
    // Halley refinement with erfc.
    let e = 0.5 * erfc(-x / std::f64::consts::SQRT_2) - p;
    let u = e * (2.0 * std::f64::consts::PI).sqrt() * (x * x / 2.0).exp();
    x - u / (1.0 + x * u / 2.0)
}

/// Complementary error function (Numerical Recipes' erfcc, |error| < 1.2e-7),
/// enough for the Halley step above.
fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let r = t
        * (-z * z - 1.26551223
            + t * (1.00002368
                + t * (0.37409196
                    + t * (0.09678418
                        + t * (-0.18628806
                            + t * (0.27886807
                                + t * (-1.13520398
                                    + t * (1.48851587 + t * (-0.82215223 + t * 0.17087277)))))))))
            .exp();
    if x >= 0.0 { r } else { 2.0 - r }
}

/// Smallest k with P(Binomial(n, p) > k) <= alpha.
pub fn binomial_upper_quantile(n: usize, p: f64, alpha: f64) -> usize {
    let lq = (1.0 - p).ln();
    let ratio = (p / (1.0 - p)).ln();
    let mut log_pmf = n as f64 * lq;
    let mut cdf = 0.0f64;
    for k in 0..=n {
        cdf += log_pmf.exp();
        if 1.0 - cdf <= alpha {
            return k;
        }
        log_pmf += ((n - k) as f64 / (k + 1) as f64).ln() + ratio;
    }
    n
}

/// One block-channel test: its z, where (block x, y in units of `edge`,
/// channel) and the block edge in pixels.
#[derive(Clone, Copy, Debug)]
struct BlockZ {
    z: f64,
    at: (u32, u32, usize),
    edge: u32,
}

/// The verdict over every block test; the first `fine` are the 8x8 blocks'
/// (the global test counts those alone).
fn decide(zs: &[BlockZ], fine: usize, alpha: f64, mean_a: Vec3, mean_b: Vec3) -> CompareReport {
    let n = zs.len().max(1);
    let a_local = 1.0 - (1.0 - alpha / 2.0).powf(1.0 / n as f64);
    let z_local = normal_quantile(1.0 - a_local / 2.0);
    let z_global = normal_quantile(1.0 - P_GLOBAL / 2.0);
    let mut z_max = 0.0f64;
    let mut worst = (0, 0, 0);
    let mut worst_edge = BLOCK;
    // Blocks (not block-channels) with some channel above the 1% level:
    // the channels of one block share their paths and are far from
    // independent, so they count once.
    let mut exceeding_blocks = std::collections::BTreeSet::new();
    let mut blocks = std::collections::BTreeSet::new();
    for (k, t) in zs.iter().enumerate() {
        let (z, at) = (t.z.abs(), t.at);
        if z.is_nan() || z > z_max {
            z_max = if z.is_nan() { f64::INFINITY } else { z };
            worst = at;
            worst_edge = t.edge;
        }
        if k >= fine {
            continue;
        }
        blocks.insert((at.0, at.1));
        if !(z <= z_global) {
            exceeding_blocks.insert((at.0, at.1));
        }
    }
    // Under the null hypothesis a block exceeds with probability between
    // P_GLOBAL (channels identical) and 1 - (1 - P_GLOBAL)^3 (independent
    // channels); the latter bound keeps the test valid either way.
    let channels = (fine / blocks.len().max(1)).max(1) as i32;
    let p_block = 1.0 - (1.0 - P_GLOBAL).powi(channels);
    let allowed_global = binomial_upper_quantile(blocks.len(), p_block, alpha / 2.0);
    let exceed_global = exceeding_blocks.len();
    CompareReport {
        tests: zs.len(),
        z_max,
        worst,
        worst_edge,
        z_local,
        exceed_global,
        allowed_global,
        mean_a,
        mean_b,
        skipped: 0,
        pass: z_max <= z_local && exceed_global <= allowed_global,
    }
}

fn overall_mean(b: &Blocks) -> Vec3 {
    let mut s = glam::DVec3::ZERO;
    let mut n = 0u64;
    for &(m, _, c) in &b.data {
        s += m * c as f64;
        n += c as u64;
    }
    if n == 0 {
        Vec3::ZERO
    } else {
        (s / n as f64).as_vec3()
    }
}

/// A film's means and variances of the mean, owned.
fn film_planes(f: &Film) -> (Vec<Vec3>, Vec<Vec3>) {
    (
        f.means(),
        (0..f.sum.len()).map(|i| f.variance_of_mean(i)).collect(),
    )
}

/// A film as the test sees it, over its [`film_planes`]: the variance
/// estimated from `spp / variance_batch` independent values per pixel.
fn film_estimate<'a>(f: &Film, planes: &'a (Vec<Vec3>, Vec<Vec3>)) -> Estimate<'a> {
    Estimate {
        width: f.width,
        height: f.height,
        mean: &planes.0,
        variance: &planes.1,
        samples: Some(f.spp / f.variance_batch()),
    }
}

/// Compare two renders of the same scene (see the module notes).
pub fn compare_films(a: &Film, b: &Film) -> Result<CompareReport, CompareError> {
    compare_films_masked(a, b, &|_, _| true, ALPHA)
}

/// [`compare_films`] over the pixels where `mask(x, y)`, at significance `alpha`.
pub fn compare_films_masked(
    a: &Film,
    b: &Film,
    mask: &dyn Fn(u32, u32) -> bool,
    alpha: f64,
) -> Result<CompareReport, CompareError> {
    if (a.width, a.height) != (b.width, b.height) {
        return Err(CompareError::Size(a.width, a.height, b.width, b.height));
    }
    if a.spp == 0 || b.spp == 0 {
        return Err(CompareError::Empty);
    }
    let (pa, pb) = (film_planes(a), film_planes(b));
    compare_core(
        &film_estimate(a, &pa),
        &film_estimate(b, &pb),
        false,
        mask,
        alpha,
    )
}

/// Compare two noisy images given as means and variances of the mean
/// (what `glint diff` reads from two EXRs), at significance `alpha`.
pub fn compare_estimates(
    a: &Estimate,
    b: &Estimate,
    alpha: f64,
) -> Result<CompareReport, CompareError> {
    compare_core(a, b, false, &|_, _| true, alpha)
}

/// Pixels (under the mask) whose mean or variance is not finite.
fn non_finite(e: &Estimate, mask: &dyn Fn(u32, u32) -> bool) -> usize {
    let w = e.width as usize;
    (0..e.mean.len())
        .filter(|&i| {
            mask((i % w) as u32, (i / w) as u32)
                && !(e.mean[i].is_finite() && e.variance[i].is_finite())
        })
        .count()
}

/// The one rule behind every entry point: guards, blocks, z's, decision.
fn compare_core(
    a: &Estimate,
    b: &Estimate,
    b_exact: bool,
    mask: &dyn Fn(u32, u32) -> bool,
    alpha: f64,
) -> Result<CompareReport, CompareError> {
    if (a.width, a.height) != (b.width, b.height) {
        return Err(CompareError::Size(a.width, a.height, b.width, b.height));
    }
    let n = a.width as usize * a.height as usize;
    for e in [a, b] {
        if e.mean.len() != n || e.variance.len() != n {
            return Err(CompareError::Size(
                a.width,
                a.height,
                e.mean.len() as u32,
                1,
            ));
        }
    }
    if a.samples == Some(0) || b.samples == Some(0) {
        return Err(CompareError::Empty);
    }
    // An overflowed sum or sum of squares (radiance near f32's limit) is
    // infinite: its z would be 0 and pass. No verdict instead.
    let bad = non_finite(a, mask) + non_finite(b, mask);
    if bad > 0 {
        return Err(CompareError::NonFinite(bad));
    }
    // Samples behind a block, the smaller side's (exact side: unlimited).
    let samples =
        |pixels: u32, spp: Option<u32>| spp.map_or(u64::MAX, |s| pixels as u64 * s as u64);
    // The 8x8 blocks first (the global test counts those), then each
    // coarser level up to the one that holds the whole image.
    let mut zs: Vec<BlockZ> = Vec::new();
    let mut fine_tests = 0;
    let mut skipped = 0;
    let mut most = 0u64;
    let mut means = None;
    let mut edge = BLOCK;
    loop {
        let ba = blocks(a, mask, edge);
        let bb = blocks(b, mask, edge);
        for by in 0..ba.by {
            for bx in 0..ba.bx {
                let i = (by * ba.bx + bx) as usize;
                let (ma, va, n) = ba.data[i];
                let (mb, vb, _) = bb.data[i];
                if n == 0 {
                    continue;
                }
                let s = samples(n, a.samples).min(if b_exact {
                    u64::MAX
                } else {
                    samples(n, b.samples)
                });
                if s < MIN_BLOCK_SAMPLES {
                    if edge == BLOCK {
                        most = most.max(s);
                        skipped += 1;
                    }
                    continue;
                }
                for c in 0..3 {
                    let z = welch_z(ma[c], va[c], mb[c], vb[c], b_exact);
                    zs.push(BlockZ {
                        z,
                        at: (bx, by, c),
                        edge,
                    });
                }
            }
        }
        if edge == BLOCK {
            if zs.is_empty() {
                return Err(if skipped > 0 {
                    CompareError::NoPower(most)
                } else {
                    CompareError::Empty
                });
            }
            fine_tests = zs.len();
            means = Some((overall_mean(&ba), overall_mean(&bb)));
        }
        if ba.bx * ba.by <= 1 {
            break;
        }
        edge *= 2;
    }
    let (mean_a, mean_b) = means.expect("the 8x8 level ran");
    let mut r = decide(&zs, fine_tests, alpha, mean_a, mean_b);
    r.skipped = skipped;
    Ok(r)
}

/// Test a render against a known constant radiance `value` over the pixels
/// where `mask(x, y)`: the same rule with B exact (variance zero; a
/// zero-variance block must then match to the rounding floor).
pub fn compare_to_constant(
    film: &Film,
    value: Vec3,
    mask: &dyn Fn(u32, u32) -> bool,
) -> Result<CompareReport, CompareError> {
    let reference = vec![value; film.sum.len()];
    compare_to_reference(film, &reference, mask)
}

/// Test a render against exact per-pixel expected values (row-major, top
/// row first), e.g. an analytic solution integrated over each pixel.
pub fn compare_to_reference(
    film: &Film,
    reference: &[Vec3],
    mask: &dyn Fn(u32, u32) -> bool,
) -> Result<CompareReport, CompareError> {
    if film.spp == 0 {
        return Err(CompareError::Empty);
    }
    if reference.len() != film.sum.len() {
        return Err(CompareError::Size(
            film.width,
            film.height,
            reference.len() as u32,
            1,
        ));
    }
    let pa = film_planes(film);
    let zero = vec![Vec3::ZERO; reference.len()];
    let ea = film_estimate(film, &pa);
    let eb = Estimate {
        width: film.width,
        height: film.height,
        mean: reference,
        variance: &zero,
        samples: None,
    };
    compare_core(&ea, &eb, true, mask, ALPHA)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_quantile_matches_tables() {
        for (p, z) in [
            (0.5, 0.0),
            (0.975, 1.959963984540054),
            (0.995, 2.5758293035489),
            (1e-7, -5.199337582187471),
            (0.1, -1.2815515655446004),
        ] {
            assert!(
                (normal_quantile(p) - z).abs() < 1e-6,
                "{p}: {}",
                normal_quantile(p)
            );
        }
    }

    #[test]
    fn binomial_quantile_is_a_tail_bound() {
        // Binomial(100, 0.01): P(K > 4) = 0.00343, P(K > 5) = 0.000566.
        assert_eq!(binomial_upper_quantile(100, 0.01, 5e-4), 6);
        assert_eq!(binomial_upper_quantile(100, 0.01, 1e-3), 5);
        assert_eq!(binomial_upper_quantile(100, 0.01, 4e-3), 4);
        // Large n stays finite and near the mean plus a few sigma.
        let k = binomial_upper_quantile(3_000_000, 0.01, 5e-4);
        assert!(k > 30_000 && k < 30_800, "{k}");
    }

    fn film_from(f: impl Fn(u32, u32, u32) -> Vec3, w: u32, h: u32, spp: u32) -> Film {
        let mut film = Film::new(w, h);
        film.spp = spp;
        for y in 0..h {
            for x in 0..w {
                let i = film.index(x, y);
                for s in 0..spp {
                    let v = f(x, y, s);
                    film.sum[i] += v;
                    film.sum_sq[i] += v * v;
                }
            }
        }
        film
    }

    #[test]
    fn grey_noise_passes_at_the_stated_rate() {
        // Pairs of independent noisy grey films (identical channels, as a
        // white scene gives): a valid test fails about alpha = 1e-3 of
        // them. Counting channels as independent tests would fail ~2.6%
        // here (a block over the 1% level counts three times). 200 pairs:
        // more than 2 failures has probability ~1e-3 at the stated rate.
        let mut fails = 0;
        for pair in 0..200u32 {
            let noise = |seed: u32| {
                move |x: u32, y: u32, s: u32| {
                    let mut r = crate::sampling::Rng::new(seed, y * 64 + x, s);
                    Vec3::splat(0.5 + r.next_f32() - r.next_f32())
                }
            };
            let a = film_from(noise(2 * pair), 64, 64, 16);
            let b = film_from(noise(2 * pair + 1), 64, 64, 16);
            fails += !compare_films(&a, &b).unwrap().pass as u32;
        }
        assert!(fails <= 2, "{fails} of 200 independent pairs failed");
    }

    #[test]
    fn zero_variance_rules() {
        let a = film_from(|_, _, _| Vec3::splat(0.5), 16, 16, 4);
        assert!(compare_films(&a, &a).unwrap().pass);
        assert!(
            compare_to_constant(&a, Vec3::splat(0.5), &|_, _| true)
                .unwrap()
                .pass
        );
        assert!(
            !compare_to_constant(&a, Vec3::splat(0.51), &|_, _| true)
                .unwrap()
                .pass
        );
        let b = film_from(|_, _, _| Vec3::splat(0.6), 16, 16, 4);
        assert!(!compare_films(&a, &b).unwrap().pass);
        assert_eq!(
            compare_films(&a, &Film::new(8, 8)),
            Err(CompareError::Size(16, 16, 8, 8))
        );
    }

    #[test]
    fn overflowing_radiance_gets_no_verdict() {
        // 1e37 squared overflows f32's sum of squares: the variance is
        // infinite, which would make every z 0 and pass.
        let a = film_from(|_, _, s| Vec3::splat(1e37 * (1.0 + s as f32)), 16, 16, 4);
        let b = film_from(|_, _, _| Vec3::splat(3e37), 16, 16, 4);
        assert_eq!(compare_films(&a, &b), Err(CompareError::NonFinite(512)));
    }

    #[test]
    fn a_test_without_power_says_so() {
        let a = film_from(|_, _, s| Vec3::splat(s as f32), 1, 1, 4);
        let b = film_from(|_, _, s| Vec3::splat(10.0 + s as f32), 1, 1, 4);
        assert_eq!(compare_films(&a, &b), Err(CompareError::NoPower(4)));
        // Edge blocks too small are skipped, the rest tested.
        let a = film_from(|_, _, s| Vec3::splat(s as f32), 9, 7, 4);
        let r = compare_films(&a, &a).unwrap();
        // One 8x8 level block (3 channels) and the 16x16 one over all.
        assert_eq!((r.skipped, r.tests, r.pass), (1, 6, true));
    }

    #[test]
    fn a_change_spread_over_blocks_is_caught_by_the_coarser_ones() {
        // +0.03 over a 32x32 quarter of a 64x64 image: z about 1.7 in each
        // of its sixteen 8x8 blocks (per-block sd of the difference 0.018),
        // below any single-block threshold and within what chance allows
        // the global count; the 32x32 block over it sees z about 6.6.
        let noise = |seed: u32, bias: f32| {
            move |x: u32, y: u32, s: u32| {
                let mut r = crate::sampling::Rng::new(seed, y * 64 + x, s);
                let b = if x < 32 && y < 32 { bias } else { 0.0 };
                Vec3::splat(0.5 + b + r.next_f32() - r.next_f32())
            }
        };
        let mut caught = 0;
        for pair in 0..5u32 {
            let a = film_from(noise(2 * pair, 0.0), 64, 64, 16);
            let b = film_from(noise(2 * pair + 1, 0.03), 64, 64, 16);
            let r = compare_films(&a, &b).unwrap();
            let fine_max = r.z_max >= r.z_local && r.worst_edge == BLOCK;
            assert!(!fine_max, "an 8x8 block alone should not see it: {r}");
            caught += (!r.pass && r.worst_edge >= 32) as u32;
        }
        assert_eq!(caught, 5);
    }
}

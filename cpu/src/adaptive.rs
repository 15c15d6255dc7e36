//! `--target-error` and `--adaptive`: when a render stops, and which
//! pixels keep sampling, decided on the host from the film's own variance
//! estimate ([`Film::variance_of_mean`]) after every pass of
//! [`Control::step`] samples. Both backends run the same [`Control`] on
//! their own films, so for one seed they take the same decisions (up to
//! the float differences between their films).

use crate::film::{Film, RenderOptions, SamplerKind};

/// Samples per check for the independent sampler (Cycles checks every 16).
pub const CHECK_SAMPLES: u32 = 16;

/// Checks (passes of [`Control::step`] samples) an adaptive pixel takes
/// before it may stop: its estimate then has at least 3 degrees of freedom
/// per channel (Sobol: 4 batches; independent: 64 samples).
pub const ADAPTIVE_MIN_CHECKS: u32 = 4;

/// The variance batch a controlled Sobol render uses: 16 samples (a check
/// every batch, as often as Cycles checks), fewer when `cap` leaves under
/// 16 batches ([`crate::film::variance_batch_for`]).
pub fn control_batch(cap: u32) -> u32 {
    crate::film::variance_batch_for(cap, 1).min(CHECK_SAMPLES)
}

/// The stopping rule of a controlled render (`RenderOptions::target_error`
/// or `RenderOptions::adaptive` set).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Control {
    pub target_error: Option<f64>,
    pub adaptive: Option<f64>,
    /// Samples per pass: whole variance batches, so that every pixel's
    /// samples stay a stratified prefix of its Sobol sequence.
    pub step: u32,
    /// Samples before any stop: two batches for `--target-error`,
    /// [`ADAPTIVE_MIN_CHECKS`] passes for `--adaptive`.
    pub min_spp: u32,
    /// `RenderOptions::spp`.
    pub cap: u32,
}

impl Control {
    /// The rule for `opts`, or None for a plain render.
    pub fn of(opts: &RenderOptions) -> Option<Control> {
        if opts.target_error.is_none() && opts.adaptive.is_none() {
            return None;
        }
        let step = match opts.sampler {
            SamplerKind::Independent => CHECK_SAMPLES,
            SamplerKind::Sobol => opts.batch(),
        }
        .min(opts.spp)
        .max(1);
        let checks = if opts.adaptive.is_some() {
            ADAPTIVE_MIN_CHECKS
        } else {
            2
        };
        Some(Control {
            target_error: opts.target_error,
            adaptive: opts.adaptive,
            step,
            min_spp: step.saturating_mul(checks).min(opts.spp),
            cap: opts.spp,
        })
    }

    /// Samples of the next pass once `film` holds `film.spp`.
    pub fn next_count(&self, film: &Film) -> u32 {
        self.step.min(self.cap - film.spp.min(self.cap))
    }

    /// After a pass: update `active` (1 keeps a pixel sampling; a pixel
    /// once stopped stays stopped, so its samples stay a prefix) and say
    /// whether another pass runs.
    pub fn decide(&self, film: &Film, active: &mut [u32]) -> bool {
        if film.spp >= self.cap {
            return false;
        }
        if film.spp < self.min_spp {
            return true;
        }
        if let Some(e) = self.target_error
            && estimated_relmse(film) <= e
        {
            return false;
        }
        match self.adaptive {
            Some(t) => update_mask(film, t, active) > 0,
            None => true,
        }
    }
}

/// The contract's relMSE with each pixel's variance of the mean in place
/// of its squared error: mean over pixels and channels of
/// var / (mean^2 + 0.01).
pub fn estimated_relmse(film: &Film) -> f64 {
    let n = film.sum.len();
    if n == 0 {
        return 0.0;
    }
    let mut total = 0.0f64;
    for i in 0..n {
        let m = film.mean(i);
        let v = film.variance_of_mean(i);
        for c in 0..3 {
            total += v[c] as f64 / (m[c] as f64 * m[c] as f64 + 0.01);
        }
    }
    total / (3 * n) as f64
}

/// Pixel i's estimated relative standard error: the root of its mean
/// channel variance of the mean over its mean intensity, the intensity
/// replaced by its square root below 1 (Cycles' protection of dark
/// pixels, whose relative error would otherwise never get small).
pub fn relative_error(film: &Film, i: usize) -> f64 {
    let v = film.variance_of_mean(i).as_dvec3();
    let se = ((v.x + v.y + v.z) / 3.0).sqrt();
    if se == 0.0 {
        return 0.0;
    }
    let m = film.mean(i).as_dvec3();
    let intensity = ((m.x + m.y + m.z) / 3.0).max(1e-8);
    let scale = if intensity < 1.0 {
        intensity.sqrt()
    } else {
        intensity
    };
    se / scale
}

/// Stop the active pixels whose own error and whose 8 neighbours' errors
/// are below `t` (a 1-pixel dilation of the unconverged set, as Cycles
/// does, so that a noisy neighbourhood stays alive). Returns the pixels
/// left active.
pub fn update_mask(film: &Film, t: f64, active: &mut [u32]) -> usize {
    let (w, h) = (film.width as i64, film.height as i64);
    let noisy: Vec<bool> = (0..active.len())
        .map(|i| active[i] != 0 && relative_error(film, i) >= t)
        .collect();
    let mut left = 0;
    for y in 0..h {
        for x in 0..w {
            let i = (y * w + x) as usize;
            if active[i] == 0 {
                continue;
            }
            let near = (-1..=1).any(|dy| {
                (-1..=1).any(|dx| {
                    let (nx, ny) = (x + dx, y + dy);
                    nx >= 0 && ny >= 0 && nx < w && ny < h && noisy[(ny * w + nx) as usize]
                })
            });
            active[i] = near as u32;
            left += near as usize;
        }
    }
    left
}

/// Add a pass of `count` samples to the per-pixel counts of the pixels
/// `active` names (the film's `counts`, created on the first pass).
pub fn count_pass(film: &mut Film, active: &[u32], count: u32) {
    if film.counts.is_empty() {
        film.counts = vec![film.spp; film.sum.len()];
    }
    for (c, &a) in film.counts.iter_mut().zip(active) {
        if a != 0 {
            *c += count;
        }
    }
    film.spp += count;
}

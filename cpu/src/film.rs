//! Render options and the film both backends accumulate into.

use std::io::{Seek, Write};
use std::path::{Path, PathBuf};

use glam::Vec3;

/// What `glint render` asks of either backend (the contract's options).
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOptions {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    /// Mitsuba's convention: 1 = emitters seen directly, 2 = direct lighting,
    /// -1 = unbounded (Russian roulette ends paths).
    pub max_depth: i32,
    pub seed: u64,
    /// Index into `Scene::cameras`; ignored when the scene has none (the
    /// documented default viewpoint is used).
    pub camera: usize,
    /// Next-event estimation (light sampling) on; off: BSDF sampling alone.
    pub nee: bool,
    /// How light and BSDF samples of area emitters and the background are
    /// weighted against each other.
    pub mis: Mis,
    /// Where the random numbers come from.
    pub sampler: SamplerKind,
    /// How light sampling picks a point on an emissive triangle.
    pub light_sampling: LightSampling,
    /// First sample index rendered: a render covers sample indices
    /// `[sample_start, sample_start + spp)` of every pixel (shards).
    pub sample_start: u32,
    /// Stop at the last whole sample pass that fits this many seconds of
    /// sampling (`spp` is then the most samples taken).
    pub time_limit: Option<f64>,
    /// Samples per batch of the variance estimate ([`Film::batch`]); 0:
    /// chosen by [`RenderOptions::batch`]. Shards of one render must share
    /// it, so `render --shard` sets it from the full sample count.
    pub variance_batch: u32,
    /// Whole passes until the image's estimated relMSE is at most this
    /// (`--target-error`; `spp` is the cap). See [`crate::adaptive`].
    pub target_error: Option<f64>,
    /// Per-pixel stopping once a pixel's estimated relative standard error
    /// is below this (`--adaptive`; `spp` is the per-pixel cap).
    pub adaptive: Option<f64>,
}

/// How next-event estimation picks a point on an emissive triangle
/// (`--light-sampling`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum LightSampling {
    /// Uniformly in the solid angle the triangle subtends, where that is
    /// large and well conditioned (0.1 to 6.22 sr, no sliver, not grazing:
    /// [`crate::lights::spherical_sampling_angle`]; Arvo 1995), by area
    /// elsewhere.
    #[default]
    SolidAngle,
    /// Uniformly by area everywhere (glint before solid-angle sampling;
    /// kept to measure it against).
    Area,
}

impl LightSampling {
    pub fn name(self) -> &'static str {
        match self {
            LightSampling::SolidAngle => "solid-angle",
            LightSampling::Area => "area",
        }
    }
}

/// Multiple importance sampling between next-event estimation and BSDF
/// sampling (Veach 1997, ch. 9).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Mis {
    /// w = a^2 / (a^2 + b^2) (Veach's power heuristic, beta 2; Mitsuba 3).
    #[default]
    Power,
    /// w = a / (a + b).
    Balance,
    /// Light sampling alone for area emitters and the background: a BSDF
    /// sample that finds an emitter the vertex also sampled lights for
    /// counts 0, a light sample counts 1.
    None,
}

impl Mis {
    /// The GPU's encoding (`Params.mis`).
    pub fn code(self) -> u32 {
        match self {
            Mis::Power => crate::abi::MIS_POWER,
            Mis::Balance => crate::abi::MIS_BALANCE,
            Mis::None => crate::abi::MIS_NONE,
        }
    }
    pub fn name(self) -> &'static str {
        match self {
            Mis::Power => "power",
            Mis::Balance => "balance",
            Mis::None => "none",
        }
    }
}

/// The source of each path's random numbers.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum SamplerKind {
    /// Owen-scrambled Sobol points, per-pixel scrambles (`sobol`).
    #[default]
    Sobol,
    /// Independent uniform numbers from a counter-based hash
    /// (`sampling::Rng`).
    Independent,
}

impl SamplerKind {
    /// The GPU's encoding (`Params.sampler`).
    pub fn code(self) -> u32 {
        match self {
            SamplerKind::Independent => crate::abi::SAMPLER_INDEPENDENT,
            SamplerKind::Sobol => crate::abi::SAMPLER_SOBOL,
        }
    }
    pub fn name(self) -> &'static str {
        match self {
            SamplerKind::Independent => "independent",
            SamplerKind::Sobol => "sobol",
        }
    }
}

/// The largest image side a render accepts (both backends, every verb).
pub const MAX_IMAGE_SIDE: u32 = 16384;

/// Per-pixel sums over the samples, enough for the mean and for the
/// variance of the mean that statistical image comparisons need.
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    /// Samples per pixel accumulated.
    pub spp: u32,
    /// Row-major, top row first: sum of the radiance samples.
    pub sum: Vec<Vec3>,
    /// Sum of the squared radiance samples (per channel).
    pub sum_sq: Vec<Vec3>,
    /// Samples per variance batch: consecutive sample indices
    /// `[k L, (k + 1) L)` form batch k (see [`Film::variance_of_mean`]).
    pub batch: u32,
    /// Sum of the samples of the batch in progress (0 between batches).
    pub batch_run: Vec<Vec3>,
    /// Sum over the completed batches of (the batch's sum of samples)^2.
    pub batch_sq: Vec<Vec3>,
    /// Samples each pixel holds (adaptive renders, a prefix of whole
    /// batches of its sample indices); empty: every pixel holds `spp`.
    pub counts: Vec<u32>,
}

/// Counts and timings a backend reports for `--stats`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RenderStats {
    /// Rays traced (camera, continuation and shadow rays).
    pub rays: u64,
    pub render_seconds: f64,
}

impl RenderOptions {
    /// The contract's defaults for a given image size: 64 spp, unbounded
    /// depth, seed 0, the first camera, the Sobol sampler.
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            spp: 64,
            max_depth: -1,
            seed: 0,
            camera: 0,
            nee: true,
            mis: Mis::Power,
            sampler: SamplerKind::default(),
            light_sampling: LightSampling::default(),
            sample_start: 0,
            time_limit: None,
            variance_batch: 0,
            target_error: None,
            adaptive: None,
        }
    }

    /// Samples per batch of the variance estimate ([`Film::batch`]): 1
    /// (every sample its own batch, the independent estimate) for the
    /// independent sampler; for Sobol, `variance_batch` when set, else
    /// [`variance_batch_for`] of the render's sample count. A batch that
    /// does not divide `sample_start` falls back to 1 (batches must start
    /// where the render starts). A controlled render (`target_error` or
    /// `adaptive`) defaults to [`crate::adaptive::control_batch`].
    pub fn batch(&self) -> u32 {
        let l = match (self.sampler, self.variance_batch) {
            (SamplerKind::Independent, _) => 1,
            (SamplerKind::Sobol, 0) if self.target_error.is_some() || self.adaptive.is_some() => {
                crate::adaptive::control_batch(self.spp)
            }
            (SamplerKind::Sobol, 0) => variance_batch_for(self.spp, 1),
            (SamplerKind::Sobol, l) => l,
        };
        if self.sample_start.is_multiple_of(l) {
            l
        } else {
            1
        }
    }
}

/// Fewest batches a batched variance estimate uses: 15 degrees of freedom
/// per pixel, about a thousand per 8x8 block of `compare`.
pub const MIN_VARIANCE_BATCHES: u32 = 16;

/// The batch size for `spp` Sobol samples split into `shards`: the largest
/// power of two L that divides `spp` and leaves at least
/// max([`MIN_VARIANCE_BATCHES`], 2 shards) batches, so that every shard
/// holds at least two whole batches (its EXR's variance, from which
/// `merge` recovers the batch sums, needs two); 1 when none does.
pub fn variance_batch_for(spp: u32, shards: u32) -> u32 {
    let need = MIN_VARIANCE_BATCHES.max(shards.saturating_mul(2));
    let mut l = 1u32;
    while l <= u32::MAX / 2 && spp.is_multiple_of(2 * l) && spp / (2 * l) >= need {
        l *= 2;
    }
    l
}

/// Bytes per pixel a CPU render holds at its peak: the film's four sums
/// (48), its means (12) and the EXR writer's planes of mean and variance
/// with their compressed copy (about 36).
pub const CPU_BYTES_PER_PIXEL: u64 = 96;

/// Refuse a CPU film the machine cannot hold ([`crate::safe_fs::available_memory`]),
/// before anything is allocated: the allocator would otherwise abort the
/// process, leaving its temporaries behind.
pub fn check_memory(width: u32, height: u32) -> Result<(), String> {
    let need = width as u64 * height as u64 * CPU_BYTES_PER_PIXEL;
    match crate::safe_fs::available_memory() {
        Some(have) if need > have => Err(format!(
            "a {width}x{height} CPU render needs about {:.1} GB but about {:.1} GB is available; \
             render a smaller image (--width/--height) or split the samples with --shard \
             across machines with more memory",
            need as f64 / 1e9,
            have as f64 / 1e9
        )),
        _ => Ok(()),
    }
}

/// The image formats `glint render` writes, chosen by file extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OutputFormat {
    /// Linear RGB radiance, 32-bit float, no tone mapping.
    Exr,
    /// 8-bit sRGB (the sRGB OETF), clamped to [0, 1].
    Png,
}

impl OutputFormat {
    /// From the extension (case-insensitive): `.exr` or `.png`.
    pub fn from_path(path: &Path) -> Option<Self> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "exr" => Some(Self::Exr),
            "png" => Some(Self::Png),
            _ => None,
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum ImageWriteError {
    #[error("{path}: unsupported output format (use .exr or .png)")]
    Format { path: PathBuf },
    #[error("{path}: {message}")]
    Io { path: PathBuf, message: String },
}

/// One sample into a pixel's sums (both backends' order of operations:
/// the GPU kernel does the same in `pathtrace.comp`).
#[inline]
pub fn add_sample(
    batch: u32,
    s: u32,
    l: Vec3,
    sum: &mut Vec3,
    sum_sq: &mut Vec3,
    run: &mut Vec3,
    sq: &mut Vec3,
) {
    *sum += l;
    *sum_sq += l * l;
    *run += l;
    if (s + 1).is_multiple_of(batch.max(1)) {
        *sq += *run * *run;
        *run = Vec3::ZERO;
    }
}

/// The sRGB OETF (IEC 61966-2-1) of a linear value clamped to [0, 1],
/// quantised to 8 bits with rounding.
pub fn srgb_encode_u8(linear: f32) -> u8 {
    let c = if linear.is_nan() {
        0.0
    } else {
        linear.clamp(0.0, 1.0)
    };
    let s = if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5).floor().clamp(0.0, 255.0) as u8
}

impl Film {
    /// An empty film (no samples).
    pub fn new(width: u32, height: u32) -> Self {
        let n = width as usize * height as usize;
        Self {
            width,
            height,
            spp: 0,
            sum: vec![Vec3::ZERO; n],
            sum_sq: vec![Vec3::ZERO; n],
            batch: 1,
            batch_run: vec![Vec3::ZERO; n],
            batch_sq: vec![Vec3::ZERO; n],
            counts: Vec::new(),
        }
    }

    /// An empty film whose variance estimate uses batches of `batch` samples.
    pub fn with_batch(width: u32, height: u32, batch: u32) -> Self {
        Self {
            batch: batch.max(1),
            ..Self::new(width, height)
        }
    }

    /// The batch size the variance estimate uses: [`Film::batch`] when the
    /// samples are whole batches (at least two), else 1.
    pub fn variance_batch(&self) -> u32 {
        let l = self.batch.max(1);
        if l > 1 && self.spp.is_multiple_of(l) && self.spp / l >= 2 {
            l
        } else {
            1
        }
    }

    /// Samples pixel i holds ([`Film::counts`], else `spp`).
    pub fn count(&self, i: usize) -> u32 {
        self.counts.get(i).copied().unwrap_or(self.spp)
    }

    /// Mean samples per pixel.
    pub fn mean_spp(&self) -> f64 {
        if self.counts.is_empty() {
            return self.spp as f64;
        }
        self.counts.iter().map(|&c| c as f64).sum::<f64>() / self.counts.len().max(1) as f64
    }

    pub fn index(&self, x: u32, y: u32) -> usize {
        y as usize * self.width as usize + x as usize
    }

    /// Per-pixel mean radiance (the image).
    pub fn mean(&self, i: usize) -> Vec3 {
        match self.count(i) {
            0 => Vec3::ZERO,
            n => self.sum[i] / n as f32,
        }
    }

    /// Estimate of the variance of pixel i's mean, clamped at 0 against
    /// rounding; zero with fewer than two samples (unknown).
    ///
    /// Independent samples (batch 1): (sum_sq - n mean^2) / (n (n - 1)),
    /// unbiased. Scrambled Sobol points are not independent (the sample
    /// variance / n overestimates a pixel mean's variance 4-6x), so their
    /// films use batch means: with C = n / L batches of L consecutive
    /// sample indices, batch means y_k, the estimate is
    /// sum (y_k - y)^2 / (C (C - 1)) (batch means, as in MCMC output
    /// analysis; randomised QMC error estimates by Owen). Each aligned
    /// batch of a scrambled net is itself a scrambled net; the estimate
    /// is unbiased when batches are uncorrelated and conservative when
    /// they are negatively correlated, as sub-nets of one net are (the
    /// full net stratifies better than its parts). Measured, not assumed:
    /// `cpu/tests/render_stats.rs`. Adaptive films divide by the pixel's
    /// own count ([`Film::count`], whole batches).
    pub fn variance_of_mean(&self, i: usize) -> Vec3 {
        let l = self.variance_batch();
        let count = self.count(i);
        if l > 1 && count / l >= 2 {
            let c = (count / l) as f64;
            let lf = l as f64;
            let s = self.sum[i].as_dvec3() / lf;
            let s2 = self.batch_sq[i].as_dvec3() / (lf * lf);
            return ((s2 - s * s / c) / (c * (c - 1.0)))
                .max(glam::DVec3::ZERO)
                .as_vec3();
        }
        let n = count as f64;
        if count < 2 {
            return Vec3::ZERO;
        }
        let s = self.sum[i].as_dvec3();
        let s2 = self.sum_sq[i].as_dvec3();
        let v = (s2 - s * s / n) / (n * (n - 1.0));
        v.max(glam::DVec3::ZERO).as_vec3()
    }

    /// The image: per-pixel means, row-major, top row first.
    pub fn means(&self) -> Vec<Vec3> {
        (0..self.sum.len()).map(|i| self.mean(i)).collect()
    }

    /// Encode the image in `format` into `w`.
    pub fn encode<W: Write + Seek>(
        &self,
        w: &mut W,
        format: OutputFormat,
    ) -> image::ImageResult<()> {
        let means = self.means();
        match format {
            OutputFormat::Exr => {
                let data: Vec<f32> = means.iter().flat_map(|m| m.to_array()).collect();
                let img = image::Rgb32FImage::from_raw(self.width, self.height, data)
                    .expect("buffer sized from the film");
                image::DynamicImage::ImageRgb32F(img).write_to(w, image::ImageFormat::OpenExr)
            }
            OutputFormat::Png => {
                let data: Vec<u8> = means
                    .iter()
                    .flat_map(|m| m.to_array().map(srgb_encode_u8))
                    .collect();
                let img = image::RgbImage::from_raw(self.width, self.height, data)
                    .expect("buffer sized from the film");
                image::DynamicImage::ImageRgb8(img).write_to(w, image::ImageFormat::Png)
            }
        }
    }

    /// Write the image to `path` (format from its extension) through a
    /// temporary file in the same directory, renamed over `path` only once
    /// complete: no partial file is ever left under the final name, and the
    /// temporary is removed on failure.
    pub fn write_image(&self, path: &Path) -> Result<(), ImageWriteError> {
        let format = OutputFormat::from_path(path).ok_or_else(|| ImageWriteError::Format {
            path: path.to_path_buf(),
        })?;
        let io = |e: &dyn std::fmt::Display| ImageWriteError::Io {
            path: path.to_path_buf(),
            message: e.to_string(),
        };
        let (file, tmp) = crate::safe_fs::create_temp_beside(path).map_err(|e| io(&e))?;
        let result = (|| {
            let mut w = std::io::BufWriter::new(file);
            self.encode(&mut w, format).map_err(|e| io(&e))?;
            let file = w.into_inner().map_err(|e| io(&e.error().to_string()))?;
            file.sync_all().map_err(|e| io(&e))?;
            std::fs::rename(&tmp, path).map_err(|e| io(&e))
        })();
        if result.is_err() {
            let _ = std::fs::remove_file(&tmp);
        }
        result
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_oetf_and_clamping() {
        assert_eq!(srgb_encode_u8(0.0), 0);
        assert_eq!(srgb_encode_u8(1.0), 255);
        assert_eq!(srgb_encode_u8(7.5), 255);
        assert_eq!(srgb_encode_u8(-1.0), 0);
        assert_eq!(srgb_encode_u8(f32::NAN), 0);
        // Linear segment: 12.92 x 0.003 x 255 = 9.88.
        assert_eq!(srgb_encode_u8(0.003), 10);
        // Power segment: 1.055 x 0.5^(1/2.4) - 0.055 = 0.7354 -> 187.5.
        assert_eq!(srgb_encode_u8(0.5), 188);
        assert_eq!(srgb_encode_u8(0.18), 118);
    }

    #[test]
    fn mean_and_variance_of_the_mean() {
        let mut f = Film::new(1, 1);
        for v in [1.0f32, 2.0, 3.0, 6.0] {
            f.sum[0] += Vec3::splat(v);
            f.sum_sq[0] += Vec3::splat(v * v);
        }
        f.spp = 4;
        assert_eq!(f.mean(0), Vec3::splat(3.0));
        // Sample variance 14/3, of the mean 14/12.
        assert!((f.variance_of_mean(0).x - 14.0 / 12.0).abs() < 1e-5);
    }

    #[test]
    fn images_are_written_whole_or_not_at_all() {
        let dir = std::env::temp_dir().join(format!("glint-film-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut f = Film::new(3, 2);
        f.spp = 1;
        f.sum[4] = Vec3::new(0.25, 2.0, 1e-3);
        let exr = dir.join("a.exr");
        f.write_image(&exr).unwrap();
        let img = image::open(&exr).unwrap().into_rgb32f();
        assert_eq!((img.width(), img.height()), (3, 2));
        assert_eq!(img.get_pixel(1, 1).0, [0.25, 2.0, 1e-3]);
        let png = dir.join("a.png");
        f.write_image(&png).unwrap();
        assert_eq!(
            image::open(&png).unwrap().to_rgb8().get_pixel(1, 1).0,
            [137, 255, 3]
        );
        assert!(matches!(
            f.write_image(&dir.join("a.tiff")),
            Err(ImageWriteError::Format { .. })
        ));
        assert!(f.write_image(&dir.join("missing/a.png")).is_err());
        let mut names: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        names.sort();
        assert_eq!(names, ["a.exr", "a.png"]);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

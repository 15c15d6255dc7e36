//! Equirectangular environment light (`--envmap`), importance sampled by a
//! 2D piecewise-constant distribution (pbrt-v3 sec. 13.6.7, 14.2.4):
//! a marginal CDF over rows, a conditional CDF over each row's texels,
//! texel weights luminance x sin(theta) so the density is proportional to
//! radiance per solid angle. `shaders/integrator/lights.glsl` mirrors
//! [`EnvMap::sample`], [`EnvMap::pdf`] and [`EnvMap::radiance`].
//!
//! Mapping (+Y up; the image's top row looks up): for image coordinates
//! (u, v) in [0, 1]^2, theta = v pi, phi = u 2 pi and
//! d = (sin theta sin phi, cos theta, -sin theta cos phi): the left edge
//! looks down -Z, a quarter across +X, the centre +Z. `rotation` turns the
//! map about +Y (right-handed, radians). Radiance is the nearest texel (so
//! the sampling density is exact), times `--envmap-scale`.

// `!(x > 0.0)` on floats is meant: it rejects NaN too.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use std::f32::consts::PI;
use std::path::Path;

use glam::{Vec2, Vec3};

use crate::lights::luminance;
use crate::sampling::sample_cdf;

/// Largest envmap side accepted (checked from the header).
pub const MAX_ENVMAP_SIDE: u32 = 16384;
/// Most texels accepted (2^26: 1 GiB as RGBA f32 with the CDFs).
pub const MAX_ENVMAP_TEXELS: u64 = 1 << 26;

/// The direction of image coordinates (u, v) in the map's own frame
/// (before its rotation): the mapping of the module documentation.
pub fn uv_to_map_direction(uv: Vec2) -> Vec3 {
    let theta = uv.y * PI;
    let phi = uv.x * 2.0 * PI;
    let (st, ct) = theta.sin_cos();
    let (sp, cp) = phi.sin_cos();
    Vec3::new(st * sp, ct, -st * cp)
}

#[derive(Clone, Debug, Default)]
pub struct EnvMap {
    pub width: u32,
    pub height: u32,
    /// Linear RGB radiance (times the scale), row 0 the top, `.w` unused.
    pub texels: Vec<[f32; 4]>,
    /// Rotation about +Y in radians.
    pub rotation: f32,
    /// `height` inclusive CDF entries over rows, then `height` row pmfs.
    pub marginal: Vec<f32>,
    /// Per row: `width` inclusive CDF entries, then `width` pmfs
    /// (row y at `2 * width * y`).
    pub conditional: Vec<f32>,
}

/// A sampled direction and its solid-angle density.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EnvSample {
    pub wi: Vec3,
    pub pdf: f32,
    pub radiance: Vec3,
}

/// Inclusive CDF and pmf of `w` (uniform when all are zero).
fn cdf_pmf(w: &[f64]) -> (Vec<f32>, Vec<f32>, f64) {
    let total: f64 = w.iter().sum();
    let n = w.len();
    let (mut cdf, mut pmf) = (Vec::with_capacity(n), Vec::with_capacity(n));
    let mut acc = 0.0f64;
    for &x in w {
        let p = if total > 0.0 {
            x / total
        } else {
            1.0 / n as f64
        };
        acc += p;
        cdf.push(acc as f32);
        pmf.push(p as f32);
    }
    if let Some(l) = cdf.last_mut() {
        *l = 1.0;
    }
    (cdf, pmf, total)
}

impl EnvMap {
    /// An envmap from linear RGB texels (row 0 the top).
    pub fn new(width: u32, height: u32, rgb: &[[f32; 3]], scale: f32, rotation: f32) -> Self {
        let (w, h) = (width as usize, height as usize);
        let texels: Vec<[f32; 4]> = rgb
            .iter()
            .map(|c| {
                // A texel with a non-finite channel emits nothing (the
                // load's warning says so): tested before the clamp, whose
                // max() would make a NaN channel 0 and keep the others.
                let c = Vec3::from(*c) * scale;
                let c = if c.is_finite() {
                    c.max(Vec3::ZERO)
                } else {
                    Vec3::ZERO
                };
                [c.x, c.y, c.z, 0.0]
            })
            .collect();
        let mut conditional = Vec::with_capacity(2 * w * h);
        let mut rows = Vec::with_capacity(h);
        for y in 0..h {
            let sin_t = (PI * (y as f32 + 0.5) / h as f32).sin() as f64;
            let weights: Vec<f64> = (0..w)
                .map(|x| {
                    let c = texels[y * w + x];
                    luminance(Vec3::new(c[0], c[1], c[2])).max(0.0) as f64 * sin_t
                })
                .collect();
            let (cdf, pmf, total) = cdf_pmf(&weights);
            conditional.extend(cdf);
            conditional.extend(pmf);
            rows.push(total);
        }
        let (mcdf, mpmf, _) = cdf_pmf(&rows);
        let mut marginal = mcdf;
        marginal.extend(mpmf);
        EnvMap {
            width,
            height,
            texels,
            rotation,
            marginal,
            conditional,
        }
    }

    /// Read an equirectangular `.exr` or `.hdr` (linear RGB), size checked
    /// from the header before decoding.
    pub fn load(path: &Path, scale: f32, rotation_degrees: f32) -> Result<Self, String> {
        Self::load_checked(path, scale, rotation_degrees).map(|(map, _)| map)
    }

    /// [`EnvMap::load`], and how many texels were not finite (NaN or
    /// infinite, after `scale`): those light nothing (they become 0), which
    /// the caller warns about. Only a regular file is opened (a FIFO or a
    /// device is refused without blocking).
    pub fn load_checked(
        path: &Path,
        scale: f32,
        rotation_degrees: f32,
    ) -> Result<(Self, usize), String> {
        let open = || -> Result<image::ImageReader<std::io::BufReader<std::fs::File>>, String> {
            let file = crate::safe_fs::open_regular(path)?;
            image::ImageReader::new(std::io::BufReader::new(file))
                .with_guessed_format()
                .map_err(|e| format!("cannot read: {e}"))
        };
        let reader = open()?;
        match reader.format() {
            Some(image::ImageFormat::OpenExr) | Some(image::ImageFormat::Hdr) => {}
            _ => return Err("not an .exr or .hdr image".into()),
        }
        let (w, h) = reader
            .into_dimensions()
            .map_err(|e| format!("does not decode: {e}"))?;
        if w == 0 || h == 0 || w > MAX_ENVMAP_SIDE || h > MAX_ENVMAP_SIDE {
            return Err(format!(
                "is {w}x{h}; glint reads environment maps of 1..={MAX_ENVMAP_SIDE} pixels a side"
            ));
        }
        if w as u64 * h as u64 > MAX_ENVMAP_TEXELS {
            return Err(format!(
                "is {w}x{h}; glint reads environment maps of at most {MAX_ENVMAP_TEXELS} pixels"
            ));
        }
        let img = open()?
            .decode()
            .map_err(|e| format!("does not decode: {e}"))?
            .to_rgb32f();
        let rgb: Vec<[f32; 3]> = img.pixels().map(|p| p.0).collect();
        let bad = rgb
            .iter()
            .filter(|c| !(Vec3::from(**c) * scale).is_finite())
            .count();
        Ok((
            Self::new(w, h, &rgb, scale, rotation_degrees.to_radians()),
            bad,
        ))
    }

    /// World direction to map direction (undo the rotation about +Y).
    fn to_map(&self, d: Vec3) -> Vec3 {
        let (s, c) = self.rotation.sin_cos();
        Vec3::new(c * d.x - s * d.z, d.y, s * d.x + c * d.z)
    }

    fn to_world(&self, d: Vec3) -> Vec3 {
        let (s, c) = self.rotation.sin_cos();
        Vec3::new(c * d.x + s * d.z, d.y, -s * d.x + c * d.z)
    }

    /// Image coordinates (u, v) of world direction `d`.
    pub fn direction_to_uv(&self, d: Vec3) -> Vec2 {
        let m = self.to_map(d);
        let theta = m.y.clamp(-1.0, 1.0).acos();
        let mut phi = m.x.atan2(-m.z);
        if phi < 0.0 {
            phi += 2.0 * PI;
        }
        Vec2::new(phi / (2.0 * PI), theta / PI)
    }

    /// World direction of image coordinates (u, v).
    pub fn uv_to_direction(&self, uv: Vec2) -> Vec3 {
        self.to_world(uv_to_map_direction(uv))
    }

    fn texel_of(&self, uv: Vec2) -> (u32, u32) {
        let x = ((uv.x * self.width as f32) as u32).min(self.width - 1);
        let y = ((uv.y * self.height as f32) as u32).min(self.height - 1);
        (x, y)
    }

    /// Radiance arriving from direction `d` (pointing away from the scene).
    pub fn radiance(&self, d: Vec3) -> Vec3 {
        let (x, y) = self.texel_of(self.direction_to_uv(d));
        let c = self.texels[(y * self.width + x) as usize];
        Vec3::new(c[0], c[1], c[2])
    }

    /// Probability of choosing texel (x, y).
    pub fn texel_pmf(&self, x: u32, y: u32) -> f32 {
        let h = self.height as usize;
        let w = self.width as usize;
        self.marginal[h + y as usize] * self.conditional[2 * w * y as usize + w + x as usize]
    }

    /// Solid-angle density of sampling direction `d`.
    pub fn pdf(&self, d: Vec3) -> f32 {
        let uv = self.direction_to_uv(d);
        let sin_t = (uv.y * PI).sin();
        if !(sin_t > 0.0) {
            return 0.0;
        }
        let (x, y) = self.texel_of(uv);
        self.texel_pmf(x, y) * (self.width * self.height) as f32 / (2.0 * PI * PI * sin_t)
    }

    /// A direction with density proportional to the texel weights: a row
    /// by the marginal CDF, a texel by its row's CDF, each uniform number
    /// reused (rescaled) for the position inside the texel.
    pub fn sample(&self, u: Vec2) -> Option<EnvSample> {
        let (w, h) = (self.width as usize, self.height as usize);
        let y = sample_cdf(|i| self.marginal[i as usize], self.height, u.y);
        let py = self.marginal[h + y as usize];
        let cy = if y > 0 {
            self.marginal[y as usize - 1]
        } else {
            0.0
        };
        let fy = ((u.y - cy) / py).clamp(0.0, 1.0);
        let row = 2 * w * y as usize;
        let x = sample_cdf(|i| self.conditional[row + i as usize], self.width, u.x);
        let px = self.conditional[row + w + x as usize];
        let cx = if x > 0 {
            self.conditional[row + x as usize - 1]
        } else {
            0.0
        };
        let fx = ((u.x - cx) / px).clamp(0.0, 1.0);
        let uv = Vec2::new(
            (x as f32 + fx) / self.width as f32,
            (y as f32 + fy) / self.height as f32,
        );
        let wi = self.uv_to_direction(uv);
        // Density and radiance of the texel chosen (not re-derived from the
        // direction, which at a texel edge may round into a neighbour).
        let sin_t = (uv.y * PI).sin();
        let pdf = px * py * (self.width * self.height) as f32 / (2.0 * PI * PI * sin_t);
        if !(pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        let c = self.texels[y as usize * w + x as usize];
        Some(EnvSample {
            wi,
            pdf,
            radiance: Vec3::new(c[0], c[1], c[2]),
        })
    }

    /// Bytes the GPU holds for it.
    pub fn bytes(&self) -> usize {
        self.texels.len() * 16 + (self.marginal.len() + self.conditional.len()) * 4
    }
}

//! Image error metrics, one implementation for `converge`, `compare`,
//! `diff` and the tests (contract, "Metrics").
//!
//! - relMSE: mean over pixels and channels of (x - r)^2 / (r^2 + 0.01)
//!   (the 0.01 keeps black reference pixels from dominating, as in
//!   Rousselle et al. and Mitsuba's and pbrt's convergence studies).
//! - trimmed relMSE: the same after dropping the 0.1% of pixels with the
//!   largest error (a pixel's error: the mean over its channels), so a
//!   handful of fireflies does not decide a chart.
//! - RMSE: root mean square of x - r over pixels and channels.
//! - FLIP: NVIDIA's FLIP (Andersson et al. 2020, LDR version) through the
//!   `nv-flip` crate (bindings to NVIDIA's own implementation) on the 8-bit
//!   sRGB encodings that `glint render` writes to PNG, at the default 67
//!   pixels per degree; the mean of the error map.
//! - mean ratio: per channel, the image's mean over the reference's.

use glam::{DVec3, Vec3};

use crate::film::srgb_encode_u8;

/// The constant in relMSE's denominator.
pub const RELMSE_EPS: f64 = 0.01;
/// Fraction of pixels (the largest errors) `relmse_trim` drops.
pub const TRIM_FRACTION: f64 = 0.001;

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum MetricsError {
    #[error("images differ in size: {0}x{1} against {2}x{3}")]
    Size(u32, u32, u32, u32),
    #[error("image data does not match its size ({0} pixels for {1}x{2})")]
    Data(usize, u32, u32),
}

/// An image as the metrics see it: linear RGB, row-major, top row first.
#[derive(Clone, Copy, Debug)]
pub struct ImageRef<'a> {
    pub width: u32,
    pub height: u32,
    pub pixels: &'a [Vec3],
}

impl<'a> ImageRef<'a> {
    pub fn new(width: u32, height: u32, pixels: &'a [Vec3]) -> Result<Self, MetricsError> {
        if pixels.len() != width as usize * height as usize {
            return Err(MetricsError::Data(pixels.len(), width, height));
        }
        Ok(Self {
            width,
            height,
            pixels,
        })
    }
}

/// Every metric of one image against a reference.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Metrics {
    pub relmse: f64,
    pub relmse_trim: f64,
    pub rmse: f64,
    pub flip: f64,
    /// The image's mean per channel.
    pub mean: DVec3,
    /// The reference's mean per channel.
    pub reference_mean: DVec3,
}

impl Metrics {
    /// Per channel, the image's mean over the reference's (NaN for a
    /// black reference channel).
    pub fn mean_ratio(&self) -> DVec3 {
        self.mean / self.reference_mean
    }
}

fn check(a: &ImageRef, b: &ImageRef) -> Result<(), MetricsError> {
    if (a.width, a.height) != (b.width, b.height) {
        return Err(MetricsError::Size(a.width, a.height, b.width, b.height));
    }
    Ok(())
}

/// Per-pixel relative squared error, the mean over the channels.
fn pixel_relse(x: Vec3, r: Vec3) -> f64 {
    let (x, r) = (x.as_dvec3(), r.as_dvec3());
    let d = x - r;
    let e = d * d / (r * r + DVec3::splat(RELMSE_EPS));
    (e.x + e.y + e.z) / 3.0
}

pub fn relmse(img: &ImageRef, reference: &ImageRef) -> Result<f64, MetricsError> {
    check(img, reference)?;
    let n = img.pixels.len().max(1) as f64;
    Ok(img
        .pixels
        .iter()
        .zip(reference.pixels)
        .map(|(&x, &r)| pixel_relse(x, r))
        .sum::<f64>()
        / n)
}

/// relMSE after dropping the `TRIM_FRACTION` of pixels with the largest
/// error (floor of the count: images under 1000 pixels drop none).
pub fn relmse_trim(img: &ImageRef, reference: &ImageRef) -> Result<f64, MetricsError> {
    check(img, reference)?;
    let mut e: Vec<f64> = img
        .pixels
        .iter()
        .zip(reference.pixels)
        .map(|(&x, &r)| pixel_relse(x, r))
        .collect();
    let drop = (e.len() as f64 * TRIM_FRACTION).floor() as usize;
    // NaN sorts last (as the largest error).
    e.sort_by(|a, b| a.total_cmp(b));
    let keep = &e[..e.len() - drop];
    Ok(keep.iter().sum::<f64>() / keep.len().max(1) as f64)
}

pub fn rmse(img: &ImageRef, reference: &ImageRef) -> Result<f64, MetricsError> {
    check(img, reference)?;
    let n = (img.pixels.len().max(1) * 3) as f64;
    let s: f64 = img
        .pixels
        .iter()
        .zip(reference.pixels)
        .map(|(&x, &r)| (x.as_dvec3() - r.as_dvec3()).length_squared())
        .sum();
    Ok((s / n).sqrt())
}

/// Mean per channel.
pub fn channel_means(img: &ImageRef) -> DVec3 {
    let n = img.pixels.len().max(1) as f64;
    img.pixels.iter().map(|p| p.as_dvec3()).sum::<DVec3>() / n
}

/// The 8-bit sRGB encoding `glint render` writes to PNG.
pub fn srgb8(img: &ImageRef) -> Vec<u8> {
    img.pixels
        .iter()
        .flat_map(|p| p.to_array().map(srgb_encode_u8))
        .collect()
}

/// FLIP's per-pixel error map (values in [0, 1]) of `img` against
/// `reference`, both encoded to 8-bit sRGB first.
pub fn flip_map(img: &ImageRef, reference: &ImageRef) -> Result<Vec<f32>, MetricsError> {
    check(img, reference)?;
    let (w, h) = (img.width, img.height);
    let r = nv_flip::FlipImageRgb8::with_data(w, h, &srgb8(reference));
    let t = nv_flip::FlipImageRgb8::with_data(w, h, &srgb8(img));
    Ok(nv_flip::flip(r, t, nv_flip::DEFAULT_PIXELS_PER_DEGREE).to_vec())
}

/// Mean FLIP error.
pub fn flip(img: &ImageRef, reference: &ImageRef) -> Result<f64, MetricsError> {
    let map = flip_map(img, reference)?;
    Ok(map.iter().map(|&v| v as f64).sum::<f64>() / map.len().max(1) as f64)
}

/// Every metric at once.
pub fn compute(img: &ImageRef, reference: &ImageRef) -> Result<Metrics, MetricsError> {
    Ok(Metrics {
        relmse: relmse(img, reference)?,
        relmse_trim: relmse_trim(img, reference)?,
        rmse: rmse(img, reference)?,
        flip: flip(img, reference)?,
        mean: channel_means(img),
        reference_mean: channel_means(reference),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gradient(w: u32, h: u32) -> Vec<Vec3> {
        (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f32 / w as f32, (i / w) as f32 / h as f32);
                Vec3::new(x, y, 0.5 * (x + y))
            })
            .collect()
    }

    #[test]
    fn identical_images_have_zero_error() {
        let p = gradient(32, 24);
        let a = ImageRef::new(32, 24, &p).unwrap();
        let m = compute(&a, &a).unwrap();
        assert_eq!(m.relmse, 0.0);
        assert_eq!(m.relmse_trim, 0.0);
        assert_eq!(m.rmse, 0.0);
        assert_eq!(m.flip, 0.0);
    }

    #[test]
    fn relmse_by_hand() {
        let r = [Vec3::new(1.0, 0.0, 2.0)];
        let x = [Vec3::new(1.5, 0.1, 2.0)];
        let (a, b) = (
            ImageRef::new(1, 1, &x).unwrap(),
            ImageRef::new(1, 1, &r).unwrap(),
        );
        let want = (0.25 / 1.01 + 0.01 / 0.01 + 0.0) / 3.0;
        assert!((relmse(&a, &b).unwrap() - want).abs() < 1e-6);
        let want_rmse = ((0.25 + 0.01) / 3.0f64).sqrt();
        assert!((rmse(&a, &b).unwrap() - want_rmse).abs() < 1e-6);
    }

    #[test]
    fn trimming_drops_the_worst_tenth_of_a_percent() {
        let r = vec![Vec3::ONE; 2000];
        let mut x = vec![Vec3::splat(1.1); 2000];
        x[7] = Vec3::splat(100.0);
        x[1999] = Vec3::splat(50.0);
        let (a, b) = (
            ImageRef::new(2000, 1, &x).unwrap(),
            ImageRef::new(2000, 1, &r).unwrap(),
        );
        let per = 0.01 / 1.01;
        assert!((relmse_trim(&a, &b).unwrap() - per).abs() < 1e-6 * per);
        assert!(relmse(&a, &b).unwrap() > 10.0 * per);
    }

    #[test]
    fn flip_grows_with_the_error() {
        let r = gradient(64, 64);
        let reference = ImageRef::new(64, 64, &r).unwrap();
        let mut last = 0.0;
        for k in [0.02f32, 0.1, 0.3] {
            let x: Vec<Vec3> = r
                .iter()
                .enumerate()
                .map(|(i, p)| *p * (1.0 + if i % 2 == 0 { k } else { -k }))
                .collect();
            let f = flip(&ImageRef::new(64, 64, &x).unwrap(), &reference).unwrap();
            assert!(f > last, "FLIP {f} at error {k} not above {last}");
            last = f;
        }
    }

    #[test]
    fn sizes_must_match() {
        let p = gradient(4, 4);
        let q = gradient(2, 8);
        let a = ImageRef::new(4, 4, &p).unwrap();
        let b = ImageRef::new(2, 8, &q).unwrap();
        assert_eq!(relmse(&a, &b), Err(MetricsError::Size(4, 4, 2, 8)));
        assert!(ImageRef::new(3, 3, &p).is_err());
    }
}

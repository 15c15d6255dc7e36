//! `glint merge SHARD.exr ... -o OUT.exr`: shards of one render combined
//! exactly.
//!
//! Each shard's EXR holds its mean m, the variance of its mean v and its
//! sample count n (`glint.spp`). Those give back its sums exactly (up to
//! the f32 the file stores): sum = n m, sum of squares = n (n - 1) v +
//! n m^2 (the inverse of `Film::variance_of_mean`; with n = 1, v is 0 and
//! the sum of squares is m^2, still exact). The merged film is the sum of
//! the shards' sums, so its mean is the sample-weighted mean and its
//! variance the pooled one: what one render of all the samples gives, up
//! to the order of the floating-point additions. Nothing beyond what
//! `--variance` writes is stored.
//!
//! Sobol renders estimate the variance from batch means
//! (`glint.variance_batch` = L samples per batch, `Film::variance_of_mean`):
//! the same pooling then runs over batches, n / L per shard, each a batch
//! mean. Shards of one render share L and hold whole batches
//! (`render --shard`), so the pooled estimate is again exactly the single
//! render's; shards with different L are refused.

use std::path::{Path, PathBuf};

use anyhow::{Result, anyhow, bail};
use glam::DVec3;
use glint::cpu::exr_file::{RadianceImage, RenderMeta, format_ranges};

use super::outputs::Outputs;
use super::outputs::names_same;
use crate::cli::MergeArgs;

struct Shard {
    path: PathBuf,
    img: RadianceImage,
    meta: RenderMeta,
}

fn read(path: &Path) -> Result<Shard> {
    super::check_input_file(path, "an EXR image")?;
    let img = RadianceImage::read(path).map_err(|e| anyhow!("{}: {e}", path.display()))?;
    let Some(meta) = img.meta.clone() else {
        bail!(
            "{}: not a glint render (no glint.* header attributes)",
            path.display()
        );
    };
    if meta.scene.is_none() {
        bail!(
            "{}: no glint.scene attribute to match shards by",
            path.display()
        );
    }
    // A NaN or infinite shard would poison every merged pixel it covers.
    if let Some(at) = super::first_non_finite(img.width, &img.mean) {
        bail!(
            "{}: a non-finite value (NaN or infinite) at {at}",
            path.display()
        );
    }
    if let Some(at) = img
        .variance
        .as_ref()
        .and_then(|v| super::first_non_finite(img.width, v))
    {
        bail!(
            "{}: a non-finite variance (NaN or infinite) at {at}",
            path.display()
        );
    }
    Ok(Shard {
        path: path.to_path_buf(),
        img,
        meta,
    })
}

/// The refusals, one clear line each, naming the shard that does not fit.
fn check(shards: &[Shard]) -> Result<()> {
    let first = &shards[0];
    let f = first.path.display();
    for s in &shards[1..] {
        let p = s.path.display();
        let (a, b) = (&first.meta, &s.meta);
        if (s.img.width, s.img.height) != (first.img.width, first.img.height) {
            bail!(
                "{p}: {}x{} but {f} is {}x{}",
                s.img.width,
                s.img.height,
                first.img.width,
                first.img.height
            );
        }
        if a.scene != b.scene {
            bail!("{p}: a different scene or image options (camera, depth, methods) than {f}");
        }
        if a.seed != b.seed {
            bail!("{p}: seed {} but {f} has seed {}", b.seed, a.seed);
        }
        if a.sampler != b.sampler {
            bail!("{p}: sampler {} but {f} has {}", b.sampler, a.sampler);
        }
        if s.img.variance.is_some() != first.img.variance.is_some() {
            bail!(
                "{p}: {} variance but {f} {} (render every shard with --variance, or none)",
                if s.img.variance.is_some() {
                    "holds"
                } else {
                    "holds no"
                },
                if first.img.variance.is_some() {
                    "does"
                } else {
                    "does not"
                }
            );
        }
        if s.img.variance.is_some() && a.variance_batch != b.variance_batch {
            bail!(
                "{p}: variance estimated in batches of {} samples but {f} in batches of {} \
                 (render the shards with one --spp and shard count)",
                b.variance_batch,
                a.variance_batch
            );
        }
        if a.version != b.version {
            eprintln!(
                "glint: warning: {p}: written by glint {} but {f} by glint {}",
                b.version, a.version
            );
        } else if let (Some(x), Some(y)) = (&a.build, &b.build)
            && x != y
        {
            eprintln!(
                "glint: warning: {p}: rendered by build {y} of glint {} but {f} by build {x} \
                 (different builds of one version may render differently)",
                b.version
            );
        }
    }
    // Overlap: every pair of sample ranges, sorted by start.
    let mut ranges: Vec<((u32, u32), &Path)> = shards
        .iter()
        .flat_map(|s| s.meta.samples.iter().map(move |r| (*r, s.path.as_path())))
        .collect();
    ranges.sort_by_key(|(r, _)| *r);
    for w in ranges.windows(2) {
        let ((a, pa), (b, pb)) = (w[0], w[1]);
        if a == b {
            bail!(
                "{}: holds the same samples ({}-{}) as {} (a duplicate shard)",
                pb.display(),
                b.0,
                b.1,
                pa.display()
            );
        }
        if b.0 < a.1 {
            bail!(
                "{}: samples {}-{} overlap {}'s {}-{}",
                pb.display(),
                b.0,
                b.1,
                pa.display(),
                a.0,
                a.1
            );
        }
    }
    Ok(())
}

/// Pool the shards (see the module notes), in f64: each with its count of
/// samples (or of variance batches).
pub fn pool(images: &[(&RadianceImage, u32)]) -> RadianceImage {
    let (w, h) = (images[0].0.width, images[0].0.height);
    let n_px = images[0].0.mean.len();
    let total: f64 = images.iter().map(|(_, n)| *n as f64).sum();
    let with_var = images.iter().all(|(i, _)| i.variance.is_some());
    let mut mean = Vec::with_capacity(n_px);
    let mut variance = Vec::with_capacity(if with_var { n_px } else { 0 });
    for px in 0..n_px {
        let mut s = DVec3::ZERO;
        let mut q = DVec3::ZERO;
        for (img, n) in images {
            let n = *n as f64;
            let m = img.mean[px].as_dvec3();
            s += n * m;
            if let Some(v) = &img.variance {
                q += n * (n - 1.0) * v[px].as_dvec3() + n * m * m;
            }
        }
        mean.push((s / total).as_vec3());
        if with_var {
            let v = if total < 2.0 {
                DVec3::ZERO
            } else {
                ((q - s * s / total) / (total * (total - 1.0))).max(DVec3::ZERO)
            };
            variance.push(v.as_vec3());
        }
    }
    RadianceImage {
        width: w,
        height: h,
        mean,
        variance: with_var.then_some(variance),
        meta: None,
    }
}

/// Adjacent ranges joined.
fn coalesce(mut r: Vec<(u32, u32)>) -> Vec<(u32, u32)> {
    r.sort();
    let mut out: Vec<(u32, u32)> = Vec::new();
    for x in r {
        match out.last_mut() {
            Some(last) if last.1 == x.0 => last.1 = x.1,
            _ => out.push(x),
        }
    }
    out
}

pub fn run(args: &MergeArgs) -> Result<()> {
    let out = &args.output;
    if glint::cpu::OutputFormat::from_path(out) != Some(glint::cpu::OutputFormat::Exr) {
        bail!("{}: merge writes .exr only", out.display());
    }
    for s in &args.shards {
        if names_same(out, s) {
            bail!(
                "{}: is one of the shards; refusing to overwrite it",
                out.display()
            );
        }
    }
    let mut outputs = Outputs::new();
    let slot = outputs.reserve(out)?;
    let shards = args
        .shards
        .iter()
        .map(|p| read(p))
        .collect::<Result<Vec<_>>>()?;
    check(&shards)?;
    // Pooled in units of variance batches (module notes).
    let images: Vec<(&RadianceImage, u32)> = shards
        .iter()
        .map(|s| (&s.img, s.meta.spp / s.meta.variance_batch.max(1)))
        .collect();
    let mut merged = pool(&images);
    let samples = coalesce(shards.iter().flat_map(|s| s.meta.samples.clone()).collect());
    let spp: u32 = shards.iter().map(|s| s.meta.spp).sum();
    let first = &shards[0].meta;
    let shard = if samples == [(0, spp)] {
        "0/1".to_string()
    } else {
        shards
            .iter()
            .map(|s| s.meta.shard.clone())
            .collect::<Vec<_>>()
            .join("+")
    };
    merged.meta = Some(RenderMeta {
        spp,
        seed: first.seed,
        sampler: first.sampler.clone(),
        shard,
        // The version and build that rendered the samples, where the shards
        // share one (the merging binary's version otherwise).
        version: if shards.iter().all(|s| s.meta.version == first.version) {
            first.version.clone()
        } else {
            env!("CARGO_PKG_VERSION").to_string()
        },
        build: first
            .build
            .clone()
            .filter(|b| shards.iter().all(|s| s.meta.build.as_ref() == Some(b))),
        samples: samples.clone(),
        scene: first.scene.clone(),
        files: first.files.clone(),
        variance_batch: first.variance_batch,
    });
    outputs.write(slot, |w| merged.write(w).map_err(|e| anyhow!("{e}")))?;
    outputs.commit()?;
    eprintln!(
        "glint: wrote {} ({} shards, {spp} spp: samples {}{})",
        out.display(),
        shards.len(),
        format_ranges(&samples),
        if merged.variance.is_some() {
            ", variance pooled"
        } else {
            ""
        }
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use glint::cpu::Film;

    #[test]
    fn pooling_equals_one_film_of_all_samples() {
        // Two shards of 3 and 5 samples against one film of all 8.
        let samples: Vec<f32> = vec![0.5, 2.0, 0.25, 4.0, 1.0, 3.5, 0.0, 7.0];
        let film = |xs: &[f32]| {
            let mut f = Film::new(1, 1);
            for &x in xs {
                f.sum[0] += Vec3::splat(x);
                f.sum_sq[0] += Vec3::splat(x * x);
            }
            f.spp = xs.len() as u32;
            f
        };
        let (a, b, all) = (film(&samples[..3]), film(&samples[3..]), film(&samples));
        let (ia, ib) = (
            RadianceImage::from_film(&a, true, None),
            RadianceImage::from_film(&b, true, None),
        );
        let m = pool(&[(&ia, 3), (&ib, 5)]);
        let rel = |x: f32, y: f32| ((x - y) / y).abs();
        assert!(rel(m.mean[0].x, all.mean(0).x) < 1e-6);
        assert!(rel(m.variance.unwrap()[0].x, all.variance_of_mean(0).x) < 1e-5);
        assert_eq!(coalesce(vec![(4, 8), (0, 4), (9, 10)]), [(0, 8), (9, 10)]);
    }
}

//! `--shard I/N` and what every `.exr` records (glint's header
//! attributes): the sample range a render covers, and the content key that
//! tells `merge` two shards are of one image.

use std::str::FromStr;

use anyhow::{Result, bail};
use glint::cpu::exr_file::RenderMeta;
use glint::cpu::{RenderOptions, Scene};

use glint::cache::{KeyScope, SourceKey, render_key};

/// Shard `index` of `count` (0-based).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    pub index: u32,
    pub count: u32,
}

impl Shard {
    pub const WHOLE: Shard = Shard { index: 0, count: 1 };

    /// Sample indices `[start, end)` of this shard of `spp` samples in
    /// whole variance batches of `batch` samples (which divides `spp`):
    /// `[floor(I C / N) L, floor((I + 1) C / N) L)` with C = spp / L
    /// batches. The N ranges tile `[0, spp)` exactly, each within one
    /// batch of spp / N.
    pub fn range(self, spp: u32, batch: u32) -> (u32, u32) {
        let batch = batch.max(1);
        let c = (spp / batch) as u64;
        let at = |i: u32| (i as u64 * c / self.count as u64) as u32 * batch;
        (at(self.index), at(self.index + 1))
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl FromStr for Shard {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || format!("'{s}' is not I/N (shard I of N, 0 <= I < N, e.g. 0/4)");
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let (index, count) = (
            i.trim().parse::<u32>().map_err(|_| bad())?,
            n.trim().parse::<u32>().map_err(|_| bad())?,
        );
        if count == 0 || index >= count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }
}

/// Set `opts` to render only `shard` of its samples; a shard that would
/// hold no samples is an error.
///
/// Sobol shards share the variance batch of the full render
/// ([`glint::cpu::film::variance_batch_for`] of `--spp` and N), and each
/// holds whole batches, so that merging them pools exactly what one render
/// of all the samples estimates.
pub fn apply(opts: &mut RenderOptions, shard: Shard) -> Result<()> {
    if opts.variance_batch == 0 {
        opts.variance_batch = match opts.sampler {
            glint::cpu::SamplerKind::Sobol => {
                glint::cpu::film::variance_batch_for(opts.spp, shard.count)
            }
            glint::cpu::SamplerKind::Independent => 1,
        };
    }
    let (start, end) = shard.range(opts.spp, opts.variance_batch);
    if start == end {
        bail!(
            "--shard {shard} of --spp {} holds no samples (at most {} shards)",
            opts.spp,
            opts.spp
        );
    }
    opts.sample_start = start;
    opts.spp = end - start;
    Ok(())
}

/// The key of what defines the image apart from its samples
/// ([`KeyScope::Image`]), recorded in every shard's EXR.
pub fn image_key(source: SourceKey, scene: &Scene, opts: &RenderOptions) -> String {
    render_key(source, scene, opts, KeyScope::Image)
}

/// What an `.exr` of a finished render records; `spp` is the samples
/// taken (a time limit may stop short of `opts.spp`).
pub fn render_meta(
    source: SourceKey,
    scene: &Scene,
    opts: &RenderOptions,
    shard: Shard,
    spp: u32,
) -> RenderMeta {
    RenderMeta {
        spp,
        seed: opts.seed,
        sampler: opts.sampler.name().to_string(),
        shard: shard.to_string(),
        version: env!("CARGO_PKG_VERSION").to_string(),
        build: glint::build_id::build_id().map(String::from),
        samples: vec![(opts.sample_start, opts.sample_start + spp)],
        scene: Some(image_key(source, scene, opts)),
        files: Some(source.to_string()),
        variance_batch: opts.batch(),
    }
}

/// Why the image `there` records was not made from what `here` records
/// (their scene keys differ), saying whether the scene's files or the image
/// options differ where both record the files' part; None when the keys
/// match or `here` records none.
pub fn key_mismatch(here: Option<&RenderMeta>, there: Option<&RenderMeta>) -> Option<String> {
    let scene = |m: Option<&RenderMeta>| m.and_then(|m| m.scene.clone());
    let a = here?;
    if scene(Some(a)) == scene(there) {
        return None;
    }
    let what = match (&a.files, there.and_then(|m| m.files.as_ref())) {
        (Some(x), Some(y)) if x == y => {
            "made with other image options (size, camera, depth, NEE, MIS or light sampling)"
        }
        (Some(_), Some(_)) => {
            "made from other scene files (or --multiscatter, --background or the environment map)"
        }
        _ => "made from another scene or settings (or by a glint that keyed scenes otherwise)",
    };
    Some(format!(
        "{what}: scene key {} here, {} in the reference",
        scene(Some(a)).unwrap_or_else(|| "none".into()),
        scene(there).unwrap_or_else(|| "none".into())
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_tile_the_samples() {
        for spp in [1u32, 3, 4, 7, 64, 100, 256, 4096] {
            for n in (1..=spp.min(9)).chain([16, 64].into_iter().filter(|&n| n <= spp)) {
                let mut next = 0;
                for i in 0..n {
                    let batch = glint::cpu::film::variance_batch_for(spp, n);
                    let (a, b) = Shard { index: i, count: n }.range(spp, batch);
                    assert_eq!(a % batch, 0);
                    // Two whole batches at least, where batches are used.
                    assert!(batch == 1 || b - a >= 2 * batch, "{i}/{n} of {spp}");
                    assert_eq!(a, next);
                    assert!(b > a, "{i}/{n} of {spp}");
                    next = b;
                }
                assert_eq!(next, spp);
            }
        }
        assert_eq!("2/4".parse::<Shard>(), Ok(Shard { index: 2, count: 4 }));
        for bad in ["4/4", "1/0", "-1/4", "1", "a/b"] {
            assert!(bad.parse::<Shard>().is_err(), "{bad}");
        }
    }
}

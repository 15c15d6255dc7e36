//! OpenEXR files as glint writes and reads them: the image (`R`, `G`, `B`:
//! each pixel's mean radiance, 32-bit float), optionally `variance.R`,
//! `variance.G`, `variance.B` (the variance of each pixel's mean), and
//! glint's header attributes (contract, "Additions"):
//!
//! | attribute | type | meaning |
//! |---|---|---|
//! | `glint.spp` | int | samples per pixel in this image |
//! | `glint.seed` | string | the random seed (decimal; a u64 does not fit an EXR int) |
//! | `glint.sampler` | string | `RenderOptions::sampler.name()` |
//! | `glint.shard` | string | `I/N` for shard I of N, `0/1` for a whole render, `I,J,.../N` for a merge of some shards |
//! | `glint.version` | string | the glint version that rendered it (a merge: the shards' where they share one, else the merging glint's) |
//! | `glint.build` | string | the build of glint that rendered it: the executable's build ID, 16 hex digits (`glint merge` tells builds of one version apart by it); absent where none was found, in older files, and in a merge of shards of different builds |
//! | `glint.samples` | string | the sample indices held, half-open ranges `a-b,c-d` (merge's overlap check) |
//! | `glint.scene` | string | a content key of the scene's files and the image-defining options (merge's same-scene check, `glint test`'s reference check) |
//! | `glint.files` | string | the part of `glint.scene` that the scene's files and the options changing what they load give (`glint test` says which part differs) |
//! | `glint.variance_batch` | int | samples per batch of the variance estimate (`Film::variance_of_mean`; 1: samples treated as independent); 1 when absent |
//!
//! The attributes come from [`RenderMeta`], which the caller builds from
//! the render options (the film holds sums, not how they were taken).
//! `image`'s EXR encoder cannot write extra channels or attributes, so this
//! module uses the `exr` crate directly. Any reader that knows `R`, `G`,
//! `B` still reads the image (extra channels are ignored by convention).

use std::collections::HashMap;
use std::io::{Seek, Write};
use std::path::Path;

use exr::prelude::*;
// The prelude brings its own `Result` alias.
use glam::Vec3;
use std::result::Result;

use crate::film::Film;

/// How an image was rendered: what every `.exr` glint writes records.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RenderMeta {
    pub spp: u32,
    pub seed: u64,
    pub sampler: String,
    /// `I/N`, `0/1` for a whole render.
    pub shard: String,
    pub version: String,
    /// The build that rendered it (the executable's build ID); absent in
    /// older files and where the platform gives none.
    pub build: Option<String>,
    /// Sample indices held, as half-open ranges, sorted, disjoint.
    pub samples: Vec<(u32, u32)>,
    /// Content key of the scene and the options that define the image
    /// (size, camera, depth, methods); absent in files from elsewhere.
    pub scene: Option<String>,
    /// The part of `scene` that comes from the scene's files (and the
    /// options that change what they load); absent in older files.
    pub files: Option<String>,
    /// Samples per batch of the variance estimate ([`Film::variance_batch`]).
    pub variance_batch: u32,
}

/// A radiance image read back or about to be written: the film-like view
/// `diff` and `merge` work on.
#[derive(Clone, Debug, PartialEq)]
pub struct RadianceImage {
    pub width: u32,
    pub height: u32,
    /// Per-pixel mean radiance, row-major, top row first.
    pub mean: Vec<Vec3>,
    /// Per-pixel variance of the mean, when the file holds it.
    pub variance: Option<Vec<Vec3>>,
    /// glint's attributes; `None` for an EXR glint did not write.
    pub meta: Option<RenderMeta>,
}

#[derive(Debug, thiserror::Error)]
pub enum ExrError {
    #[error("{0}")]
    Exr(#[from] exr::error::Error),
    #[error("no {0} channel (a linear RGB EXR needs R, G and B)")]
    Channel(&'static str),
    #[error("header attribute {0}: {1}")]
    Attribute(&'static str, String),
    #[error("holds variance.{0} but not all of variance.R, variance.G, variance.B")]
    PartialVariance(&'static str),
    /// Not a regular file, unreadable, or a header whose size the file (or
    /// the machine) cannot back.
    #[error("{0}")]
    Refused(String),
}

/// The largest side glint reads (and renders).
pub const MAX_SIDE: usize = 16384;

/// How many times its file size an EXR's pixels may claim to be. Deflate
/// (ZIP, and DWA's final stage) packs at most about 1032:1; RLE, PIZ, PXR24
/// and B44 far less. A header claiming more is lying about its size.
pub const MAX_COMPRESSION_RATIO: u64 = 2048;

/// Check what an EXR's headers claim against the file's bytes and against
/// [`MAX_SIDE`] and the machine's memory, before any pixel is allocated.
fn check_headers(meta: &exr::meta::MetaData, file_bytes: u64) -> Result<(), ExrError> {
    let mut need = 0u64;
    for h in meta.headers.iter() {
        let (w, ht) = (h.layer_size.width(), h.layer_size.height());
        if w > MAX_SIDE || ht > MAX_SIDE {
            return Err(ExrError::Refused(format!(
                "header claims {w}x{ht} pixels; glint reads images up to {MAX_SIDE} on a side"
            )));
        }
        let raw = (w as u64) * (ht as u64) * (h.channels.bytes_per_pixel as u64);
        // Each chunk costs an 8-byte offset and an 8-byte chunk header at
        // least, whatever it compresses to.
        let floor = (h.chunk_count as u64).saturating_mul(16);
        if raw > file_bytes.saturating_mul(MAX_COMPRESSION_RATIO) || floor > file_bytes {
            return Err(ExrError::Refused(format!(
                "header claims {w}x{ht} pixels ({raw} bytes) but the file holds only {file_bytes} bytes"
            )));
        }
        // The decoded planes, their f32 copies and the Vec3 images.
        let channels = h.channels.list.len() as u64;
        need += (w as u64) * (ht as u64) * (h.channels.bytes_per_pixel as u64 + 8 * channels + 24);
    }
    if let Some(have) = crate::safe_fs::available_memory()
        && need > have
    {
        return Err(ExrError::Refused(format!(
            "reading it needs about {:.1} GB but about {:.1} GB is available",
            need as f64 / 1e9,
            have as f64 / 1e9
        )));
    }
    Ok(())
}

/// Sort a single-part EXR header's attributes by name, in place. The
/// `exr` crate writes custom attributes from a `HashMap` (a new order each
/// run); sorted, the same image gives the same bytes. The header's length
/// is unchanged, so the offset table after it stays valid. A layout this
/// does not recognise is left alone.
fn sort_header_attributes(bytes: &mut [u8]) {
    // Magic number and version field; then the attributes up to a 0 byte.
    let start = 8usize;
    let mut at = start;
    let mut attrs: Vec<(Vec<u8>, std::ops::Range<usize>)> = Vec::new();
    loop {
        let Some(&first) = bytes.get(at) else {
            return;
        };
        if first == 0 {
            break;
        }
        let name_end = match bytes[at..].iter().position(|&b| b == 0) {
            Some(n) => at + n,
            None => return,
        };
        let type_end = match bytes
            .get(name_end + 1..)
            .and_then(|r| r.iter().position(|&b| b == 0))
        {
            Some(n) => name_end + 1 + n,
            None => return,
        };
        let Some(size) = bytes
            .get(type_end + 1..type_end + 5)
            .map(|b| i32::from_le_bytes(b.try_into().expect("4 bytes")))
        else {
            return;
        };
        let Some(end) = usize::try_from(size)
            .ok()
            .map(|s| type_end + 5 + s)
            .filter(|&e| e <= bytes.len())
        else {
            return;
        };
        attrs.push((bytes[at..name_end].to_vec(), at..end));
        at = end;
    }
    let mut sorted: Vec<&(Vec<u8>, std::ops::Range<usize>)> = attrs.iter().collect();
    sorted.sort_by(|a, b| a.0.cmp(&b.0));
    let block: Vec<u8> = sorted
        .iter()
        .flat_map(|(_, r)| bytes[r.clone()].to_vec())
        .collect();
    bytes[start..at].copy_from_slice(&block);
}

/// Names of the attributes.
pub mod attr {
    pub const SPP: &str = "glint.spp";
    pub const SEED: &str = "glint.seed";
    pub const SAMPLER: &str = "glint.sampler";
    pub const SHARD: &str = "glint.shard";
    pub const VERSION: &str = "glint.version";
    pub const BUILD: &str = "glint.build";
    pub const SAMPLES: &str = "glint.samples";
    pub const SCENE: &str = "glint.scene";
    pub const FILES: &str = "glint.files";
    pub const VARIANCE_BATCH: &str = "glint.variance_batch";
}

/// `a-b,c-d` for half-open ranges.
pub fn format_ranges(r: &[(u32, u32)]) -> String {
    r.iter()
        .map(|(a, b)| format!("{a}-{b}"))
        .collect::<Vec<_>>()
        .join(",")
}

/// The inverse of [`format_ranges`]; each range non-empty.
pub fn parse_ranges(s: &str) -> Option<Vec<(u32, u32)>> {
    s.split(',')
        .map(|r| {
            let (a, b) = r.trim().split_once('-')?;
            let (a, b) = (a.parse::<u32>().ok()?, b.parse::<u32>().ok()?);
            (a < b).then_some((a, b))
        })
        .collect()
}

/// The `samples` channel of an adaptive film (samples each pixel holds),
/// or None when every pixel holds `spp`.
pub fn samples_channel(film: &Film) -> Option<(&'static str, Vec<f32>)> {
    (!film.counts.is_empty()).then(|| ("samples", film.counts.iter().map(|&c| c as f32).collect()))
}

impl RadianceImage {
    /// The film's means, and its variances of the mean when `variance`;
    /// `meta`'s batch is set to the one the film's estimate used.
    pub fn from_film(film: &Film, variance: bool, meta: Option<RenderMeta>) -> Self {
        let meta = meta.map(|m| RenderMeta {
            variance_batch: film.variance_batch(),
            ..m
        });
        Self {
            width: film.width,
            height: film.height,
            mean: film.means(),
            variance: variance.then(|| {
                (0..film.sum.len())
                    .map(|i| film.variance_of_mean(i))
                    .collect()
            }),
            meta,
        }
    }

    /// Samples per pixel, when recorded.
    pub fn spp(&self) -> Option<u32> {
        self.meta.as_ref().map(|m| m.spp)
    }

    /// How many independent values per pixel the variance was estimated
    /// from (samples, or variance batches), when recorded.
    pub fn variance_samples(&self) -> Option<u32> {
        self.meta.as_ref().map(|m| m.spp / m.variance_batch.max(1))
    }

    /// Encode as EXR (32-bit float, ZIP-compressed, lossless).
    pub fn write<W: Write + Seek>(&self, w: W) -> Result<(), ExrError> {
        self.write_with(w, &[])
    }

    /// [`RadianceImage::write`] with extra float channels (name, one value
    /// per pixel): an adaptive render's `samples` ([`samples_channel`]).
    pub fn write_with<W: Write + Seek>(
        &self,
        w: W,
        extra: &[(&str, Vec<f32>)],
    ) -> Result<(), ExrError> {
        let n = self.mean.len();
        assert_eq!(n, self.width as usize * self.height as usize);
        let plane = |v: &[Vec3], c: usize| FlatSamples::F32(v.iter().map(|p| p[c]).collect());
        let mut channels: Vec<AnyChannel<FlatSamples>> = ["R", "G", "B"]
            .iter()
            .enumerate()
            .map(|(c, name)| AnyChannel::new(*name, plane(&self.mean, c)))
            .collect();
        if let Some(v) = &self.variance {
            assert_eq!(v.len(), n);
            for (c, name) in ["variance.R", "variance.G", "variance.B"]
                .iter()
                .enumerate()
            {
                channels.push(AnyChannel::new(*name, plane(v, c)));
            }
        }
        for (name, v) in extra {
            assert_eq!(v.len(), n);
            channels.push(AnyChannel::new(*name, FlatSamples::F32(v.clone())));
        }
        let mut attributes = LayerAttributes::default();
        if let Some(m) = &self.meta {
            let mut put = |k: &str, v: AttributeValue| {
                attributes.other.insert(Text::from(k), v);
            };
            let text = |s: &str| AttributeValue::Text(Text::from(s));
            put(
                attr::SPP,
                AttributeValue::I32(m.spp.min(i32::MAX as u32) as i32),
            );
            put(attr::SEED, text(&m.seed.to_string()));
            put(attr::SAMPLER, text(&m.sampler));
            put(attr::SHARD, text(&m.shard));
            put(attr::VERSION, text(&m.version));
            if let Some(b) = &m.build {
                put(attr::BUILD, text(b));
            }
            put(attr::SAMPLES, text(&format_ranges(&m.samples)));
            if let Some(k) = &m.scene {
                put(attr::SCENE, text(k));
            }
            if let Some(k) = &m.files {
                put(attr::FILES, text(k));
            }
            put(
                attr::VARIANCE_BATCH,
                AttributeValue::I32(m.variance_batch.min(i32::MAX as u32) as i32),
            );
        }
        let layer = Layer::new(
            (self.width as usize, self.height as usize),
            attributes,
            Encoding::SMALL_LOSSLESS,
            AnyChannels::sort(SmallVec::from_vec(channels)),
        );
        let mut buf = std::io::Cursor::new(Vec::new());
        Image::from_layer(layer).write().to_buffered(&mut buf)?;
        let mut bytes = buf.into_inner();
        sort_header_attributes(&mut bytes);
        let mut w = w;
        w.write_all(&bytes)
            .and_then(|_| w.flush())
            .map_err(|e| ExrError::Exr(exr::error::Error::Io(e)))?;
        Ok(())
    }

    /// Write to `path` (no temporary: callers that need whole-or-nothing
    /// files go through their own temporaries).
    pub fn write_file(&self, path: &Path) -> Result<(), ExrError> {
        let f = std::fs::File::create(path).map_err(|e| ExrError::Exr(exr::error::Error::Io(e)))?;
        self.write(std::io::BufWriter::new(f))
    }

    /// Read an EXR: its first layer's `R`, `G`, `B` (any sample type),
    /// `variance.*` when present, glint's attributes when present.
    /// Only a regular file is opened (a FIFO or a device is refused without
    /// blocking), and its header's size is checked against the file's
    /// bytes, [`MAX_SIDE`] and the machine's memory before anything is
    /// allocated ([`check_headers`]).
    pub fn read(path: &Path) -> Result<Self, ExrError> {
        let mut file = crate::safe_fs::open_regular(path).map_err(ExrError::Refused)?;
        let file_bytes = file
            .metadata()
            .map_err(|e| ExrError::Refused(format!("cannot read: {e}")))?
            .len();
        let meta = exr::meta::MetaData::read_from_buffered(std::io::BufReader::new(&file), false)?;
        check_headers(&meta, file_bytes)?;
        file.rewind()
            .map_err(|e| ExrError::Refused(format!("cannot read: {e}")))?;
        let image = read()
            .no_deep_data()
            .largest_resolution_level()
            .all_channels()
            .first_valid_layer()
            .all_attributes()
            .from_buffered(std::io::BufReader::new(file))?;
        let layer = image.layer_data;
        let (w, h) = (layer.size.width(), layer.size.height());
        let n = w * h;
        let find = |name: &str| {
            layer
                .channel_data
                .list
                .iter()
                .find(|c| c.name.eq(name))
                .map(|c| c.sample_data.values_as_f32().collect::<Vec<f32>>())
        };
        let planes = |names: [&'static str; 3]| -> Vec<Option<Vec<f32>>> {
            names.iter().map(|n| find(n)).collect()
        };
        let join = |p: Vec<Vec<f32>>| -> Vec<Vec3> {
            (0..n)
                .map(|i| Vec3::new(p[0][i], p[1][i], p[2][i]))
                .collect()
        };
        let rgb = planes(["R", "G", "B"]);
        let mut mean = Vec::new();
        for (p, name) in rgb.into_iter().zip(["R", "G", "B"]) {
            mean.push(p.ok_or(ExrError::Channel(name))?);
        }
        let var = planes(["variance.R", "variance.G", "variance.B"]);
        let variance = match var.iter().filter(|p| p.is_some()).count() {
            0 => None,
            3 => Some(join(var.into_iter().map(Option::unwrap).collect())),
            _ => {
                let missing = ["R", "G", "B"][var.iter().position(|p| p.is_none()).unwrap()];
                return Err(ExrError::PartialVariance(missing));
            }
        };
        let meta = parse_meta(&layer.attributes.other)?;
        Ok(Self {
            width: w as u32,
            height: h as u32,
            mean: join(mean),
            variance,
            meta,
        })
    }
}

fn parse_meta(other: &HashMap<Text, AttributeValue>) -> Result<Option<RenderMeta>, ExrError> {
    let get = |k: &str| other.get(&Text::from(k));
    if get(attr::SPP).is_none() {
        return Ok(None);
    }
    let text = |k: &'static str| -> Result<String, ExrError> {
        match get(k) {
            Some(AttributeValue::Text(t)) => Ok(t.to_string()),
            Some(_) => Err(ExrError::Attribute(k, "not a string".into())),
            None => Err(ExrError::Attribute(k, "missing".into())),
        }
    };
    let spp = match get(attr::SPP) {
        Some(AttributeValue::I32(v)) if *v >= 1 => *v as u32,
        _ => {
            return Err(ExrError::Attribute(
                attr::SPP,
                "not a positive integer".into(),
            ));
        }
    };
    let seed = text(attr::SEED)?
        .parse::<u64>()
        .map_err(|e| ExrError::Attribute(attr::SEED, e.to_string()))?;
    let samples = match get(attr::SAMPLES) {
        None => vec![(0, spp)],
        Some(_) => {
            let s = text(attr::SAMPLES)?;
            parse_ranges(&s).ok_or_else(|| {
                ExrError::Attribute(attr::SAMPLES, format!("{s:?} is not a list of ranges a-b"))
            })?
        }
    };
    let variance_batch = match get(attr::VARIANCE_BATCH) {
        None => 1,
        Some(AttributeValue::I32(v)) if *v >= 1 && spp % *v as u32 == 0 => *v as u32,
        _ => {
            return Err(ExrError::Attribute(
                attr::VARIANCE_BATCH,
                format!("not a positive integer dividing glint.spp {spp}"),
            ));
        }
    };
    let held: u64 = samples.iter().map(|(a, b)| (b - a) as u64).sum();
    if held != spp as u64 {
        return Err(ExrError::Attribute(
            attr::SAMPLES,
            format!("holds {held} samples but glint.spp is {spp}"),
        ));
    }
    Ok(Some(RenderMeta {
        spp,
        seed,
        sampler: text(attr::SAMPLER)?,
        shard: text(attr::SHARD)?,
        version: text(attr::VERSION)?,
        build: get(attr::BUILD).map(|_| text(attr::BUILD)).transpose()?,
        samples,
        scene: get(attr::SCENE).map(|_| text(attr::SCENE)).transpose()?,
        files: get(attr::FILES).map(|_| text(attr::FILES)).transpose()?,
        variance_batch,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_with_variance_and_attributes() {
        let dir = std::env::temp_dir().join(format!("glint-exr-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut f = Film::new(3, 2);
        f.spp = 4;
        for (i, v) in [1.0f32, 2.0, 3.0, 6.0].iter().enumerate() {
            f.sum[i] = Vec3::new(*v, 2.0 * v, 0.5) * 4.0;
            f.sum_sq[i] = Vec3::new(v * v, 4.0 * v * v, 0.25) * 4.0 + Vec3::splat(i as f32);
        }
        let meta = RenderMeta {
            spp: 4,
            seed: u64::MAX - 3,
            sampler: "independent".into(),
            shard: "1/4".into(),
            version: "0.1.0".into(),
            build: Some("0123456789abcdef".into()),
            samples: vec![(4, 8)],
            scene: Some("00ff".into()),
            files: Some("0f".into()),
            variance_batch: 1,
        };
        let img = RadianceImage::from_film(&f, true, Some(meta.clone()));
        let path = dir.join("a.exr");
        img.write_file(&path).unwrap();
        let back = RadianceImage::read(&path).unwrap();
        assert_eq!(back, img);
        assert_eq!(back.variance.as_ref().unwrap()[1], f.variance_of_mean(1));
        // The image crate still reads the radiance.
        let rgb = image::open(&path).unwrap().into_rgb32f();
        assert_eq!(rgb.get_pixel(1, 0).0, [2.0, 4.0, 0.5]);
        // No variance, no attributes: a foreign file.
        let plain = RadianceImage::from_film(&f, false, None);
        plain.write_file(&path).unwrap();
        let back = RadianceImage::read(&path).unwrap();
        assert_eq!((back.variance, back.meta), (None, None));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn the_same_image_encodes_to_the_same_bytes() {
        let mut f = Film::new(4, 3);
        f.spp = 2;
        f.sum[5] = Vec3::new(1.0, 2.0, 3.0);
        let meta = RenderMeta {
            spp: 2,
            seed: 9,
            sampler: "sobol".into(),
            shard: "0/1".into(),
            version: "0.1.0".into(),
            build: None,
            samples: vec![(0, 2)],
            scene: Some("ab".into()),
            files: None,
            variance_batch: 1,
        };
        let img = RadianceImage::from_film(&f, true, Some(meta));
        let encode = || {
            let mut c = std::io::Cursor::new(Vec::new());
            img.write(&mut c).unwrap();
            c.into_inner()
        };
        // Each HashMap gets its own random keys: eight attributes came out
        // in a new order nearly every time.
        let first = encode();
        for _ in 0..8 {
            assert_eq!(encode(), first);
        }
    }

    #[test]
    fn ranges_parse() {
        assert_eq!(parse_ranges("0-4,8-12"), Some(vec![(0, 4), (8, 12)]));
        assert_eq!(parse_ranges("4-4"), None);
        assert_eq!(parse_ranges("x"), None);
        assert_eq!(format_ranges(&[(0, 4), (8, 12)]), "0-4,8-12");
    }
}

//! The user's cache folder, shared by the cached converge references and
//! the Vulkan pipeline cache: `$GLINT_CACHE_DIR`, else
//! `$XDG_CACHE_HOME/glint`, else `~/.cache/glint`.

use std::path::PathBuf;

use glint_cpu::{RenderOptions, Scene};

pub fn cache_dir() -> Option<PathBuf> {
    if let Some(d) = std::env::var_os("GLINT_CACHE_DIR").filter(|d| !d.is_empty()) {
        return Some(PathBuf::from(d));
    }
    if let Some(d) = std::env::var_os("XDG_CACHE_HOME").filter(|d| !d.is_empty()) {
        return Some(PathBuf::from(d).join("glint"));
    }
    std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache").join("glint"))
}

/// The Vulkan pipeline cache file.
pub fn pipeline_cache_path() -> Option<PathBuf> {
    cache_dir().map(|d| d.join("pipelines.bin"))
}

const FNV_OFFSET: u64 = 0xcbf2_9ce4_8422_2325;
const FNV_PRIME: u64 = 0x0000_0100_0000_01b3;

/// 64-bit FNV-1a of `bytes`: a stable content hash for the files in the
/// cache (std's hasher may change between Rust releases, which would
/// silently orphan every cached file).
pub fn fnv64(bytes: &[u8]) -> u64 {
    fnv1a(FNV_OFFSET, bytes)
}

fn fnv1a(mut h: u64, bytes: &[u8]) -> u64 {
    for &b in bytes {
        h ^= b as u64;
        h = h.wrapping_mul(FNV_PRIME);
    }
    h
}

/// FNV-1a over several fields, each followed by a separator so that
/// ("ab", "c") and ("a", "bc") differ: the cache and shard keys.
pub struct Fnv(pub u64);

impl Fnv {
    pub fn new() -> Self {
        Fnv(FNV_OFFSET)
    }

    pub fn add(&mut self, bytes: &[u8]) {
        self.0 = fnv1a(self.0, bytes).rotate_left(7) ^ 0xff;
    }
}

impl Default for Fnv {
    fn default() -> Self {
        Self::new()
    }
}

/// What a [`render_key`] covers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KeyScope {
    /// What defines the expected image apart from its samples: the loaded
    /// scene, size, camera, depth and methods. Shards of one image share
    /// it; `merge` checks seeds, samplers and sample ranges on their own,
    /// so it can say which one differs.
    Image,
    /// One render exactly: the image's key plus the sample count, seed,
    /// sampler, first sample and glint's version (the converge reference
    /// cache).
    Render,
}

/// The one content key of a render (16 hex digits): what the loaded
/// scene holds (so external buffers and images count, not only the file's
/// bytes) and the options in `scope`.
pub fn render_key(scene: &Scene, opts: &RenderOptions, scope: KeyScope) -> String {
    let mut h = Fnv::new();
    if scope == KeyScope::Render {
        h.add(env!("CARGO_PKG_VERSION").as_bytes());
    }
    hash_scene(&mut h, scene);
    h.add(
        format!(
            "{}x{} depth {} camera {} {:?} {:?} {:?}",
            opts.width,
            opts.height,
            opts.max_depth,
            opts.camera,
            opts.nee,
            opts.mis,
            opts.light_sampling
        )
        .as_bytes(),
    );
    if scope == KeyScope::Render {
        h.add(
            format!(
                "spp {} seed {} {:?} from {}",
                opts.spp, opts.seed, opts.sampler, opts.sample_start
            )
            .as_bytes(),
        );
    }
    format!("{:016x}", h.0)
}

/// Add what the loaded scene holds to `h`: geometry, shading data,
/// materials, lights, cameras, background, textures and environment map.
fn hash_scene(h: &mut Fnv, scene: &Scene) {
    h.add(bytemuck::cast_slice(&scene.triangles));
    h.add(bytemuck::cast_slice(&scene.shading));
    h.add(
        format!(
            "{:?}|{:?}|{:?}|{:?}",
            scene.materials, scene.lights, scene.cameras, scene.background
        )
        .as_bytes(),
    );
    let t = &scene.textures;
    h.add(bytemuck::cast_slice(&t.texels));
    h.add(format!("{:?}|{:?}|{:?}", t.table, t.materials, t.uvs).as_bytes());
    if let Some(e) = &scene.envmap {
        h.add(bytemuck::cast_slice(&e.texels));
        h.add(format!("{}x{} {}", e.width, e.height, e.rotation).as_bytes());
    }
}

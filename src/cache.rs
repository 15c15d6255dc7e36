//! The user's cache folder, shared by the cached converge references and
//! the Vulkan pipeline cache: `$GLINT_CACHE_DIR`, else
//! `$XDG_CACHE_HOME/glint`, else `~/.cache/glint`.

use std::path::PathBuf;

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

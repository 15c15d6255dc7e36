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

//! A persistent `VkPipelineCache`, so that a kernel variant's driver
//! compile (LLVM on lavapipe) is paid once per machine rather than once per
//! run. The file holds the driver's cache data followed by an 8-byte FNV-1a
//! checksum of it: a truncated or corrupt file is detected before the
//! driver sees it (a driver may trust data whose header matches), and is
//! then ignored with a warning; a cache from another device or driver
//! version is rejected by its header (Vulkan spec, "Pipeline Cache Header"),
//! also with a warning, and replaced on save.

use std::path::{Path, PathBuf};

use ash::vk;

use super::GpuError;
use super::context::Context;
use crate::cache::fnv64;

/// The most bytes read from a pipeline cache file (lavapipe's are 32
/// bytes, a GPU driver's a few MB).
const MAX_CACHE_BYTES: u64 = 1 << 30;

pub struct PipelineCache<'a> {
    ctx: &'a Context,
    handle: vk::PipelineCache,
    path: PathBuf,
    /// Bytes of driver data loaded (0: started empty).
    pub loaded_bytes: usize,
}

/// The driver data of a cache file, if its checksum and its header (for
/// this device) hold; else why not.
fn valid_data<'d>(ctx: &Context, file: &'d [u8]) -> Result<&'d [u8], &'static str> {
    if file.len() < 8 + 32 {
        return Err("too short");
    }
    let (data, sum) = file.split_at(file.len() - 8);
    if fnv64(data).to_le_bytes() != sum {
        return Err("checksum mismatch");
    }
    let u32_at = |o: usize| u32::from_le_bytes(data[o..o + 4].try_into().expect("4 bytes"));
    let props = unsafe {
        ctx.instance
            .get_physical_device_properties(ctx.physical_device)
    };
    let header_ok = u32_at(0) >= 32
        && u32_at(4) == vk::PipelineCacheHeaderVersion::ONE.as_raw() as u32
        && u32_at(8) == props.vendor_id
        && u32_at(12) == props.device_id
        && data[16..32] == props.pipeline_cache_uuid;
    if !header_ok {
        return Err("made by another device or driver version");
    }
    Ok(data)
}

impl<'a> PipelineCache<'a> {
    /// Open the cache at `path` (created on save if missing). Problems with
    /// the file are warnings, never errors: a cache only saves time.
    /// Only a regular file is read: a FIFO or a device under the cache's
    /// name is ignored with a warning, without being waited on.
    pub fn open(ctx: &'a Context, path: &Path) -> Result<Self, GpuError> {
        let file = match std::fs::symlink_metadata(path) {
            Err(_) => None,
            Ok(_) => match glint_cpu::safe_fs::read_regular(path, MAX_CACHE_BYTES) {
                Ok(bytes) => Some(bytes),
                Err(why) => {
                    eprintln!(
                        "glint: warning: {}: pipeline cache ignored ({why})",
                        path.display()
                    );
                    None
                }
            },
        };
        let data = match file.as_deref().map(|f| valid_data(ctx, f)) {
            None => &[][..],
            Some(Ok(d)) => d,
            Some(Err(why)) => {
                eprintln!(
                    "glint: warning: {}: pipeline cache ignored ({why})",
                    path.display()
                );
                &[][..]
            }
        };
        let handle = unsafe {
            ctx.device.create_pipeline_cache(
                &vk::PipelineCacheCreateInfo::default().initial_data(data),
                None,
            )
        }
        .map_err(|e| GpuError::from_vk("vkCreatePipelineCache", e))?;
        Ok(Self {
            ctx,
            handle,
            path: path.to_path_buf(),
            loaded_bytes: data.len(),
        })
    }

    pub fn handle(&self) -> vk::PipelineCache {
        self.handle
    }

    /// The driver's current cache data.
    pub fn data(&self) -> Result<Vec<u8>, GpuError> {
        unsafe { self.ctx.device.get_pipeline_cache_data(self.handle) }
            .map_err(|e| GpuError::from_vk("vkGetPipelineCacheData", e))
    }

    /// Write the cache back (whole or not at all); a failure is a warning.
    pub fn save(&self) {
        let result = (|| -> Result<(), String> {
            let mut data = self.data().map_err(|e| e.to_string())?;
            if data.len() <= self.loaded_bytes && self.path.is_file() {
                // Nothing new was compiled.
                return Ok(());
            }
            let sum = fnv64(&data);
            data.extend_from_slice(&sum.to_le_bytes());
            if let Some(dir) = self.path.parent() {
                std::fs::create_dir_all(dir).map_err(|e| e.to_string())?;
            }
            // Exclusive temporary, renamed over the cache: a planted link
            // is never written through. A cache path that is not a regular
            // file (a FIFO, a device) is left alone.
            if let Ok(m) = std::fs::metadata(&self.path)
                && !m.is_file()
            {
                return Err(format!(
                    "{}, not a regular file",
                    glint_cpu::safe_fs::describe(m.file_type())
                ));
            }
            glint_cpu::safe_fs::write_atomic(&self.path, &data).map_err(|e| e.to_string())
        })();
        if let Err(e) = result {
            eprintln!(
                "glint: warning: {}: cannot save the pipeline cache: {e}",
                self.path.display()
            );
        }
    }
}

impl Drop for PipelineCache<'_> {
    fn drop(&mut self) {
        unsafe { self.ctx.device.destroy_pipeline_cache(self.handle, None) };
    }
}

//! The Vulkan compute backend.
//!
//! INTERFACE FIXED BY THE LEAD; owned by the Vulkan host work (replace the
//! placeholder body of `render`, keep its signature).

use glint_cpu::{Film, RenderOptions, RenderStats, Scene};

#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    #[error("{0}")]
    Unavailable(String),
}

/// What a GPU render returns beside the film.
#[derive(Clone, Debug)]
pub struct GpuRender {
    pub film: Film,
    pub stats: RenderStats,
    /// Vulkan device name, e.g. "llvmpipe (LLVM 19.1.7, 256 bits)".
    pub device: String,
    /// Driver name and version.
    pub driver: String,
    /// Instance, device, pipeline creation and scene upload.
    pub setup_seconds: f64,
}

/// Render `scene` on the Vulkan device whose name contains `device` (or the
/// best one: discrete, integrated, then CPU). `progress(done, total)` is
/// called after each batch of samples.
pub fn render(
    scene: &Scene,
    opts: &RenderOptions,
    device: Option<&str>,
    progress: &dyn Fn(u32, u32),
) -> Result<GpuRender, GpuError> {
    let _ = (scene, opts, device, progress);
    Err(GpuError::Unavailable(
        "the Vulkan backend is not built yet; use --backend cpu".into(),
    ))
}

//! The path tracer's host side.
use super::{GpuError, GpuRender};
use glint_cpu::{RenderOptions, Scene};
pub fn render(
    scene: &Scene,
    opts: &RenderOptions,
    device: Option<&str>,
    progress: &dyn Fn(u32, u32),
) -> Result<GpuRender, GpuError> {
    let _ = (scene, opts, device, progress);
    Err(GpuError::Unavailable("not yet".into()))
}

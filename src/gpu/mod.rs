//! The Vulkan compute backend.
//!
//! One concern per module: [`context`] (instance, device, queue, allocator,
//! validation), [`buffer`] (device buffers, upload, readback), [`kernel`]
//! (compute pipelines over buffers at bindings 0..N), [`shaders`] (the
//! SPIR-V build.rs compiled) and [`render`](mod@render) (the path tracer's
//! host side).

pub mod accel;
pub mod buffer;
pub mod context;
pub mod kernel;
pub mod pipeline_cache;
pub mod render;
pub mod rt_pipeline;
pub mod shaders;

use ash::vk;
use glint_cpu::{Film, RenderStats};

pub use buffer::{Buffer, BufferKind};
pub use context::{Context, ContextDesc, DeviceInfo, Validation, ValidationLog};
pub use kernel::{Kernel, KernelOptions, groups};

#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    #[error(
        "cannot load the Vulkan loader (libvulkan.so.1): {0}; install the Vulkan loader and a driver (e.g. mesa-vulkan-drivers for lavapipe), or use --backend cpu"
    )]
    Loader(String),
    #[error(
        "no Vulkan driver found (vkCreateInstance: ERROR_INCOMPATIBLE_DRIVER); install a GPU driver or mesa-vulkan-drivers (lavapipe), or use --backend cpu"
    )]
    NoDriver,
    #[error(
        "no Vulkan device found; install a GPU driver or mesa-vulkan-drivers (lavapipe), or use --backend cpu"
    )]
    NoDevice,
    #[error("no Vulkan device name contains '{wanted}'; available: {}", available.join(", "))]
    DeviceNotFound {
        wanted: String,
        available: Vec<String>,
    },
    #[error("no Vulkan device supports Vulkan 1.2 with a compute queue; found: {}", available.join(", "))]
    NoUsableDevice { available: Vec<String> },
    #[error(
        "validation was requested (GLINT_VALIDATION) but VK_LAYER_KHRONOS_validation is not installed"
    )]
    ValidationUnavailable,
    #[error(
        "the Vulkan device was lost ({what}): the driver reset or crashed, possibly a watchdog timeout"
    )]
    DeviceLost { what: &'static str },
    #[error("out of {kind} memory in {what}")]
    OutOfMemory {
        kind: &'static str,
        what: &'static str,
    },
    #[error("{what} failed: {result}")]
    Vk {
        what: &'static str,
        result: vk::Result,
    },
    #[error("cannot allocate GPU memory for {what}: {source}")]
    Allocation {
        what: String,
        #[source]
        source: gpu_allocator::AllocationError,
    },
    #[error(
        "buffer '{name}' needs {size} bytes, more than the device's limit of {max} bytes per buffer binding; use a smaller image or scene, or --backend cpu"
    )]
    BufferTooLarge { name: String, size: u64, max: u64 },
    #[error("no compiled kernel named '{0}' (shaders/{0}.comp)")]
    UnknownKernel(String),
    #[error(
        "--traversal hardware needs Vulkan ray tracing (acceleration structures, with ray queries or a ray tracing pipeline), which device '{device}' lacks (missing: {}); use --traversal software",
        missing.join(", ")
    )]
    NoRayQuery {
        device: String,
        missing: Vec<String>,
    },
    #[error("{0}")]
    Invalid(String),
    #[error("the Vulkan validation layer reported errors:\n{}", .0.join("\n"))]
    Validation(Vec<String>),
}

impl GpuError {
    /// Map a failed Vulkan call, singling out device loss and exhaustion.
    pub fn from_vk(what: &'static str, result: vk::Result) -> Self {
        match result {
            vk::Result::ERROR_DEVICE_LOST => GpuError::DeviceLost { what },
            vk::Result::ERROR_OUT_OF_DEVICE_MEMORY => GpuError::OutOfMemory {
                kind: "device",
                what,
            },
            vk::Result::ERROR_OUT_OF_HOST_MEMORY => GpuError::OutOfMemory { kind: "host", what },
            _ => GpuError::Vk { what, result },
        }
    }
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
    /// Which kernel rendered, and the features it was built for.
    pub kernel: render::KernelChoice,
    /// How the kernel traced rays (`--traversal`).
    pub traversal: render::Traversal,
    pub features: glint_cpu::features::Features,
}

//! The one interface every verb renders through: render options in, film
//! and statistics out, on either backend. `render`, `compare`, `bench` and
//! `converge` call [`render`], the methods sweep a [`Renderer`] it keeps; a new sampler or kernel variant is a field of
//! [`RenderOptions`] (or of [`GpuOptions`]) that both backends read, not a
//! change to the verbs.

use std::time::Instant;

use glint_cpu::features::Features;
use glint_cpu::{Film, RenderOptions, Scene};

/// Which renderer runs the path tracer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, clap::ValueEnum)]
pub enum Backend {
    /// A GPU (a discrete, integrated or virtual Vulkan device) when one
    /// exists, else the CPU backend (lavapipe is a CPU device: on a machine
    /// without a GPU the CPU crate is 2-3x faster than Vulkan on it).
    Auto,
    /// Vulkan compute (lavapipe where no GPU exists).
    Gpu,
    /// The CPU reference renderer.
    Cpu,
}

impl Backend {
    pub fn name(self) -> &'static str {
        match self {
            Backend::Auto => "auto",
            Backend::Gpu => "gpu",
            Backend::Cpu => "cpu",
        }
    }

    /// The backend that runs: `Auto` becomes `Gpu` when Vulkan lists a GPU,
    /// else `Cpu`; with `--device NAME` (a Vulkan device asked for by name,
    /// lavapipe included) it is `Gpu`.
    pub fn resolve(self, device: Option<&str>) -> Backend {
        match self {
            Backend::Auto if device.is_some() => Backend::Gpu,
            Backend::Auto if crate::gpu::context::gpu_available(None) => Backend::Gpu,
            Backend::Auto => Backend::Cpu,
            b => b,
        }
    }
}

pub use crate::gpu::render::{KernelChoice, Traversal};

/// Options only the GPU backend reads.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GpuOptions {
    /// Use the Vulkan device whose name contains this.
    pub device: Option<String>,
    /// The kernel built for the scene's features, or the generic one.
    pub kernel: KernelChoice,
    /// glint's BVH or Vulkan ray tracing (`--traversal`, `--ray-tracing`).
    pub traversal: Traversal,
    /// Hardware traversal: bottom-level structures to split the scene into
    /// (`--blas-parts`; 0 and 1: one).
    pub blas_parts: u32,
    /// Keep the driver's compiled pipelines in the user's cache folder.
    pub pipeline_cache: bool,
}

/// A finished render on either backend.
#[derive(Clone, Debug)]
pub struct BackendRender {
    pub backend: Backend,
    /// The samples; `film.spp` is the count taken (a time limit may stop
    /// short of `RenderOptions::spp`).
    pub film: Film,
    pub rays: u64,
    /// The sampling alone.
    pub render_seconds: f64,
    /// Backend set-up after loading (device, pipelines, upload; CPU: lights).
    pub setup_seconds: f64,
    pub device: String,
    pub driver: Option<String>,
    pub threads: Option<usize>,
    /// GPU: the kernel that rendered.
    pub kernel: Option<KernelChoice>,
    /// GPU: how it traced rays.
    pub traversal: Option<Traversal>,
    /// What the scene uses (the GPU's specialized kernel is built for it).
    pub features: Features,
}

#[derive(Debug, thiserror::Error)]
pub enum BackendError {
    #[error("{0}")]
    Cpu(#[from] glint_cpu::RenderError),
    #[error("GPU backend: {0}")]
    Gpu(#[from] crate::gpu::GpuError),
}

/// Render `scene` with `opts` on `backend`; `progress(done, total)` reports.
/// One render through a new [`Renderer`] (its set-up time counted in the
/// render's), finished so that what the validation layer reports while
/// the device is destroyed counts too.
pub fn render(
    backend: Backend,
    scene: &Scene,
    opts: &RenderOptions,
    gpu: &GpuOptions,
    progress: &(dyn Fn(u32, u32) + Sync),
) -> Result<BackendRender, BackendError> {
    let renderer = Renderer::new(backend, gpu)?;
    let mut r = renderer.render(scene, opts, progress)?;
    r.setup_seconds += renderer.setup_seconds;
    renderer.finish()?;
    Ok(r)
}

/// A backend made ready once, rendering any number of scenes: the CPU, or
/// a Vulkan context (with `--traversal hardware`, one with ray tracing),
/// made once, its validation messages checked after every render.
/// [`render`] is one render through a new one; the methods sweep keeps
/// one for all its cells.
pub struct Renderer {
    backend: Backend,
    gpu: GpuOptions,
    ctx: Option<crate::gpu::Context>,
    /// Making the context (0 for the CPU).
    pub setup_seconds: f64,
}

impl Renderer {
    /// `backend` resolved (`Auto` to a GPU or the CPU) and made ready.
    pub fn new(backend: Backend, gpu: &GpuOptions) -> Result<Self, BackendError> {
        let backend = backend.resolve(gpu.device.as_deref());
        let start = Instant::now();
        let ctx = match backend {
            Backend::Gpu => {
                let desc = crate::gpu::ContextDesc {
                    device: gpu.device.as_deref(),
                    ..Default::default()
                };
                Some(match gpu.traversal {
                    Traversal::Software => crate::gpu::Context::new(&desc)?,
                    _ => crate::gpu::Context::new_ray_tracing(&desc)?,
                })
            }
            _ => None,
        };
        Ok(Renderer {
            backend,
            gpu: gpu.clone(),
            ctx,
            setup_seconds: start.elapsed().as_secs_f64(),
        })
    }

    /// The backend that renders (never `Auto`).
    pub fn backend(&self) -> Backend {
        self.backend
    }

    /// The device's name: the Vulkan device's, or the CPU's with its threads.
    pub fn device_name(&self) -> String {
        match &self.ctx {
            Some(ctx) => ctx.info().name.clone(),
            None => cpu_device_name(rayon::current_num_threads()),
        }
    }

    /// Render `scene` with `opts`; `progress(done, total)` reports.
    pub fn render(
        &self,
        scene: &Scene,
        opts: &RenderOptions,
        progress: &(dyn Fn(u32, u32) + Sync),
    ) -> Result<BackendRender, BackendError> {
        let Some(ctx) = &self.ctx else {
            let start = Instant::now();
            let pt = glint_cpu::PathTracer::new(scene, opts)?;
            let setup_seconds = start.elapsed().as_secs_f64();
            let (film, st) = pt.render(opts.spp, progress);
            let threads = rayon::current_num_threads();
            return Ok(BackendRender {
                backend: self.backend,
                film,
                rays: st.rays,
                render_seconds: st.render_seconds,
                setup_seconds,
                device: cpu_device_name(threads),
                driver: None,
                threads: Some(threads),
                kernel: None,
                traversal: None,
                features: Features::of(scene, opts),
            });
        };
        let cache_path = self
            .gpu
            .pipeline_cache
            .then(crate::cache::pipeline_cache_path)
            .flatten();
        let cache = match &cache_path {
            Some(p) => Some(crate::gpu::pipeline_cache::PipelineCache::open(ctx, p)?),
            None => None,
        };
        let handle = cache
            .as_ref()
            .map_or(ash::vk::PipelineCache::null(), |c| c.handle());
        let setup = crate::gpu::render::GpuSetup {
            kernel: self.gpu.kernel,
            traversal: self.gpu.traversal,
            blas_parts: self.gpu.blas_parts,
        };
        let r = crate::gpu::render::render_with(ctx, scene, opts, setup, handle, progress)?;
        if let Some(c) = &cache {
            c.save();
        }
        check_validation(ctx.validation_log())?;
        Ok(BackendRender {
            backend: self.backend,
            film: r.film,
            rays: r.stats.rays,
            render_seconds: r.stats.render_seconds,
            setup_seconds: r.setup_seconds,
            device: r.device,
            driver: Some(r.driver),
            threads: None,
            kernel: Some(r.kernel),
            traversal: Some(r.traversal),
            features: Features::of(scene, opts),
        })
    }

    /// Destroy the device, then fail if the validation layer reported an
    /// error at any point, its destruction included.
    pub fn finish(mut self) -> Result<(), BackendError> {
        let log = self.ctx.as_ref().and_then(|c| c.validation_log());
        drop(self.ctx.take());
        check_validation(log)
    }
}

fn check_validation(
    log: Option<std::sync::Arc<crate::gpu::context::ValidationLog>>,
) -> Result<(), BackendError> {
    match log {
        Some(log) if log.errors() > 0 => {
            Err(crate::gpu::GpuError::Validation(log.messages()).into())
        }
        _ => Ok(()),
    }
}

/// The CPU's model name from /proc/cpuinfo (Linux), with the thread count
/// the renderer uses, e.g. "Intel(R) Xeon(R) Processor (2 threads)".
pub fn cpu_device_name(threads: usize) -> String {
    let model = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, v)| v.trim().to_string())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_string());
    format!("{model} ({threads} threads)")
}

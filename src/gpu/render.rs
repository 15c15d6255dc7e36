//! The path tracer's host side: upload the scene once, dispatch batches of
//! samples, read the film back.
//!
//! The binding table is [`glint_cpu::abi::PATH_TRACER_BINDINGS`] (set 0),
//! from which build.rs generates the kernel's declarations: the descriptor
//! set layout here is built from the same table, and each binding's
//! buffer is found by the table's name ([`FilmBuffers::get`]). Push
//! constants: [`SamplePush`]. One invocation per pixel, local size 8x8.
//!
//! Batching: one dispatch renders `sample_count` samples of every pixel, in
//! the passes of the render's [`PassPlan`] ([`glint_cpu::schedule`], shared
//! with the CPU backend). A dispatch that runs for seconds can trip a
//! desktop driver's watchdog (TDR, about 2 s on Windows) and starves
//! progress reports, so a plain render's dispatches are sized from the
//! measured time of the previous one to stay near [`TARGET_BATCH_SECONDS`].

use std::time::Instant;

use ash::vk;
use glam::Vec3;
use glint_cpu::abi::{self, Resource};
use glint_cpu::features::Features;
use glint_cpu::integrator::{GpuSceneData, gpu_scene_data};
use glint_cpu::schedule::{Pacing, PassPlan, Schedule};
use glint_cpu::{Film, RenderOptions, RenderStats, Scene};

use super::accel::Accel;
use super::buffer::{Buffer, BufferKind};
use super::context::Context;
use super::kernel::{Kernel, KernelOptions, groups};
use super::rt_pipeline;
use super::{GpuError, GpuRender};

/// Aim for dispatches of about this long: well under any watchdog, long
/// enough that per-dispatch overhead (submit, wait) is negligible.
pub const TARGET_BATCH_SECONDS: f64 = 0.25;
/// The path tracing kernels' workgroup size (8x8 pixels).
pub const LOCAL_SIZE: u32 = 8;

pub use glint_cpu::abi::SamplePush;

/// The bytes of bindings 0..=6 and 9..=12, ready to upload. Arrays may be empty (they
/// get a minimal buffer; the kernel learns real counts from Params).
#[derive(Clone, Copy, Debug)]
pub struct SceneBytes<'d> {
    pub params: &'d [u8],
    pub triangles: &'d [u8],
    pub bvh_nodes: &'d [u8],
    pub shading: &'d [u8],
    pub materials: &'d [u8],
    pub emitters: &'d [u8],
    pub lights: &'d [u8],
    /// Bindings 9-12: texels, texture table, material textures, triangle UVs.
    pub texels: &'d [u8],
    pub textures: &'d [u8],
    pub material_textures: &'d [u8],
    pub uvs: &'d [u8],
    /// Bindings 13-14: environment map texels and distribution.
    pub env_texels: &'d [u8],
    pub env_dist: &'d [u8],
    /// Samples per variance batch (`RenderOptions::batch`; `params`
    /// holds it too, for the kernel): the film's batch sums.
    pub variance_batch: u32,
}

impl<'d> SceneBytes<'d> {
    /// The path tracer's bindings for `scene` and the data
    /// [`gpu_scene_data`] derived from it.
    pub fn new(scene: &'d Scene, data: &'d GpuSceneData) -> Self {
        Self {
            params: bytemuck::bytes_of(&data.params),
            triangles: bytemuck::cast_slice(&scene.triangles),
            bvh_nodes: bytemuck::cast_slice(&scene.bvh.nodes),
            shading: bytemuck::cast_slice(&scene.shading),
            materials: bytemuck::cast_slice(&data.materials),
            emitters: bytemuck::cast_slice(&data.emitters),
            lights: bytemuck::cast_slice(&data.lights),
            texels: bytemuck::cast_slice(&data.texels),
            textures: bytemuck::cast_slice(&data.textures),
            material_textures: bytemuck::cast_slice(&data.material_textures),
            uvs: bytemuck::cast_slice(&data.uvs),
            env_texels: bytemuck::cast_slice(&data.env_texels),
            env_dist: bytemuck::cast_slice(&data.env_dist),
            variance_batch: data.params.variance_batch,
        }
    }
}

/// What a render produced, before the caller adds device names.
#[derive(Clone, Debug)]
pub struct FilmRender {
    pub film: Film,
    pub stats: RenderStats,
    /// Pipeline creation, scene upload and the kernel's first (compiling)
    /// dispatch, excluding context creation.
    pub setup_seconds: f64,
    /// Samples per dispatch, in order (for tests and tuning).
    pub batches: Vec<u32>,
    /// Whether `stats.render_seconds` came from GPU timestamps.
    pub timestamped: bool,
}

/// Timestamp queries around each batch's dispatch.
struct Timer<'a> {
    ctx: &'a Context,
    pool: vk::QueryPool,
    /// Seconds per tick.
    period: f64,
    /// Mask of the valid timestamp bits.
    mask: u64,
}

impl<'a> Timer<'a> {
    fn new(ctx: &'a Context) -> Result<Option<Self>, GpuError> {
        let info = ctx.info();
        if !info.timestamps() || info.timestamp_period <= 0.0 {
            return Ok(None);
        }
        let pool = unsafe {
            ctx.device.create_query_pool(
                &vk::QueryPoolCreateInfo::default()
                    .query_type(vk::QueryType::TIMESTAMP)
                    .query_count(2),
                None,
            )
        }
        .map_err(|e| GpuError::from_vk("vkCreateQueryPool", e))?;
        let bits = info.timestamp_valid_bits;
        Ok(Some(Timer {
            ctx,
            pool,
            period: info.timestamp_period as f64 * 1e-9,
            mask: if bits >= 64 {
                u64::MAX
            } else {
                (1u64 << bits) - 1
            },
        }))
    }

    fn seconds(&self) -> Result<f64, GpuError> {
        let mut ticks = [0u64; 2];
        unsafe {
            self.ctx.device.get_query_pool_results(
                self.pool,
                0,
                &mut ticks,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }
        .map_err(|e| GpuError::from_vk("vkGetQueryPoolResults", e))?;
        // Counters wrap at their valid bits.
        let dt = ticks[1].wrapping_sub(ticks[0]) & self.mask;
        Ok(dt as f64 * self.period)
    }
}

impl Drop for Timer<'_> {
    fn drop(&mut self) {
        unsafe { self.ctx.device.destroy_query_pool(self.pool, None) };
    }
}

/// Which samples a render takes: indices from `start` of every pixel, in
/// the passes of `plan` (a controlled render's film is read back after each
/// pass for the host's decision).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampleRange {
    pub start: u32,
    pub plan: PassPlan,
}

/// Render `spp` samples of a `width` x `height` image with kernel
/// `kernel_name`, which follows the binding table above.
pub fn render_film(
    ctx: &Context,
    kernel_name: &str,
    scene: &SceneBytes<'_>,
    width: u32,
    height: u32,
    spp: u32,
    progress: &dyn Fn(u32, u32),
) -> Result<FilmRender, GpuError> {
    let range = SampleRange {
        start: 0,
        plan: PassPlan::whole(spp),
    };
    let kernel = KernelConfig {
        name: kernel_name,
        options: KernelOptions::default(),
        hardware: None,
        blas_parts: 1,
    };
    render_film_range(ctx, &kernel, scene, width, height, range, progress)
}

/// The film of the accumulation buffer's sums (binding 7).
fn film_of(sums: &[[f32; 4]], width: u32, height: u32, spp: u32, batch: u32) -> Film {
    let n = width as usize * height as usize;
    let plane = |k: usize| -> Vec<Vec3> {
        (0..n)
            .map(|i| Vec3::from_slice(&sums[4 * i + k][..3]))
            .collect()
    };
    Film {
        width,
        height,
        spp,
        sum: plane(0),
        sum_sq: plane(1),
        batch,
        batch_run: plane(2),
        batch_sq: plane(3),
        counts: Vec::new(),
    }
}

/// Which kernel renders, and how its pipeline is built.
#[derive(Clone, Copy, Debug)]
pub struct KernelConfig<'k> {
    pub name: &'k str,
    pub options: KernelOptions<'k>,
    /// Hardware traversal (`pathtrace_rq` or the ray tracing pipeline):
    /// whether each triangle is alpha-tested. The render then builds the
    /// acceleration structures over the triangles and binds the tri_map
    /// (binding 17) and the TLAS (18; `abi::PATH_TRACER_BINDINGS`). `None`: the
    /// software BVH.
    pub hardware: Option<&'k [bool]>,
    /// Hardware traversal: bottom-level structures to split the triangles
    /// into (`--blas-parts`; 0 and 1: one).
    pub blas_parts: u32,
}

/// The buffers one film render binds (`abi::PATH_TRACER_BINDINGS` 0-15),
/// but for the active-pixel mask and the ray-query ones.
struct FilmBuffers<'c> {
    params: Buffer<'c>,
    triangles: Buffer<'c>,
    nodes: Buffer<'c>,
    shading: Buffer<'c>,
    materials: Buffer<'c>,
    emitters: Buffer<'c>,
    lights: Buffer<'c>,
    accum: Buffer<'c>,
    rays: Buffer<'c>,
    texels: Buffer<'c>,
    textures: Buffer<'c>,
    material_textures: Buffer<'c>,
    uvs: Buffer<'c>,
    env_texels: Buffer<'c>,
    env_dist: Buffer<'c>,
    ms_tables: Buffer<'c>,
}

impl<'c> FilmBuffers<'c> {
    fn new(
        ctx: &'c Context,
        scene: &SceneBytes<'_>,
        width: u32,
        height: u32,
    ) -> Result<Self, GpuError> {
        let pixels = width as u64 * height as u64;
        let storage =
            |name: &str, bytes: &[u8]| Buffer::from_slice(ctx, name, BufferKind::Storage, bytes);
        let params = Buffer::from_slice(ctx, "params", BufferKind::Uniform, scene.params)?;
        let triangles = storage("triangles", scene.triangles)?;
        let nodes = storage("bvh nodes", scene.bvh_nodes)?;
        let shading = storage("shading", scene.shading)?;
        let materials = storage("materials", scene.materials)?;
        let emitters = storage("emitters", scene.emitters)?;
        let lights = storage("lights", scene.lights)?;
        let texels = storage("texels", scene.texels)?;
        let textures = storage("textures", scene.textures)?;
        let material_textures = storage("material textures", scene.material_textures)?;
        let uvs = storage("triangle uvs", scene.uvs)?;
        let env_texels = storage("environment map", scene.env_texels)?;
        let env_dist = storage("environment map distribution", scene.env_dist)?;
        let ms_tables = storage(
            "multiscatter tables",
            bytemuck::cast_slice(&glint_cpu::bsdf::multiscatter::gpu_tables()),
        )?;
        let accum = Buffer::new(
            ctx,
            &format!("accumulation film ({width}x{height} pixels, 64 bytes each)"),
            BufferKind::Storage,
            pixels * 64,
        )?;
        let rays = Buffer::new(
            ctx,
            &format!("ray counts ({width}x{height} pixels)"),
            BufferKind::Storage,
            pixels * 4,
        )?;
        Ok(FilmBuffers {
            params,
            triangles,
            nodes,
            shading,
            materials,
            emitters,
            lights,
            accum,
            rays,
            texels,
            textures,
            material_textures,
            uvs,
            env_texels,
            env_dist,
            ms_tables,
        })
    }

    /// The buffer of the binding named `name` in the table.
    fn get(&self, name: &str) -> Option<&Buffer<'c>> {
        Some(match name {
            "params" => &self.params,
            "triangles" => &self.triangles,
            "bvh_nodes" => &self.nodes,
            "shading" => &self.shading,
            "materials" => &self.materials,
            "emitters" => &self.emitters,
            "lights" => &self.lights,
            "accum" => &self.accum,
            "ray_counts" => &self.rays,
            "texels" => &self.texels,
            "textures" => &self.textures,
            "material_textures" => &self.material_textures,
            "triangle_uvs" => &self.uvs,
            "env_texels" => &self.env_texels,
            "env_dist" => &self.env_dist,
            "ms_tables" => &self.ms_tables,
            _ => return None,
        })
    }
}

/// One batch: the dispatch between two timestamps (where the device has
/// them). Returns (wall seconds, device seconds; wall where no timer).
fn timed_dispatch(
    ctx: &Context,
    kernel: &Kernel,
    timer: Option<&Timer>,
    push: &SamplePush,
    grid: [u32; 3],
) -> Result<(f64, f64), GpuError> {
    let t = Instant::now();
    let mut recorded = Ok(());
    ctx.submit_and_wait(|cmd| unsafe {
        if let Some(timer) = timer {
            ctx.device.cmd_reset_query_pool(cmd, timer.pool, 0, 2);
            ctx.device
                .cmd_write_timestamp(cmd, vk::PipelineStageFlags::TOP_OF_PIPE, timer.pool, 0);
        }
        recorded = kernel.record_dispatch(cmd, bytemuck::bytes_of(push), grid);
        if let Some(timer) = timer {
            ctx.device.cmd_write_timestamp(
                cmd,
                vk::PipelineStageFlags::BOTTOM_OF_PIPE,
                timer.pool,
                1,
            );
        }
    })?;
    recorded?;
    let wall = t.elapsed().as_secs_f64();
    let seconds = match timer {
        Some(timer) => timer.seconds()?,
        None => wall,
    };
    Ok((wall, seconds))
}

/// The acceleration structures over the `count` `triangles` (hardware
/// traversal), `masked[i]` saying whether triangle i is alpha-tested.
fn build_accel<'c>(
    ctx: &'c Context,
    triangles: &Buffer<'c>,
    count: u32,
    masked: &[bool],
    parts: u32,
) -> Result<Accel<'c>, GpuError> {
    let alpha = |i: u32| masked.get(i as usize).copied().unwrap_or(false);
    Accel::build_parts(ctx, triangles, count, &alpha, parts)
}

/// The path-tracing kernel `cfg` names, its descriptor set laid out from
/// `abi::PATH_TRACER_BINDINGS` and bound to `b`'s buffers by the table's
/// names (the acceleration structure, the last binding, goes through the
/// kernel options).
fn path_tracer_kernel<'c>(
    ctx: &'c Context,
    cfg: &KernelConfig<'_>,
    b: &FilmBuffers<'_>,
    active: &Buffer<'_>,
    accel: Option<&Accel<'_>>,
) -> Result<Kernel<'c>, GpuError> {
    let mut options = cfg.options;
    if let Some(a) = accel {
        options.acceleration_structure = a.tlas();
    }
    let mut kinds = Vec::new();
    let mut buffers = Vec::new();
    for binding in abi::path_tracer_bindings(accel.is_some()) {
        let buffer = match (binding.name, accel) {
            (_, _) if binding.resource == Resource::AccelerationStructure => continue,
            ("active_pixels", _) => active,
            ("tri_map", Some(a)) => &a.tri_map,
            (name, _) => b.get(name).ok_or_else(|| {
                GpuError::Invalid(format!("binding {}: no buffer for {name}", binding.binding))
            })?,
        };
        kinds.push(match binding.resource {
            Resource::Uniform => BufferKind::Uniform,
            _ => BufferKind::Storage,
        });
        buffers.push(buffer);
    }
    let push_size = size_of::<SamplePush>() as u32;
    let mut kernel = Kernel::with_options(ctx, cfg.name, &kinds, push_size, &options)?;
    kernel.bind(&buffers)?;
    Ok(kernel)
}

/// Drivers compile the pipeline at its first dispatch (lavapipe: LLVM,
/// 0.1-0.5 s cold): do that in setup with an empty batch on one group, so
/// it neither counts as render time nor skews the first batch size; then
/// zero the film, whatever the kernel wrote.
fn warm_up(kernel: &Kernel<'_>, accum: &Buffer<'_>, rays: &Buffer<'_>) -> Result<(), GpuError> {
    kernel.dispatch(bytemuck::bytes_of(&SamplePush::default()), [1, 1, 1])?;
    accum.fill_zero()?;
    rays.fill_zero()
}

/// [`render_film`] over a [`SampleRange`]; the film's `spp` is the number
/// of samples taken.
pub fn render_film_range(
    ctx: &Context,
    kernel_cfg: &KernelConfig<'_>,
    scene: &SceneBytes<'_>,
    width: u32,
    height: u32,
    range: SampleRange,
    progress: &dyn Fn(u32, u32),
) -> Result<FilmRender, GpuError> {
    let spp = range.plan.spp;
    if width == 0 || height == 0 {
        return Err(GpuError::Invalid(format!(
            "image size {width}x{height}: both must be at least 1"
        )));
    }
    let setup_start = Instant::now();
    let pixels = width as u64 * height as u64;
    let b = FilmBuffers::new(ctx, scene, width, height)?;
    let (triangles, accum, rays) = (&b.triangles, &b.accum, &b.rays);
    let accel = match kernel_cfg.hardware {
        Some(masked) => {
            let count = scene.triangles.len() / size_of::<glint_cpu::Triangle>();
            Some(build_accel(
                ctx,
                triangles,
                count as u32,
                masked,
                kernel_cfg.blas_parts,
            )?)
        }
        None => None,
    };
    let active = Buffer::from_slice(
        ctx,
        &format!("active pixels ({width}x{height})"),
        BufferKind::Storage,
        &vec![1u32; pixels as usize],
    )?;
    let kernel = path_tracer_kernel(ctx, kernel_cfg, &b, &active, accel.as_ref())?;
    let grid = [groups(width, LOCAL_SIZE), groups(height, LOCAL_SIZE), 1];

    warm_up(&kernel, accum, rays)?;
    let timer = Timer::new(ctx)?;
    let setup_seconds = setup_start.elapsed().as_secs_f64();

    let batch_size = scene.variance_batch.max(1);
    let mut mask = vec![1u32; pixels as usize];
    let mut counts = Vec::new();
    let mut batches = Vec::new();
    let mut render_seconds = 0.0;
    let wall = Instant::now();
    let mut schedule = Schedule::new(range.plan, Pacing::Target(TARGET_BATCH_SECONDS));
    while let Some(count) = schedule.next() {
        let done = schedule.done();
        let push = SamplePush {
            sample_start: range.start.wrapping_add(done),
            sample_count: count,
        };
        let (wall_batch, seconds) = timed_dispatch(ctx, &kernel, timer.as_ref(), &push, grid)?;
        render_seconds += seconds;
        batches.push(count);
        progress(done + count, spp);
        let mut more = true;
        if let Some(c) = schedule.control() {
            let mut film = film_of(&accum.read()?, width, height, done, batch_size);
            film.counts = std::mem::take(&mut counts);
            if c.adaptive.is_some() {
                glint_cpu::adaptive::count_pass(&mut film, &mask, count);
            } else {
                film.spp = done + count;
            }
            more = c.decide(&film, &mut mask);
            counts = film.counts;
            if more {
                active.write(&mask)?;
            }
        }
        schedule.passed(wall_batch, more);
    }
    let done = schedule.done();
    if timer.is_none() {
        render_seconds = wall.elapsed().as_secs_f64();
    }

    let mut film = film_of(&accum.read()?, width, height, done, batch_size);
    film.counts = counts;
    let ray_counts: Vec<u32> = rays.read()?;
    let stats = RenderStats {
        rays: ray_counts.iter().map(|&c| c as u64).sum(),
        render_seconds,
    };
    Ok(FilmRender {
        film,
        stats,
        setup_seconds,
        batches,
        timestamped: timer.is_some(),
    })
}

/// Which path tracing kernel a render uses.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum KernelChoice {
    /// Built for the scene's features (specialization constants).
    #[default]
    Specialized,
    /// The kernel that handles every scene.
    Generic,
}

impl KernelChoice {
    pub fn name(self) -> &'static str {
        match self {
            KernelChoice::Specialized => "specialized",
            KernelChoice::Generic => "generic",
        }
    }
}

/// How the GPU kernel finds the ray's hits (`--traversal`, and for the
/// hardware one `--ray-tracing`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Traversal {
    /// glint's own BVH, walked in the compute kernel (shaders/bvh.glsl).
    #[default]
    Software,
    /// Vulkan ray tracing against acceleration structures built on the
    /// device, through whichever of the two below the device has
    /// ([`Traversal::resolve`]).
    Hardware,
    /// Ray queries in the compute kernel (`pathtrace_rq`,
    /// shaders/ray_query.glsl).
    RayQuery,
    /// A ray tracing pipeline whose ray generation shader is the path
    /// tracer (`rt/raygen`, shaders/rt/; src/gpu/rt_pipeline.rs).
    Pipeline,
}

impl Traversal {
    /// `--traversal`'s value (and `--stats` `traversal`).
    pub fn name(self) -> &'static str {
        match self {
            Traversal::Software => "software",
            _ => "hardware",
        }
    }

    /// The hardware traversal's Vulkan API (`--stats` `ray_tracing`):
    /// "query" or "pipeline"; `None` for the software one or one not yet
    /// resolved.
    pub fn api(self) -> Option<&'static str> {
        match self {
            Traversal::RayQuery => Some("query"),
            Traversal::Pipeline => Some("pipeline"),
            _ => None,
        }
    }

    pub fn is_hardware(self) -> bool {
        self != Traversal::Software
    }

    /// `Hardware` made concrete for `ctx`: ray queries where enabled (on
    /// lavapipe the pipeline runs at 0.93-0.97 of their speed,
    /// docs/benchmarks.md), else the pipeline; the others as they are.
    pub fn resolve(self, ctx: &Context) -> Traversal {
        match self {
            Traversal::Hardware if !ctx.ray_query() && ctx.ray_tracing().pipeline.is_some() => {
                Traversal::Pipeline
            }
            Traversal::Hardware => Traversal::RayQuery,
            t => t,
        }
    }

    /// The path tracing kernel of this traversal (resolved).
    pub fn kernel_name(self) -> &'static str {
        match self {
            Traversal::Software => "pathtrace",
            Traversal::Hardware | Traversal::RayQuery => "pathtrace_rq",
            Traversal::Pipeline => rt_pipeline::PATH_TRACER_RAYGEN,
        }
    }

    /// Whether `ctx` has what this traversal needs.
    fn check(self, ctx: &Context) -> Result<(), GpuError> {
        let missing = match self {
            Traversal::Software => None,
            Traversal::Hardware | Traversal::RayQuery => {
                (!ctx.ray_query()).then_some("VK_KHR_ray_query")
            }
            Traversal::Pipeline => ctx
                .ray_tracing()
                .pipeline
                .is_none()
                .then_some("VK_KHR_ray_tracing_pipeline"),
        };
        match missing {
            Some(m) => Err(GpuError::NoRayQuery {
                device: ctx.info().name.clone(),
                missing: vec![m.to_string()],
            }),
            None => Ok(()),
        }
    }
}

/// A render on an existing context (tests share one validated context
/// across scenes), with the specialized kernel and no pipeline cache
/// (`backend::Renderer` is the CLI's, with the options' kernel and cache).
/// `setup_seconds` covers scene preparation, upload and pipeline creation,
/// not the context.
pub fn render_on(
    ctx: &Context,
    scene: &Scene,
    opts: &RenderOptions,
    progress: &dyn Fn(u32, u32),
) -> Result<GpuRender, GpuError> {
    let kernel = (KernelChoice::Specialized, Traversal::Software);
    render_with(
        ctx,
        scene,
        opts,
        kernel,
        vk::PipelineCache::null(),
        progress,
    )
}

/// Whether each of `scene`'s triangles is alpha-tested (MASK, BLEND).
pub fn alpha_tested(scene: &Scene) -> Vec<bool> {
    let masked: Vec<bool> = (0..scene.materials.len() as u32)
        .map(|m| {
            scene
                .textures
                .material(m)
                .is_some_and(|t| t.has_alpha_test())
        })
        .collect();
    scene
        .triangles
        .iter()
        .map(|t| masked.get(t.material as usize).copied().unwrap_or(false))
        .collect()
}

/// The GPU's choices for one render: kernel, traversal and, for the
/// hardware traversal, the bottom-level structures to split the scene into.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GpuSetup {
    pub kernel: KernelChoice,
    pub traversal: Traversal,
    /// 1: one BLAS over the scene (the default).
    pub blas_parts: u32,
}

impl From<(KernelChoice, Traversal)> for GpuSetup {
    fn from((kernel, traversal): (KernelChoice, Traversal)) -> Self {
        GpuSetup {
            kernel,
            traversal,
            blas_parts: 1,
        }
    }
}

/// [`render_on`] with a choice of kernel and traversal (a hardware one
/// needs a context from [`Context::new_ray_tracing`] with its API) and a
/// pipeline cache.
pub fn render_with(
    ctx: &Context,
    scene: &Scene,
    opts: &RenderOptions,
    setup: impl Into<GpuSetup>,
    cache: vk::PipelineCache,
    progress: &dyn Fn(u32, u32),
) -> Result<GpuRender, GpuError> {
    let GpuSetup {
        kernel,
        traversal,
        blas_parts,
    } = setup.into();
    let start = Instant::now();
    let traversal = traversal.resolve(ctx);
    traversal.check(ctx)?;
    let data = gpu_scene_data(scene, opts).map_err(|e| GpuError::Invalid(e.to_string()))?;
    let mut bytes = SceneBytes::new(scene, &data);
    let masked = if traversal.is_hardware() {
        // The hardware traversals do not read the BVH.
        bytes.bvh_nodes = &[];
        Some(alpha_tested(scene))
    } else {
        None
    };
    let features = match kernel {
        KernelChoice::Specialized => Features::of(scene, opts),
        KernelChoice::Generic => Features::ALL,
    };
    let prepare_seconds = start.elapsed().as_secs_f64();
    let range = SampleRange {
        start: opts.sample_start,
        plan: PassPlan::of(opts),
    };
    let spec = [features.0];
    let cfg = KernelConfig {
        name: traversal.kernel_name(),
        options: KernelOptions {
            specialization: &spec,
            cache,
            ray_tracing: (traversal == Traversal::Pipeline)
                .then_some(rt_pipeline::PATH_TRACER_STAGES),
            ..Default::default()
        },
        hardware: masked.as_deref(),
        blas_parts,
    };
    let r = render_film_range(ctx, &cfg, &bytes, opts.width, opts.height, range, progress)?;
    let info = ctx.info();
    Ok(GpuRender {
        film: r.film,
        stats: r.stats,
        device: info.name.clone(),
        driver: info.driver.clone(),
        setup_seconds: prepare_seconds + r.setup_seconds,
        kernel,
        traversal,
        features,
    })
}

//! Compute kernels: a pipeline built from one of the compiled SPIR-V kernels
//! with buffers at bindings `0..N` of set 0 and optional push constants.
//!
//! The quickest way to run a test kernel is [`Context::run_kernel`]: inputs
//! are uploaded to bindings `0..inputs.len()`, outputs follow them, start
//! with the caller's contents and are read back in place.
//!
//! ```no_run
//! use glint::gpu::{Context, ContextDesc, Validation};
//! # fn main() -> Result<(), glint::gpu::GpuError> {
//! let ctx = Context::new(&ContextDesc { device: None, validation: Validation::IfAvailable, loader: None })?;
//! let a = [1.0f32, 2.0, 3.0];
//! let b = [10.0f32, 20.0, 30.0];
//! let mut c = [0.0f32; 3];
//! let mut count = [0u32];
//! // shaders/tests/smoke.comp: c[i] = a[i] + b[i] * scale; local size 64.
//! let push: [u32; 2] = [3, 2.0f32.to_bits()];
//! ctx.run_kernel(
//!     "tests/smoke",
//!     &[bytemuck::cast_slice(&a), bytemuck::cast_slice(&b)],
//!     &mut [bytemuck::cast_slice_mut(&mut c), bytemuck::cast_slice_mut(&mut count)],
//!     bytemuck::bytes_of(&push),
//!     [glint::gpu::groups(3, 64), 1, 1],
//! )?;
//! assert_eq!(c, [21.0, 42.0, 63.0]);
//! # Ok(()) }
//! ```
//!
//! For repeated dispatches over the same buffers (the renderer), build a
//! [`Kernel`] once, [`Kernel::bind`] the buffers, and call
//! [`Kernel::dispatch`] or record [`Kernel::record_dispatch`] into a command
//! buffer of your own.
//!
//! A kernel may also be the ray generation shader of a ray tracing pipeline
//! ([`KernelOptions::ray_tracing`], src/gpu/rt_pipeline.rs): the same
//! bindings and push constants, seen by every stage, and a dispatch of
//! `groups` launches `groups * group_size` rays through its shader binding
//! table.

use std::ffi::CStr;

use ash::vk;

use super::GpuError;
use super::buffer::{Buffer, BufferKind};
use super::context::Context;
use super::rt_pipeline::{self, RtStages, Sbt};

/// How a kernel's pipeline is built.
#[derive(Clone, Copy, Debug, Default)]
pub struct KernelOptions<'s> {
    /// Values of the shader's specialization constants 0, 1, ... (4 bytes
    /// each: `uint`, `int`, `float` or `bool` as a 32-bit value).
    pub specialization: &'s [u32],
    /// A pipeline cache to create through (null: none).
    pub cache: vk::PipelineCache,
    /// An acceleration structure at the binding after the buffers' (null:
    /// none), written once at creation.
    pub acceleration_structure: vk::AccelerationStructureKHR,
    /// The kernel is the ray generation shader of a ray tracing pipeline
    /// with these other stages (`None`: a compute kernel).
    pub ray_tracing: Option<RtStages>,
}

/// What defines a built pipeline: the kernel, its descriptor types, push
/// constant size and specialization constants.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub(crate) struct PipelineKey {
    name: String,
    types: Vec<i32>,
    push_constant_size: u32,
    specialization: Vec<u32>,
    ray_tracing: Option<RtStages>,
}

/// A built pipeline and its layouts, owned by the context's cache.
#[derive(Clone, Copy, Debug)]
pub(crate) struct BuiltPipeline {
    set_layout: vk::DescriptorSetLayout,
    pipeline_layout: vk::PipelineLayout,
    pipeline: vk::Pipeline,
}

/// The context's pipelines ([`Context`]'s `pipelines`).
#[derive(Debug, Default)]
pub(crate) struct Pipelines(std::collections::HashMap<PipelineKey, BuiltPipeline>);

impl Pipelines {
    /// Destroy every pipeline (the context is going; nothing is in flight).
    pub(crate) fn destroy(&mut self, device: &ash::Device) {
        for (_, p) in self.0.drain() {
            unsafe {
                device.destroy_pipeline(p.pipeline, None);
                device.destroy_pipeline_layout(p.pipeline_layout, None);
                device.destroy_descriptor_set_layout(p.set_layout, None);
            }
        }
    }
}

/// Workgroups needed to cover `n` items with `local_size` per group.
pub fn groups(n: u32, local_size: u32) -> u32 {
    n.div_ceil(local_size.max(1))
}

pub struct Kernel<'a> {
    ctx: &'a Context,
    name: String,
    bindings: Vec<BufferKind>,
    push_constant_size: u32,
    set_layout: vk::DescriptorSetLayout,
    pipeline_layout: vk::PipelineLayout,
    pipeline: vk::Pipeline,
    descriptor_pool: vk::DescriptorPool,
    set: vk::DescriptorSet,
    /// Whether `set` has been written since creation.
    bound: bool,
    /// The pipeline and layouts are the context's (its cache); else this
    /// kernel's own, to destroy (a build that failed half way).
    cached: bool,
    /// A ray tracing pipeline's stages and shader binding table.
    rt: Option<(RtStages, Sbt<'a>)>,
}

impl<'a> Kernel<'a> {
    /// Kernel `name` with `num_bindings` storage buffers at bindings
    /// `0..num_bindings` and `push_constant_size` bytes of push constants.
    pub fn new(
        ctx: &'a Context,
        name: &str,
        num_bindings: usize,
        push_constant_size: u32,
    ) -> Result<Self, GpuError> {
        Self::with_bindings(
            ctx,
            name,
            &vec![BufferKind::Storage; num_bindings],
            push_constant_size,
        )
    }

    /// Kernel `name` with binding `i` of set 0 of kind `bindings[i]`.
    pub fn with_bindings(
        ctx: &'a Context,
        name: &str,
        bindings: &[BufferKind],
        push_constant_size: u32,
    ) -> Result<Self, GpuError> {
        Self::with_options(
            ctx,
            name,
            bindings,
            push_constant_size,
            &KernelOptions::default(),
        )
    }

    /// [`Kernel::with_bindings`] with specialization constants and a
    /// pipeline cache.
    pub fn with_options(
        ctx: &'a Context,
        name: &str,
        bindings: &[BufferKind],
        push_constant_size: u32,
        options: &KernelOptions<'_>,
    ) -> Result<Self, GpuError> {
        let code =
            super::shaders::spirv(name).ok_or_else(|| GpuError::UnknownKernel(name.to_string()))?;
        let max_push = ctx.info().limits.max_push_constants_size;
        if push_constant_size > max_push || !push_constant_size.is_multiple_of(4) {
            return Err(GpuError::Invalid(format!(
                "kernel '{name}': {push_constant_size} bytes of push constants (must be a multiple of 4, at most {max_push})"
            )));
        }
        let mut kernel = Kernel {
            ctx,
            name: name.to_string(),
            bindings: bindings.to_vec(),
            push_constant_size,
            set_layout: vk::DescriptorSetLayout::null(),
            pipeline_layout: vk::PipelineLayout::null(),
            pipeline: vk::Pipeline::null(),
            descriptor_pool: vk::DescriptorPool::null(),
            set: vk::DescriptorSet::null(),
            bound: false,
            cached: false,
            rt: None,
        };
        // `kernel`'s Drop destroys whatever it created if a step fails; the
        // pipeline and its layouts belong to the context's cache once there.
        let accel = options.acceleration_structure != vk::AccelerationStructureKHR::null();
        let types: Vec<vk::DescriptorType> = bindings
            .iter()
            .map(|k| k.descriptor_type())
            .chain(accel.then_some(vk::DescriptorType::ACCELERATION_STRUCTURE_KHR))
            .collect();
        let key = PipelineKey {
            name: name.to_string(),
            types: types.iter().map(|t| t.as_raw()).collect(),
            push_constant_size,
            specialization: options.specialization.to_vec(),
            ray_tracing: options.ray_tracing,
        };
        let cached = ctx
            .pipelines
            .lock()
            .ok()
            .and_then(|p| p.0.get(&key).copied());
        match cached {
            Some(p) => {
                kernel.set_layout = p.set_layout;
                kernel.pipeline_layout = p.pipeline_layout;
                kernel.pipeline = p.pipeline;
            }
            None => {
                kernel.create_layouts(&types, stage_flags(options))?;
                match &options.ray_tracing {
                    None => kernel.create_pipeline(code, options)?,
                    Some(stages) => {
                        kernel.pipeline = rt_pipeline::create_pipeline(
                            ctx,
                            kernel.pipeline_layout,
                            name,
                            stages,
                            options.specialization,
                            options.cache,
                        )?
                    }
                }
                if let Ok(mut p) = ctx.pipelines.lock() {
                    p.0.insert(
                        key,
                        BuiltPipeline {
                            set_layout: kernel.set_layout,
                            pipeline_layout: kernel.pipeline_layout,
                            pipeline: kernel.pipeline,
                        },
                    );
                }
            }
        }
        kernel.cached = true;
        if let Some(stages) = options.ray_tracing {
            kernel.rt = Some((stages, Sbt::new(ctx, kernel.pipeline, &stages)?));
        }
        if !types.is_empty() {
            kernel.create_descriptor_set(&types)?;
        }
        if accel {
            kernel.write_acceleration_structure(options.acceleration_structure);
        }
        Ok(kernel)
    }

    /// The descriptor set layout of `types` (binding i is types[i]) and the
    /// pipeline layout with the push constants.
    fn create_layouts(
        &mut self,
        types: &[vk::DescriptorType],
        stages: vk::ShaderStageFlags,
    ) -> Result<(), GpuError> {
        let layout_bindings: Vec<_> = types
            .iter()
            .enumerate()
            .map(|(i, &t)| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(i as u32)
                    .descriptor_type(t)
                    .descriptor_count(1)
                    .stage_flags(stages)
            })
            .collect();
        self.set_layout = unsafe {
            self.ctx.device.create_descriptor_set_layout(
                &vk::DescriptorSetLayoutCreateInfo::default().bindings(&layout_bindings),
                None,
            )
        }
        .map_err(|e| GpuError::from_vk("vkCreateDescriptorSetLayout", e))?;

        let set_layouts = [self.set_layout];
        let ranges = [vk::PushConstantRange::default()
            .stage_flags(stages)
            .offset(0)
            .size(self.push_constant_size)];
        let mut layout_info = vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts);
        if self.push_constant_size > 0 {
            layout_info = layout_info.push_constant_ranges(&ranges);
        }
        self.pipeline_layout =
            unsafe { self.ctx.device.create_pipeline_layout(&layout_info, None) }
                .map_err(|e| GpuError::from_vk("vkCreatePipelineLayout", e))?;

        Ok(())
    }

    /// The compute pipeline of SPIR-V `code` with `options`' specialization
    /// constants and pipeline cache.
    fn create_pipeline(
        &mut self,
        code: &[u32],
        options: &KernelOptions<'_>,
    ) -> Result<(), GpuError> {
        let module = unsafe {
            self.ctx
                .device
                .create_shader_module(&vk::ShaderModuleCreateInfo::default().code(code), None)
        }
        .map_err(|e| GpuError::from_vk("vkCreateShaderModule", e))?;
        let entry: &CStr = c"main";
        let map = specialization_map(options.specialization);
        let data: &[u8] = bytemuck::cast_slice(options.specialization);
        let spec = vk::SpecializationInfo::default()
            .map_entries(&map)
            .data(data);
        let mut stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(module)
            .name(entry);
        if !options.specialization.is_empty() {
            stage = stage.specialization_info(&spec);
        }
        let info = [vk::ComputePipelineCreateInfo::default()
            .stage(stage)
            .layout(self.pipeline_layout)];
        let pipelines = unsafe {
            self.ctx
                .device
                .create_compute_pipelines(options.cache, &info, None)
        };
        unsafe { self.ctx.device.destroy_shader_module(module, None) };
        self.pipeline =
            pipelines.map_err(|(_, e)| GpuError::from_vk("vkCreateComputePipelines", e))?[0];

        Ok(())
    }

    /// A descriptor pool and the one set of `types`.
    fn create_descriptor_set(&mut self, types: &[vk::DescriptorType]) -> Result<(), GpuError> {
        let set_layouts = [self.set_layout];
        let mut sizes = Vec::new();
        for ty in [
            vk::DescriptorType::STORAGE_BUFFER,
            vk::DescriptorType::UNIFORM_BUFFER,
            vk::DescriptorType::ACCELERATION_STRUCTURE_KHR,
        ] {
            let n = types.iter().filter(|&&t| t == ty).count() as u32;
            if n > 0 {
                sizes.push(vk::DescriptorPoolSize::default().ty(ty).descriptor_count(n));
            }
        }
        self.descriptor_pool = unsafe {
            self.ctx.device.create_descriptor_pool(
                &vk::DescriptorPoolCreateInfo::default()
                    .max_sets(1)
                    .pool_sizes(&sizes),
                None,
            )
        }
        .map_err(|e| GpuError::from_vk("vkCreateDescriptorPool", e))?;
        self.set = unsafe {
            self.ctx.device.allocate_descriptor_sets(
                &vk::DescriptorSetAllocateInfo::default()
                    .descriptor_pool(self.descriptor_pool)
                    .set_layouts(&set_layouts),
            )
        }
        .map_err(|e| GpuError::from_vk("vkAllocateDescriptorSets", e))?[0];
        Ok(())
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    /// Point the binding after the buffers' at `structure`.
    fn write_acceleration_structure(&self, structure: vk::AccelerationStructureKHR) {
        let structures = [structure];
        let mut info = vk::WriteDescriptorSetAccelerationStructureKHR::default()
            .acceleration_structures(&structures);
        let write = vk::WriteDescriptorSet::default()
            .dst_set(self.set)
            .dst_binding(self.bindings.len() as u32)
            .descriptor_type(vk::DescriptorType::ACCELERATION_STRUCTURE_KHR)
            .descriptor_count(1)
            .push_next(&mut info);
        unsafe { self.ctx.device.update_descriptor_sets(&[write], &[]) };
    }

    /// Point bindings `0..N` at `buffers` (one per binding, matching kinds).
    /// Must not be called while a dispatch using this kernel is in flight;
    /// [`Kernel::dispatch`] always waits, so that holds for its users.
    pub fn bind(&mut self, buffers: &[&Buffer<'_>]) -> Result<(), GpuError> {
        if buffers.len() != self.bindings.len() {
            return Err(GpuError::Invalid(format!(
                "kernel '{}' has {} bindings, got {} buffers",
                self.name,
                self.bindings.len(),
                buffers.len()
            )));
        }
        for (i, (b, k)) in buffers.iter().zip(&self.bindings).enumerate() {
            if b.kind() != *k {
                return Err(GpuError::Invalid(format!(
                    "kernel '{}' binding {i} wants a {k:?} buffer, got {:?}",
                    self.name,
                    b.kind()
                )));
            }
        }
        let infos: Vec<[vk::DescriptorBufferInfo; 1]> = buffers
            .iter()
            .map(|b| {
                [vk::DescriptorBufferInfo::default()
                    .buffer(b.raw())
                    .offset(0)
                    .range(b.size())]
            })
            .collect();
        let writes: Vec<_> = infos
            .iter()
            .zip(&self.bindings)
            .enumerate()
            .map(|(i, (info, k))| {
                vk::WriteDescriptorSet::default()
                    .dst_set(self.set)
                    .dst_binding(i as u32)
                    .descriptor_type(k.descriptor_type())
                    .buffer_info(info)
            })
            .collect();
        unsafe { self.ctx.device.update_descriptor_sets(&writes, &[]) };
        self.bound = true;
        Ok(())
    }

    fn check_dispatch(&self, push_constants: &[u8], groups: [u32; 3]) -> Result<(), GpuError> {
        if push_constants.len() != self.push_constant_size as usize {
            return Err(GpuError::Invalid(format!(
                "kernel '{}' takes {} bytes of push constants, got {}",
                self.name,
                self.push_constant_size,
                push_constants.len()
            )));
        }
        if !self.bound && !self.bindings.is_empty() {
            return Err(GpuError::Invalid(format!(
                "kernel '{}' dispatched before its buffers were bound",
                self.name
            )));
        }
        if let Some((stages, _)) = &self.rt {
            let max = self
                .ctx
                .ray_tracing()
                .pipeline
                .map_or(0, |p| p.max_ray_dispatch_invocation_count) as u64;
            let launch = launch_size(stages, groups);
            if launch.iter().map(|&n| n as u64).product::<u64>() > max {
                return Err(GpuError::Invalid(format!(
                    "kernel '{}': a launch of {launch:?} rays exceeds the device limit of {max}",
                    self.name
                )));
            }
            return Ok(());
        }
        let max = self.ctx.info().limits.max_compute_work_group_count;
        if groups.iter().zip(max).any(|(&g, m)| g > m) {
            return Err(GpuError::Invalid(format!(
                "kernel '{}': {groups:?} workgroups exceed the device limit {max:?}",
                self.name
            )));
        }
        Ok(())
    }

    /// Record bind + push constants + dispatch into `cmd`, followed by a
    /// barrier that makes the shader's writes visible to later dispatches,
    /// transfers and the host.
    pub fn record_dispatch(
        &self,
        cmd: vk::CommandBuffer,
        push_constants: &[u8],
        groups: [u32; 3],
    ) -> Result<(), GpuError> {
        self.check_dispatch(push_constants, groups)?;
        let d = &self.ctx.device;
        let (bind_point, stages, stage) = match &self.rt {
            None => (
                vk::PipelineBindPoint::COMPUTE,
                vk::ShaderStageFlags::COMPUTE,
                vk::PipelineStageFlags::COMPUTE_SHADER,
            ),
            Some(_) => (
                vk::PipelineBindPoint::RAY_TRACING_KHR,
                rt_pipeline::RT_STAGE_FLAGS,
                vk::PipelineStageFlags::RAY_TRACING_SHADER_KHR,
            ),
        };
        unsafe {
            d.cmd_bind_pipeline(cmd, bind_point, self.pipeline);
            if !self.bindings.is_empty() {
                d.cmd_bind_descriptor_sets(
                    cmd,
                    bind_point,
                    self.pipeline_layout,
                    0,
                    &[self.set],
                    &[],
                );
            }
            if !push_constants.is_empty() {
                d.cmd_push_constants(cmd, self.pipeline_layout, stages, 0, push_constants);
            }
            match &self.rt {
                None => d.cmd_dispatch(cmd, groups[0], groups[1], groups[2]),
                Some((rt_stages, sbt)) => {
                    let [w, h, depth] = launch_size(rt_stages, groups);
                    let [raygen, miss, hit, callable] = &sbt.regions;
                    let (loader, _) = self.ctx.rt_pipeline()?;
                    loader.cmd_trace_rays(cmd, raygen, miss, hit, callable, w, h, depth);
                }
            }
            let barrier = [vk::MemoryBarrier::default()
                .src_access_mask(vk::AccessFlags::SHADER_WRITE)
                .dst_access_mask(
                    vk::AccessFlags::SHADER_READ
                        | vk::AccessFlags::SHADER_WRITE
                        | vk::AccessFlags::TRANSFER_READ
                        | vk::AccessFlags::HOST_READ,
                )];
            d.cmd_pipeline_barrier(
                cmd,
                stage,
                stage | vk::PipelineStageFlags::TRANSFER | vk::PipelineStageFlags::HOST,
                vk::DependencyFlags::empty(),
                &barrier,
                &[],
                &[],
            );
        }
        Ok(())
    }

    /// Dispatch over the bound buffers and wait for completion.
    pub fn dispatch(&self, push_constants: &[u8], groups: [u32; 3]) -> Result<(), GpuError> {
        self.check_dispatch(push_constants, groups)?;
        let mut recorded = Ok(());
        self.ctx.submit_and_wait(|cmd| {
            recorded = self.record_dispatch(cmd, push_constants, groups);
        })?;
        recorded
    }
}

/// Constant i of the shader (`layout(constant_id = i)`) is the 4 bytes
/// `values[i]`.
pub(crate) fn specialization_map(values: &[u32]) -> Vec<vk::SpecializationMapEntry> {
    (0..values.len() as u32)
        .map(|i| {
            vk::SpecializationMapEntry::default()
                .constant_id(i)
                .offset(4 * i)
                .size(4)
        })
        .collect()
}

/// The shader stages that see a kernel's bindings and push constants.
fn stage_flags(options: &KernelOptions<'_>) -> vk::ShaderStageFlags {
    match options.ray_tracing {
        None => vk::ShaderStageFlags::COMPUTE,
        Some(_) => rt_pipeline::RT_STAGE_FLAGS,
    }
}

/// The ray generation launch of a dispatch of `groups`.
fn launch_size(stages: &RtStages, groups: [u32; 3]) -> [u32; 3] {
    [
        groups[0].saturating_mul(stages.group_size[0]),
        groups[1].saturating_mul(stages.group_size[1]),
        groups[2],
    ]
}

impl Drop for Kernel<'_> {
    fn drop(&mut self) {
        let d = &self.ctx.device;
        // Null handles are ignored by vkDestroy*, so a half-built kernel
        // tears down cleanly too.
        unsafe {
            d.destroy_descriptor_pool(self.descriptor_pool, None);
            if !self.cached {
                d.destroy_pipeline(self.pipeline, None);
                d.destroy_pipeline_layout(self.pipeline_layout, None);
                d.destroy_descriptor_set_layout(self.set_layout, None);
            }
        }
    }
}

impl Context {
    /// Run kernel `name` once: `inputs` at bindings `0..I`, `outputs` at
    /// `I..I+O` (all storage buffers), uploaded with their current contents;
    /// waits, then reads each output back into its slice. Push constants
    /// must be exactly the size the kernel declares (empty for none).
    pub fn run_kernel(
        &self,
        name: &str,
        inputs: &[&[u8]],
        outputs: &mut [&mut [u8]],
        push_constants: &[u8],
        groups: [u32; 3],
    ) -> Result<(), GpuError> {
        let mut buffers = Vec::with_capacity(inputs.len() + outputs.len());
        for (i, data) in inputs.iter().enumerate() {
            buffers.push(Buffer::from_slice(
                self,
                &format!("{name} input {i}"),
                BufferKind::Storage,
                data,
            )?);
        }
        for (i, data) in outputs.iter().enumerate() {
            buffers.push(Buffer::from_slice(
                self,
                &format!("{name} output {i}"),
                BufferKind::Storage,
                data,
            )?);
        }
        let mut kernel = Kernel::new(self, name, buffers.len(), push_constants.len() as u32)?;
        let refs: Vec<&Buffer<'_>> = buffers.iter().collect();
        kernel.bind(&refs)?;
        kernel.dispatch(push_constants, groups)?;
        for (out, buf) in outputs.iter_mut().zip(&buffers[inputs.len()..]) {
            buf.read_into(out)?;
        }
        Ok(())
    }
}

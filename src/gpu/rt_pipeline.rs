//! Ray tracing pipelines (`VK_KHR_ray_tracing_pipeline`): the path tracer's
//! ray generation shader (`shaders/rt/raygen.rgen`, the compute kernel's
//! source, pathtrace.glsl) with its miss, closest-hit and any-hit shaders,
//! and the shader binding table that `vkCmdTraceRaysKHR` reads, laid out
//! per the device's handle size and alignments.
//!
//! A [`super::Kernel`] built with [`super::KernelOptions::ray_tracing`]
//! holds one: it binds and pushes constants as a compute kernel does (every
//! stage sees every binding) and its "dispatch" of `groups` launches
//! `groups * group_size` ray generation items.
//!
//! Shader groups, in shader binding table order: 0 ray generation, then one
//! general group per miss shader (`rt/miss` for a path's rays, index
//! `RT_MISS_HIT`; `rt/shadow_miss` for shadow rays, `RT_MISS_SHADOW`;
//! shaders/rt/payload.glsl), then one triangles hit group (closest hit and
//! any hit). Every ray uses hit group 0: the any-hit shader runs only on
//! the non-opaque geometry (the alpha-tested triangles), and shadow rays
//! skip the closest-hit shader by their flags.

use std::ffi::CStr;

use ash::vk;

use super::GpuError;
use super::buffer::Buffer;
use super::context::{Context, RtPipelineProperties};

/// The stages beside ray generation (the kernel's name), by module name
/// (`shaders/<name>.<stage>`), and the launch items per group of a
/// dispatch (the compute kernel's local size, so the two share a grid).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct RtStages {
    /// Miss shaders, by miss index.
    pub miss: &'static [&'static str],
    pub closest_hit: &'static str,
    /// Runs on non-opaque geometry only.
    pub any_hit: &'static str,
    pub group_size: [u32; 2],
}

/// The path tracer's pipeline: `rt/raygen` with these.
pub const PATH_TRACER_RAYGEN: &str = "rt/raygen";
pub const PATH_TRACER_STAGES: RtStages = RtStages {
    miss: &["rt/miss", "rt/shadow_miss"],
    closest_hit: "rt/closest_hit",
    any_hit: "rt/any_hit",
    // The compute kernel's grid (render.rs dispatches both alike).
    group_size: [super::render::LOCAL_SIZE, super::render::LOCAL_SIZE],
};

/// The descriptor and push-constant stages of a ray tracing pipeline.
pub const RT_STAGE_FLAGS: vk::ShaderStageFlags = vk::ShaderStageFlags::from_raw(
    vk::ShaderStageFlags::RAYGEN_KHR.as_raw()
        | vk::ShaderStageFlags::MISS_KHR.as_raw()
        | vk::ShaderStageFlags::CLOSEST_HIT_KHR.as_raw()
        | vk::ShaderStageFlags::ANY_HIT_KHR.as_raw(),
);

/// One region of the shader binding table, relative to its start.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SbtRegion {
    pub offset: u64,
    pub stride: u64,
    pub size: u64,
}

/// Where each group's handle goes in the shader binding table.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SbtLayout {
    pub raygen: SbtRegion,
    pub miss: SbtRegion,
    pub hit: SbtRegion,
    /// Bytes from the table's start to the end of the last region.
    pub size: u64,
}

fn align_up(v: u64, a: u64) -> u64 {
    v.next_multiple_of(a.max(1))
}

/// The table of one ray generation group, `miss` miss groups and `hit` hit
/// groups: each region starts on `shaderGroupBaseAlignment`, each record is
/// a handle rounded up to `shaderGroupHandleAlignment`, and the ray
/// generation region's size equals its stride (as vkCmdTraceRaysKHR
/// requires).
pub fn sbt_layout(p: &RtPipelineProperties, miss: u32, hit: u32) -> SbtLayout {
    let base = p.shader_group_base_alignment as u64;
    let stride = align_up(
        p.shader_group_handle_size as u64,
        p.shader_group_handle_alignment as u64,
    );
    let raygen = SbtRegion {
        offset: 0,
        stride,
        size: stride,
    };
    let miss = SbtRegion {
        offset: align_up(raygen.size, base),
        stride,
        size: stride * miss as u64,
    };
    let hit = SbtRegion {
        offset: align_up(miss.offset + miss.size, base),
        stride,
        size: stride * hit as u64,
    };
    SbtLayout {
        raygen,
        miss,
        hit,
        size: hit.offset + hit.size,
    }
}

/// Builds the ray tracing pipeline of ray generation `raygen` and `stages`
/// over `layout`, every stage specialised with `specialization` (constant
/// i is its 4 bytes i).
pub(crate) fn create_pipeline(
    ctx: &Context,
    layout: vk::PipelineLayout,
    raygen: &str,
    stages: &RtStages,
    specialization: &[u32],
    cache: vk::PipelineCache,
) -> Result<vk::Pipeline, GpuError> {
    let (loader, props) = ctx.rt_pipeline()?;
    if props.max_ray_recursion_depth < 1 {
        return Err(GpuError::Invalid(
            "the device's maxRayRecursionDepth is 0".into(),
        ));
    }
    // Module order: raygen, miss..., closest hit, any hit.
    let mut names = vec![(raygen, vk::ShaderStageFlags::RAYGEN_KHR)];
    names.extend(
        stages
            .miss
            .iter()
            .map(|&m| (m, vk::ShaderStageFlags::MISS_KHR)),
    );
    names.push((stages.closest_hit, vk::ShaderStageFlags::CLOSEST_HIT_KHR));
    names.push((stages.any_hit, vk::ShaderStageFlags::ANY_HIT_KHR));
    let mut modules = Vec::with_capacity(names.len());
    let result = (|| {
        for &(name, _) in &names {
            let code = super::shaders::spirv(name)
                .ok_or_else(|| GpuError::UnknownKernel(name.to_string()))?;
            let info = vk::ShaderModuleCreateInfo::default().code(code);
            let module = unsafe { ctx.device.create_shader_module(&info, None) }
                .map_err(|e| GpuError::from_vk("vkCreateShaderModule", e))?;
            modules.push(module);
        }
        let map = super::kernel::specialization_map(specialization);
        let spec = vk::SpecializationInfo::default()
            .map_entries(&map)
            .data(bytemuck::cast_slice(specialization));
        let entry: &CStr = c"main";
        let stage_infos: Vec<_> = names
            .iter()
            .zip(&modules)
            .map(|(&(_, stage), &module)| {
                let s = vk::PipelineShaderStageCreateInfo::default()
                    .stage(stage)
                    .module(module)
                    .name(entry);
                if specialization.is_empty() {
                    s
                } else {
                    s.specialization_info(&spec)
                }
            })
            .collect();
        let groups = shader_groups(stages.miss.len() as u32);
        let info = [vk::RayTracingPipelineCreateInfoKHR::default()
            .stages(&stage_infos)
            .groups(&groups)
            .max_pipeline_ray_recursion_depth(1)
            .layout(layout)];
        let pipelines = unsafe {
            loader.create_ray_tracing_pipelines(
                vk::DeferredOperationKHR::null(),
                cache,
                &info,
                None,
            )
        };
        pipelines
            .map(|p| p[0])
            .map_err(|(_, e)| GpuError::from_vk("vkCreateRayTracingPipelinesKHR", e))
    })();
    for m in modules {
        unsafe { ctx.device.destroy_shader_module(m, None) };
    }
    result
}

/// The groups over the modules raygen, `n_miss` miss shaders, closest hit,
/// any hit: one general group each for ray generation and the misses, then
/// the triangles hit group.
fn shader_groups(n_miss: u32) -> Vec<vk::RayTracingShaderGroupCreateInfoKHR<'static>> {
    let group = |ty, general, closest, any| {
        vk::RayTracingShaderGroupCreateInfoKHR::default()
            .ty(ty)
            .general_shader(general)
            .closest_hit_shader(closest)
            .any_hit_shader(any)
            .intersection_shader(vk::SHADER_UNUSED_KHR)
    };
    let unused = vk::SHADER_UNUSED_KHR;
    let mut groups: Vec<_> = (0..=n_miss)
        .map(|i| group(vk::RayTracingShaderGroupTypeKHR::GENERAL, i, unused, unused))
        .collect();
    groups.push(group(
        vk::RayTracingShaderGroupTypeKHR::TRIANGLES_HIT_GROUP,
        unused,
        n_miss + 1,
        n_miss + 2,
    ));
    groups
}

/// A pipeline's shader binding table on the device and its regions, as
/// vkCmdTraceRaysKHR takes them (raygen, miss, hit, callable: none).
pub(crate) struct Sbt<'a> {
    _buffer: Buffer<'a>,
    pub regions: [vk::StridedDeviceAddressRegionKHR; 4],
}

impl<'a> Sbt<'a> {
    /// The table of `pipeline`, built from `stages` ([`create_pipeline`]'s
    /// group order).
    pub(crate) fn new(
        ctx: &'a Context,
        pipeline: vk::Pipeline,
        stages: &RtStages,
    ) -> Result<Self, GpuError> {
        let (loader, props) = ctx.rt_pipeline()?;
        let n_miss = stages.miss.len() as u32;
        let groups = n_miss + 2;
        let handle = props.shader_group_handle_size as usize;
        let handles = unsafe {
            loader.get_ray_tracing_shader_group_handles(
                pipeline,
                0,
                groups,
                groups as usize * handle,
            )
        }
        .map_err(|e| GpuError::from_vk("vkGetRayTracingShaderGroupHandlesKHR", e))?;
        let layout = sbt_layout(&props, n_miss, 1);
        // The buffer's own address need not be on the base alignment: start
        // the table at the first aligned byte of it.
        let base = props.shader_group_base_alignment as u64;
        let buffer = Buffer::with_usage(
            ctx,
            "shader binding table",
            vk::BufferUsageFlags::SHADER_BINDING_TABLE_KHR
                | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS,
            layout.size + base,
        )?;
        let address = buffer.device_address();
        let start = align_up(address, base) - address;
        let mut bytes = vec![0u8; (start + layout.size) as usize];
        let mut put = |group: usize, at: u64| {
            let at = (start + at) as usize;
            bytes[at..at + handle].copy_from_slice(&handles[group * handle..(group + 1) * handle]);
        };
        put(0, layout.raygen.offset);
        for m in 0..n_miss as usize {
            put(1 + m, layout.miss.offset + m as u64 * layout.miss.stride);
        }
        put(1 + n_miss as usize, layout.hit.offset);
        buffer.write(&bytes)?;
        let region = |r: SbtRegion| {
            vk::StridedDeviceAddressRegionKHR::default()
                .device_address(address + start + r.offset)
                .stride(r.stride)
                .size(r.size)
        };
        Ok(Sbt {
            _buffer: buffer,
            regions: [
                region(layout.raygen),
                region(layout.miss),
                region(layout.hit),
                vk::StridedDeviceAddressRegionKHR::default(),
            ],
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn props(size: u32, handle_align: u32, base: u32) -> RtPipelineProperties {
        RtPipelineProperties {
            shader_group_handle_size: size,
            shader_group_handle_alignment: handle_align,
            shader_group_base_alignment: base,
            max_ray_recursion_depth: 1,
            max_ray_dispatch_invocation_count: 1 << 30,
        }
    }

    /// NVIDIA's figures (32-byte handles, 32 and 64 alignments) and
    /// lavapipe-like ones where a handle is smaller than its alignment.
    #[test]
    fn regions_start_on_the_base_alignment_and_records_on_the_handle_alignment() {
        let l = sbt_layout(&props(32, 32, 64), 2, 1);
        assert_eq!(
            l.raygen,
            SbtRegion {
                offset: 0,
                stride: 32,
                size: 32
            }
        );
        assert_eq!(
            l.miss,
            SbtRegion {
                offset: 64,
                stride: 32,
                size: 64
            }
        );
        assert_eq!(
            l.hit,
            SbtRegion {
                offset: 128,
                stride: 32,
                size: 32
            }
        );
        assert_eq!(l.size, 160);

        let l = sbt_layout(&props(20, 32, 64), 3, 2);
        assert_eq!(l.raygen.stride, 32);
        assert_eq!(l.raygen.size, l.raygen.stride);
        assert_eq!(l.miss.offset, 64);
        assert_eq!(l.miss.size, 96);
        assert_eq!(l.hit.offset, 192);
        assert_eq!(l.hit.size, 64);
        for r in [l.raygen, l.miss, l.hit] {
            assert_eq!(r.offset % 64, 0);
            assert_eq!(r.stride % 32, 0);
            assert!(r.stride >= 20);
        }
    }
}

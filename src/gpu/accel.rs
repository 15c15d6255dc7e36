//! Acceleration structures for `--traversal hardware` (the kernel
//! `pathtrace_rq`, shaders/ray_query.glsl, and the ray tracing pipeline,
//! shaders/rt/), built on the device through a command buffer (lavapipe
//! does not implement the host-side builds).
//!
//! Bottom-level structures (BLAS) read the triangles in place from the
//! triangles buffer (binding 1: 48-byte `Triangle`s, so vertex `k` of
//! triangle `i` is vertex `3i + k` at a 16-byte stride); the top-level
//! structure (TLAS) holds one identity instance of each. By default one
//! BLAS holds every triangle of the scene: the scene is flattened to world
//! space at load, so there is nothing to instance, and on lavapipe a split
//! into per-object structures only costs (`--blas-parts`,
//! docs/benchmarks.md). [`Accel::build_parts`] builds the split: contiguous
//! ranges of the triangles (in BVH leaf order, so each range is a compact
//! cluster, as a mesh is), one BLAS each.
//!
//! Without alpha-tested materials a BLAS has one opaque geometry, not
//! indexed, so the primitive index plus the instance's custom index is the
//! triangle index. With them it has two indexed geometries, the opaque
//! triangles (flagged opaque) and the alpha-tested ones (not), and the
//! tri_map buffer maps them back from the instance's custom index (its
//! layout: shaders/tri_map.glsl).
//!
//! Each BLAS is built with `ALLOW_COMPACTION`, its compacted size queried
//! and the structure copied into a buffer of that size.

use std::time::Instant;

use ash::vk;

use super::GpuError;
use super::buffer::Buffer;
use super::context::Context;

/// What the build cost and made, for tests and `docs/benchmarks.md`.
#[derive(Clone, Copy, Debug, Default)]
pub struct AccelStats {
    pub build_seconds: f64,
    /// Bottom-level structures (TLAS instances).
    pub blas_count: u32,
    /// Bytes of the BLASes as built, and after compaction.
    pub blas_bytes: u64,
    pub compacted_bytes: u64,
    pub tlas_bytes: u64,
    /// Triangles in the non-opaque (alpha-tested) geometry.
    pub masked_triangles: u32,
}

/// An acceleration structure and the buffer holding it.
struct Structure<'a> {
    handle: vk::AccelerationStructureKHR,
    buffer: Buffer<'a>,
}

/// The scene's TLAS (and the BLASes it refers to) and the tri_map buffer.
pub struct Accel<'a> {
    loader: ash::khr::acceleration_structure::Device,
    /// Each BLAS with its instance's custom index.
    blas: Vec<(Structure<'a>, u32)>,
    tlas: Option<Structure<'a>>,
    /// Binding 17 of `pathtrace_rq`.
    pub tri_map: Buffer<'a>,
    pub stats: AccelStats,
}

impl<'a> Accel<'a> {
    /// Build the structures over the first `count` triangles of
    /// `triangles`; `masked(i)`: triangle `i` is alpha-tested. The context
    /// must have acceleration structures enabled
    /// ([`Context::new_ray_tracing`]).
    pub fn build(
        ctx: &'a Context,
        triangles: &Buffer<'a>,
        count: u32,
        masked: &dyn Fn(u32) -> bool,
    ) -> Result<Self, GpuError> {
        Self::build_parts(ctx, triangles, count, masked, 1)
    }

    /// [`Accel::build`] with the triangles split into `parts` contiguous
    /// ranges of (nearly) equal size, one BLAS and one TLAS instance each
    /// (at most one per triangle).
    pub fn build_parts(
        ctx: &'a Context,
        triangles: &Buffer<'a>,
        count: u32,
        masked: &dyn Fn(u32) -> bool,
        parts: u32,
    ) -> Result<Self, GpuError> {
        if !ctx.acceleration_structures() {
            return Err(GpuError::Invalid(
                "acceleration structures need a context with ray tracing enabled".into(),
            ));
        }
        let start = Instant::now();
        let parts = parts.clamp(1, count.max(1)) as u64;
        let any_alpha = (0..count).any(masked);
        // Per part: its range, its custom index and (with alpha tests) its
        // opaque and alpha-tested triangles, whose map starts at the
        // custom index (shaders/tri_map.glsl).
        let mut map = Vec::new();
        let mut plan = Vec::new();
        let mut masked_triangles = 0;
        for p in 0..parts {
            let range = (count as u64 * p / parts) as u32..(count as u64 * (p + 1) / parts) as u32;
            if any_alpha {
                let (opaque, alpha): (Vec<u32>, Vec<u32>) =
                    range.clone().partition(|&i| !masked(i));
                masked_triangles += alpha.len() as u32;
                let custom = map.len() as u32;
                map.push(opaque.len() as u32);
                map.extend(&opaque);
                map.extend(&alpha);
                plan.push((range, custom, vec![opaque, alpha]));
            } else {
                plan.push((range.clone(), range.start, vec![]));
            }
        }
        // The custom index has 24 bits (one part: always 0).
        if plan.iter().any(|(_, custom, _)| *custom >= 1 << 24) {
            return Err(GpuError::Invalid(format!(
                "{count} triangles in {parts} acceleration structures: a custom index past 2^24"
            )));
        }
        let tri_map = Buffer::from_slice(
            ctx,
            "acceleration structure triangle map",
            super::BufferKind::Storage,
            &map,
        )?;
        let mut accel = Accel {
            loader: ash::khr::acceleration_structure::Device::new(&ctx.instance, &ctx.device),
            blas: Vec::new(),
            tlas: None,
            tri_map,
            stats: AccelStats {
                masked_triangles,
                ..Default::default()
            },
        };
        if count > 0 {
            for (range, custom, groups) in &plan {
                let blas = accel.build_blas(ctx, triangles, count, range.clone(), groups)?;
                accel.blas.push((blas, *custom));
            }
        }
        accel.stats.blas_count = accel.blas.len() as u32;
        accel.build_tlas(ctx)?;
        accel.stats.build_seconds = start.elapsed().as_secs_f64();
        Ok(accel)
    }

    /// The TLAS, for the kernel's acceleration structure binding.
    pub fn tlas(&self) -> vk::AccelerationStructureKHR {
        self.tlas
            .as_ref()
            .map_or(vk::AccelerationStructureKHR::null(), |s| s.handle)
    }

    /// The BLAS over triangles `range` of the `count`: one opaque geometry,
    /// or (`groups` non-empty) the opaque and the alpha-tested triangles as
    /// two indexed geometries; then compacted.
    fn build_blas(
        &mut self,
        ctx: &'a Context,
        triangles: &Buffer<'a>,
        count: u32,
        range: std::ops::Range<u32>,
        groups: &[Vec<u32>],
    ) -> Result<Structure<'a>, GpuError> {
        let indices: Vec<u32> = groups
            .iter()
            .flatten()
            .flat_map(|&t| [3 * t, 3 * t + 1, 3 * t + 2])
            .collect();
        let index_buf = Buffer::with_usage(
            ctx,
            "acceleration structure indices",
            vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS
                | vk::BufferUsageFlags::ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_KHR,
            indices.len() as u64 * 4,
        )?;
        index_buf.write(&indices)?;
        let vertices = |first: u32| vk::DeviceOrHostAddressConstKHR {
            device_address: triangles.device_address() + 48 * first as u64,
        };
        let base = vk::AccelerationStructureGeometryTrianglesDataKHR::default()
            .vertex_format(vk::Format::R32G32B32_SFLOAT)
            .vertex_data(vertices(0))
            .vertex_stride(16)
            .max_vertex(3 * count - 1)
            .index_type(vk::IndexType::NONE_KHR);
        let geometry = |data, flags| {
            vk::AccelerationStructureGeometryKHR::default()
                .geometry_type(vk::GeometryTypeKHR::TRIANGLES)
                .geometry(vk::AccelerationStructureGeometryDataKHR { triangles: data })
                .flags(flags)
        };
        let mut geometries = Vec::new();
        let mut counts = Vec::new();
        if groups.is_empty() {
            // Not indexed: the range's triangles from its first vertex on.
            let data = base
                .vertex_data(vertices(range.start))
                .max_vertex(3 * range.len() as u32 - 1);
            geometries.push(geometry(data, vk::GeometryFlagsKHR::OPAQUE));
            counts.push(range.len() as u32);
        }
        let mut offset = 0u64;
        for (g, tris) in groups.iter().enumerate() {
            let data = base.index_type(vk::IndexType::UINT32).index_data(
                vk::DeviceOrHostAddressConstKHR {
                    device_address: index_buf.device_address() + offset,
                },
            );
            let flags = if g == 0 {
                vk::GeometryFlagsKHR::OPAQUE
            } else {
                vk::GeometryFlagsKHR::NO_DUPLICATE_ANY_HIT_INVOCATION
            };
            geometries.push(geometry(data, flags));
            counts.push(tris.len() as u32);
            offset += tris.len() as u64 * 12;
        }
        let flags = vk::BuildAccelerationStructureFlagsKHR::PREFER_FAST_TRACE
            | vk::BuildAccelerationStructureFlagsKHR::ALLOW_COMPACTION;
        let built = self.build_structure(
            ctx,
            vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL,
            &geometries,
            &counts,
            flags,
        )?;
        self.stats.blas_bytes += built.buffer.size();
        let compact = self.compact(ctx, &built);
        self.destroy(built);
        let compact = compact?;
        self.stats.compacted_bytes += compact.buffer.size();
        Ok(compact)
    }

    /// The TLAS: one identity instance of each BLAS, or none for an empty
    /// scene (every ray misses).
    fn build_tlas(&mut self, ctx: &'a Context) -> Result<(), GpuError> {
        let mut bytes = Vec::new();
        for (blas, custom) in &self.blas {
            let reference = unsafe {
                self.loader.get_acceleration_structure_device_address(
                    &vk::AccelerationStructureDeviceAddressInfoKHR::default()
                        .acceleration_structure(blas.handle),
                )
            };
            let instance = vk::AccelerationStructureInstanceKHR {
                transform: vk::TransformMatrixKHR {
                    matrix: [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0],
                },
                instance_custom_index_and_mask: vk::Packed24_8::new(*custom, 0xff),
                instance_shader_binding_table_record_offset_and_flags: vk::Packed24_8::new(
                    0,
                    vk::GeometryInstanceFlagsKHR::TRIANGLE_FACING_CULL_DISABLE.as_raw() as u8,
                ),
                acceleration_structure_reference: vk::AccelerationStructureReferenceKHR {
                    device_handle: reference,
                },
            };
            // SAFETY: a plain repr(C) struct of 64 bytes without padding.
            bytes.extend_from_slice(unsafe {
                std::slice::from_raw_parts(
                    (&instance as *const vk::AccelerationStructureInstanceKHR).cast::<u8>(),
                    size_of::<vk::AccelerationStructureInstanceKHR>(),
                )
            });
        }
        let instances = Buffer::with_usage(
            ctx,
            "acceleration structure instances",
            vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS
                | vk::BufferUsageFlags::ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_KHR,
            bytes.len().max(64) as u64,
        )?;
        instances.write(&bytes)?;
        let data = vk::AccelerationStructureGeometryInstancesDataKHR::default()
            .array_of_pointers(false)
            .data(vk::DeviceOrHostAddressConstKHR {
                device_address: instances.device_address(),
            });
        let geometry = vk::AccelerationStructureGeometryKHR::default()
            .geometry_type(vk::GeometryTypeKHR::INSTANCES)
            .geometry(vk::AccelerationStructureGeometryDataKHR { instances: data })
            .flags(vk::GeometryFlagsKHR::empty());
        let tlas = self.build_structure(
            ctx,
            vk::AccelerationStructureTypeKHR::TOP_LEVEL,
            &[geometry],
            &[(bytes.len() / 64) as u32],
            vk::BuildAccelerationStructureFlagsKHR::PREFER_FAST_TRACE,
        )?;
        self.stats.tlas_bytes = tlas.buffer.size();
        self.tlas = Some(tlas);
        Ok(())
    }

    /// An empty structure of type `ty` and `size` bytes.
    fn create(
        &self,
        ctx: &'a Context,
        ty: vk::AccelerationStructureTypeKHR,
        size: u64,
    ) -> Result<Structure<'a>, GpuError> {
        let buffer = Buffer::with_usage(
            ctx,
            "acceleration structure",
            vk::BufferUsageFlags::ACCELERATION_STRUCTURE_STORAGE_KHR
                | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS,
            size,
        )?;
        let info = vk::AccelerationStructureCreateInfoKHR::default()
            .buffer(buffer.raw())
            .size(size)
            .ty(ty);
        let handle = unsafe { self.loader.create_acceleration_structure(&info, None) }
            .map_err(|e| GpuError::from_vk("vkCreateAccelerationStructureKHR", e))?;
        Ok(Structure { handle, buffer })
    }

    /// Build a structure over `geometries` (`counts[i]` primitives each) on
    /// the device, and wait for it.
    fn build_structure(
        &self,
        ctx: &'a Context,
        ty: vk::AccelerationStructureTypeKHR,
        geometries: &[vk::AccelerationStructureGeometryKHR<'_>],
        counts: &[u32],
        flags: vk::BuildAccelerationStructureFlagsKHR,
    ) -> Result<Structure<'a>, GpuError> {
        let mut info = vk::AccelerationStructureBuildGeometryInfoKHR::default()
            .ty(ty)
            .flags(flags)
            .mode(vk::BuildAccelerationStructureModeKHR::BUILD)
            .geometries(geometries);
        let mut sizes = vk::AccelerationStructureBuildSizesInfoKHR::default();
        unsafe {
            self.loader.get_acceleration_structure_build_sizes(
                vk::AccelerationStructureBuildTypeKHR::DEVICE,
                &info,
                counts,
                &mut sizes,
            )
        };
        let s = self.create(ctx, ty, sizes.acceleration_structure_size)?;
        let align = scratch_alignment(ctx);
        let scratch = Buffer::with_usage(
            ctx,
            "acceleration structure scratch",
            vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS,
            sizes.build_scratch_size + align,
        )?;
        info = info
            .dst_acceleration_structure(s.handle)
            .scratch_data(vk::DeviceOrHostAddressKHR {
                device_address: scratch.device_address().next_multiple_of(align),
            });
        let ranges: Vec<vk::AccelerationStructureBuildRangeInfoKHR> = counts
            .iter()
            .map(|&n| vk::AccelerationStructureBuildRangeInfoKHR::default().primitive_count(n))
            .collect();
        ctx.submit_and_wait(|cmd| unsafe {
            // Uploads (host writes or staging copies) before the build reads.
            barrier(
                ctx,
                cmd,
                vk::PipelineStageFlags::HOST | vk::PipelineStageFlags::TRANSFER,
                vk::AccessFlags::HOST_WRITE | vk::AccessFlags::TRANSFER_WRITE,
            );
            self.loader
                .cmd_build_acceleration_structures(cmd, &[info], &[&ranges]);
            barrier(
                ctx,
                cmd,
                vk::PipelineStageFlags::ACCELERATION_STRUCTURE_BUILD_KHR,
                vk::AccessFlags::ACCELERATION_STRUCTURE_WRITE_KHR,
            );
        })?;
        Ok(s)
    }

    /// A copy of `s` in a buffer of its compacted size.
    fn compact(&self, ctx: &'a Context, s: &Structure<'a>) -> Result<Structure<'a>, GpuError> {
        let pool = unsafe {
            ctx.device.create_query_pool(
                &vk::QueryPoolCreateInfo::default()
                    .query_type(vk::QueryType::ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR)
                    .query_count(1),
                None,
            )
        }
        .map_err(|e| GpuError::from_vk("vkCreateQueryPool", e))?;
        let mut size = [0u64];
        let queried = ctx
            .submit_and_wait(|cmd| unsafe {
                ctx.device.cmd_reset_query_pool(cmd, pool, 0, 1);
                self.loader.cmd_write_acceleration_structures_properties(
                    cmd,
                    &[s.handle],
                    vk::QueryType::ACCELERATION_STRUCTURE_COMPACTED_SIZE_KHR,
                    pool,
                    0,
                );
            })
            .and_then(|()| {
                unsafe {
                    ctx.device.get_query_pool_results(
                        pool,
                        0,
                        &mut size,
                        vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
                    )
                }
                .map_err(|e| GpuError::from_vk("vkGetQueryPoolResults", e))
            });
        unsafe { ctx.device.destroy_query_pool(pool, None) };
        queried?;
        let c = self.create(ctx, vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL, size[0])?;
        let copy = vk::CopyAccelerationStructureInfoKHR::default()
            .src(s.handle)
            .dst(c.handle)
            .mode(vk::CopyAccelerationStructureModeKHR::COMPACT);
        ctx.submit_and_wait(|cmd| unsafe {
            self.loader.cmd_copy_acceleration_structure(cmd, &copy);
            barrier(
                ctx,
                cmd,
                vk::PipelineStageFlags::ACCELERATION_STRUCTURE_BUILD_KHR,
                vk::AccessFlags::ACCELERATION_STRUCTURE_WRITE_KHR,
            );
        })?;
        Ok(c)
    }

    fn destroy(&self, s: Structure<'a>) {
        unsafe { self.loader.destroy_acceleration_structure(s.handle, None) };
    }
}

impl Drop for Accel<'_> {
    fn drop(&mut self) {
        // The structures go before their buffers (dropped after this).
        let blas = std::mem::take(&mut self.blas).into_iter().map(|(s, _)| s);
        for s in self.tlas.take().into_iter().chain(blas) {
            self.destroy(s);
        }
    }
}

/// `minAccelerationStructureScratchOffsetAlignment`.
fn scratch_alignment(ctx: &Context) -> u64 {
    let mut accel = vk::PhysicalDeviceAccelerationStructurePropertiesKHR::default();
    let mut props = vk::PhysicalDeviceProperties2::default().push_next(&mut accel);
    unsafe {
        ctx.instance
            .get_physical_device_properties2(ctx.physical_device, &mut props)
    };
    (accel.min_acceleration_structure_scratch_offset_alignment as u64).max(1)
}

/// Make `src_access` at `src_stage` visible to later builds, copies, queries
/// and shader reads of acceleration structures.
unsafe fn barrier(
    ctx: &Context,
    cmd: vk::CommandBuffer,
    src_stage: vk::PipelineStageFlags,
    src_access: vk::AccessFlags,
) {
    let b = [vk::MemoryBarrier::default()
        .src_access_mask(src_access)
        .dst_access_mask(
            vk::AccessFlags::ACCELERATION_STRUCTURE_READ_KHR
                | vk::AccessFlags::ACCELERATION_STRUCTURE_WRITE_KHR
                | vk::AccessFlags::SHADER_READ,
        )];
    // Ray tracing shaders read them too where the pipeline is enabled (the
    // stage is invalid where it is not).
    let rt = match ctx.ray_tracing().pipeline {
        Some(_) => vk::PipelineStageFlags::RAY_TRACING_SHADER_KHR,
        None => vk::PipelineStageFlags::empty(),
    };
    unsafe {
        ctx.device.cmd_pipeline_barrier(
            cmd,
            src_stage,
            vk::PipelineStageFlags::ACCELERATION_STRUCTURE_BUILD_KHR
                | vk::PipelineStageFlags::COMPUTE_SHADER
                | rt,
            vk::DependencyFlags::empty(),
            &b,
            &[],
            &[],
        )
    };
}

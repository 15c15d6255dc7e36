//! Storage and uniform buffers through gpu-allocator.
//!
//! Buffers live in device-local memory. Where that memory is also
//! host-visible and coherent (lavapipe's single memory type, integrated
//! GPUs, resizable BAR) uploads and readbacks go through the mapping;
//! elsewhere they go through a temporary staging buffer and a copy.
//!
//! Vulkan forbids size-0 buffers, so an empty upload gets a 16-byte buffer
//! (kernels must not read it: they learn the real count from a parameter).
//! Every buffer is checked against `maxStorageBufferRange` /
//! `maxUniformBufferRange` at creation, because a descriptor cannot cover
//! more: an over-large scene fails with [`GpuError::BufferTooLarge`].

use ash::vk;
use bytemuck::Pod;
use gpu_allocator::MemoryLocation;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};

use super::GpuError;
use super::context::Context;

/// Smallest buffer created, for empty arrays (Vulkan forbids size 0).
pub const MIN_SIZE: u64 = 16;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BufferKind {
    Storage,
    Uniform,
}

impl BufferKind {
    pub fn descriptor_type(self) -> vk::DescriptorType {
        match self {
            BufferKind::Storage => vk::DescriptorType::STORAGE_BUFFER,
            BufferKind::Uniform => vk::DescriptorType::UNIFORM_BUFFER,
        }
    }
}

/// A device buffer. Borrows the context so it cannot outlive the device.
pub struct Buffer<'a> {
    ctx: &'a Context,
    pub(crate) raw: vk::Buffer,
    allocation: Option<Allocation>,
    /// Bytes the caller asked for (the Vulkan buffer may be larger).
    len: u64,
    /// Bytes of the Vulkan buffer (the descriptor range).
    size: u64,
    kind: BufferKind,
    name: String,
}

impl<'a> Buffer<'a> {
    /// An uninitialised buffer of `len` bytes (at least [`MIN_SIZE`]).
    pub fn new(ctx: &'a Context, name: &str, kind: BufferKind, len: u64) -> Result<Self, GpuError> {
        let size = len.max(MIN_SIZE).next_multiple_of(4);
        let limits = &ctx.info().limits;
        let max = match kind {
            BufferKind::Storage => limits.max_storage_buffer_range as u64,
            BufferKind::Uniform => limits.max_uniform_buffer_range as u64,
        };
        if size > max {
            return Err(GpuError::BufferTooLarge {
                name: name.to_string(),
                size,
                max,
            });
        }
        let usage = match kind {
            BufferKind::Storage => vk::BufferUsageFlags::STORAGE_BUFFER,
            BufferKind::Uniform => vk::BufferUsageFlags::UNIFORM_BUFFER,
        } | vk::BufferUsageFlags::TRANSFER_SRC
            | vk::BufferUsageFlags::TRANSFER_DST;
        // With acceleration structures on, a storage buffer may also feed an
        // acceleration structure build (the triangles' vertices).
        let usage = if ctx.acceleration_structures() && kind == BufferKind::Storage {
            usage
                | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS
                | vk::BufferUsageFlags::ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_KHR
        } else {
            usage
        };
        let (raw, allocation) = create_raw(ctx, name, size, usage, MemoryLocation::GpuOnly)?;
        Ok(Buffer {
            ctx,
            raw,
            allocation: Some(allocation),
            len,
            size,
            kind,
            name: name.to_string(),
        })
    }

    /// A buffer of `len` bytes (at least [`MIN_SIZE`]) for Vulkan's own use
    /// (acceleration structure storage, scratch, build inputs), with
    /// `usage` plus transfers; never bound as a descriptor, so not held to
    /// the binding limits. Needs [`Context::acceleration_structures`] for device
    /// addresses.
    pub fn with_usage(
        ctx: &'a Context,
        name: &str,
        usage: vk::BufferUsageFlags,
        len: u64,
    ) -> Result<Self, GpuError> {
        let size = len.max(MIN_SIZE).next_multiple_of(4);
        let usage = usage | vk::BufferUsageFlags::TRANSFER_SRC | vk::BufferUsageFlags::TRANSFER_DST;
        let (raw, allocation) = create_raw(ctx, name, size, usage, MemoryLocation::GpuOnly)?;
        Ok(Buffer {
            ctx,
            raw,
            allocation: Some(allocation),
            len,
            size,
            kind: BufferKind::Storage,
            name: name.to_string(),
        })
    }

    /// The buffer's device address (its usage must include
    /// `SHADER_DEVICE_ADDRESS`).
    pub fn device_address(&self) -> vk::DeviceAddress {
        let info = vk::BufferDeviceAddressInfo::default().buffer(self.raw);
        unsafe { self.ctx.device.get_buffer_device_address(&info) }
    }

    /// A buffer holding `data`.
    pub fn from_slice<T: Pod>(
        ctx: &'a Context,
        name: &str,
        kind: BufferKind,
        data: &[T],
    ) -> Result<Self, GpuError> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let buf = Self::new(ctx, name, kind, bytes.len() as u64)?;
        // The padding of small and empty arrays reads as zeros, not garbage.
        if bytes.len() as u64 != buf.size {
            buf.fill_zero()?;
        }
        buf.write(bytes)?;
        Ok(buf)
    }

    /// A buffer of `len` zero bytes.
    pub fn zeroed(
        ctx: &'a Context,
        name: &str,
        kind: BufferKind,
        len: u64,
    ) -> Result<Self, GpuError> {
        let buf = Self::new(ctx, name, kind, len)?;
        buf.fill_zero()?;
        Ok(buf)
    }

    /// Bytes requested at creation.
    pub fn len(&self) -> u64 {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Bytes of the Vulkan buffer (what a descriptor covers).
    pub fn size(&self) -> u64 {
        self.size
    }

    pub fn kind(&self) -> BufferKind {
        self.kind
    }

    pub fn raw(&self) -> vk::Buffer {
        self.raw
    }

    /// Zero the whole buffer on the device.
    pub fn fill_zero(&self) -> Result<(), GpuError> {
        self.ctx.submit_and_wait(|cmd| unsafe {
            self.ctx
                .device
                .cmd_fill_buffer(cmd, self.raw, 0, vk::WHOLE_SIZE, 0);
            transfer_to_compute_barrier(self.ctx, cmd);
        })
    }

    /// Overwrite the start of the buffer with `data` (at most `len` bytes).
    pub fn write<T: Pod>(&self, data: &[T]) -> Result<(), GpuError> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        if bytes.len() as u64 > self.size {
            return Err(GpuError::Invalid(format!(
                "writing {} bytes into buffer '{}' of {} bytes",
                bytes.len(),
                self.name,
                self.size
            )));
        }
        if bytes.is_empty() {
            return Ok(());
        }
        if let Some(ptr) = self.mapped_ptr() {
            // SAFETY: the mapping covers `size` >= bytes.len() bytes, memory is
            // coherent, and no command using the buffer is in flight (every
            // submission is waited for).
            unsafe { std::ptr::copy_nonoverlapping(bytes.as_ptr(), ptr, bytes.len()) };
            return Ok(());
        }
        let (staging, mut alloc) = create_raw(
            self.ctx,
            "staging upload",
            bytes.len() as u64,
            vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::CpuToGpu,
        )?;
        let result = (|| {
            let dst = alloc
                .mapped_slice_mut()
                .ok_or_else(|| GpuError::Invalid("staging memory is not mapped".into()))?;
            dst[..bytes.len()].copy_from_slice(bytes);
            self.ctx.submit_and_wait(|cmd| unsafe {
                let region = [vk::BufferCopy::default().size(bytes.len() as u64)];
                self.ctx
                    .device
                    .cmd_copy_buffer(cmd, staging, self.raw, &region);
                transfer_to_compute_barrier(self.ctx, cmd);
            })
        })();
        destroy_raw(self.ctx, staging, alloc);
        result
    }

    /// Read back the first `len` bytes as `T`s (`len` must be a multiple of
    /// `size_of::<T>()`).
    pub fn read<T: Pod>(&self) -> Result<Vec<T>, GpuError> {
        let elem = size_of::<T>() as u64;
        if elem == 0 || !self.len.is_multiple_of(elem) {
            return Err(GpuError::Invalid(format!(
                "buffer '{}' holds {} bytes, not a whole number of {}-byte elements",
                self.name, self.len, elem
            )));
        }
        let mut out = vec![T::zeroed(); (self.len / elem) as usize];
        self.read_into(bytemuck::cast_slice_mut(&mut out))?;
        Ok(out)
    }

    /// Read back `out.len()` bytes from the start of the buffer.
    pub fn read_into(&self, out: &mut [u8]) -> Result<(), GpuError> {
        let n = out.len();
        if n as u64 > self.size {
            return Err(GpuError::Invalid(format!(
                "reading {n} bytes from buffer '{}' of {} bytes",
                self.name, self.size
            )));
        }
        if n == 0 {
            return Ok(());
        }
        if let Some(ptr) = self.mapped_ptr() {
            // SAFETY: as in `write`; the queue is idle after every submission.
            unsafe { std::ptr::copy_nonoverlapping(ptr as *const u8, out.as_mut_ptr(), n) };
            return Ok(());
        }
        let (staging, alloc) = create_raw(
            self.ctx,
            "staging readback",
            n as u64,
            vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuToCpu,
        )?;
        let result = (|| {
            self.ctx.submit_and_wait(|cmd| unsafe {
                let barrier = [vk::MemoryBarrier::default()
                    .src_access_mask(
                        vk::AccessFlags::SHADER_WRITE | vk::AccessFlags::TRANSFER_WRITE,
                    )
                    .dst_access_mask(vk::AccessFlags::TRANSFER_READ)];
                self.ctx.device.cmd_pipeline_barrier(
                    cmd,
                    vk::PipelineStageFlags::COMPUTE_SHADER | vk::PipelineStageFlags::TRANSFER,
                    vk::PipelineStageFlags::TRANSFER,
                    vk::DependencyFlags::empty(),
                    &barrier,
                    &[],
                    &[],
                );
                let region = [vk::BufferCopy::default().size(n as u64)];
                self.ctx
                    .device
                    .cmd_copy_buffer(cmd, self.raw, staging, &region);
                let host = [vk::MemoryBarrier::default()
                    .src_access_mask(vk::AccessFlags::TRANSFER_WRITE)
                    .dst_access_mask(vk::AccessFlags::HOST_READ)];
                self.ctx.device.cmd_pipeline_barrier(
                    cmd,
                    vk::PipelineStageFlags::TRANSFER,
                    vk::PipelineStageFlags::HOST,
                    vk::DependencyFlags::empty(),
                    &host,
                    &[],
                    &[],
                );
            })?;
            let src = alloc
                .mapped_slice()
                .ok_or_else(|| GpuError::Invalid("readback memory is not mapped".into()))?;
            out.copy_from_slice(&src[..n]);
            Ok(())
        })();
        destroy_raw(self.ctx, staging, alloc);
        result
    }

    /// The host pointer when the buffer's memory is mapped and coherent.
    fn mapped_ptr(&self) -> Option<*mut u8> {
        if self.ctx.force_staging() {
            return None;
        }
        let a = self.allocation.as_ref()?;
        let coherent =
            vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT;
        if !a.memory_properties().contains(coherent) {
            return None;
        }
        a.mapped_ptr().map(|p| p.as_ptr() as *mut u8)
    }
}

impl Drop for Buffer<'_> {
    fn drop(&mut self) {
        if let Some(a) = self.allocation.take() {
            destroy_raw(self.ctx, self.raw, a);
        }
    }
}

/// Make transfer writes visible to compute shaders and later transfers.
fn transfer_to_compute_barrier(ctx: &Context, cmd: vk::CommandBuffer) {
    let barrier = [vk::MemoryBarrier::default()
        .src_access_mask(vk::AccessFlags::TRANSFER_WRITE)
        .dst_access_mask(
            vk::AccessFlags::SHADER_READ
                | vk::AccessFlags::SHADER_WRITE
                | vk::AccessFlags::UNIFORM_READ
                | vk::AccessFlags::TRANSFER_READ
                | vk::AccessFlags::TRANSFER_WRITE,
        )];
    unsafe {
        ctx.device.cmd_pipeline_barrier(
            cmd,
            vk::PipelineStageFlags::TRANSFER,
            vk::PipelineStageFlags::COMPUTE_SHADER | vk::PipelineStageFlags::TRANSFER,
            vk::DependencyFlags::empty(),
            &barrier,
            &[],
            &[],
        )
    };
}

fn create_raw(
    ctx: &Context,
    name: &str,
    size: u64,
    usage: vk::BufferUsageFlags,
    location: MemoryLocation,
) -> Result<(vk::Buffer, Allocation), GpuError> {
    let info = vk::BufferCreateInfo::default()
        .size(size)
        .usage(usage)
        .sharing_mode(vk::SharingMode::EXCLUSIVE);
    let raw = unsafe { ctx.device.create_buffer(&info, None) }
        .map_err(|e| GpuError::from_vk("vkCreateBuffer", e))?;
    let requirements = unsafe { ctx.device.get_buffer_memory_requirements(raw) };
    let allocation = ctx.allocator().allocate(&AllocationCreateDesc {
        name,
        requirements,
        location,
        linear: true,
        allocation_scheme: AllocationScheme::GpuAllocatorManaged,
    });
    let allocation = match allocation {
        Ok(a) => a,
        Err(e) => {
            unsafe { ctx.device.destroy_buffer(raw, None) };
            return Err(GpuError::Allocation {
                what: format!("buffer '{name}' ({size} bytes)"),
                source: e,
            });
        }
    };
    if let Err(e) = unsafe {
        ctx.device
            .bind_buffer_memory(raw, allocation.memory(), allocation.offset())
    } {
        destroy_raw(ctx, raw, allocation);
        return Err(GpuError::from_vk("vkBindBufferMemory", e));
    }
    Ok((raw, allocation))
}

fn destroy_raw(ctx: &Context, raw: vk::Buffer, allocation: Allocation) {
    unsafe { ctx.device.destroy_buffer(raw, None) };
    // A free can only fail on allocator bookkeeping bugs; nothing to do then.
    let _ = ctx.allocator().free(allocation);
}

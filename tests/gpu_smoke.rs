//! The Vulkan plumbing end to end on the default device (lavapipe in CI),
//! under the validation layer: context, buffers, kernels, error paths.

mod common;

use ash::vk;
use glint::gpu::{
    Buffer, BufferKind, Context, ContextDesc, GpuError, Kernel, Validation, groups, shaders,
};

#[test]
fn smoke_kernel_adds_arrays() {
    smoke(common::context());
}

#[test]
fn smoke_kernel_through_staging_buffers() {
    smoke(common::staging_context());
}

fn smoke(ctx: common::ValidatedContext) {
    // Not a multiple of the local size (64), to exercise the bounds check.
    let n = 1000u32;
    let a: Vec<f32> = (0..n).map(|i| i as f32).collect();
    let b: Vec<f32> = (0..n).map(|i| 0.5 * i as f32 + 1.0).collect();
    let mut c = vec![-1.0f32; n as usize];
    let mut count = [7u32];
    let push: [u32; 2] = [n, 2.0f32.to_bits()];
    ctx.run_kernel(
        "tests/smoke",
        &[bytemuck::cast_slice(&a), bytemuck::cast_slice(&b)],
        &mut [
            bytemuck::cast_slice_mut(&mut c),
            bytemuck::cast_slice_mut(&mut count),
        ],
        bytemuck::bytes_of(&push),
        [groups(n, 64), 1, 1],
    )
    .unwrap();
    for i in 0..n as usize {
        assert_eq!(c[i], a[i] + b[i] * 2.0, "element {i}");
    }
    // Outputs start from the caller's contents: 7 + one per invocation.
    assert_eq!(count[0], 7 + n);
}

#[test]
fn kernel_reuse_and_zero_length_buffers() {
    reuse(common::context());
}

#[test]
fn kernel_reuse_through_staging_buffers() {
    reuse(common::staging_context());
}

fn reuse(ctx: common::ValidatedContext) {
    let empty: [f32; 0] = [];
    // Empty arrays still get a (small) buffer: Vulkan forbids size 0.
    let a = Buffer::from_slice(&ctx, "a", BufferKind::Storage, &empty).unwrap();
    let b = Buffer::from_slice(&ctx, "b", BufferKind::Storage, &empty).unwrap();
    let c = Buffer::zeroed(&ctx, "c", BufferKind::Storage, 0).unwrap();
    let count = Buffer::zeroed(&ctx, "count", BufferKind::Storage, 4).unwrap();
    assert!(a.is_empty() && a.size() > 0);
    let mut k = Kernel::new(&ctx, "tests/smoke", 4, 8).unwrap();
    k.bind(&[&a, &b, &c, &count]).unwrap();
    // n = 0: every invocation returns before touching memory.
    for _ in 0..3 {
        k.dispatch(bytemuck::bytes_of(&[0u32, 0]), [1, 1, 1])
            .unwrap();
    }
    assert_eq!(count.read::<u32>().unwrap(), vec![0]);
    assert_eq!(c.read::<f32>().unwrap(), Vec::<f32>::new());

    // Rebind to real data and dispatch again with the same pipeline.
    let a = Buffer::from_slice(&ctx, "a", BufferKind::Storage, &[1.0f32, 2.0]).unwrap();
    let b = Buffer::from_slice(&ctx, "b", BufferKind::Storage, &[3.0f32, 4.0]).unwrap();
    let c = Buffer::zeroed(&ctx, "c", BufferKind::Storage, 8).unwrap();
    k.bind(&[&a, &b, &c, &count]).unwrap();
    k.dispatch(bytemuck::bytes_of(&[2u32, 1.0f32.to_bits()]), [1, 1, 1])
        .unwrap();
    k.dispatch(bytemuck::bytes_of(&[2u32, 1.0f32.to_bits()]), [1, 1, 1])
        .unwrap();
    assert_eq!(c.read::<f32>().unwrap(), vec![4.0, 6.0]);
    assert_eq!(count.read::<u32>().unwrap(), vec![4]);
    drop(k);
}

#[test]
fn misuse_is_a_clear_error_not_a_crash() {
    let ctx = common::context();
    assert!(matches!(
        Kernel::new(&ctx, "no/such/kernel", 1, 0),
        Err(GpuError::UnknownKernel(_))
    ));
    let max = ctx.info().limits.max_storage_buffer_range as u64;
    let err = Buffer::new(&ctx, "huge", BufferKind::Storage, max + 4)
        .err()
        .unwrap();
    assert!(matches!(err, GpuError::BufferTooLarge { .. }), "{err}");
    assert!(err.to_string().contains("huge"));

    let buf = Buffer::zeroed(&ctx, "x", BufferKind::Storage, 16).unwrap();
    let mut k = Kernel::new(&ctx, "tests/smoke", 4, 8).unwrap();
    assert!(matches!(
        k.dispatch(&[0; 8], [1, 1, 1]),
        Err(GpuError::Invalid(_))
    ));
    assert!(matches!(k.bind(&[&buf]), Err(GpuError::Invalid(_))));
    k.bind(&[&buf, &buf, &buf, &buf]).unwrap();
    assert!(matches!(
        k.dispatch(&[0; 4], [1, 1, 1]),
        Err(GpuError::Invalid(_))
    ));
    assert!(matches!(
        k.dispatch(&[0; 8], [u32::MAX, 1, 1]),
        Err(GpuError::Invalid(_))
    ));
    let uniform = Buffer::zeroed(&ctx, "u", BufferKind::Uniform, 16).unwrap();
    assert!(matches!(
        k.bind(&[&buf, &buf, &uniform, &buf]),
        Err(GpuError::Invalid(_))
    ));
    assert!(matches!(buf.write(&[0u8; 17]), Err(GpuError::Invalid(_))));
}

#[test]
fn device_override_by_name() {
    let ctx = common::context();
    let name = ctx.info().name.clone();
    assert!(!name.is_empty());
    assert!(!ctx.info().driver.is_empty());
    drop(ctx);
    // A substring of the default device's name, in another case, finds it.
    let part = name[..name.len().min(4)].to_uppercase();
    let again = Context::new(&ContextDesc {
        device: Some(&part),
        validation: Validation::Off,
        loader: None,
    })
    .unwrap();
    assert_eq!(again.info().name, name);
    drop(again);
    match Context::new(&ContextDesc {
        device: Some("no such device 1234"),
        validation: Validation::Off,
        loader: None,
    }) {
        Err(e @ GpuError::DeviceNotFound { .. }) => {
            let msg = e.to_string();
            assert!(
                msg.contains("no such device 1234") && msg.contains(&name),
                "{msg}"
            );
        }
        Err(e) => panic!("wrong error: {e}"),
        Ok(_) => panic!("found a device that does not exist"),
    }
}

/// The test of the test: the validation plumbing must actually see errors.
/// A buffer with no usage flags breaks VUID-VkBufferCreateInfo-usage-requiredbitmask.
#[test]
fn validation_log_catches_a_deliberate_error() {
    let ctx = Context::new(&ContextDesc {
        device: None,
        validation: common::validation(),
        loader: None,
    })
    .unwrap();
    let Some(log) = ctx.validation_log() else {
        // Without the layer (and without GLINT_VALIDATION, which requires it)
        // there is nothing to check.
        eprintln!("VK_LAYER_KHRONOS_validation not installed: skipping");
        return;
    };
    let info = vk::BufferCreateInfo::default()
        .size(16)
        .usage(vk::BufferUsageFlags::empty());
    unsafe {
        if let Ok(b) = ctx.device().create_buffer(&info, None) {
            ctx.device().destroy_buffer(b, None);
        }
    }
    drop(ctx);
    assert!(
        log.errors() >= 1,
        "no validation error seen: {:?}",
        log.messages()
    );
    assert!(
        log.messages().iter().any(|m| m.contains("usage")),
        "{:?}",
        log.messages()
    );
}

#[test]
fn kernels_are_compiled_and_named_by_path() {
    let names: Vec<&str> = shaders::names().collect();
    assert!(names.contains(&"tests/smoke"), "{names:?}");
    let words = shaders::spirv("tests/smoke").unwrap();
    assert_eq!(words[0], 0x0723_0203, "SPIR-V magic");
    assert!(shaders::spirv("smoke").is_none());
}

/// Leaks count too: the layer reports objects still alive at
/// vkDestroyDevice, after the context is gone, and the log must see that.
#[test]
fn validation_log_catches_a_leak() {
    let ctx = Context::new(&ContextDesc {
        device: None,
        validation: common::validation(),
        loader: None,
    })
    .unwrap();
    let Some(log) = ctx.validation_log() else {
        eprintln!("VK_LAYER_KHRONOS_validation not installed: skipping");
        return;
    };
    let info = vk::BufferCreateInfo::default()
        .size(16)
        .usage(vk::BufferUsageFlags::STORAGE_BUFFER);
    // Deliberately never destroyed.
    let _leaked = unsafe { ctx.device().create_buffer(&info, None) }.unwrap();
    assert_eq!(log.errors(), 0, "{:?}", log.messages());
    drop(ctx);
    assert!(log.errors() >= 1, "leak not reported: {:?}", log.messages());
}

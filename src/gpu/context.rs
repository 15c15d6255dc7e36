//! The Vulkan context: instance, physical device choice, logical device with
//! one compute queue, memory allocator and command pool.
//!
//! Headless: no surface extensions. The loader (`libvulkan.so.1`) is opened
//! at run time, so a machine without one gets [`GpuError::Loader`], not a
//! link error or a panic.
//!
//! Validation: with [`Validation::IfAvailable`] or [`Validation::Required`]
//! the `VK_LAYER_KHRONOS_validation` layer is enabled with a
//! `VK_EXT_debug_utils` messenger that counts and keeps every warning and
//! error ([`Context::validation_log`]). The messenger is also chained into
//! `VkInstanceCreateInfo`, so messages from instance creation and
//! destruction are counted too, and the log outlives the context: the layer
//! reports leaked objects at `vkDestroyDevice`, which a test can only see
//! after dropping the context.

use std::borrow::Cow;
use std::ffi::{CStr, c_void};
use std::mem::ManuallyDrop;
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Instant;

use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};

use super::GpuError;

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// Whether to run under the Khronos validation layer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Validation {
    Off,
    /// Enable it when it is installed (tests).
    IfAvailable,
    /// Fail with [`GpuError::ValidationUnavailable`] when it is not installed.
    Required,
}

impl Validation {
    /// `GLINT_VALIDATION=1` (or any value but `0`/empty) asks for the layer
    /// where it is installed (scripts/test.sh sets it for the whole suite).
    pub fn from_env() -> Self {
        match std::env::var("GLINT_VALIDATION") {
            Ok(v) if !v.is_empty() && v != "0" => Validation::IfAvailable,
            _ => Validation::Off,
        }
    }
}

/// How to create a [`Context`].
#[derive(Clone, Debug)]
pub struct ContextDesc<'a> {
    /// Case-insensitive substring of the wanted device's name; `None` picks
    /// the best device (discrete, integrated, virtual, then CPU).
    pub device: Option<&'a str>,
    pub validation: Validation,
    /// The Vulkan loader library to open; `None`: the system's
    /// `libvulkan.so.1` (what everyone but tests of the error path wants).
    pub loader: Option<&'a std::path::Path>,
}

impl Default for ContextDesc<'_> {
    fn default() -> Self {
        ContextDesc {
            device: None,
            validation: Validation::from_env(),
            loader: None,
        }
    }
}

/// Warnings and errors the validation layer reported. Shared with the
/// debug messenger callback, hence atomics and a mutex.
#[derive(Debug, Default)]
pub struct ValidationLog {
    errors: AtomicU32,
    warnings: AtomicU32,
    messages: Mutex<Vec<String>>,
    /// Print each message to stderr as it arrives.
    echo: bool,
}

impl ValidationLog {
    pub fn errors(&self) -> u32 {
        self.errors.load(Ordering::SeqCst)
    }
    pub fn warnings(&self) -> u32 {
        self.warnings.load(Ordering::SeqCst)
    }
    /// Every warning and error, in arrival order, prefixed with its severity.
    pub fn messages(&self) -> Vec<String> {
        self.messages
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .clone()
    }
    fn record(&self, error: bool, message: String) {
        if error {
            self.errors.fetch_add(1, Ordering::SeqCst);
        } else {
            self.warnings.fetch_add(1, Ordering::SeqCst);
        }
        let line = format!("{}: {message}", if error { "error" } else { "warning" });
        if self.echo {
            eprintln!("vulkan validation {line}");
        }
        self.messages
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .push(line);
    }
}

/// Called by the validation layer on any thread; must not unwind.
unsafe extern "system" fn debug_callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    if user.is_null() || data.is_null() {
        return vk::FALSE;
    }
    // SAFETY: `user` is `Arc::as_ptr` of the log, which the context keeps
    // alive until after the instance (and with it the messenger) is gone;
    // `data` is valid for the duration of the call per the Vulkan spec.
    let (log, data) = unsafe { (&*(user as *const ValidationLog), &*data) };
    let message = if data.p_message.is_null() {
        Cow::Borrowed("(no message)")
    } else {
        // SAFETY: a non-null p_message is a NUL-terminated string.
        unsafe { CStr::from_ptr(data.p_message) }.to_string_lossy()
    };
    let error = severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR);
    log.record(error, message.into_owned());
    vk::FALSE
}

/// Facts about the chosen device that callers report or check against.
#[derive(Clone, Debug)]
pub struct DeviceInfo {
    /// `VkPhysicalDeviceProperties::deviceName`.
    pub name: String,
    /// `VkPhysicalDeviceDriverProperties` driverName and driverInfo.
    pub driver: String,
    pub device_type: vk::PhysicalDeviceType,
    pub api_version: u32,
    pub limits: vk::PhysicalDeviceLimits,
    /// Nanoseconds per timestamp tick.
    pub timestamp_period: f32,
    /// Valid bits of timestamps on the compute queue; 0 = no timestamps.
    pub timestamp_valid_bits: u32,
    /// True when every buffer memory the allocator hands out is host-visible
    /// and coherent (lavapipe, integrated GPUs): uploads skip staging.
    pub unified_memory: bool,
}

impl DeviceInfo {
    pub fn timestamps(&self) -> bool {
        self.timestamp_valid_bits > 0
    }
}

/// Wall-clock cost of creating the context, for `--stats` setup time.
#[derive(Clone, Copy, Debug, Default)]
pub struct ContextTimings {
    pub loader_seconds: f64,
    pub instance_seconds: f64,
    pub device_seconds: f64,
}

pub struct Context {
    // Field order does not matter for destruction: `Drop` below tears down
    // explicitly (allocator before device, device before instance).
    pub(crate) entry: ash::Entry,
    pub(crate) instance: ash::Instance,
    debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    pub(crate) physical_device: vk::PhysicalDevice,
    pub(crate) device: ash::Device,
    pub(crate) queue: vk::Queue,
    pub(crate) queue_family: u32,
    pub(crate) command_pool: vk::CommandPool,
    allocator: ManuallyDrop<Mutex<Allocator>>,
    info: DeviceInfo,
    validation_log: Option<Arc<ValidationLog>>,
    timings: ContextTimings,
    force_staging: bool,
    /// What of Vulkan ray tracing is enabled ([`Context::new_ray_tracing`]).
    ray_tracing: RayTracing,
    /// `VK_KHR_ray_tracing_pipeline`'s functions, where it is enabled.
    rt_pipeline_fn: Option<ash::khr::ray_tracing_pipeline::Device>,
    /// Every pipeline this context built, by what defines it
    /// ([`super::kernel::PipelineKey`]), kept until the context goes: a
    /// kernel made again (the next render of a sweep, a converge series,
    /// `bench --repeat`) reuses it instead of paying lavapipe's 3.3 s of
    /// pipeline set-up per render of the path tracer.
    pub(crate) pipelines: Mutex<super::kernel::Pipelines>,
}

fn vk_err(what: &'static str) -> impl FnOnce(vk::Result) -> GpuError {
    move |result| GpuError::from_vk(what, result)
}

fn cstr_array(bytes: Result<&CStr, std::ffi::FromBytesUntilNulError>) -> String {
    bytes
        .map(|c| c.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// Lower is better: discrete, integrated, virtual, CPU, other.
fn type_rank(t: vk::PhysicalDeviceType) -> u32 {
    match t {
        vk::PhysicalDeviceType::DISCRETE_GPU => 0,
        vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
        vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
        vk::PhysicalDeviceType::CPU => 3,
        _ => 4,
    }
}

/// What of Vulkan ray tracing a context enabled: acceleration structures
/// and buffer device addresses come with ray queries, a ray tracing
/// pipeline, or both (none of it for [`Context::new`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct RayTracing {
    /// `VK_KHR_ray_query`.
    pub query: bool,
    /// `VK_KHR_ray_tracing_pipeline`, with the device's shader binding
    /// table sizes and alignments.
    pub pipeline: Option<RtPipelineProperties>,
}

/// `VkPhysicalDeviceRayTracingPipelinePropertiesKHR`, what glint needs of it.
#[derive(Clone, Copy, Debug)]
pub struct RtPipelineProperties {
    pub shader_group_handle_size: u32,
    pub shader_group_handle_alignment: u32,
    pub shader_group_base_alignment: u32,
    pub max_ray_recursion_depth: u32,
    pub max_ray_dispatch_invocation_count: u32,
}

impl RayTracing {
    /// `VK_KHR_acceleration_structure` (and buffer device addresses): with
    /// either API.
    pub fn acceleration_structures(&self) -> bool {
        self.query || self.pipeline.is_some()
    }
}

/// What [`Context::create`] enables of ray tracing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum RayTracingWant {
    None,
    /// Everything the device has of queries and pipelines; at least one.
    Any,
    /// Ray queries, required.
    Query,
}

struct Candidate {
    pd: vk::PhysicalDevice,
    name: String,
    device_type: vk::PhysicalDeviceType,
    props: vk::PhysicalDeviceProperties,
    /// (family index, timestamp valid bits) of the best compute family.
    queue: Option<(u32, u32)>,
}

impl Context {
    /// Create a context: load the Vulkan loader, create the instance, pick a
    /// device, create the logical device, allocator and command pool.
    pub fn new(desc: &ContextDesc<'_>) -> Result<Context, GpuError> {
        Self::create(desc, RayTracingWant::None)
    }

    /// [`Context::new`] with `VK_KHR_acceleration_structure` (and
    /// `VK_KHR_deferred_host_operations`, which it requires), buffer device
    /// addresses, and whichever of `VK_KHR_ray_query` and
    /// `VK_KHR_ray_tracing_pipeline` the device has, for `--traversal
    /// hardware` ([`Context::ray_tracing`] says which);
    /// [`GpuError::NoRayQuery`] when it lacks acceleration structures or
    /// both. Only these constructors enable them: the software traversal
    /// runs on devices without.
    pub fn new_ray_tracing(desc: &ContextDesc<'_>) -> Result<Context, GpuError> {
        Self::create(desc, RayTracingWant::Any)
    }

    /// [`Context::new_ray_tracing`], failing unless the device has ray
    /// queries.
    pub fn new_ray_query(desc: &ContextDesc<'_>) -> Result<Context, GpuError> {
        Self::create(desc, RayTracingWant::Query)
    }

    fn create(desc: &ContextDesc<'_>, want: RayTracingWant) -> Result<Context, GpuError> {
        let t0 = Instant::now();
        // SAFETY: loading libvulkan runs its initialisers; this is the
        // documented way to use ash without linking the loader.
        let entry = match desc.loader {
            None => unsafe { ash::Entry::load() },
            Some(path) => unsafe { ash::Entry::load_from(path) },
        }
        .map_err(|e| GpuError::Loader(e.to_string()))?;
        let loader_seconds = t0.elapsed().as_secs_f64();

        let t1 = Instant::now();
        let (instance, mut guard, log) = create_instance(&entry, desc.validation)?;
        let instance_seconds = t1.elapsed().as_secs_f64();

        let t2 = Instant::now();
        let candidate = pick_device(&instance, desc.device)?;
        let (queue_family, timestamp_valid_bits) = candidate.queue.expect("filtered");
        let pd = candidate.pd;

        let driver = driver_name(&instance, pd);

        let (device, ray_tracing) =
            create_device(&instance, pd, queue_family, want, &candidate.name)?;
        let queue = unsafe { device.get_device_queue(queue_family, 0) };

        let (command_pool, allocator) = command_pool_and_allocator(
            &instance,
            &device,
            pd,
            queue_family,
            ray_tracing.acceleration_structures(),
        )?;
        // The pipeline's entry points, loaded once for every pipeline,
        // shader binding table and launch.
        let rt_pipeline_fn = ray_tracing
            .pipeline
            .map(|_| ash::khr::ray_tracing_pipeline::Device::new(&instance, &device));

        let unified_memory = unified_memory(&instance, pd);

        let info = DeviceInfo {
            name: candidate.name,
            driver,
            device_type: candidate.device_type,
            api_version: candidate.props.api_version,
            limits: candidate.props.limits,
            timestamp_period: candidate.props.limits.timestamp_period,
            timestamp_valid_bits,
            unified_memory,
        };
        let device_seconds = t2.elapsed().as_secs_f64();

        let debug = guard.debug.take();
        guard.instance = None;
        Ok(Context {
            entry,
            instance,
            debug,
            physical_device: pd,
            device,
            queue,
            queue_family,
            command_pool,
            allocator: ManuallyDrop::new(Mutex::new(allocator)),
            info,
            validation_log: log,
            timings: ContextTimings {
                loader_seconds,
                instance_seconds,
                device_seconds,
            },
            force_staging: false,
            ray_tracing,
            rt_pipeline_fn,
            pipelines: Mutex::new(Default::default()),
        })
    }

    /// Whether acceleration structures (and buffer device addresses) are
    /// enabled.
    pub fn acceleration_structures(&self) -> bool {
        self.ray_tracing.acceleration_structures()
    }

    /// Whether ray queries are enabled.
    pub fn ray_query(&self) -> bool {
        self.ray_tracing.query
    }

    /// What of ray tracing is enabled.
    pub fn ray_tracing(&self) -> RayTracing {
        self.ray_tracing
    }

    /// The ray tracing pipeline's functions and the device's properties
    /// for it, or the error where the pipeline is not enabled.
    pub(crate) fn rt_pipeline(
        &self,
    ) -> Result<
        (
            &ash::khr::ray_tracing_pipeline::Device,
            RtPipelineProperties,
        ),
        GpuError,
    > {
        match (&self.rt_pipeline_fn, self.ray_tracing.pipeline) {
            (Some(f), Some(p)) => Ok((f, p)),
            _ => Err(GpuError::Invalid(
                "a ray tracing pipeline needs a context with VK_KHR_ray_tracing_pipeline enabled"
                    .into(),
            )),
        }
    }

    pub fn info(&self) -> &DeviceInfo {
        &self.info
    }

    pub fn timings(&self) -> ContextTimings {
        self.timings
    }

    /// Upload and read back through staging buffers and copies even where
    /// device memory is host-visible: runs a discrete GPU's path on
    /// lavapipe, so tests cover it on machines without one.
    pub fn set_force_staging(&mut self, on: bool) {
        self.force_staging = on;
    }

    pub fn force_staging(&self) -> bool {
        self.force_staging
    }

    /// The validation log when the layer is enabled. Keep the `Arc` past the
    /// context's drop to see messages from device and instance destruction.
    pub fn validation_log(&self) -> Option<Arc<ValidationLog>> {
        self.validation_log.clone()
    }

    pub fn device(&self) -> &ash::Device {
        &self.device
    }

    pub fn entry(&self) -> &ash::Entry {
        &self.entry
    }

    pub fn instance(&self) -> &ash::Instance {
        &self.instance
    }

    pub fn physical_device(&self) -> vk::PhysicalDevice {
        self.physical_device
    }

    pub fn queue(&self) -> vk::Queue {
        self.queue
    }

    pub fn queue_family(&self) -> u32 {
        self.queue_family
    }

    pub(crate) fn allocator(&self) -> MutexGuard<'_, Allocator> {
        self.allocator.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Record commands with `record`, submit them to the compute queue and
    /// wait for completion.
    pub fn submit_and_wait(&self, record: impl FnOnce(vk::CommandBuffer)) -> Result<(), GpuError> {
        let alloc_info = vk::CommandBufferAllocateInfo::default()
            .command_pool(self.command_pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        let cmd = unsafe { self.device.allocate_command_buffers(&alloc_info) }
            .map_err(vk_err("vkAllocateCommandBuffers"))?[0];
        let result = (|| {
            let begin = vk::CommandBufferBeginInfo::default()
                .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
            unsafe { self.device.begin_command_buffer(cmd, &begin) }
                .map_err(vk_err("vkBeginCommandBuffer"))?;
            record(cmd);
            unsafe { self.device.end_command_buffer(cmd) }.map_err(vk_err("vkEndCommandBuffer"))?;
            let fence = unsafe {
                self.device
                    .create_fence(&vk::FenceCreateInfo::default(), None)
            }
            .map_err(vk_err("vkCreateFence"))?;
            let cmds = [cmd];
            let submit = [vk::SubmitInfo::default().command_buffers(&cmds)];
            let waited = unsafe { self.device.queue_submit(self.queue, &submit, fence) }
                .map_err(vk_err("vkQueueSubmit"))
                .and_then(|()| {
                    unsafe { self.device.wait_for_fences(&[fence], true, u64::MAX) }
                        .map_err(vk_err("vkWaitForFences"))
                });
            unsafe { self.device.destroy_fence(fence, None) };
            waited
        })();
        unsafe { self.device.free_command_buffers(self.command_pool, &[cmd]) };
        result
    }
}

/// The device extensions every hardware traversal needs.
const ACCEL_EXTENSIONS: [&CStr; 2] = [
    ash::khr::acceleration_structure::NAME,
    ash::khr::deferred_host_operations::NAME,
];

/// What of ray tracing `pd` has, for [`Context::new_ray_tracing`] (`want`
/// Any) or [`Context::new_ray_query`] (Query): acceleration structures and
/// buffer device addresses always, and ray queries, a ray tracing pipeline
/// or (Any) either; [`GpuError::NoRayQuery`] names what is missing.
fn check_ray_tracing(
    instance: &ash::Instance,
    pd: vk::PhysicalDevice,
    name: &str,
    have12: &vk::PhysicalDeviceVulkan12Features<'_>,
    want: RayTracingWant,
) -> Result<RayTracing, GpuError> {
    let exts = unsafe { instance.enumerate_device_extension_properties(pd) }
        .map_err(vk_err("vkEnumerateDeviceExtensionProperties"))?;
    let has = |want: &CStr| exts.iter().any(|e| e.extension_name_as_c_str() == Ok(want));
    let mut missing: Vec<String> = ACCEL_EXTENSIONS
        .iter()
        .filter(|&&e| !has(e))
        .map(|n| n.to_string_lossy().into_owned())
        .collect();
    let mut accel = vk::PhysicalDeviceAccelerationStructureFeaturesKHR::default();
    let mut rq = vk::PhysicalDeviceRayQueryFeaturesKHR::default();
    let mut rtp = vk::PhysicalDeviceRayTracingPipelineFeaturesKHR::default();
    let mut f = vk::PhysicalDeviceFeatures2::default()
        .push_next(&mut accel)
        .push_next(&mut rq)
        .push_next(&mut rtp);
    unsafe { instance.get_physical_device_features2(pd, &mut f) };
    if missing.is_empty() && accel.acceleration_structure != vk::TRUE {
        missing.push("accelerationStructure".into());
    }
    if have12.buffer_device_address != vk::TRUE {
        missing.push("bufferDeviceAddress".into());
    }
    let query = has(ash::khr::ray_query::NAME) && rq.ray_query == vk::TRUE;
    let pipeline = has(ash::khr::ray_tracing_pipeline::NAME)
        && rtp.ray_tracing_pipeline == vk::TRUE
        && want != RayTracingWant::Query;
    if !query && (want == RayTracingWant::Query || !pipeline) {
        missing.push(match want {
            RayTracingWant::Query => "VK_KHR_ray_query".into(),
            _ => "VK_KHR_ray_query or VK_KHR_ray_tracing_pipeline".into(),
        });
    }
    if !missing.is_empty() {
        return Err(GpuError::NoRayQuery {
            device: name.to_string(),
            missing,
        });
    }
    let pipeline = pipeline.then(|| {
        let mut p = vk::PhysicalDeviceRayTracingPipelinePropertiesKHR::default();
        let mut props = vk::PhysicalDeviceProperties2::default().push_next(&mut p);
        unsafe { instance.get_physical_device_properties2(pd, &mut props) };
        RtPipelineProperties {
            shader_group_handle_size: p.shader_group_handle_size,
            shader_group_handle_alignment: p.shader_group_handle_alignment,
            shader_group_base_alignment: p.shader_group_base_alignment,
            max_ray_recursion_depth: p.max_ray_recursion_depth,
            max_ray_dispatch_invocation_count: p.max_ray_dispatch_invocation_count,
        }
    });
    Ok(RayTracing { query, pipeline })
}

/// Destroys the instance (and messenger) when device setup fails part way.
/// The instance, with the validation layer and its messenger where
/// `validation` asks for them (the log the messenger writes to), and the
/// guard that destroys both on a later failure.
fn create_instance(
    entry: &ash::Entry,
    validation: Validation,
) -> Result<(ash::Instance, InstanceGuard, Option<Arc<ValidationLog>>), GpuError> {
    let layers = unsafe { entry.enumerate_instance_layer_properties() }
        .map_err(vk_err("vkEnumerateInstanceLayerProperties"))?;
    let have_validation = layers
        .iter()
        .any(|l| l.layer_name_as_c_str() == Ok(VALIDATION_LAYER));
    let validate = match validation {
        Validation::Off => false,
        Validation::IfAvailable => have_validation,
        Validation::Required if have_validation => true,
        Validation::Required => return Err(GpuError::ValidationUnavailable),
    };

    let extensions = unsafe { entry.enumerate_instance_extension_properties(None) }
        .map_err(vk_err("vkEnumerateInstanceExtensionProperties"))?;
    let has_ext = |name: &CStr| {
        extensions
            .iter()
            .any(|e| e.extension_name_as_c_str() == Ok(name))
    };
    let mut ext_names: Vec<*const std::ffi::c_char> = Vec::new();
    let mut flags = vk::InstanceCreateFlags::empty();
    // Lets the loader list portability drivers (MoltenVK) as well.
    if has_ext(ash::khr::portability_enumeration::NAME) {
        ext_names.push(ash::khr::portability_enumeration::NAME.as_ptr());
        flags |= vk::InstanceCreateFlags::ENUMERATE_PORTABILITY_KHR;
    }
    let layer_names: Vec<*const std::ffi::c_char> = if validate {
        // The validation layer implements VK_EXT_debug_utils itself.
        ext_names.push(ash::ext::debug_utils::NAME.as_ptr());
        vec![VALIDATION_LAYER.as_ptr()]
    } else {
        Vec::new()
    };

    let log = validate.then(|| {
        Arc::new(ValidationLog {
            echo: true,
            ..Default::default()
        })
    });
    let mut messenger_info = vk::DebugUtilsMessengerCreateInfoEXT::default()
        .message_severity(
            vk::DebugUtilsMessageSeverityFlagsEXT::WARNING
                | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR,
        )
        .message_type(
            vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
        )
        .pfn_user_callback(Some(debug_callback));
    if let Some(log) = &log {
        messenger_info = messenger_info.user_data(Arc::as_ptr(log) as *mut c_void);
    }

    let app_name = c"glint";
    let app = vk::ApplicationInfo::default()
        .application_name(app_name)
        .application_version(1)
        .engine_name(app_name)
        .engine_version(1)
        .api_version(vk::API_VERSION_1_2);
    let mut instance_info = vk::InstanceCreateInfo::default()
        .application_info(&app)
        .enabled_layer_names(&layer_names)
        .enabled_extension_names(&ext_names)
        .flags(flags);
    if validate {
        instance_info = instance_info.push_next(&mut messenger_info);
    }
    let instance = match unsafe { entry.create_instance(&instance_info, None) } {
        Ok(i) => i,
        Err(vk::Result::ERROR_INCOMPATIBLE_DRIVER) => return Err(GpuError::NoDriver),
        Err(e) => return Err(GpuError::from_vk("vkCreateInstance", e)),
    };
    // From here on, failures must destroy what exists: the guard does
    // it, and is defused once the context owns everything.
    let mut guard = InstanceGuard {
        instance: Some(instance.clone()),
        debug: None,
    };
    if validate {
        let du = ash::ext::debug_utils::Instance::new(entry, &instance);
        let messenger = unsafe { du.create_debug_utils_messenger(&messenger_info, None) }
            .map_err(vk_err("vkCreateDebugUtilsMessengerEXT"))?;
        guard.debug = Some((du, messenger));
    }
    Ok((instance, guard, log))
}

/// The command pool on `queue_family` and the memory allocator (with
/// buffer device addresses for acceleration structures); on failure, what exists is
/// destroyed, the device included.
fn command_pool_and_allocator(
    instance: &ash::Instance,
    device: &ash::Device,
    pd: vk::PhysicalDevice,
    queue_family: u32,
    device_addresses: bool,
) -> Result<(vk::CommandPool, Allocator), GpuError> {
    let pool_info = vk::CommandPoolCreateInfo::default()
        .queue_family_index(queue_family)
        .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
    let command_pool = match unsafe { device.create_command_pool(&pool_info, None) } {
        Ok(p) => p,
        Err(e) => {
            unsafe { device.destroy_device(None) };
            return Err(GpuError::from_vk("vkCreateCommandPool", e));
        }
    };

    let allocator = match Allocator::new(&AllocatorCreateDesc {
        instance: instance.clone(),
        device: device.clone(),
        physical_device: pd,
        debug_settings: Default::default(),
        buffer_device_address: device_addresses,
        allocation_sizes: Default::default(),
    }) {
        Ok(a) => a,
        Err(e) => {
            unsafe {
                device.destroy_command_pool(command_pool, None);
                device.destroy_device(None);
            }
            return Err(GpuError::Allocation {
                what: "allocator".into(),
                source: e,
            });
        }
    };

    Ok((command_pool, allocator))
}

struct InstanceGuard {
    instance: Option<ash::Instance>,
    debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
}

impl Drop for InstanceGuard {
    fn drop(&mut self) {
        unsafe {
            if let Some((du, m)) = self.debug.take() {
                du.destroy_debug_utils_messenger(m, None);
            }
            if let Some(i) = self.instance.take() {
                i.destroy_instance(None);
            }
        }
    }
}

/// Whether Vulkan lists a GPU: a discrete, integrated or virtual device
/// (not a CPU implementation such as lavapipe) with a compute queue and
/// Vulkan 1.2, whose name contains `wanted` when given. `--backend auto`
/// asks this; any failure (no loader, no driver) is "no".
pub fn gpu_available(wanted: Option<&str>) -> bool {
    // SAFETY: as in `Context::new`.
    let Ok(entry) = (unsafe { ash::Entry::load() }) else {
        return false;
    };
    let app = vk::ApplicationInfo::default().api_version(vk::API_VERSION_1_2);
    let info = vk::InstanceCreateInfo::default().application_info(&app);
    // SAFETY: a plain instance without layers or extensions, destroyed
    // below; nothing else holds it.
    let Ok(instance) = (unsafe { entry.create_instance(&info, None) }) else {
        return false;
    };
    let found = pick_device(&instance, wanted).is_ok_and(|c| {
        matches!(
            c.device_type,
            vk::PhysicalDeviceType::DISCRETE_GPU
                | vk::PhysicalDeviceType::INTEGRATED_GPU
                | vk::PhysicalDeviceType::VIRTUAL_GPU
        )
    });
    unsafe { instance.destroy_instance(None) };
    found
}

/// What of ray tracing the device [`Context::new_ray_tracing`] would pick
/// (for `wanted`) has: a context made and dropped; its error where the
/// device has neither API.
pub fn ray_tracing_support(wanted: Option<&str>) -> Result<RayTracing, GpuError> {
    let desc = ContextDesc {
        device: wanted,
        validation: Validation::Off,
        loader: None,
    };
    Ok(Context::new_ray_tracing(&desc)?.ray_tracing())
}

fn pick_device(instance: &ash::Instance, wanted: Option<&str>) -> Result<Candidate, GpuError> {
    let pds = unsafe { instance.enumerate_physical_devices() }
        .map_err(vk_err("vkEnumeratePhysicalDevices"))?;
    let mut candidates: Vec<Candidate> = pds
        .into_iter()
        .map(|pd| {
            let props = unsafe { instance.get_physical_device_properties(pd) };
            let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
            // Prefer a compute family with timestamps; among those, the first.
            let queue = families
                .iter()
                .enumerate()
                .filter(|(_, f)| f.queue_flags.contains(vk::QueueFlags::COMPUTE))
                .map(|(i, f)| (i as u32, f.timestamp_valid_bits))
                .min_by_key(|&(i, bits)| (bits == 0, i));
            Candidate {
                pd,
                name: cstr_array(props.device_name_as_c_str()),
                device_type: props.device_type,
                props,
                queue,
            }
        })
        .collect();
    if candidates.is_empty() {
        return Err(GpuError::NoDevice);
    }
    let describe = |cs: &[Candidate]| -> Vec<String> {
        cs.iter()
            .map(|c| format!("{} ({:?})", c.name, c.device_type))
            .collect()
    };
    let usable = |c: &Candidate| c.queue.is_some() && c.props.api_version >= vk::API_VERSION_1_2;
    if let Some(w) = wanted {
        let lw = w.to_lowercase();
        let all = describe(&candidates);
        candidates.retain(|c| c.name.to_lowercase().contains(&lw));
        if candidates.is_empty() {
            return Err(GpuError::DeviceNotFound {
                wanted: w.to_string(),
                available: all,
            });
        }
    }
    let all = describe(&candidates);
    candidates.retain(usable);
    candidates.sort_by_key(|c| type_rank(c.device_type));
    candidates
        .into_iter()
        .next()
        .ok_or(GpuError::NoUsableDevice { available: all })
}

impl Drop for Context {
    fn drop(&mut self) {
        unsafe {
            // Nothing may be in flight when memory and the device go away;
            // an error here (device lost) leaves nothing better to do.
            let _ = self.device.device_wait_idle();
            if let Ok(pipelines) = self.pipelines.get_mut() {
                pipelines.destroy(&self.device);
            }
            self.device.destroy_command_pool(self.command_pool, None);
            // The allocator frees its memory blocks through the device.
            ManuallyDrop::drop(&mut self.allocator);
            self.device.destroy_device(None);
            if let Some((du, m)) = self.debug.take() {
                du.destroy_debug_utils_messenger(m, None);
            }
            self.instance.destroy_instance(None);
        }
    }
}

/// The driver's name and info (core in 1.2; every device glint accepts is
/// 1.2+).
fn driver_name(instance: &ash::Instance, pd: vk::PhysicalDevice) -> String {
    let mut driver_props = vk::PhysicalDeviceDriverProperties::default();
    let mut props2 = vk::PhysicalDeviceProperties2::default().push_next(&mut driver_props);
    unsafe { instance.get_physical_device_properties2(pd, &mut props2) };
    let name = cstr_array(driver_props.driver_name_as_c_str());
    let info = cstr_array(driver_props.driver_info_as_c_str());
    if info.is_empty() {
        name
    } else {
        format!("{name} {info}")
    }
}

/// The logical device: the optional shader features kernels may use where
/// the device has them, and what `want` asks of ray tracing.
fn create_device(
    instance: &ash::Instance,
    pd: vk::PhysicalDevice,
    queue_family: u32,
    want: RayTracingWant,
    name: &str,
) -> Result<(ash::Device, RayTracing), GpuError> {
    // Enable the optional shader features kernels may use when the device
    // has them; robustBufferAccess stays off (bounds checks cost speed and
    // kernels index in range).
    let mut have11 = vk::PhysicalDeviceVulkan11Features::default();
    let mut have12 = vk::PhysicalDeviceVulkan12Features::default();
    let mut have = vk::PhysicalDeviceFeatures2::default()
        .push_next(&mut have11)
        .push_next(&mut have12);
    unsafe { instance.get_physical_device_features2(pd, &mut have) };
    let have10 = have.features;
    let features10 = vk::PhysicalDeviceFeatures::default()
        .shader_int64(have10.shader_int64 == vk::TRUE)
        .shader_int16(have10.shader_int16 == vk::TRUE)
        .shader_float64(have10.shader_float64 == vk::TRUE);
    let mut features11 = vk::PhysicalDeviceVulkan11Features::default()
        .storage_buffer16_bit_access(have11.storage_buffer16_bit_access == vk::TRUE);
    let mut features12 = vk::PhysicalDeviceVulkan12Features::default()
        .scalar_block_layout(have12.scalar_block_layout == vk::TRUE)
        .shader_int8(have12.shader_int8 == vk::TRUE)
        .storage_buffer8_bit_access(have12.storage_buffer8_bit_access == vk::TRUE)
        .uniform_buffer_standard_layout(have12.uniform_buffer_standard_layout == vk::TRUE)
        .vulkan_memory_model(have12.vulkan_memory_model == vk::TRUE)
        // glslang emits Device-scope atomics, which the memory model
        // only allows with this feature on.
        .vulkan_memory_model_device_scope(have12.vulkan_memory_model_device_scope == vk::TRUE)
        .host_query_reset(have12.host_query_reset == vk::TRUE);
    let mut accel_features =
        vk::PhysicalDeviceAccelerationStructureFeaturesKHR::default().acceleration_structure(true);
    let mut rq_features = vk::PhysicalDeviceRayQueryFeaturesKHR::default().ray_query(true);
    let mut rtp_features =
        vk::PhysicalDeviceRayTracingPipelineFeaturesKHR::default().ray_tracing_pipeline(true);
    let mut ray_tracing = RayTracing::default();
    let mut device_extensions = Vec::new();
    if want != RayTracingWant::None {
        ray_tracing = check_ray_tracing(instance, pd, name, &have12, want)?;
        features12 = features12.buffer_device_address(true);
        device_extensions.extend(ACCEL_EXTENSIONS.map(CStr::as_ptr));
    }
    let mut features = vk::PhysicalDeviceFeatures2::default()
        .features(features10)
        .push_next(&mut features11)
        .push_next(&mut features12);
    if ray_tracing.acceleration_structures() {
        features = features.push_next(&mut accel_features);
    }
    if ray_tracing.query {
        device_extensions.push(ash::khr::ray_query::NAME.as_ptr());
        features = features.push_next(&mut rq_features);
    }
    if ray_tracing.pipeline.is_some() {
        device_extensions.push(ash::khr::ray_tracing_pipeline::NAME.as_ptr());
        features = features.push_next(&mut rtp_features);
    }

    let priorities = [1.0f32];
    let queue_infos = [vk::DeviceQueueCreateInfo::default()
        .queue_family_index(queue_family)
        .queue_priorities(&priorities)];
    let device_info = vk::DeviceCreateInfo::default()
        .queue_create_infos(&queue_infos)
        .enabled_extension_names(&device_extensions)
        .push_next(&mut features);
    let device = unsafe { instance.create_device(pd, &device_info, None) }
        .map_err(vk_err("vkCreateDevice"))?;
    Ok((device, ray_tracing))
}

/// Whether every device-local memory type is also host-visible and
/// coherent, so whatever the allocator picks for GpuOnly can be written
/// directly.
fn unified_memory(instance: &ash::Instance, pd: vk::PhysicalDevice) -> bool {
    let mem = unsafe { instance.get_physical_device_memory_properties(pd) };
    let host = vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT;
    mem.memory_types_as_slice()
        .iter()
        .filter(|t| {
            t.property_flags
                .contains(vk::MemoryPropertyFlags::DEVICE_LOCAL)
        })
        .all(|t| t.property_flags.contains(host))
}

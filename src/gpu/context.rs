//! Vulkan device setup: a headless context the CLI, tests and benchmarks share, or a context
//! wrapped around a device and queue a host application owns (engine embedding).
//!
//! Needs Vulkan 1.3 (dynamic rendering and synchronization2, both on lavapipe). Line
//! rasterization uses VK_EXT_line_rasterization's rectangular (or Bresenham) mode when present
//! so that every link line covers exactly its texels (see [`LineMode`]).

use crate::error::{Error, Result};
use crate::gpu::error::VkContext;
use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};
use std::ffi::{c_void, CString};
use std::mem::ManuallyDrop;
use std::sync::{Arc, Mutex};

use super::device::pick_device;
pub use super::validation::ValidationLog;
use super::validation::{on_message, VALIDATION_LAYER};

/// How lines are rasterized, which decides where the vertex shaders put line endpoints.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum LineMode {
    /// Rectangular lines (VK_EXT_line_rasterization or strict core lines): endpoints on texel
    /// edges cover the texel centers strictly between them.
    Rectangular,
    /// Bresenham lines with the diamond-exit rule: endpoints on texel centers cover the first
    /// texel and not the last.
    Bresenham,
}

impl LineMode {
    /// Offset added to texel-edge coordinates of line endpoints in this mode.
    pub fn endpoint_offset(self) -> f32 {
        match self {
            LineMode::Rectangular => 0.0,
            LineMode::Bresenham => 0.5,
        }
    }
}

/// Options for a headless context.
#[derive(Debug, Clone, Default)]
pub struct ContextOptions {
    /// Enable VK_LAYER_KHRONOS_validation and record its messages (an error if the layer is
    /// missing). Also switched on by the environment variable `ANTIRADIANCE_VALIDATION=1`.
    pub validation: bool,
    /// Pick the first device whose name contains this (else `ANTIRADIANCE_DEVICE`, else prefer
    /// a discrete GPU).
    pub device_name: Option<String>,
    /// Do not read or write the pipeline cache file ([`super::cache`]; by default it is kept in
    /// the user's cache directory, `ANTIRADIANCE_CACHE_DIR` overrides it).
    pub no_pipeline_cache: bool,
}

/// What the solver learned about the device.
#[derive(Debug, Clone, serde::Serialize)]
pub struct DeviceInfo {
    /// `deviceName`.
    pub name: String,
    /// Driver name (e.g. `llvmpipe`, `NVIDIA`).
    pub driver: String,
    /// `maxImageDimension2D`.
    pub max_image_dimension: u32,
    /// `maxStorageBufferRange`: the largest storage buffer a shader may read (link records).
    pub max_storage_buffer_range: u32,
    /// Nanoseconds per timestamp tick.
    pub timestamp_period: f32,
    /// Whether the queue writes timestamps.
    pub timestamps: bool,
    /// Line rasterization in use.
    pub line_mode: LineMode,
    /// Widest line the solver draws, texels: `lineWidthRange`'s maximum where the device has
    /// `wideLines` and rectangular lines, else 1 (the global pass then draws one line per bin
    /// row of a footprint).
    pub max_line_width: u32,
    /// Largest single allocation / heap size of device-local memory, bytes.
    pub device_local_bytes: u64,
    /// Whether fragment shaders may write storage buffers (`fragmentStoresAndAtomics`,
    /// enabled on headless devices that have it): emulated float16 blending needs it.
    pub fragment_stores: bool,
}

/// A Vulkan device, queue and allocator, owned or borrowed from a host application.
pub struct Context {
    /// Loader entry points.
    pub entry: ash::Entry,
    /// Instance.
    pub instance: ash::Instance,
    /// Physical device.
    pub physical_device: vk::PhysicalDevice,
    /// Logical device.
    pub device: ash::Device,
    /// Graphics queue the solver submits to (or records for).
    pub queue: vk::Queue,
    /// Its family.
    pub queue_family: u32,
    /// Memory allocator (ours, even on a host's device).
    pub allocator: ManuallyDrop<Mutex<Allocator>>,
    /// Debug-utils device functions, when the instance has the extension.
    pub debug: Option<ash::ext::debug_utils::Device>,
    /// Device properties the solver uses.
    pub info: DeviceInfo,
    messenger: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    validation: Arc<ValidationLog>,
    pool: vk::CommandPool,
    /// The one command buffer and fence every submission reuses; the queue and the command
    /// pool need external synchronization, so this lock also makes it one submission at a time.
    submit_lock: Mutex<Submitter>,
    owned: bool,
    line_ext: bool,
    pub(crate) f16_rounding: std::sync::OnceLock<BlendRounding>,
    pipeline_cache: super::cache::PipelineCache,
}

/// A device created by a host application, for [`Context::from_host`].
pub struct HostDevice {
    /// Loader.
    pub entry: ash::Entry,
    /// Host's instance (kept alive by the host).
    pub instance: ash::Instance,
    /// Host's physical device.
    pub physical_device: vk::PhysicalDevice,
    /// Host's device; must have Vulkan 1.3 dynamic rendering and synchronization2 enabled, and
    /// the core `independentBlend` feature.
    pub device: ash::Device,
    /// Queue (graphics) the solver's command buffers will be submitted to.
    pub queue: vk::Queue,
    /// Its family.
    pub queue_family: u32,
    /// Whether the host enabled VK_EXT_line_rasterization with `rectangularLines`.
    pub rectangular_lines: bool,
    /// Whether the host enabled the core `wideLines` feature (the global pass then draws a
    /// footprint's bin rows as one line).
    pub wide_lines: bool,
    /// Whether the host's instance has VK_EXT_debug_utils enabled.
    pub debug_utils: bool,
}

impl Context {
    /// Creates a headless instance and device.
    pub fn headless(opts: &ContextOptions) -> Result<Arc<Self>> {
        let entry = unsafe { ash::Entry::load() }
            .map_err(|e| Error::Device(format!("cannot load the Vulkan loader: {e}")))?;
        let validation =
            opts.validation || std::env::var("ANTIRADIANCE_VALIDATION").is_ok_and(|v| v == "1");
        let layers = unsafe { entry.enumerate_instance_layer_properties() }.vk("listing layers")?;
        let has_layer = layers
            .iter()
            .any(|l| l.layer_name_as_c_str().ok() == Some(VALIDATION_LAYER));
        if validation && !has_layer {
            return Err(Error::Device(
                "validation requested but VK_LAYER_KHRONOS_validation is not installed \
                 (apt-get install vulkan-validationlayers)"
                    .into(),
            ));
        }
        let exts = unsafe { entry.enumerate_instance_extension_properties(None) }
            .vk("listing instance extensions")?;
        let has_debug = exts
            .iter()
            .any(|e| e.extension_name_as_c_str().ok() == Some(vk::EXT_DEBUG_UTILS_NAME));
        let app = CString::new("antiradiance").unwrap();
        let app_info = vk::ApplicationInfo::default()
            .application_name(&app)
            .engine_name(&app)
            .api_version(vk::API_VERSION_1_3);
        let layer_ptrs = if validation {
            vec![VALIDATION_LAYER.as_ptr()]
        } else {
            vec![]
        };
        let ext_ptrs = if has_debug {
            vec![vk::EXT_DEBUG_UTILS_NAME.as_ptr()]
        } else {
            vec![]
        };
        let instance = unsafe {
            entry.create_instance(
                &vk::InstanceCreateInfo::default()
                    .application_info(&app_info)
                    .enabled_layer_names(&layer_ptrs)
                    .enabled_extension_names(&ext_ptrs),
                None,
            )
        }
        .vk("vkCreateInstance")?;
        let log = Arc::new(ValidationLog::default());
        let messenger = if has_debug && validation {
            let du = ash::ext::debug_utils::Instance::new(&entry, &instance);
            let info = vk::DebugUtilsMessengerCreateInfoEXT::default()
                .message_severity(
                    vk::DebugUtilsMessageSeverityFlagsEXT::ERROR
                        | vk::DebugUtilsMessageSeverityFlagsEXT::WARNING,
                )
                .message_type(
                    vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                        | vk::DebugUtilsMessageTypeFlagsEXT::GENERAL,
                )
                .pfn_user_callback(Some(on_message))
                .user_data(Arc::as_ptr(&log) as *mut c_void);
            let m = unsafe { du.create_debug_utils_messenger(&info, None) }
                .vk("creating the debug messenger")?;
            Some((du, m))
        } else {
            None
        };
        // On failure before the device exists, the messenger goes before the instance (else the
        // layer reports the instance destroyed with a messenger still alive).
        let abandon = |messenger: &Option<(
            ash::ext::debug_utils::Instance,
            vk::DebugUtilsMessengerEXT,
        )>| unsafe {
            if let Some((du, m)) = messenger {
                du.destroy_debug_utils_messenger(*m, None);
            }
            instance.destroy_instance(None);
        };
        let (physical_device, queue_family) = match pick_device(&instance, opts.device_name.clone())
        {
            Ok(p) => p,
            Err(e) => {
                abandon(&messenger);
                return Err(e);
            }
        };
        let dev_exts = unsafe { instance.enumerate_device_extension_properties(physical_device) }
            .vk("listing device extensions")?;
        let has_lines = dev_exts
            .iter()
            .any(|e| e.extension_name_as_c_str().ok() == Some(vk::EXT_LINE_RASTERIZATION_NAME));
        let mut line_feat = vk::PhysicalDeviceLineRasterizationFeaturesEXT::default();
        let mut f13 = vk::PhysicalDeviceVulkan13Features::default();
        let mut f2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut f13);
        if has_lines {
            f2 = f2.push_next(&mut line_feat);
        }
        unsafe { instance.get_physical_device_features2(physical_device, &mut f2) };
        let blend_ok = f2.features.independent_blend == vk::TRUE;
        let wide = f2.features.wide_lines == vk::TRUE;
        let stores = f2.features.fragment_stores_and_atomics == vk::TRUE;
        let (dyn_ok, sync_ok) = (
            f13.dynamic_rendering == vk::TRUE,
            f13.synchronization2 == vk::TRUE,
        );
        let (rect, bres) = (
            has_lines && line_feat.rectangular_lines == vk::TRUE,
            has_lines && line_feat.bresenham_lines == vk::TRUE,
        );
        if !dyn_ok || !sync_ok || !blend_ok {
            abandon(&messenger);
            return Err(Error::Device(
                "the device lacks dynamicRendering, synchronization2 (Vulkan 1.3) or independentBlend".into(),
            ));
        }
        let mut en13 = vk::PhysicalDeviceVulkan13Features::default()
            .dynamic_rendering(true)
            .synchronization2(true);
        let mut en_lines = vk::PhysicalDeviceLineRasterizationFeaturesEXT::default()
            .rectangular_lines(rect)
            .bresenham_lines(bres);
        let prio = [1.0f32];
        let qinfo = [vk::DeviceQueueCreateInfo::default()
            .queue_family_index(queue_family)
            .queue_priorities(&prio)];
        let dev_ext_ptrs = if rect || bres {
            vec![vk::EXT_LINE_RASTERIZATION_NAME.as_ptr()]
        } else {
            vec![]
        };
        // The antiradiance step masks I_total while writing I_ex: per-attachment blend state.
        // Wide lines draw a filter's footprint as one line per rectangle of bins.
        let core = vk::PhysicalDeviceFeatures::default()
            .independent_blend(true)
            .wide_lines(wide)
            .fragment_stores_and_atomics(stores);
        let mut dinfo = vk::DeviceCreateInfo::default()
            .queue_create_infos(&qinfo)
            .enabled_features(&core)
            .enabled_extension_names(&dev_ext_ptrs)
            .push_next(&mut en13);
        if rect || bres {
            dinfo = dinfo.push_next(&mut en_lines);
        }
        let device = unsafe { instance.create_device(physical_device, &dinfo, None) }
            .vk("vkCreateDevice")?;
        let queue = unsafe { device.get_device_queue(queue_family, 0) };
        let line_mode = if rect || !bres {
            LineMode::Rectangular
        } else {
            LineMode::Bresenham
        };
        let cache_dir = (!opts.no_pipeline_cache)
            .then(super::cache::default_dir)
            .flatten();
        Self::finish(
            entry,
            instance,
            physical_device,
            device,
            queue,
            queue_family,
            line_mode,
            rect || bres,
            wide,
            stores,
            has_debug,
            messenger,
            log,
            cache_dir,
            true,
        )
    }

    /// Wraps a host application's device and queue. The solver records into command buffers the
    /// host gives it and never destroys the host's objects.
    pub fn from_host(host: HostDevice) -> Result<Arc<Self>> {
        // Without the extension, strict core lines are rectangular too.
        let line_mode = LineMode::Rectangular;
        let line_ext = host.rectangular_lines;
        let wide = host.wide_lines;
        Self::finish(
            host.entry,
            host.instance,
            host.physical_device,
            host.device,
            host.queue,
            host.queue_family,
            line_mode,
            line_ext,
            wide,
            // A host's device is used as the host enabled it; emulated blending is for tests.
            false,
            host.debug_utils,
            None,
            Arc::new(ValidationLog::default()),
            super::cache::default_dir(),
            false,
        )
    }

    #[allow(clippy::too_many_arguments)]
    fn finish(
        entry: ash::Entry,
        instance: ash::Instance,
        physical_device: vk::PhysicalDevice,
        device: ash::Device,
        queue: vk::Queue,
        queue_family: u32,
        line_mode: LineMode,
        line_ext: bool,
        wide_lines: bool,
        fragment_stores: bool,
        has_debug: bool,
        messenger: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
        validation: Arc<ValidationLog>,
        cache_dir: Option<std::path::PathBuf>,
        owned: bool,
    ) -> Result<Arc<Self>> {
        let props = unsafe { instance.get_physical_device_properties(physical_device) };
        let mut driver = vk::PhysicalDeviceDriverProperties::default();
        let mut p2 = vk::PhysicalDeviceProperties2::default().push_next(&mut driver);
        unsafe { instance.get_physical_device_properties2(physical_device, &mut p2) };
        let qprops =
            unsafe { instance.get_physical_device_queue_family_properties(physical_device) };
        let mem = unsafe { instance.get_physical_device_memory_properties(physical_device) };
        let device_local_bytes = mem.memory_heaps[..mem.memory_heap_count as usize]
            .iter()
            .filter(|h| h.flags.contains(vk::MemoryHeapFlags::DEVICE_LOCAL))
            .map(|h| h.size)
            .max()
            .unwrap_or(0);
        let info = DeviceInfo {
            name: props
                .device_name_as_c_str()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default(),
            driver: driver
                .driver_name_as_c_str()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default(),
            max_image_dimension: props.limits.max_image_dimension2_d,
            max_storage_buffer_range: props.limits.max_storage_buffer_range,
            timestamp_period: props.limits.timestamp_period,
            timestamps: qprops[queue_family as usize].timestamp_valid_bits > 0,
            line_mode,
            // A horizontal wide line covers whole texel rows only when rasterized as a
            // rectangle (Bresenham's wide lines are a column of fragments per x).
            max_line_width: if wide_lines && line_mode == LineMode::Rectangular {
                (props.limits.line_width_range[1].floor() as u32).max(1)
            } else {
                1
            },
            device_local_bytes,
            fragment_stores,
        };
        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: instance.clone(),
            device: device.clone(),
            physical_device,
            debug_settings: Default::default(),
            buffer_device_address: false,
            allocation_sizes: Default::default(),
        })
        .map_err(|e| Error::Device(format!("creating the allocator: {e}")))?;
        let pool = unsafe {
            device.create_command_pool(
                &vk::CommandPoolCreateInfo::default()
                    .queue_family_index(queue_family)
                    .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER),
                None,
            )
        }
        .vk("creating the command pool")?;
        let submitter = Submitter::new(&device, pool)?;
        let debug = has_debug.then(|| ash::ext::debug_utils::Device::new(&instance, &device));
        let pipeline_cache =
            super::cache::PipelineCache::open(&device, &props, cache_dir.as_deref());
        let ctx = Self {
            entry,
            instance,
            physical_device,
            device,
            queue,
            queue_family,
            allocator: ManuallyDrop::new(Mutex::new(allocator)),
            debug,
            info,
            messenger,
            validation,
            pool,
            submit_lock: Mutex::new(submitter),
            owned,
            line_ext,
            f16_rounding: std::sync::OnceLock::new(),
            pipeline_cache,
        };
        ctx.name(pool, "antiradiance command pool");
        Ok(Arc::new(ctx))
    }

    /// The pipeline cache every pipeline of this context is created with (kept between runs
    /// in the cache directory, see [`super::cache`]).
    pub fn pipeline_cache(&self) -> vk::PipelineCache {
        self.pipeline_cache.raw()
    }

    /// Whether pipelines must chain VK_EXT_line_rasterization state.
    pub fn line_rasterization_ext(&self) -> bool {
        self.line_ext
    }

    /// Validation messages recorded so far (empty unless validation is on).
    pub fn validation_messages(&self) -> Vec<String> {
        self.validation.messages()
    }

    /// Whether the validation layer is active on this context.
    pub fn validation_enabled(&self) -> bool {
        self.messenger.is_some()
    }

    /// Gives a Vulkan object a debug-utils name (seen by validation messages and RenderDoc).
    pub fn name<H: vk::Handle>(&self, handle: H, name: &str) {
        if let Some(d) = &self.debug {
            let n = CString::new(name).unwrap_or_default();
            let info = vk::DebugUtilsObjectNameInfoEXT::default()
                .object_handle(handle)
                .object_name(&n);
            unsafe {
                let _ = d.set_debug_utils_object_name(&info);
            }
        }
    }

    /// Waits until the device is idle (serialized with submissions: the queue needs external
    /// synchronization).
    pub fn wait_idle(&self) {
        let _one_at_a_time = self.submit_lock.lock().unwrap_or_else(|e| e.into_inner());
        unsafe {
            let _ = self.device.device_wait_idle();
        }
    }

    /// Records a one-time command buffer, submits it and waits for it (one submission at a time
    /// per context, so a context may be shared between threads).
    pub fn submit_and_wait(&self, record: impl FnOnce(vk::CommandBuffer)) -> Result<()> {
        let s = self.submit_lock.lock().unwrap_or_else(|e| e.into_inner());
        let d = &self.device;
        unsafe {
            d.reset_command_buffer(s.cmd, vk::CommandBufferResetFlags::empty())
                .vk("vkResetCommandBuffer")?;
            d.reset_fences(&[s.fence]).vk("vkResetFences")?;
            d.begin_command_buffer(
                s.cmd,
                &vk::CommandBufferBeginInfo::default()
                    .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
            )
            .vk("vkBeginCommandBuffer")?;
        }
        record(s.cmd);
        unsafe {
            d.end_command_buffer(s.cmd).vk("vkEndCommandBuffer")?;
            let cmds = [s.cmd];
            let submit = vk::SubmitInfo::default().command_buffers(&cmds);
            d.queue_submit(self.queue, &[submit], s.fence)
                .vk("vkQueueSubmit")?;
            d.wait_for_fences(&[s.fence], true, u64::MAX)
                .vk("waiting for the GPU")?;
            // The queue is idle once the fence has signalled, so this returns at once on a
            // driver; it makes the validation layer finish retiring the submission (its own
            // thread) before the caller reads timestamps, frees or records again. Without it,
            // Debian's layer (1.3.239) on lavapipe corrupted the heap in about one run in five
            // of the stability suite (0 in 12 with validation off).
            d.queue_wait_idle(self.queue).vk("vkQueueWaitIdle")
        }
    }
}

/// The command buffer and fence of [`Context::submit_and_wait`], made once per context: a
/// submission per upload, read-back and batch made and destroyed thousands of each in a run.
struct Submitter {
    cmd: vk::CommandBuffer,
    fence: vk::Fence,
}

impl Submitter {
    fn new(device: &ash::Device, pool: vk::CommandPool) -> Result<Self> {
        let cmd = unsafe {
            device.allocate_command_buffers(
                &vk::CommandBufferAllocateInfo::default()
                    .command_pool(pool)
                    .command_buffer_count(1),
            )
        }
        .vk("allocating a command buffer")?[0];
        let fence = unsafe { device.create_fence(&vk::FenceCreateInfo::default(), None) }
            .vk("creating a fence")?;
        Ok(Self { cmd, fence })
    }
}

impl Drop for Context {
    fn drop(&mut self) {
        unsafe {
            let _ = self.device.device_wait_idle();
            self.pipeline_cache.save_and_destroy(&self.device);
            if let Ok(s) = self.submit_lock.get_mut() {
                self.device.destroy_fence(s.fence, None);
            }
            self.device.destroy_command_pool(self.pool, None);
            ManuallyDrop::drop(&mut self.allocator);
            if self.owned {
                self.device.destroy_device(None);
                if let Some((du, m)) = self.messenger.take() {
                    du.destroy_debug_utils_messenger(m, None);
                }
                self.instance.destroy_instance(None);
            }
        }
    }
}

/// How a device rounds additive blending into float16 targets.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum BlendRounding {
    /// Round to nearest (what GPUs do; errors grow as √N over N additions).
    Nearest,
    /// Truncation toward zero (lavapipe): every addition loses half an ulp on average, a bias
    /// that grows as N.
    TowardZero,
}

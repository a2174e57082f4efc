//! The viewer's own Vulkan instance and device (the library is embedded in them through
//! `Context::from_host`): the instance has the window system's surface extensions, the device
//! the swapchain, plus what the library needs (Vulkan 1.3 dynamic rendering and
//! synchronization2, `independentBlend`, rectangular and wide lines where offered).

use anyhow::{anyhow, bail, Context as _, Result};
use ash::vk;
use std::ffi::{c_void, CStr};
use std::sync::atomic::{AtomicUsize, Ordering};
use winit::raw_window_handle::{RawDisplayHandle, RawWindowHandle};

use antiradiance::gpu::validation::VALIDATION_LAYER;

/// Validation errors and warnings seen by the messenger (the viewer fails when any were seen).
pub static VALIDATION_MESSAGES: AtomicUsize = AtomicUsize::new(0);

unsafe extern "system" fn on_message(
    _severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _kind: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    _user: *mut c_void,
) -> vk::Bool32 {
    if !data.is_null() {
        let msg = unsafe { (*data).message_as_c_str() }
            .map(|m| m.to_string_lossy().into_owned())
            .unwrap_or_default();
        eprintln!("vulkan validation: {msg}");
    }
    VALIDATION_MESSAGES.fetch_add(1, Ordering::SeqCst);
    vk::FALSE
}

/// Whether validation is asked for (as for every command: `ANTIRADIANCE_VALIDATION=1`).
pub fn validation_requested() -> bool {
    std::env::var("ANTIRADIANCE_VALIDATION").is_ok_and(|v| v == "1")
}

/// The instance, its debug messenger and the window's surface; destroyed in reverse order.
pub struct Instance {
    /// Loader.
    pub entry: ash::Entry,
    /// Instance with the surface extensions.
    pub instance: ash::Instance,
    /// Surface functions.
    pub surface_fn: ash::khr::surface::Instance,
    /// The window's surface.
    pub surface: vk::SurfaceKHR,
    /// Whether the instance has VK_EXT_debug_utils.
    pub debug_utils: bool,
    messenger: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
}

impl Drop for Instance {
    fn drop(&mut self) {
        unsafe {
            if self.surface != vk::SurfaceKHR::null() {
                self.surface_fn.destroy_surface(self.surface, None);
            }
            if let Some((du, m)) = self.messenger.take() {
                du.destroy_debug_utils_messenger(m, None);
            }
            self.instance.destroy_instance(None);
        }
    }
}

/// The device and its presenting queue; the device is destroyed on drop, before the
/// instance (field order), once everything made on it is gone (the owner drops the engine
/// first).
pub struct Host {
    /// Physical device that can present to the surface.
    pub physical_device: vk::PhysicalDevice,
    /// Device with the swapchain extension.
    pub device: ash::Device,
    /// Graphics queue that also presents.
    pub queue: vk::Queue,
    /// Its family.
    pub queue_family: u32,
    /// Swapchain functions.
    pub swapchain_fn: ash::khr::swapchain::Device,
    /// Whether VK_EXT_line_rasterization with rectangular lines is on.
    pub rectangular_lines: bool,
    /// Whether the core `wideLines` feature is enabled.
    pub wide_lines: bool,
    /// Instance and surface (dropped after the device).
    pub inst: Instance,
}

impl Drop for Host {
    fn drop(&mut self) {
        unsafe {
            let _ = self.device.device_wait_idle();
            self.device.destroy_device(None);
        }
    }
}

impl Host {
    /// Creates the instance (validation when asked), the window's surface and a device that
    /// can draw and present to it; `device_name` picks a device whose name contains it.
    pub fn new(
        display: RawDisplayHandle,
        window: RawWindowHandle,
        validation: bool,
        device_name: Option<&str>,
    ) -> Result<Self> {
        let inst = Instance::new(display, window, validation)?;
        let (physical_device, queue_family) = pick(&inst, device_name)?;
        let i = &inst.instance;
        let dev_exts = unsafe { i.enumerate_device_extension_properties(physical_device) }?;
        let has = |name: &CStr| {
            dev_exts
                .iter()
                .any(|e| e.extension_name_as_c_str().ok() == Some(name))
        };
        let mut line_feat = vk::PhysicalDeviceLineRasterizationFeaturesEXT::default();
        let mut f13 = vk::PhysicalDeviceVulkan13Features::default();
        let mut f2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut f13);
        let has_lines = has(vk::EXT_LINE_RASTERIZATION_NAME);
        if has_lines {
            f2 = f2.push_next(&mut line_feat);
        }
        unsafe { i.get_physical_device_features2(physical_device, &mut f2) };
        let wide = f2.features.wide_lines == vk::TRUE;
        if f2.features.independent_blend != vk::TRUE
            || f13.dynamic_rendering != vk::TRUE
            || f13.synchronization2 != vk::TRUE
        {
            bail!("the device lacks dynamicRendering, synchronization2 (Vulkan 1.3) or independentBlend");
        }
        let rect = has_lines && line_feat.rectangular_lines == vk::TRUE;
        let mut exts = vec![vk::KHR_SWAPCHAIN_NAME.as_ptr()];
        if rect {
            exts.push(vk::EXT_LINE_RASTERIZATION_NAME.as_ptr());
        }
        let mut en13 = vk::PhysicalDeviceVulkan13Features::default()
            .dynamic_rendering(true)
            .synchronization2(true);
        let mut en_lines =
            vk::PhysicalDeviceLineRasterizationFeaturesEXT::default().rectangular_lines(true);
        let prio = [1.0f32];
        let queues = [vk::DeviceQueueCreateInfo::default()
            .queue_family_index(queue_family)
            .queue_priorities(&prio)];
        let core = vk::PhysicalDeviceFeatures::default()
            .independent_blend(true)
            .wide_lines(wide);
        let mut info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queues)
            .enabled_features(&core)
            .enabled_extension_names(&exts)
            .push_next(&mut en13);
        if rect {
            info = info.push_next(&mut en_lines);
        }
        let device = unsafe { i.create_device(physical_device, &info, None) }
            .context("vkCreateDevice (with the swapchain extension)")?;
        let queue = unsafe { device.get_device_queue(queue_family, 0) };
        let swapchain_fn = ash::khr::swapchain::Device::new(i, &device);
        Ok(Self {
            physical_device,
            device,
            queue,
            queue_family,
            swapchain_fn,
            rectangular_lines: rect,
            wide_lines: wide,
            inst,
        })
    }
}

impl Instance {
    fn new(display: RawDisplayHandle, window: RawWindowHandle, validation: bool) -> Result<Self> {
        let entry = unsafe { ash::Entry::load() }.context("cannot load the Vulkan loader")?;
        let layers = unsafe { entry.enumerate_instance_layer_properties() }?;
        if validation
            && !layers
                .iter()
                .any(|l| l.layer_name_as_c_str().ok() == Some(VALIDATION_LAYER))
        {
            bail!("validation requested but VK_LAYER_KHRONOS_validation is not installed (scripts/setup.sh)");
        }
        let available = unsafe { entry.enumerate_instance_extension_properties(None) }?;
        let debug_utils = available
            .iter()
            .any(|e| e.extension_name_as_c_str().ok() == Some(vk::EXT_DEBUG_UTILS_NAME));
        let mut exts = ash_window::enumerate_required_extensions(display)
            .context("the window system offers no Vulkan surface")?
            .to_vec();
        if debug_utils {
            exts.push(vk::EXT_DEBUG_UTILS_NAME.as_ptr());
        }
        let layer_ptrs = if validation {
            vec![VALIDATION_LAYER.as_ptr()]
        } else {
            vec![]
        };
        let app = vk::ApplicationInfo::default()
            .application_name(c"antiradiance view")
            .api_version(vk::API_VERSION_1_3);
        let instance = unsafe {
            entry.create_instance(
                &vk::InstanceCreateInfo::default()
                    .application_info(&app)
                    .enabled_layer_names(&layer_ptrs)
                    .enabled_extension_names(&exts),
                None,
            )
        }
        .context("vkCreateInstance (with the window system's surface extensions)")?;
        let surface_fn = ash::khr::surface::Instance::new(&entry, &instance);
        // From here on, drop cleans up whatever exists.
        let mut me = Self {
            entry,
            instance,
            surface_fn,
            surface: vk::SurfaceKHR::null(),
            debug_utils,
            messenger: None,
        };
        if validation && debug_utils {
            let du = ash::ext::debug_utils::Instance::new(&me.entry, &me.instance);
            let info = vk::DebugUtilsMessengerCreateInfoEXT::default()
                .message_severity(
                    vk::DebugUtilsMessageSeverityFlagsEXT::ERROR
                        | vk::DebugUtilsMessageSeverityFlagsEXT::WARNING,
                )
                .message_type(
                    vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                        | vk::DebugUtilsMessageTypeFlagsEXT::GENERAL,
                )
                .pfn_user_callback(Some(on_message));
            let m = unsafe { du.create_debug_utils_messenger(&info, None) }?;
            me.messenger = Some((du, m));
        }
        me.surface =
            unsafe { ash_window::create_surface(&me.entry, &me.instance, display, window, None) }
                .context("creating the window's Vulkan surface")?;
        Ok(me)
    }
}

/// The first device (whose name contains `name`, when given; a discrete GPU preferred) with a
/// graphics queue that can present to the surface.
fn pick(inst: &Instance, name: Option<&str>) -> Result<(vk::PhysicalDevice, u32)> {
    let devices = unsafe { inst.instance.enumerate_physical_devices() }?;
    let mut found = Vec::new();
    for pd in devices {
        let props = unsafe { inst.instance.get_physical_device_properties(pd) };
        let dev_name = props
            .device_name_as_c_str()
            .map(|c| c.to_string_lossy().into_owned())
            .unwrap_or_default();
        if name.is_some_and(|n| !dev_name.contains(n)) {
            continue;
        }
        let families = unsafe {
            inst.instance
                .get_physical_device_queue_family_properties(pd)
        };
        for (q, f) in families.iter().enumerate() {
            let present = unsafe {
                inst.surface_fn
                    .get_physical_device_surface_support(pd, q as u32, inst.surface)
            }
            .unwrap_or(false);
            if f.queue_flags.contains(vk::QueueFlags::GRAPHICS) && present {
                let discrete = props.device_type == vk::PhysicalDeviceType::DISCRETE_GPU;
                found.push((!discrete, pd, q as u32));
                break;
            }
        }
    }
    found.sort_by_key(|f| f.0);
    found.first().map(|f| (f.1, f.2)).ok_or_else(|| match name {
        Some(n) => anyhow!("no Vulkan device named like `{n}` can present to the window"),
        None => anyhow!("no Vulkan device can present to the window"),
    })
}

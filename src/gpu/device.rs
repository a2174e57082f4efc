//! Which physical device a headless context takes: one named like `--device` (or
//! `ANTIRADIANCE_DEVICE`), else the best kind (discrete, integrated, CPU), Vulkan 1.3 with a
//! graphics queue.

use crate::error::{Error, Result};
use crate::gpu::error::VkContext;
use ash::vk;

/// The device and its graphics queue family.
pub(super) fn pick_device(
    instance: &ash::Instance,
    wanted: Option<String>,
) -> Result<(vk::PhysicalDevice, u32)> {
    let wanted = wanted.or_else(|| std::env::var("ANTIRADIANCE_DEVICE").ok());
    let devices = unsafe { instance.enumerate_physical_devices() }.vk("listing devices")?;
    let mut best: Option<(i32, vk::PhysicalDevice, u32)> = None;
    for pd in devices {
        let props = unsafe { instance.get_physical_device_properties(pd) };
        if props.api_version < vk::API_VERSION_1_3 {
            continue;
        }
        let name = props
            .device_name_as_c_str()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        if let Some(w) = &wanted {
            if !name.contains(w.as_str()) {
                continue;
            }
        }
        let qf = unsafe { instance.get_physical_device_queue_family_properties(pd) };
        let Some(family) = qf
            .iter()
            .position(|q| q.queue_flags.contains(vk::QueueFlags::GRAPHICS))
        else {
            continue;
        };
        let score = match props.device_type {
            vk::PhysicalDeviceType::DISCRETE_GPU => 3,
            vk::PhysicalDeviceType::INTEGRATED_GPU => 2,
            vk::PhysicalDeviceType::CPU => 1,
            _ => 0,
        };
        if best.is_none_or(|b| score > b.0) {
            best = Some((score, pd, family as u32));
        }
    }
    best.map(|b| (b.1, b.2)).ok_or_else(|| {
        Error::Device(match wanted {
            Some(w) => format!("no Vulkan 1.3 device with a graphics queue named like `{w}`"),
            None => "no Vulkan 1.3 device with a graphics queue (install mesa-vulkan-drivers for lavapipe)".into(),
        })
    })
}

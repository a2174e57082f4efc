//! A `VkPipelineCache` kept between runs, so that a second run builds its pipelines from the
//! driver's cache instead of compiling them again. The file lives in the user's cache directory
//! (`$ANTIRADIANCE_CACHE_DIR`, else `$XDG_CACHE_HOME/antiradiance`, else
//! `~/.cache/antiradiance`), one per device, and is safe when stale or corrupt: it carries its
//! own length and checksum, and the device's pipeline-cache header (vendor, device, UUID) is
//! checked before the driver sees it; anything that does not match starts an empty cache.

use ash::vk;
use std::path::{Path, PathBuf};

/// Our header before the driver's data: magic, data length, FNV-1a checksum of the data.
const MAGIC: &[u8; 8] = b"ARPCACHE";
const HEADER: usize = 8 + 8 + 8;

/// Where pipeline caches are kept: the override, or the user's cache directory; `None` when
/// `ANTIRADIANCE_CACHE_DIR` is empty (caching off) or no home is known.
pub fn default_dir() -> Option<PathBuf> {
    if let Some(d) = std::env::var_os("ANTIRADIANCE_CACHE_DIR") {
        return (!d.is_empty()).then(|| PathBuf::from(d));
    }
    let base = std::env::var_os("XDG_CACHE_HOME")
        .filter(|d| !d.is_empty())
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))?;
    Some(base.join("antiradiance"))
}

fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// Wraps driver cache data in our header.
pub fn wrap(data: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(HEADER + data.len());
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&(data.len() as u64).to_le_bytes());
    out.extend_from_slice(&fnv1a(data).to_le_bytes());
    out.extend_from_slice(data);
    out
}

/// The driver data inside a cache file, if the file is intact and was written by a device
/// with this `vendor`, `device` and pipeline-cache `uuid`.
pub fn unwrap<'a>(file: &'a [u8], vendor: u32, device: u32, uuid: &[u8; 16]) -> Option<&'a [u8]> {
    if file.len() < HEADER || &file[..8] != MAGIC {
        return None;
    }
    let len = u64::from_le_bytes(file[8..16].try_into().ok()?) as usize;
    let sum = u64::from_le_bytes(file[16..24].try_into().ok()?);
    let data = file.get(HEADER..)?;
    if data.len() != len || fnv1a(data) != sum || len < 32 {
        return None;
    }
    // VkPipelineCacheHeaderVersionOne: length, version, vendorID, deviceID, UUID.
    let word = |i: usize| u32::from_le_bytes(data[4 * i..4 * i + 4].try_into().unwrap());
    let ok = word(0) as usize >= 32
        && word(1) == vk::PipelineCacheHeaderVersion::ONE.as_raw() as u32
        && word(2) == vendor
        && word(3) == device
        && &data[16..32] == uuid;
    ok.then_some(data)
}

/// The context's pipeline cache and the file it is saved to.
pub struct PipelineCache {
    raw: vk::PipelineCache,
    file: Option<PathBuf>,
}

impl PipelineCache {
    /// Creates the cache, seeded from `dir`'s file for this device when it is intact.
    pub fn open(
        device: &ash::Device,
        props: &vk::PhysicalDeviceProperties,
        dir: Option<&Path>,
    ) -> Self {
        let file = dir.map(|d| {
            d.join(format!(
                "pipelines-{:04x}-{:04x}-{:08x}.bin",
                props.vendor_id, props.device_id, props.driver_version
            ))
        });
        let bytes = file.as_ref().and_then(|f| std::fs::read(f).ok());
        let seed = bytes.as_deref().and_then(|b| {
            unwrap(
                b,
                props.vendor_id,
                props.device_id,
                &props.pipeline_cache_uuid,
            )
        });
        let create = |data: &[u8]| unsafe {
            device.create_pipeline_cache(
                &vk::PipelineCacheCreateInfo::default().initial_data(data),
                None,
            )
        };
        let raw = create(seed.unwrap_or(&[]))
            .or_else(|_| create(&[]))
            .unwrap_or(vk::PipelineCache::null());
        Self { raw, file }
    }

    /// The handle (null when the driver refused to make one: pipelines are then uncached).
    pub fn raw(&self) -> vk::PipelineCache {
        self.raw
    }

    /// Writes the cache to its file (atomically: a temporary file renamed) and destroys it.
    /// Failures to save are ignored: the cache only saves time.
    ///
    /// # Safety
    /// `device` made the cache and no pipeline creation is in flight.
    pub unsafe fn save_and_destroy(&mut self, device: &ash::Device) {
        if self.raw == vk::PipelineCache::null() {
            return;
        }
        if let (Some(file), Ok(data)) = (&self.file, unsafe {
            device.get_pipeline_cache_data(self.raw)
        }) {
            let tmp = file.with_extension(format!("tmp{}", std::process::id()));
            let saved = file
                .parent()
                .map_or(Ok(()), std::fs::create_dir_all)
                .and_then(|_| std::fs::write(&tmp, wrap(&data)))
                .and_then(|_| std::fs::rename(&tmp, file));
            if saved.is_err() {
                let _ = std::fs::remove_file(&tmp);
            }
        }
        unsafe { device.destroy_pipeline_cache(self.raw, None) };
        self.raw = vk::PipelineCache::null();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn driver_data(vendor: u32, device: u32, uuid: [u8; 16]) -> Vec<u8> {
        let mut d = Vec::new();
        for w in [32u32, 1, vendor, device] {
            d.extend_from_slice(&w.to_le_bytes());
        }
        d.extend_from_slice(&uuid);
        d.extend_from_slice(b"driver payload");
        d
    }

    #[test]
    fn intact_files_of_the_same_device_are_used_and_nothing_else() {
        let uuid = [7u8; 16];
        let data = driver_data(0x10de, 0x2335, uuid);
        let file = wrap(&data);
        assert_eq!(unwrap(&file, 0x10de, 0x2335, &uuid), Some(&data[..]));
        // Another device, another driver build, a corrupt or truncated file: ignored.
        assert_eq!(unwrap(&file, 0x10de, 0x2336, &uuid), None);
        assert_eq!(unwrap(&file, 0x10de, 0x2335, &[8u8; 16]), None);
        let mut flipped = file.clone();
        *flipped.last_mut().unwrap() ^= 1;
        assert_eq!(unwrap(&flipped, 0x10de, 0x2335, &uuid), None);
        assert_eq!(unwrap(&file[..file.len() - 1], 0x10de, 0x2335, &uuid), None);
        assert_eq!(unwrap(b"garbage", 0x10de, 0x2335, &uuid), None);
        assert_eq!(unwrap(&[], 0x10de, 0x2335, &uuid), None);
    }
}

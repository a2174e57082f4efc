//! Buffers and images on gpu-allocator: creation with debug names, uploads through staging
//! buffers, image readback. Every resource is destroyed explicitly by its owner.

use super::barrier::{transition, Access};
use super::context::Context;
use crate::error::{Error, Result, VkContext};
use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;

/// A buffer and its memory.
pub struct Buffer {
    /// Vulkan handle.
    pub raw: vk::Buffer,
    /// Size in bytes.
    pub size: u64,
    allocation: Option<Allocation>,
}

/// A 2D image, its view and memory, with the access it was last transitioned to.
pub struct Image {
    /// Vulkan handle.
    pub raw: vk::Image,
    /// Color view over the whole image.
    pub view: vk::ImageView,
    /// Texel format.
    pub format: vk::Format,
    /// Size in texels.
    pub extent: vk::Extent2D,
    /// Current layout/access (kept by [`transition`]).
    pub access: Access,
    /// Debug name.
    pub name: String,
    allocation: Option<Allocation>,
}

impl Image {
    /// Bytes per texel of `format` (the formats the solver uses).
    pub fn texel_bytes(format: vk::Format) -> u64 {
        match format {
            vk::Format::R16G16B16A16_SFLOAT => 8,
            vk::Format::R32G32B32A32_SFLOAT => 16,
            vk::Format::R32_SFLOAT | vk::Format::D32_SFLOAT => 4,
            vk::Format::R16_SFLOAT => 2,
            _ => 16,
        }
    }

    /// Bytes of texel memory.
    pub fn bytes(&self) -> u64 {
        self.extent.width as u64 * self.extent.height as u64 * Self::texel_bytes(self.format)
    }
}

impl Context {
    fn allocate(
        &self,
        name: &str,
        requirements: vk::MemoryRequirements,
        location: MemoryLocation,
        linear: bool,
    ) -> Result<Allocation> {
        self.allocator
            .lock()
            .map_err(|_| Error::Device("allocator lock poisoned".into()))?
            .allocate(&AllocationCreateDesc {
                name,
                requirements,
                location,
                linear,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            })
            .map_err(|e| Error::Device(format!("allocating {name}: {e}")))
    }

    /// Creates a buffer in `location`.
    pub fn create_buffer(
        &self,
        name: &str,
        size: u64,
        usage: vk::BufferUsageFlags,
        location: MemoryLocation,
    ) -> Result<Buffer> {
        let d = &self.device;
        let raw = unsafe {
            d.create_buffer(
                &vk::BufferCreateInfo::default()
                    .size(size.max(4))
                    .usage(usage),
                None,
            )
        }
        .vk(name)?;
        let requirements = unsafe { d.get_buffer_memory_requirements(raw) };
        let allocation = self
            .allocate(name, requirements, location, true)
            .inspect_err(|_| unsafe { d.destroy_buffer(raw, None) })?;
        unsafe { d.bind_buffer_memory(raw, allocation.memory(), allocation.offset()) }.vk(name)?;
        self.name(raw, name);
        Ok(Buffer {
            raw,
            size,
            allocation: Some(allocation),
        })
    }

    /// Creates a device-local buffer holding `bytes` (copied through a staging buffer).
    pub fn upload_buffer(
        &self,
        name: &str,
        bytes: &[u8],
        usage: vk::BufferUsageFlags,
    ) -> Result<Buffer> {
        let buf = self.create_buffer(
            name,
            bytes.len() as u64,
            usage | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuOnly,
        )?;
        if bytes.is_empty() {
            return Ok(buf);
        }
        let mut staging = self.staging(name, bytes)?;
        let size = bytes.len() as u64;
        let r = self.submit_and_wait(|cmd| unsafe {
            self.device.cmd_copy_buffer(
                cmd,
                staging.raw,
                buf.raw,
                &[vk::BufferCopy::default().size(size)],
            )
        });
        self.destroy_buffer(&mut staging);
        r.map(|_| buf)
    }

    fn staging(&self, name: &str, bytes: &[u8]) -> Result<Buffer> {
        let mut s = self.create_buffer(
            &format!("{name} (staging)"),
            bytes.len() as u64,
            vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::CpuToGpu,
        )?;
        let slice = s
            .allocation
            .as_mut()
            .and_then(|a| a.mapped_slice_mut())
            .ok_or_else(|| Error::Device("staging buffer is not host-visible".into()))?;
        slice[..bytes.len()].copy_from_slice(bytes);
        Ok(s)
    }

    /// Creates a sampled color-attachment image of `width × height` texels (or, for
    /// [`DEPTH_FORMAT`], a depth attachment).
    pub fn create_image(
        &self,
        name: &str,
        width: u32,
        height: u32,
        format: vk::Format,
    ) -> Result<Image> {
        let d = &self.device;
        let usage = if format == DEPTH_FORMAT {
            vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT
        } else {
            vk::ImageUsageFlags::COLOR_ATTACHMENT
                | vk::ImageUsageFlags::SAMPLED
                | vk::ImageUsageFlags::TRANSFER_SRC
                | vk::ImageUsageFlags::TRANSFER_DST
        };
        let extent = vk::Extent2D { width, height };
        let raw = unsafe {
            d.create_image(
                &vk::ImageCreateInfo::default()
                    .image_type(vk::ImageType::TYPE_2D)
                    .format(format)
                    .extent(extent.into())
                    .mip_levels(1)
                    .array_layers(1)
                    .samples(vk::SampleCountFlags::TYPE_1)
                    .tiling(vk::ImageTiling::OPTIMAL)
                    .usage(usage)
                    .initial_layout(vk::ImageLayout::UNDEFINED),
                None,
            )
        }
        .vk(name)?;
        let requirements = unsafe { d.get_image_memory_requirements(raw) };
        let allocation = self
            .allocate(name, requirements, MemoryLocation::GpuOnly, false)
            .inspect_err(|_| unsafe { d.destroy_image(raw, None) })?;
        unsafe { d.bind_image_memory(raw, allocation.memory(), allocation.offset()) }.vk(name)?;
        let view = unsafe {
            d.create_image_view(
                &vk::ImageViewCreateInfo::default()
                    .image(raw)
                    .view_type(vk::ImageViewType::TYPE_2D)
                    .format(format)
                    .subresource_range(range_for(format)),
                None,
            )
        }
        .vk(name)?;
        self.name(raw, name);
        self.name(view, name);
        Ok(Image {
            raw,
            view,
            format,
            extent,
            access: Access::Undefined,
            name: name.to_string(),
            allocation: Some(allocation),
        })
    }

    /// Fills an image with `bytes` (tightly packed texels) and leaves it ready for sampling.
    pub fn upload_image(&self, image: &mut Image, bytes: &[u8]) -> Result<()> {
        let mut staging = self.staging(&image.name, bytes)?;
        let extent = image.extent;
        let r = self.submit_and_wait(|cmd| {
            transition(self, cmd, &mut [(&mut *image, Access::TransferDst)]);
            unsafe {
                self.device.cmd_copy_buffer_to_image(
                    cmd,
                    staging.raw,
                    image.raw,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    &[copy_region(extent)],
                )
            };
            transition(self, cmd, &mut [(&mut *image, Access::Sampled)]);
        });
        self.destroy_buffer(&mut staging);
        r
    }

    /// Reads an image back to the host (tightly packed texels), then restores its access.
    pub fn read_image(&self, image: &mut Image) -> Result<Vec<u8>> {
        let size = image.bytes();
        let mut buf = self.create_buffer(
            &format!("{} (readback)", image.name),
            size,
            vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuToCpu,
        )?;
        let before = image.access;
        let extent = image.extent;
        let r = self.submit_and_wait(|cmd| {
            transition(self, cmd, &mut [(&mut *image, Access::TransferSrc)]);
            unsafe {
                self.device.cmd_copy_image_to_buffer(
                    cmd,
                    image.raw,
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    buf.raw,
                    &[copy_region(extent)],
                )
            };
            if before != Access::Undefined {
                transition(self, cmd, &mut [(&mut *image, before)]);
            }
        });
        let out = r.and_then(|_| {
            buf.allocation
                .as_ref()
                .and_then(|a| a.mapped_slice())
                .map(|s| s[..size as usize].to_vec())
                .ok_or_else(|| Error::Device("readback buffer is not host-visible".into()))
        });
        self.destroy_buffer(&mut buf);
        out
    }

    /// Frees a buffer (idempotent).
    pub fn destroy_buffer(&self, b: &mut Buffer) {
        if let Some(a) = b.allocation.take() {
            unsafe { self.device.destroy_buffer(b.raw, None) };
            if let Ok(mut al) = self.allocator.lock() {
                let _ = al.free(a);
            }
        }
    }

    /// Frees an image and its view (idempotent).
    pub fn destroy_image(&self, i: &mut Image) {
        if let Some(a) = i.allocation.take() {
            unsafe {
                self.device.destroy_image_view(i.view, None);
                self.device.destroy_image(i.raw, None);
            }
            if let Ok(mut al) = self.allocator.lock() {
                let _ = al.free(a);
            }
        }
    }
}

/// Format of depth attachments (frame and shadow-map passes).
pub const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;

/// The single subresource of an image of `format` (depth aspect for [`DEPTH_FORMAT`]).
pub fn range_for(format: vk::Format) -> vk::ImageSubresourceRange {
    vk::ImageSubresourceRange {
        aspect_mask: if format == DEPTH_FORMAT {
            vk::ImageAspectFlags::DEPTH
        } else {
            vk::ImageAspectFlags::COLOR
        },
        base_mip_level: 0,
        level_count: 1,
        base_array_layer: 0,
        layer_count: 1,
    }
}

fn copy_region(extent: vk::Extent2D) -> vk::BufferImageCopy {
    vk::BufferImageCopy::default()
        .image_subresource(vk::ImageSubresourceLayers {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            mip_level: 0,
            base_array_layer: 0,
            layer_count: 1,
        })
        .image_extent(extent.into())
}

//! GPU resources as data: an image or buffer is described once ([`ImageDesc`], [`BufferDesc`]:
//! name, size, format, usage, purpose); creation, the memory figures of `info` and `profile`
//! ([`MemoryReport`]) and destruction all derive from that description. Handles free
//! themselves when dropped (they keep their [`Context`] alive), uploads go through staging
//! buffers, and images can be read back.

use super::barrier::{transition, Access};
use super::context::Context;
use super::error::VkContext;
use crate::error::{Error, Result};
use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;
use serde::Serialize;
use std::collections::BTreeMap;
use std::sync::Arc;

/// What a resource is for: the groups of the memory report (`memory_bytes` of `info` and
/// `profile`), in report order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Purpose {
    /// Solver tables: I_ex (ping-pong and clusters), L_in, L_push, I_total, direct light, lobe factors.
    Tables,
    /// The global pass's link records.
    Links,
    /// Cone-filter tables.
    FilterTables,
    /// Per-row attributes and irradiance images, materials, bin centers.
    ElementAttributes,
    /// Push quads, local runs, pull lines.
    PushPullPrimitives,
    /// The frame's G-buffer, splat and output images.
    FrameImages,
    /// Shadow maps and their depth.
    ShadowMaps,
    /// The frame's geometry, lights and per-element records.
    FrameBuffers,
    /// Temporary probes and readbacks (not reported).
    Scratch,
}

impl Purpose {
    /// The key in `memory_bytes`.
    pub fn key(self) -> &'static str {
        match self {
            Purpose::Tables => "tables",
            Purpose::Links => "links",
            Purpose::FilterTables => "filter_tables",
            Purpose::ElementAttributes => "element_attributes",
            Purpose::PushPullPrimitives => "push_pull_primitives",
            Purpose::FrameImages => "frame_images",
            Purpose::ShadowMaps => "shadow_maps",
            Purpose::FrameBuffers => "frame_buffers",
            Purpose::Scratch => "scratch",
        }
    }
}

/// One 2D image: everything needed to create it and to know its memory.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ImageDesc {
    /// Debug name (also in validation messages).
    pub name: String,
    /// Width, texels.
    pub width: u32,
    /// Height, texels.
    pub height: u32,
    /// Texel format ([`DEPTH_FORMAT`] makes a depth attachment).
    pub format: vk::Format,
    /// Report group.
    pub purpose: Purpose,
}

impl ImageDesc {
    /// An image of `width × height` texels of `format`.
    pub fn new(
        name: impl Into<String>,
        width: u32,
        height: u32,
        format: vk::Format,
        purpose: Purpose,
    ) -> Self {
        Self {
            name: name.into(),
            width,
            height,
            format,
            purpose,
        }
    }

    /// Bytes of texel memory.
    pub fn bytes(&self) -> u64 {
        self.width as u64 * self.height as u64 * texel_bytes(self.format)
    }

    /// Usage flags: depth attachment, or color attachment + sampled + transfer.
    pub fn usage(&self) -> vk::ImageUsageFlags {
        if self.format == DEPTH_FORMAT {
            vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT
        } else {
            vk::ImageUsageFlags::COLOR_ATTACHMENT
                | vk::ImageUsageFlags::SAMPLED
                | vk::ImageUsageFlags::TRANSFER_SRC
                | vk::ImageUsageFlags::TRANSFER_DST
        }
    }

    /// Creates the image (device-local, with a view over all of it).
    pub fn create(&self, ctx: &Arc<Context>) -> Result<Image> {
        Image::new(ctx, self)
    }
}

/// One buffer: name, size, usage and purpose.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BufferDesc {
    /// Debug name.
    pub name: String,
    /// Bytes.
    pub size: u64,
    /// Usage (vertex or storage; transfer destination is added for uploads).
    pub usage: vk::BufferUsageFlags,
    /// Report group.
    pub purpose: Purpose,
}

impl BufferDesc {
    /// A buffer holding `count` records of `T`.
    pub fn of<T>(
        name: impl Into<String>,
        count: usize,
        usage: vk::BufferUsageFlags,
        purpose: Purpose,
    ) -> Self {
        Self {
            name: name.into(),
            size: (count * std::mem::size_of::<T>()) as u64,
            usage,
            purpose,
        }
    }

    /// Creates the buffer on the device and fills it with `bytes` (exactly [`BufferDesc::size`]).
    pub fn upload(&self, ctx: &Arc<Context>, bytes: &[u8]) -> Result<Buffer> {
        debug_assert_eq!(bytes.len() as u64, self.size, "{}", self.name);
        Buffer::upload(ctx, &self.name, bytes, self.usage)
    }
}

/// Bytes per texel of the formats the passes use.
pub fn texel_bytes(format: vk::Format) -> u64 {
    match format {
        vk::Format::R16G16B16A16_SFLOAT => 8,
        vk::Format::R32G32B32A32_SFLOAT | vk::Format::R32G32B32A32_UINT => 16,
        vk::Format::R32G32_SFLOAT => 8,
        vk::Format::R32_SFLOAT | vk::Format::D32_SFLOAT | vk::Format::R32_UINT => 4,
        vk::Format::R16_SFLOAT => 2,
        vk::Format::B8G8R8A8_UNORM
        | vk::Format::B8G8R8A8_SRGB
        | vk::Format::R8G8B8A8_UNORM
        | vk::Format::R8G8B8A8_SRGB => 4,
        _ => 16,
    }
}

/// Bytes of GPU memory by purpose (the `memory_bytes` of `info` and `profile`), summed from
/// resource descriptions or from the created resources, which are made from the same ones.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize)]
pub struct MemoryReport {
    /// Bytes per purpose.
    pub by_purpose: BTreeMap<Purpose, u64>,
}

impl MemoryReport {
    /// Adds `bytes` of `purpose` (scratch is not reported).
    pub fn add(&mut self, purpose: Purpose, bytes: u64) {
        if purpose != Purpose::Scratch {
            *self.by_purpose.entry(purpose).or_insert(0) += bytes;
        }
    }

    /// Adds every image description.
    pub fn images<'a>(mut self, descs: impl IntoIterator<Item = &'a ImageDesc>) -> Self {
        for d in descs {
            self.add(d.purpose, d.bytes());
        }
        self
    }

    /// Adds every buffer description.
    pub fn buffers<'a>(mut self, descs: impl IntoIterator<Item = &'a BufferDesc>) -> Self {
        for d in descs {
            self.add(d.purpose, d.size);
        }
        self
    }

    /// Bytes of one purpose.
    pub fn get(&self, purpose: Purpose) -> u64 {
        self.by_purpose.get(&purpose).copied().unwrap_or(0)
    }

    /// All bytes.
    pub fn total(&self) -> u64 {
        self.by_purpose.values().sum()
    }

    /// The solver's groups (every group but the frame's) and their total, by key: `tables`,
    /// `links`, `filter_tables`, `element_attributes`, `push_pull_primitives`, `total`.
    pub fn by_name(&self) -> BTreeMap<String, u64> {
        let mut m: BTreeMap<String, u64> = [
            Purpose::Tables,
            Purpose::Links,
            Purpose::FilterTables,
            Purpose::ElementAttributes,
            Purpose::PushPullPrimitives,
        ]
        .into_iter()
        .map(|p| (p.key().to_string(), self.get(p)))
        .collect();
        for (p, b) in &self.by_purpose {
            m.entry(p.key().to_string()).or_insert(*b);
        }
        m.insert("total".into(), self.total());
        m
    }
}

fn allocate(
    ctx: &Context,
    name: &str,
    requirements: vk::MemoryRequirements,
    location: MemoryLocation,
    linear: bool,
) -> Result<Allocation> {
    ctx.allocator
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

fn free(ctx: &Context, allocation: Allocation) {
    if let Ok(mut al) = ctx.allocator.lock() {
        let _ = al.free(allocation);
    }
}

/// A buffer and its memory; freed when dropped.
pub struct Buffer {
    ctx: Arc<Context>,
    /// Vulkan handle.
    pub raw: vk::Buffer,
    /// Size in bytes.
    pub size: u64,
    allocation: Option<Allocation>,
}

impl Buffer {
    /// Creates a buffer of `size` bytes in `location`.
    pub fn new(
        ctx: &Arc<Context>,
        name: &str,
        size: u64,
        usage: vk::BufferUsageFlags,
        location: MemoryLocation,
    ) -> Result<Self> {
        let d = &ctx.device;
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
        let allocation = allocate(ctx, name, requirements, location, true)
            .inspect_err(|_| unsafe { d.destroy_buffer(raw, None) })?;
        let buffer = Self {
            ctx: ctx.clone(),
            raw,
            size,
            allocation: Some(allocation),
        };
        let a = buffer.allocation.as_ref().expect("just allocated");
        unsafe { d.bind_buffer_memory(raw, a.memory(), a.offset()) }.vk(name)?;
        ctx.name(raw, name);
        Ok(buffer)
    }

    /// Creates a device-local buffer holding `bytes` (copied through a staging buffer).
    pub fn upload(
        ctx: &Arc<Context>,
        name: &str,
        bytes: &[u8],
        usage: vk::BufferUsageFlags,
    ) -> Result<Self> {
        let buf = Self::new(
            ctx,
            name,
            bytes.len() as u64,
            usage | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuOnly,
        )?;
        if bytes.is_empty() {
            return Ok(buf);
        }
        let staging = Self::staging(ctx, name, bytes)?;
        let size = bytes.len() as u64;
        ctx.submit_and_wait(|cmd| unsafe {
            ctx.device.cmd_copy_buffer(
                cmd,
                staging.raw,
                buf.raw,
                &[vk::BufferCopy::default().size(size)],
            )
        })?;
        Ok(buf)
    }

    /// A host-visible buffer holding `bytes`, the source of a copy.
    pub(crate) fn staging(ctx: &Arc<Context>, name: &str, bytes: &[u8]) -> Result<Self> {
        let mut s = Self::new(
            ctx,
            &format!("{name} (staging)"),
            bytes.len() as u64,
            vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::CpuToGpu,
        )?;
        s.mapped_mut()?[..bytes.len()].copy_from_slice(bytes);
        Ok(s)
    }

    /// The mapped bytes of a host-visible buffer.
    pub fn mapped(&self) -> Result<&[u8]> {
        self.allocation
            .as_ref()
            .and_then(|a| a.mapped_slice())
            .map(|s| &s[..self.size as usize])
            .ok_or_else(|| Error::Device("buffer is not host-visible".into()))
    }

    /// The mapped bytes of a host-visible buffer, writable.
    pub fn mapped_mut(&mut self) -> Result<&mut [u8]> {
        let size = self.size as usize;
        self.allocation
            .as_mut()
            .and_then(|a| a.mapped_slice_mut())
            .map(|s| &mut s[..size])
            .ok_or_else(|| Error::Device("buffer is not host-visible".into()))
    }
}

impl Drop for Buffer {
    fn drop(&mut self) {
        if let Some(a) = self.allocation.take() {
            unsafe { self.ctx.device.destroy_buffer(self.raw, None) };
            free(&self.ctx, a);
        }
    }
}

/// A 2D image, its view and memory, with the access it was last transitioned to; freed when
/// dropped.
pub struct Image {
    ctx: Arc<Context>,
    /// Vulkan handle.
    pub raw: vk::Image,
    /// Color (or depth) view over the whole image.
    pub view: vk::ImageView,
    /// Texel format.
    pub format: vk::Format,
    /// Size in texels.
    pub extent: vk::Extent2D,
    /// Current layout/access (kept by [`transition`]).
    pub access: Access,
    /// The description it was made from.
    pub desc: ImageDesc,
    allocation: Option<Allocation>,
}

impl Image {
    /// Creates the image `desc` describes.
    pub fn new(ctx: &Arc<Context>, desc: &ImageDesc) -> Result<Self> {
        let d = &ctx.device;
        let name = desc.name.as_str();
        let extent = vk::Extent2D {
            width: desc.width,
            height: desc.height,
        };
        let raw = unsafe {
            d.create_image(
                &vk::ImageCreateInfo::default()
                    .image_type(vk::ImageType::TYPE_2D)
                    .format(desc.format)
                    .extent(extent.into())
                    .mip_levels(1)
                    .array_layers(1)
                    .samples(vk::SampleCountFlags::TYPE_1)
                    .tiling(vk::ImageTiling::OPTIMAL)
                    .usage(desc.usage())
                    .initial_layout(vk::ImageLayout::UNDEFINED),
                None,
            )
        }
        .vk(name)?;
        let requirements = unsafe { d.get_image_memory_requirements(raw) };
        let allocation = allocate(ctx, name, requirements, MemoryLocation::GpuOnly, false)
            .inspect_err(|_| unsafe { d.destroy_image(raw, None) })?;
        let mut image = Self {
            ctx: ctx.clone(),
            raw,
            view: vk::ImageView::null(),
            format: desc.format,
            extent,
            access: Access::Undefined,
            desc: desc.clone(),
            allocation: Some(allocation),
        };
        let a = image.allocation.as_ref().expect("just allocated");
        unsafe { d.bind_image_memory(raw, a.memory(), a.offset()) }.vk(name)?;
        image.view = unsafe {
            d.create_image_view(
                &vk::ImageViewCreateInfo::default()
                    .image(raw)
                    .view_type(vk::ImageViewType::TYPE_2D)
                    .format(desc.format)
                    .subresource_range(range_for(desc.format)),
                None,
            )
        }
        .vk(name)?;
        ctx.name(raw, name);
        ctx.name(image.view, name);
        Ok(image)
    }

    /// Bytes of texel memory.
    pub fn bytes(&self) -> u64 {
        self.desc.bytes()
    }

    /// Debug name.
    pub fn name(&self) -> &str {
        &self.desc.name
    }

    /// Fills the image with `bytes` (tightly packed texels) and leaves it ready for sampling.
    pub fn upload(&mut self, bytes: &[u8]) -> Result<()> {
        let ctx = self.ctx.clone();
        let staging = Buffer::staging(&ctx, self.name(), bytes)?;
        let extent = self.extent;
        ctx.submit_and_wait(|cmd| {
            transition(&ctx, cmd, &mut [(&mut *self, Access::TransferDst)]);
            unsafe {
                ctx.device.cmd_copy_buffer_to_image(
                    cmd,
                    staging.raw,
                    self.raw,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    &[copy_region(extent)],
                )
            };
            transition(&ctx, cmd, &mut [(&mut *self, Access::Sampled)]);
        })
    }

    /// Reads the image back to the host (tightly packed texels), then restores its access.
    pub fn read(&mut self) -> Result<Vec<u8>> {
        let ctx = self.ctx.clone();
        let size = self.bytes();
        let buf = Buffer::new(
            &ctx,
            &format!("{} (readback)", self.name()),
            size,
            vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuToCpu,
        )?;
        let before = self.access;
        let extent = self.extent;
        ctx.submit_and_wait(|cmd| {
            transition(&ctx, cmd, &mut [(&mut *self, Access::TransferSrc)]);
            unsafe {
                ctx.device.cmd_copy_image_to_buffer(
                    cmd,
                    self.raw,
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    buf.raw,
                    &[copy_region(extent)],
                )
            };
            if before != Access::Undefined {
                transition(&ctx, cmd, &mut [(&mut *self, before)]);
            }
        })?;
        Ok(buf.mapped()?.to_vec())
    }
}

impl Drop for Image {
    fn drop(&mut self) {
        if let Some(a) = self.allocation.take() {
            unsafe {
                self.ctx.device.destroy_image_view(self.view, None);
                self.ctx.device.destroy_image(self.raw, None);
            }
            free(&self.ctx, a);
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

pub(crate) fn copy_region(extent: vk::Extent2D) -> vk::BufferImageCopy {
    vk::BufferImageCopy::default()
        .image_subresource(vk::ImageSubresourceLayers {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            mip_level: 0,
            base_array_layer: 0,
            layer_count: 1,
        })
        .image_extent(extent.into())
}

/// Declares a named set of resources, one field each, generic over what a field holds: a
/// description ([`ImageDesc`], [`BufferDesc`]) in the plan, the created [`Image`] or [`Buffer`]
/// on the device. `iter` visits every field; `try_map` turns descriptions into resources.
macro_rules! resource_set {
    ($(#[$m:meta])* pub struct $name:ident { $($(#[$fm:meta])* pub $field:ident,)+ }) => {
        $(#[$m])*
        pub struct $name<T> {
            $($(#[$fm])* pub $field: T,)+
        }

        impl<T> $name<T> {
            /// Every field, in declaration order.
            pub fn iter(&self) -> impl Iterator<Item = &T> {
                [$(&self.$field),+].into_iter()
            }

            /// Every field, writable, in declaration order.
            #[allow(dead_code)]
            pub fn iter_mut(&mut self) -> impl Iterator<Item = &mut T> {
                [$(&mut self.$field),+].into_iter()
            }

            /// The same set with every field mapped by `f` (stops at the first error).
            pub fn try_map<U, E>(
                &self,
                mut f: impl FnMut(&T) -> std::result::Result<U, E>,
            ) -> std::result::Result<$name<U>, E> {
                Ok($name { $($field: f(&self.$field)?,)+ })
            }
        }
    };
}
pub(crate) use resource_set;

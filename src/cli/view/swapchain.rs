//! The window's swapchain (recreated on resize, out-of-date and suboptimal; one
//! render-finished semaphore per image, as the validation layers expect) and the one recorded
//! step of presenting: the engine's frame image blitted onto a swapchain image (sRGB-encoded by
//! the blit, letterboxed to keep the camera's aspect), optionally copied to a host buffer for a
//! screenshot.

use super::vulkan::Host;
use anyhow::{bail, Context as _, Result};
use ash::vk;

/// The swapchain, its images and their render-finished semaphores.
pub struct Swapchain {
    /// The swapchain (null after [`Swapchain::destroy`]).
    pub raw: vk::SwapchainKHR,
    /// Its images.
    pub images: Vec<vk::Image>,
    /// Their format (an sRGB one when offered).
    pub format: vk::Format,
    /// Their size.
    pub extent: vk::Extent2D,
    /// Signalled by the frame's submission, waited on by the present of that image.
    pub render_finished: Vec<vk::Semaphore>,
}

impl Swapchain {
    /// A swapchain of the surface at `size` (the surface's own extent wins where it has one),
    /// replacing `old` (destroyed here, after the new one exists).
    pub fn new(host: &Host, size: (u32, u32), old: Option<Swapchain>) -> Result<Self> {
        let (s, pd, surface) = (
            &host.inst.surface_fn,
            host.physical_device,
            host.inst.surface,
        );
        let caps = unsafe { s.get_physical_device_surface_capabilities(pd, surface) }?;
        let formats = unsafe { s.get_physical_device_surface_formats(pd, surface) }?;
        let srgb = [vk::Format::B8G8R8A8_SRGB, vk::Format::R8G8B8A8_SRGB];
        let format = formats
            .iter()
            .find(|f| {
                srgb.contains(&f.format) && f.color_space == vk::ColorSpaceKHR::SRGB_NONLINEAR
            })
            .copied()
            .context("the surface offers no 8-bit sRGB format (B8G8R8A8_SRGB / R8G8B8A8_SRGB)")?;
        let need = vk::ImageUsageFlags::TRANSFER_DST | vk::ImageUsageFlags::TRANSFER_SRC;
        if !caps.supported_usage_flags.contains(need) {
            bail!("the surface's images cannot be blitted to and read back (transfer usage)");
        }
        let extent = if caps.current_extent.width != u32::MAX {
            caps.current_extent
        } else {
            vk::Extent2D {
                width: size
                    .0
                    .clamp(caps.min_image_extent.width, caps.max_image_extent.width),
                height: size
                    .1
                    .clamp(caps.min_image_extent.height, caps.max_image_extent.height),
            }
        };
        let mut count = caps.min_image_count + 1;
        if caps.max_image_count > 0 {
            count = count.min(caps.max_image_count);
        }
        let old_raw = old.as_ref().map_or(vk::SwapchainKHR::null(), |o| o.raw);
        let info = vk::SwapchainCreateInfoKHR::default()
            .surface(surface)
            .min_image_count(count)
            .image_format(format.format)
            .image_color_space(format.color_space)
            .image_extent(extent)
            .image_array_layers(1)
            .image_usage(need)
            .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
            .pre_transform(caps.current_transform)
            .composite_alpha(vk::CompositeAlphaFlagsKHR::OPAQUE)
            .present_mode(vk::PresentModeKHR::FIFO)
            .clipped(true)
            .old_swapchain(old_raw);
        let raw = unsafe { host.swapchain_fn.create_swapchain(&info, None) }
            .context("creating the swapchain")?;
        if let Some(mut o) = old {
            o.destroy(host);
        }
        let images = unsafe { host.swapchain_fn.get_swapchain_images(raw) }?;
        let mut render_finished = Vec::with_capacity(images.len());
        for _ in &images {
            render_finished.push(unsafe {
                host.device
                    .create_semaphore(&vk::SemaphoreCreateInfo::default(), None)?
            });
        }
        Ok(Self {
            raw,
            images,
            format: format.format,
            extent,
            render_finished,
        })
    }

    /// Destroys the swapchain and its semaphores (the device must be idle).
    pub fn destroy(&mut self, host: &Host) {
        unsafe {
            let _ = host.device.device_wait_idle();
            for s in self.render_finished.drain(..) {
                host.device.destroy_semaphore(s, None);
            }
            if self.raw != vk::SwapchainKHR::null() {
                host.swapchain_fn.destroy_swapchain(self.raw, None);
            }
        }
        self.raw = vk::SwapchainKHR::null();
        self.images.clear();
    }
}

/// A host-visible buffer a screenshot is copied into.
pub struct Readback {
    /// The buffer.
    pub buffer: vk::Buffer,
    memory: vk::DeviceMemory,
    /// Its size in bytes.
    pub size: u64,
}

impl Readback {
    /// A host-visible, coherent buffer of `size` bytes.
    pub fn new(host: &Host, size: u64) -> Result<Self> {
        let d = &host.device;
        let buffer = unsafe {
            d.create_buffer(
                &vk::BufferCreateInfo::default()
                    .size(size)
                    .usage(vk::BufferUsageFlags::TRANSFER_DST),
                None,
            )
        }?;
        let req = unsafe { d.get_buffer_memory_requirements(buffer) };
        let props = unsafe {
            host.inst
                .instance
                .get_physical_device_memory_properties(host.physical_device)
        };
        let want = vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT;
        let Some(kind) = (0..props.memory_type_count).find(|&i| {
            req.memory_type_bits & (1 << i) != 0
                && props.memory_types[i as usize].property_flags.contains(want)
        }) else {
            unsafe { d.destroy_buffer(buffer, None) };
            bail!("no host-visible memory for the screenshot");
        };
        let memory = unsafe {
            d.allocate_memory(
                &vk::MemoryAllocateInfo::default()
                    .allocation_size(req.size)
                    .memory_type_index(kind),
                None,
            )
        };
        let memory = match memory {
            Ok(m) => m,
            Err(e) => {
                unsafe { d.destroy_buffer(buffer, None) };
                return Err(e.into());
            }
        };
        unsafe { d.bind_buffer_memory(buffer, memory, 0) }?;
        Ok(Self {
            buffer,
            memory,
            size,
        })
    }

    /// The buffer's bytes (after the copy's submission completed).
    pub fn read(&self, host: &Host) -> Result<Vec<u8>> {
        let d = &host.device;
        unsafe {
            let p = d.map_memory(self.memory, 0, self.size, vk::MemoryMapFlags::empty())?;
            let bytes = std::slice::from_raw_parts(p as *const u8, self.size as usize).to_vec();
            d.unmap_memory(self.memory);
            Ok(bytes)
        }
    }

    /// Frees the buffer and its memory.
    pub fn destroy(&self, host: &Host) {
        unsafe {
            host.device.destroy_buffer(self.buffer, None);
            host.device.free_memory(self.memory, None);
        }
    }
}

/// The engine's frame image as the blit's source.
pub struct Source {
    /// The image (in shader-read layout after the engine's recorded frame; left so).
    pub image: vk::Image,
    /// Its size.
    pub extent: vk::Extent2D,
    /// Whether its format can be filtered linearly (else a scaled blit samples nearest).
    pub linear: bool,
}

fn barrier(
    image: vk::Image,
    (old, new): (vk::ImageLayout, vk::ImageLayout),
) -> vk::ImageMemoryBarrier2<'static> {
    // Coarse stages: one blit per frame, clarity over overlap.
    vk::ImageMemoryBarrier2::default()
        .src_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
        .src_access_mask(vk::AccessFlags2::MEMORY_WRITE)
        .dst_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
        .dst_access_mask(vk::AccessFlags2::MEMORY_READ | vk::AccessFlags2::MEMORY_WRITE)
        .old_layout(old)
        .new_layout(new)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .image(image)
        .subresource_range(
            vk::ImageSubresourceRange::default()
                .aspect_mask(vk::ImageAspectFlags::COLOR)
                .level_count(1)
                .layer_count(1),
        )
}

fn barriers(d: &ash::Device, cmd: vk::CommandBuffer, list: &[vk::ImageMemoryBarrier2]) {
    unsafe {
        d.cmd_pipeline_barrier2(
            cmd,
            &vk::DependencyInfo::default().image_memory_barriers(list),
        )
    };
}

/// Where the frame lands in a `dst` image: as large as fits with the frame's aspect, centred.
pub fn letterbox(src: vk::Extent2D, dst: vk::Extent2D) -> [vk::Offset3D; 2] {
    let scale = (dst.width as f64 / src.width as f64).min(dst.height as f64 / src.height as f64);
    let (w, h) = (
        ((src.width as f64 * scale).round() as i32).clamp(1, dst.width as i32),
        ((src.height as f64 * scale).round() as i32).clamp(1, dst.height as i32),
    );
    let (x, y) = ((dst.width as i32 - w) / 2, (dst.height as i32 - h) / 2);
    [
        vk::Offset3D { x, y, z: 0 },
        vk::Offset3D {
            x: x + w,
            y: y + h,
            z: 1,
        },
    ]
}

/// Records: clear swapchain image `dst` (of `extent`), blit `src` onto it letterboxed, and
/// either leave it for presenting or first copy it into `shot`.
pub fn record_present(
    d: &ash::Device,
    cmd: vk::CommandBuffer,
    src: &Source,
    dst: vk::Image,
    extent: vk::Extent2D,
    shot: Option<&Readback>,
) {
    use vk::ImageLayout as L;
    barriers(
        d,
        cmd,
        &[
            barrier(
                src.image,
                (L::SHADER_READ_ONLY_OPTIMAL, L::TRANSFER_SRC_OPTIMAL),
            ),
            barrier(dst, (L::UNDEFINED, L::TRANSFER_DST_OPTIMAL)),
        ],
    );
    let range = vk::ImageSubresourceRange::default()
        .aspect_mask(vk::ImageAspectFlags::COLOR)
        .level_count(1)
        .layer_count(1);
    unsafe {
        d.cmd_clear_color_image(
            cmd,
            dst,
            L::TRANSFER_DST_OPTIMAL,
            &vk::ClearColorValue::default(),
            &[range],
        )
    };
    barriers(
        d,
        cmd,
        &[barrier(
            dst,
            (L::TRANSFER_DST_OPTIMAL, L::TRANSFER_DST_OPTIMAL),
        )],
    );
    let layers = vk::ImageSubresourceLayers::default()
        .aspect_mask(vk::ImageAspectFlags::COLOR)
        .layer_count(1);
    let to = letterbox(src.extent, extent);
    let same = (to[1].x - to[0].x) as u32 == src.extent.width
        && (to[1].y - to[0].y) as u32 == src.extent.height;
    let region = vk::ImageBlit::default()
        .src_subresource(layers)
        .src_offsets([
            vk::Offset3D::default(),
            vk::Offset3D {
                x: src.extent.width as i32,
                y: src.extent.height as i32,
                z: 1,
            },
        ])
        .dst_subresource(layers)
        .dst_offsets(to);
    // 1:1 is an exact copy either way; a scaled view filters when the format allows.
    let filter = if !same && src.linear {
        vk::Filter::LINEAR
    } else {
        vk::Filter::NEAREST
    };
    unsafe {
        d.cmd_blit_image(
            cmd,
            src.image,
            L::TRANSFER_SRC_OPTIMAL,
            dst,
            L::TRANSFER_DST_OPTIMAL,
            &[region],
            filter,
        )
    };
    let back = barrier(
        src.image,
        (L::TRANSFER_SRC_OPTIMAL, L::SHADER_READ_ONLY_OPTIMAL),
    );
    match shot {
        None => barriers(
            d,
            cmd,
            &[
                back,
                barrier(dst, (L::TRANSFER_DST_OPTIMAL, L::PRESENT_SRC_KHR)),
            ],
        ),
        Some(buf) => {
            barriers(
                d,
                cmd,
                &[
                    back,
                    barrier(dst, (L::TRANSFER_DST_OPTIMAL, L::TRANSFER_SRC_OPTIMAL)),
                ],
            );
            let copy = vk::BufferImageCopy::default()
                .image_subresource(layers)
                .image_extent(vk::Extent3D {
                    width: extent.width,
                    height: extent.height,
                    depth: 1,
                });
            unsafe {
                d.cmd_copy_image_to_buffer(cmd, dst, L::TRANSFER_SRC_OPTIMAL, buf.buffer, &[copy])
            };
            barriers(
                d,
                cmd,
                &[barrier(dst, (L::TRANSFER_SRC_OPTIMAL, L::PRESENT_SRC_KHR))],
            );
        }
    }
}

/// The screenshot's pixels as RGB bytes, from a swapchain image of `format`.
pub fn to_rgb(bytes: &[u8], format: vk::Format) -> Vec<u8> {
    let bgr = format == vk::Format::B8G8R8A8_SRGB;
    bytes
        .chunks_exact(4)
        .flat_map(|p| {
            if bgr {
                [p[2], p[1], p[0]]
            } else {
                [p[0], p[1], p[2]]
            }
        })
        .collect()
}

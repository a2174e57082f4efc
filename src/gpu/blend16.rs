//! Float16 blending rounded to nearest, emulated: the paper's float16 accumulation of L_in and
//! L_push on a device whose float16 blending truncates (lavapipe), so that CI measures and holds
//! the error of that path. The incident tables are then float32 images; the global pass and the
//! push's additive depths add their fragments into the `rounded` buffer instead of blending
//! (`glsl/round16.glsl`: a compare-and-swap loop that rounds every sum to the nearest float16,
//! ties to even, as a rounding device blends), and the buffer is copied over L_in after each such
//! draw. The push's overwriting depths round what they store (`glsl/push_even.frag`). Test-only
//! ([`crate::gpu::GpuOptions::emulate_f16_rounding`]): a real device blends.

use super::barrier::{transition, Access};
use super::context::Context;
use super::resources::Resources;
use ash::vk;

fn barrier(
    ctx: &Context,
    cmd: vk::CommandBuffer,
    src: (vk::PipelineStageFlags2, vk::AccessFlags2),
    dst: (vk::PipelineStageFlags2, vk::AccessFlags2),
) {
    let mb = [vk::MemoryBarrier2::default()
        .src_stage_mask(src.0)
        .src_access_mask(src.1)
        .dst_stage_mask(dst.0)
        .dst_access_mask(dst.1)];
    let dep = vk::DependencyInfo::default().memory_barriers(&mb);
    unsafe { ctx.device.cmd_pipeline_barrier2(cmd, &dep) };
}

const FRAGMENT: (vk::PipelineStageFlags2, vk::AccessFlags2) = (
    vk::PipelineStageFlags2::FRAGMENT_SHADER,
    vk::AccessFlags2::from_raw(
        vk::AccessFlags2::SHADER_STORAGE_READ.as_raw()
            | vk::AccessFlags2::SHADER_STORAGE_WRITE.as_raw(),
    ),
);

/// Before the global pass: the sums start at zero (L_in is cleared).
pub fn clear(ctx: &Context, cmd: vk::CommandBuffer, res: &Resources) {
    let transfer = (
        vk::PipelineStageFlags2::CLEAR | vk::PipelineStageFlags2::COPY,
        vk::AccessFlags2::TRANSFER_READ | vk::AccessFlags2::TRANSFER_WRITE,
    );
    // The last iteration's shader adds and its copies out of the buffer come first.
    let before = (
        FRAGMENT.0 | vk::PipelineStageFlags2::COPY,
        FRAGMENT.1 | vk::AccessFlags2::TRANSFER_READ,
    );
    barrier(ctx, cmd, before, transfer);
    unsafe {
        ctx.device
            .cmd_fill_buffer(cmd, res.buffers.rounded.raw, 0, vk::WHOLE_SIZE, 0)
    };
    barrier(
        ctx,
        cmd,
        (
            vk::PipelineStageFlags2::CLEAR,
            vk::AccessFlags2::TRANSFER_WRITE,
        ),
        FRAGMENT,
    );
}

/// After a draw that added into the buffer: L_in becomes the buffer's sums (which then go on
/// holding L_in for the push's additive depths).
pub fn store(ctx: &Context, cmd: vk::CommandBuffer, res: &mut Resources) {
    let copy_read = (
        vk::PipelineStageFlags2::COPY,
        vk::AccessFlags2::TRANSFER_READ,
    );
    barrier(ctx, cmd, FRAGMENT, copy_read);
    let l_in = &mut res.images.l_in;
    transition(ctx, cmd, &mut [(l_in, Access::TransferDst)]);
    let region = vk::BufferImageCopy::default()
        .image_subresource(vk::ImageSubresourceLayers {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            mip_level: 0,
            base_array_layer: 0,
            layer_count: 1,
        })
        .image_extent(vk::Extent3D {
            width: l_in.extent.width,
            height: l_in.extent.height,
            depth: 1,
        });
    unsafe {
        ctx.device.cmd_copy_buffer_to_image(
            cmd,
            res.buffers.rounded.raw,
            l_in.raw,
            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            &[region],
        )
    };
    // The next draw's adds wait for the copy's reads.
    barrier(ctx, cmd, copy_read, FRAGMENT);
}

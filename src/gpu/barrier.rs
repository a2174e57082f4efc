//! The one place where image layouts change: every pass declares how it will use each image and
//! [`transition`] emits the synchronization2 barrier from the image's last use.

use super::context::Context;
use super::memory::{range_for, Image};
use ash::vk;

/// How an image is used next (decides layout, stage and access mask).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Access {
    /// Never used; contents undefined.
    Undefined,
    /// Color attachment written (and blended) by a draw.
    Attachment,
    /// Depth attachment tested and written by a draw.
    Depth,
    /// Read by fragment or vertex shaders with `texelFetch`.
    Sampled,
    /// Source of a copy (readback).
    TransferSrc,
    /// Destination of a copy or clear.
    TransferDst,
}

impl Access {
    /// The image layout of this state.
    pub fn layout(self) -> vk::ImageLayout {
        match self {
            Access::Undefined => vk::ImageLayout::UNDEFINED,
            Access::Attachment => vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
            Access::Depth => vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL,
            Access::Sampled => vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
            Access::TransferSrc => vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            Access::TransferDst => vk::ImageLayout::TRANSFER_DST_OPTIMAL,
        }
    }

    /// The stages and accesses of this state (a later barrier's source scope).
    pub fn stage_access(self) -> (vk::PipelineStageFlags2, vk::AccessFlags2) {
        match self {
            Access::Undefined => (vk::PipelineStageFlags2::TOP_OF_PIPE, vk::AccessFlags2::NONE),
            Access::Attachment => (
                vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT,
                vk::AccessFlags2::COLOR_ATTACHMENT_READ | vk::AccessFlags2::COLOR_ATTACHMENT_WRITE,
            ),
            Access::Depth => (
                vk::PipelineStageFlags2::EARLY_FRAGMENT_TESTS
                    | vk::PipelineStageFlags2::LATE_FRAGMENT_TESTS,
                vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_READ
                    | vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_WRITE,
            ),
            Access::Sampled => (
                vk::PipelineStageFlags2::VERTEX_SHADER
                    | vk::PipelineStageFlags2::FRAGMENT_SHADER
                    | vk::PipelineStageFlags2::COMPUTE_SHADER,
                vk::AccessFlags2::SHADER_SAMPLED_READ,
            ),
            Access::TransferSrc => (
                vk::PipelineStageFlags2::COPY,
                vk::AccessFlags2::TRANSFER_READ,
            ),
            Access::TransferDst => (
                vk::PipelineStageFlags2::COPY | vk::PipelineStageFlags2::CLEAR,
                vk::AccessFlags2::TRANSFER_WRITE,
            ),
        }
    }
}

/// Transitions each image to its next access with one barrier command. Read-after-read
/// (sampled → sampled) needs no barrier and is skipped; everything else is synchronized.
pub fn transition(ctx: &Context, cmd: vk::CommandBuffer, images: &mut [(&mut Image, Access)]) {
    let mut barriers = Vec::with_capacity(images.len());
    for (img, next) in images.iter_mut() {
        let prev = img.access;
        if prev == Access::Sampled && *next == Access::Sampled {
            continue;
        }
        let (src_stage, src_access) = prev.stage_access();
        let (dst_stage, dst_access) = next.stage_access();
        barriers.push(
            vk::ImageMemoryBarrier2::default()
                .src_stage_mask(src_stage)
                .src_access_mask(src_access)
                .dst_stage_mask(dst_stage)
                .dst_access_mask(dst_access)
                .old_layout(prev.layout())
                .new_layout(next.layout())
                .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .image(img.raw)
                .subresource_range(range_for(img.format)),
        );
        img.access = *next;
    }
    if barriers.is_empty() {
        return;
    }
    let dep = vk::DependencyInfo::default().image_memory_barriers(&barriers);
    unsafe { ctx.device.cmd_pipeline_barrier2(cmd, &dep) };
}

/// Orders copies into buffers after the vertex input and shader reads recorded before them
/// (an update recorded into a command buffer after a frame's draws).
pub fn before_uploads(ctx: &Context, cmd: vk::CommandBuffer) {
    let mb = [vk::MemoryBarrier2::default()
        .src_stage_mask(
            vk::PipelineStageFlags2::VERTEX_INPUT
                | vk::PipelineStageFlags2::VERTEX_SHADER
                | vk::PipelineStageFlags2::FRAGMENT_SHADER,
        )
        .src_access_mask(
            vk::AccessFlags2::VERTEX_ATTRIBUTE_READ | vk::AccessFlags2::SHADER_STORAGE_READ,
        )
        .dst_stage_mask(vk::PipelineStageFlags2::COPY)
        .dst_access_mask(vk::AccessFlags2::TRANSFER_WRITE)];
    let dep = vk::DependencyInfo::default().memory_barriers(&mb);
    unsafe { ctx.device.cmd_pipeline_barrier2(cmd, &dep) };
}

/// Makes buffer uploads (copies) visible to vertex input and shader reads.
pub fn after_uploads(ctx: &Context, cmd: vk::CommandBuffer) {
    let mb = [vk::MemoryBarrier2::default()
        .src_stage_mask(vk::PipelineStageFlags2::COPY)
        .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
        .dst_stage_mask(
            vk::PipelineStageFlags2::VERTEX_INPUT
                | vk::PipelineStageFlags2::VERTEX_SHADER
                | vk::PipelineStageFlags2::FRAGMENT_SHADER,
        )
        .dst_access_mask(
            vk::AccessFlags2::VERTEX_ATTRIBUTE_READ | vk::AccessFlags2::SHADER_STORAGE_READ,
        )];
    let dep = vk::DependencyInfo::default().memory_barriers(&mb);
    unsafe { ctx.device.cmd_pipeline_barrier2(cmd, &dep) };
}

//! Splatting (§4.3, second pass): a fan around each flat-surface element's center, additive
//! into (Σ w·L, Σ w) where the G-buffer shows the same surface. Compose normalizes.

use super::targets::{FrameImages, RGBA32F};
use super::{begin_rendering, end_rendering, frame_desc, FramePass, Load};
use crate::error::Result;
use crate::gpu::barrier::{transition, Access};
use crate::gpu::context::Context;
use crate::gpu::handle::Owned;
use crate::gpu::layout::FrameConstants;
use crate::gpu::memory::Image;
use crate::gpu::pipelines::{create, PipelineDesc, Target};
use ash::vk;
use std::sync::Arc;

/// Triangles per fan × 3.
pub const FAN_VERTICES: u32 = 24;

/// The pipeline: one fan per leaf-slot instance, additive.
pub fn pipeline(
    ctx: &Arc<Context>,
    layout: &Owned<vk::PipelineLayout>,
    specialization: &[u32],
) -> Result<Owned<vk::Pipeline>> {
    let targets = [Target {
        format: RGBA32F,
        additive: true,
        write: true,
    }];
    let desc = PipelineDesc {
        stride: 4,
        attributes: &[(vk::Format::R32_UINT, 0)],
        per_vertex: false,
        ..frame_desc(
            "splat",
            "splat.vert",
            "splat.frag",
            &targets,
            specialization,
        )
    };
    create(ctx, layout, &desc)
}

/// Records the splat pass.
pub fn record(
    p: &FramePass<'_>,
    pipeline: &Owned<vk::Pipeline>,
    im: &mut FrameImages<Image>,
    instances: vk::Buffer,
    count: u32,
    constants: FrameConstants,
) {
    transition(p.ctx, p.cmd, &mut [(&mut im.splat, Access::Attachment)]);
    begin_rendering(p.ctx, p.cmd, &[(&im.splat, Load::Clear)]);
    p.bind(pipeline, &constants);
    p.draw(instances, FAN_VERTICES, count);
    end_rendering(p.ctx, p.cmd);
    transition(p.ctx, p.cmd, &mut [(&mut im.splat, Access::Sampled)]);
}

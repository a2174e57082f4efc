//! Splatting (§4.3, second pass): a fan around each flat-surface element's center, additive
//! into (Σ w·L, Σ w) where the G-buffer shows the same surface. Compose normalizes.

use super::{begin_rendering, end_rendering, FramePass, Load};
use crate::gpu::barrier::{transition, Access};
use crate::gpu::frame::FrameImages;
use crate::gpu::layout::FrameConstants;
use ash::vk;

/// Triangles per fan × 3.
pub const FAN_VERTICES: u32 = 24;

/// Records the splat pass.
pub fn record(
    p: &FramePass<'_>,
    pipeline: vk::Pipeline,
    im: &mut FrameImages,
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

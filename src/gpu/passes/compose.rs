//! Compose (§4.3 third pass, plus §3.3's per-pixel direct light): one full-screen triangle at
//! the output resolution that normalizes the splat sums, adds emission, direct light with the
//! shadow maps and the environment, and averages the 2×2 samples.

use super::{begin_rendering, end_rendering, FramePass, Load};
use crate::gpu::barrier::{transition, Access};
use crate::gpu::frame::FrameImages;
use crate::gpu::layout::FrameConstants;
use ash::vk;

/// Records the compose pass into the output image.
pub fn record(
    p: &FramePass<'_>,
    pipeline: vk::Pipeline,
    im: &mut FrameImages,
    mut constants: FrameConstants,
) {
    transition(p.ctx, p.cmd, &mut [(&mut im.output, Access::Attachment)]);
    begin_rendering(p.ctx, p.cmd, &[(&im.output, Load::Clear)]);
    constants.sizes[0] = im.output.extent.width;
    constants.sizes[1] = im.output.extent.height;
    p.bind(pipeline, &constants);
    p.draw(vk::Buffer::null(), 3, 1);
    end_rendering(p.ctx, p.cmd);
    transition(p.ctx, p.cmd, &mut [(&mut im.output, Access::Sampled)]);
}

//! The splat texels' display bins (§4.3): one full-screen triangle at the splat target's size
//! that finds, at each texel's G-buffer sample, the bin toward the eye (`surfaces::display_bin`
//! through the shading normal), so each of the ~4 splat fans over a texel reads it; found here
//! once per texel rather than in the G-buffer at every sample under its overdraw. Recorded in
//! the splat's timed scope, as the first half of splatting.

use super::targets::FrameImages;
use super::{begin_rendering, end_rendering, frame_desc, FramePass, Load};
use crate::error::Result;
use crate::gpu::barrier::{transition, Access};
use crate::gpu::context::Context;
use crate::gpu::handle::Owned;
use crate::gpu::memory::Image;
use crate::gpu::pipelines::{create, Target};
use ash::vk;
use std::sync::Arc;

/// The eye-bin pass: its pipeline, a full-screen triangle without vertex input.
pub struct EyeBins {
    pipeline: Owned<vk::Pipeline>,
}

impl EyeBins {
    /// Creates the pipeline.
    pub fn new(
        ctx: &Arc<Context>,
        layout: &Owned<vk::PipelineLayout>,
        specialization: &[u32],
    ) -> Result<Self> {
        let targets = [Target {
            format: vk::Format::R32_SFLOAT,
            additive: false,
            write: true,
        }];
        let desc = frame_desc(
            "eye bins",
            "compose.vert",
            "eye_bins.frag",
            &targets,
            specialization,
        );
        Ok(Self {
            pipeline: create(ctx, layout, &desc)?,
        })
    }

    /// Records the pass: reads the G-buffer (sampled), writes `splat_bins` (left sampled).
    pub fn record(&self, p: &FramePass<'_>, im: &mut FrameImages<Image>) {
        transition(
            p.ctx,
            p.cmd,
            &mut [(&mut im.splat_bins, Access::Attachment)],
        );
        begin_rendering(p.ctx, p.cmd, &[(&im.splat_bins, Load::ClearTo(-1.0))]);
        // sizes.xy: the target's (eye_bins.frag reads the G-buffer at its texel × the ratio).
        let mut constants = p.constants;
        constants.sizes[0] = im.splat_bins.extent.width;
        constants.sizes[1] = im.splat_bins.extent.height;
        p.bind(&self.pipeline, &constants);
        p.draw(vk::Buffer::null(), 3, 1);
        end_rendering(p.ctx, p.cmd);
        transition(p.ctx, p.cmd, &mut [(&mut im.splat_bins, Access::Sampled)]);
    }
}

//! Compose (§4.3 third pass, plus §3.3's per-pixel direct light): one full-screen triangle at
//! the output resolution that normalizes the splat sums, adds emission, direct light with the
//! shadow maps and the environment, and averages the 2×2 samples.

use super::targets::{FrameImages, RGBA32F};
use super::{begin_rendering, end_rendering, frame_desc, FramePass, Load};
use crate::error::Result;
use crate::gpu::barrier::{transition, Access};
use crate::gpu::context::Context;
use crate::gpu::handle::Owned;
use crate::gpu::memory::Image;
use crate::gpu::pipelines::{create, Target};
use ash::vk;
use std::sync::Arc;

/// The compose pass: its pipeline, a full-screen triangle without vertex input.
pub struct Compose {
    pipeline: Owned<vk::Pipeline>,
}

impl Compose {
    /// Creates the pipeline.
    pub fn new(
        ctx: &Arc<Context>,
        layout: &Owned<vk::PipelineLayout>,
        specialization: &[u32],
    ) -> Result<Self> {
        Ok(Self {
            pipeline: pipeline(ctx, layout, specialization)?,
        })
    }

    /// Records the compose pass: reads the G-buffer, the splat sums and the shadow maps (sampled),
    /// writes `output` (left sampled).
    pub fn record(&self, p: &FramePass<'_>, im: &mut FrameImages<Image>) {
        transition(p.ctx, p.cmd, &mut [(&mut im.output, Access::Attachment)]);
        begin_rendering(p.ctx, p.cmd, &[(&im.output, Load::Clear)]);
        let mut constants = p.constants;
        constants.sizes[0] = im.output.extent.width;
        constants.sizes[1] = im.output.extent.height;
        p.bind(&self.pipeline, &constants);
        p.draw(vk::Buffer::null(), 3, 1);
        end_rendering(p.ctx, p.cmd);
        transition(p.ctx, p.cmd, &mut [(&mut im.output, Access::Sampled)]);
    }
}

fn pipeline(
    ctx: &Arc<Context>,
    layout: &Owned<vk::PipelineLayout>,
    specialization: &[u32],
) -> Result<Owned<vk::Pipeline>> {
    let targets = [Target {
        format: RGBA32F,
        additive: false,
        write: true,
    }];
    let desc = frame_desc(
        "compose",
        "compose.vert",
        "compose.frag",
        &targets,
        specialization,
    );
    create(ctx, layout, &desc)
}

//! The area emitters' shared direct light per block of pixels (`frame::direct`): one
//! full-screen triangle at the blocks' grid that evaluates it at each block's corner pixel where
//! that pixel's samples share it, so compose interpolates it for the block's other pixels
//! instead of evaluating it at each (32 emitter samples × 3×3 shadow taps). Timed as
//! `direct_blocks`, before compose.

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

/// The direct-blocks pass: its pipeline, a full-screen triangle without vertex input.
pub struct DirectBlocks {
    pipeline: Owned<vk::Pipeline>,
}

impl DirectBlocks {
    /// Creates the pipeline.
    pub fn new(
        ctx: &Arc<Context>,
        layout: &Owned<vk::PipelineLayout>,
        specialization: &[u32],
    ) -> Result<Self> {
        let targets = [Target {
            format: RGBA32F,
            additive: false,
            write: true,
        }];
        let desc = frame_desc(
            "direct blocks",
            "compose.vert",
            "direct_blocks.frag",
            &targets,
            specialization,
        );
        Ok(Self {
            pipeline: create(ctx, layout, &desc)?,
        })
    }

    /// Records the pass: reads the G-buffer and the shadow maps (sampled), writes
    /// `direct_blocks` (left sampled).
    pub fn record(&self, p: &FramePass<'_>, im: &mut FrameImages<Image>) {
        transition(
            p.ctx,
            p.cmd,
            &mut [(&mut im.direct_blocks, Access::Attachment)],
        );
        begin_rendering(p.ctx, p.cmd, &[(&im.direct_blocks, Load::Clear)]);
        // sizes.xy stay the output's (compose's): the corner pixel of texel t is t × block.
        let mut constants = p.constants;
        constants.sizes[0] = im.output.extent.width;
        constants.sizes[1] = im.output.extent.height;
        p.bind(&self.pipeline, &constants);
        p.draw(vk::Buffer::null(), 3, 1);
        end_rendering(p.ctx, p.cmd);
        transition(
            p.ctx,
            p.cmd,
            &mut [(&mut im.direct_blocks, Access::Sampled)],
        );
    }
}

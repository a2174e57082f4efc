//! Splatting (§4.3, second pass): a fan around each flat-surface element's center, additive
//! into (Σ w·L, Σ w) where the G-buffer shows the same surface. Compose normalizes.

use super::targets::{FrameImages, RGBA32F};
use super::{begin_rendering, end_rendering, frame_desc, FramePass, Load, Source};
use crate::error::Result;
use crate::gpu::barrier::{transition, Access};
use crate::gpu::context::Context;
use crate::gpu::handle::Owned;
use crate::gpu::memory::Image;
use crate::gpu::pipelines::{create, PipelineDesc, Target};
use ash::vk;
use std::sync::Arc;

/// Triangles per fan × 3.
pub const FAN_VERTICES: u32 = 24;

/// The splat pass: its pipeline, one fan per leaf-slot instance, additive.
pub struct Splat {
    pipeline: Owned<vk::Pipeline>,
}

impl Splat {
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

    /// Records the splat pass, one fan per record of `instances` (leaf slots): reads the
    /// G-buffer (sampled), writes `splat` (left sampled). Where `splat` has a texel per pixel
    /// rather than per G-buffer sample, its viewport is shifted so that a texel's center is
    /// the pixel's first sample (`frame::splat`): a fan covers it exactly where it covers that
    /// sample.
    pub fn record(&self, p: &FramePass<'_>, im: &mut FrameImages<Image>, instances: Source) {
        transition(p.ctx, p.cmd, &mut [(&mut im.splat, Access::Attachment)]);
        begin_rendering(p.ctx, p.cmd, &[(&im.splat, Load::Clear)]);
        let (e, g) = (im.splat.extent, im.gbuf_position.extent);
        let per = (g.width / e.width).max(1) as f32;
        let shift = 0.5 - 0.5 / per;
        let viewport = vk::Viewport {
            x: shift,
            y: shift,
            width: e.width as f32,
            height: e.height as f32,
            min_depth: 0.0,
            max_depth: 1.0,
        };
        unsafe { p.ctx.device.cmd_set_viewport(p.cmd, 0, &[viewport]) };
        // sizes.xy: the target's (splat.frag reads the G-buffer at its texel × the ratio).
        let mut constants = p.constants;
        constants.sizes[0] = e.width;
        constants.sizes[1] = e.height;
        p.bind(&self.pipeline, &constants);
        p.draw(instances.buffer, FAN_VERTICES, instances.count);
        end_rendering(p.ctx, p.cmd);
        transition(p.ctx, p.cmd, &mut [(&mut im.splat, Access::Sampled)]);
    }
}

fn pipeline(
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

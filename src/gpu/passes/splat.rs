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
    /// G-buffer (sampled), writes `splat` (left sampled).
    pub fn record(&self, p: &FramePass<'_>, im: &mut FrameImages<Image>, instances: Source) {
        transition(p.ctx, p.cmd, &mut [(&mut im.splat, Access::Attachment)]);
        begin_rendering(p.ctx, p.cmd, &[(&im.splat, Load::Clear)]);
        p.bind(&self.pipeline, &p.constants);
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

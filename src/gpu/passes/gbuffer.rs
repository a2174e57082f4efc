//! G-buffer (§4.3, first of the three splatting passes): every element at 2×2 samples per
//! pixel, depth-tested, storing position and leaf (the surface id comes with the leaf) and the
//! vertex-interpolated indirect radiance of smooth meshes and, where the scene has OBJ `vn`, the
//! interpolated shading normal.

use super::shadow::POSITION;
use super::targets::{FrameImages, RGBA32F};
use super::{begin_rendering_with_depth, end_rendering, frame_desc, FramePass, Load, Source};
use crate::error::Result;
use crate::gpu::barrier::{transition, Access};
use crate::gpu::context::Context;
use crate::gpu::handle::Owned;
use crate::gpu::layout::CornerVertex;
use crate::gpu::memory::Image;
use crate::gpu::pipelines::{create, PipelineDesc, Target};
use crate::plan::Features;
use ash::vk;
use std::sync::Arc;

/// How many colour targets the G-buffer has under `f`: position, then vertex radiance (also
/// when only the normal needs it, attachments being positional), then the shading normal.
fn target_count(f: &Features) -> usize {
    if f.normals {
        3
    } else if f.vertex {
        2
    } else {
        1
    }
}

/// The G-buffer pass: its pipeline (corners with leaf, shared vertex and shading normal;
/// position, + vertex radiance, + shading normal targets as the features need them,
/// depth-tested) and those features.
pub struct GBuffer {
    pipeline: Owned<vk::Pipeline>,
    features: Features,
}

impl GBuffer {
    /// Creates the pipeline for a scene with `features`.
    pub fn new(
        ctx: &Arc<Context>,
        layout: &Owned<vk::PipelineLayout>,
        specialization: &[u32],
        features: &Features,
    ) -> Result<Self> {
        Ok(Self {
            pipeline: pipeline(ctx, layout, specialization, features)?,
            features: *features,
        })
    }

    /// Records the G-buffer pass drawing `corners`: writes `gbuf_position` (+ `gbuf_vertex`,
    /// + `gbuf_normal`, [`target_count`]) and `gbuf_depth`; leaves the colour targets sampled.
    pub fn record(&self, p: &FramePass<'_>, im: &mut FrameImages<Image>, corners: Source) {
        record(&self.pipeline, &self.features, p, im, corners)
    }
}

fn pipeline(
    ctx: &Arc<Context>,
    layout: &Owned<vk::PipelineLayout>,
    specialization: &[u32],
    features: &Features,
) -> Result<Owned<vk::Pipeline>> {
    let put = Target {
        format: RGBA32F,
        additive: false,
        write: true,
    };
    let targets = vec![put; target_count(features)];
    let desc = PipelineDesc {
        stride: std::mem::size_of::<CornerVertex>() as u32,
        attributes: &[
            POSITION,
            (vk::Format::R32_UINT, 12),
            (vk::Format::R32_UINT, 16),
            (vk::Format::R32G32B32_SFLOAT, 20),
        ],
        depth: true,
        wide_lines: false,
        ..frame_desc(
            "gbuffer",
            "gbuffer.vert",
            "gbuffer.frag",
            &targets,
            specialization,
        )
    };
    create(ctx, layout, &desc)
}

fn record(
    pipeline: &Owned<vk::Pipeline>,
    features: &Features,
    p: &FramePass<'_>,
    im: &mut FrameImages<Image>,
    corners: Source,
) {
    let count = target_count(features);
    let mut colors = vec![&mut im.gbuf_position];
    if count > 1 {
        colors.push(&mut im.gbuf_vertex);
    }
    if count > 2 {
        colors.push(&mut im.gbuf_normal);
    }
    let mut to_attachment: Vec<_> = colors
        .into_iter()
        .map(|img| (img, Access::Attachment))
        .collect();
    transition(p.ctx, p.cmd, &mut to_attachment);
    transition(p.ctx, p.cmd, &mut [(&mut im.gbuf_depth, Access::Depth)]);
    let attachments: Vec<_> = to_attachment
        .iter()
        .map(|(img, _)| (&**img, Load::Clear))
        .collect();
    begin_rendering_with_depth(
        p.ctx,
        p.cmd,
        &attachments,
        Some((&im.gbuf_depth, Load::Clear)),
    );
    p.bind(pipeline, &p.constants);
    p.draw(corners.buffer, corners.count, 1);
    end_rendering(p.ctx, p.cmd);
    for t in to_attachment.iter_mut() {
        t.1 = Access::Sampled;
    }
    transition(p.ctx, p.cmd, &mut to_attachment);
}

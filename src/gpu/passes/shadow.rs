//! Shadow maps (§3.3): every element corner drawn once per light view, each view into its own
//! square of one RG32F atlas, keeping the nearest linear distance and that surface's packed
//! normal (depth-tested).

use super::targets::FrameImages;
use super::{begin_rendering_with_depth, end_rendering, frame_desc, FramePass, Load, Source};
use crate::error::Result;
use crate::frame::shadow::EMPTY;
use crate::gpu::barrier::{transition, Access};
use crate::gpu::context::Context;
use crate::gpu::handle::Owned;
use crate::gpu::layout::CornerVertex;
use crate::gpu::memory::Image;
use crate::gpu::pipelines::{create, PipelineDesc, Target};
use ash::vk;
use std::sync::Arc;

/// Corner positions as vertex input (the shadow and G-buffer passes).
pub const POSITION: (vk::Format, u32) = (vk::Format::R32G32B32_SFLOAT, 0);

/// The shadow-map pass: its pipeline, corners as triangles, nearest linear distance per texel
/// (depth-tested).
pub struct Shadow {
    pipeline: Owned<vk::Pipeline>,
}

impl Shadow {
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

    /// Records the views drawing `corners`, each into its atlas square `rects[v]` (x, y, side):
    /// every view, or with `only`, the views it marks (their squares cleared first, the others'
    /// maps kept). Writes `shadow_map` (left sampled) and `shadow_depth`.
    pub fn record(
        &self,
        p: &FramePass<'_>,
        im: &mut FrameImages<Image>,
        corners: Source,
        rects: &[[u32; 3]],
        only: Option<&[bool]>,
    ) {
        record(&self.pipeline, p, im, corners, rects, only)
    }
}

fn pipeline(
    ctx: &Arc<Context>,
    layout: &Owned<vk::PipelineLayout>,
    specialization: &[u32],
) -> Result<Owned<vk::Pipeline>> {
    let targets = [Target {
        format: vk::Format::R32G32_SFLOAT,
        additive: false,
        write: true,
    }];
    let desc = PipelineDesc {
        stride: std::mem::size_of::<CornerVertex>() as u32,
        attributes: &[POSITION],
        depth: true,
        wide_lines: false,
        ..frame_desc(
            "shadow",
            "shadow.vert",
            "shadow.frag",
            &targets,
            specialization,
        )
    };
    create(ctx, layout, &desc)
}

fn record(
    pipeline: &Owned<vk::Pipeline>,
    p: &FramePass<'_>,
    im: &mut FrameImages<Image>,
    corners: Source,
    rects: &[[u32; 3]],
    only: Option<&[bool]>,
) {
    let mut constants = p.constants;
    transition(
        p.ctx,
        p.cmd,
        &mut [
            (&mut im.shadow_map, Access::Attachment),
            (&mut im.shadow_depth, Access::Depth),
        ],
    );
    let (color, depth) = match only {
        Some(_) => (Load::Keep, Load::Keep),
        None => (Load::ClearTo(EMPTY), Load::Clear),
    };
    begin_rendering_with_depth(
        p.ctx,
        p.cmd,
        &[(&im.shadow_map, color)],
        Some((&im.shadow_depth, depth)),
    );
    p.bind(pipeline, &constants);
    for (v, &[x, y, size]) in rects.iter().enumerate() {
        if only.is_some_and(|o| !o[v]) {
            continue;
        }
        let band = vk::Rect2D {
            offset: vk::Offset2D {
                x: x as i32,
                y: y as i32,
            },
            extent: vk::Extent2D {
                width: size,
                height: size,
            },
        };
        unsafe {
            p.ctx.device.cmd_set_viewport(
                p.cmd,
                0,
                &[vk::Viewport {
                    x: x as f32,
                    y: y as f32,
                    width: size as f32,
                    height: size as f32,
                    min_depth: 0.0,
                    max_depth: 1.0,
                }],
            );
            p.ctx.device.cmd_set_scissor(p.cmd, 0, &[band]);
            if only.is_some() {
                clear_square(p, band);
            }
        }
        constants.misc[1] = v as u32;
        p.push(&constants);
        p.draw(corners.buffer, corners.count, 1);
    }
    end_rendering(p.ctx, p.cmd);
    transition(p.ctx, p.cmd, &mut [(&mut im.shadow_map, Access::Sampled)]);
}

/// Clears one view's square of the atlas (nothing seen) and of its depth (far: reversed depth 0).
fn clear_square(p: &FramePass<'_>, rect: vk::Rect2D) {
    let attachments = [
        vk::ClearAttachment {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            color_attachment: 0,
            clear_value: vk::ClearValue {
                color: vk::ClearColorValue {
                    float32: [EMPTY; 4],
                },
            },
        },
        vk::ClearAttachment {
            aspect_mask: vk::ImageAspectFlags::DEPTH,
            color_attachment: 0,
            clear_value: vk::ClearValue {
                depth_stencil: vk::ClearDepthStencilValue {
                    depth: 0.0,
                    stencil: 0,
                },
            },
        },
    ];
    let rects = [vk::ClearRect {
        rect,
        base_array_layer: 0,
        layer_count: 1,
    }];
    unsafe {
        p.ctx
            .device
            .cmd_clear_attachments(p.cmd, &attachments, &rects)
    };
}

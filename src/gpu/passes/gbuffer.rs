//! G-buffer (§4.3, first of the three splatting passes): every element at 2×2 samples per
//! pixel, depth-tested, storing position and leaf (the surface id comes with the leaf) and the
//! vertex-interpolated indirect radiance of smooth meshes.

use super::{begin_rendering_with_depth, end_rendering, FramePass, Load};
use crate::gpu::barrier::{transition, Access};
use crate::gpu::frame::FrameImages;
use crate::gpu::layout::FrameConstants;
use ash::vk;

/// Records the G-buffer pass.
pub fn record(
    p: &FramePass<'_>,
    pipeline: vk::Pipeline,
    im: &mut FrameImages,
    corners: vk::Buffer,
    corner_count: u32,
    constants: FrameConstants,
) {
    transition(
        p.ctx,
        p.cmd,
        &mut [
            (&mut im.gbuf_position, Access::Attachment),
            (&mut im.gbuf_vertex, Access::Attachment),
            (&mut im.gbuf_depth, Access::Depth),
        ],
    );
    begin_rendering_with_depth(
        p.ctx,
        p.cmd,
        &[
            (&im.gbuf_position, Load::Clear),
            (&im.gbuf_vertex, Load::Clear),
        ],
        Some((&im.gbuf_depth, Load::Clear)),
    );
    p.bind(pipeline, &constants);
    p.draw(corners, corner_count, 1);
    end_rendering(p.ctx, p.cmd);
    transition(
        p.ctx,
        p.cmd,
        &mut [
            (&mut im.gbuf_position, Access::Sampled),
            (&mut im.gbuf_vertex, Access::Sampled),
        ],
    );
}

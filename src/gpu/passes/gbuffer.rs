//! G-buffer (§4.3, first of the three splatting passes): every element at 2×2 samples per
//! pixel, depth-tested, storing position and leaf (the surface id comes with the leaf) and the
//! vertex-interpolated indirect radiance of smooth meshes.

use super::{begin_rendering_with_depth, end_rendering, FramePass, Load};
use crate::gpu::barrier::{transition, Access};
use crate::gpu::frame::FrameImages;
use crate::gpu::layout::FrameConstants;
use ash::vk;

/// Records the G-buffer pass; the vertex-radiance target exists only when `vertex` (smooth
/// meshes are interpolated).
#[allow(clippy::too_many_arguments)]
pub fn record(
    p: &FramePass<'_>,
    pipeline: vk::Pipeline,
    im: &mut FrameImages,
    corners: vk::Buffer,
    corner_count: u32,
    constants: FrameConstants,
    vertex: bool,
) {
    let mut colors = vec![&mut im.gbuf_position];
    if vertex {
        colors.push(&mut im.gbuf_vertex);
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
    p.bind(pipeline, &constants);
    p.draw(corners, corner_count, 1);
    end_rendering(p.ctx, p.cmd);
    for t in to_attachment.iter_mut() {
        t.1 = Access::Sampled;
    }
    transition(p.ctx, p.cmd, &mut to_attachment);
}

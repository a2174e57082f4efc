//! The shared vertices' display radiance toward the eye (`frame::surfaces::vertex_values`, the
//! smooth meshes' vertex interpolation): one full-screen triangle over a texel per shared
//! vertex, so each vertex's blend of the leaves around it is computed once per frame, in
//! parallel, and the G-buffer's vertex shader reads it at each corner. Computed in that vertex
//! shader instead, every corner repeated its vertex's sum (six times on a closed mesh), and
//! llvmpipe shades vertices on one thread: the breakfast room's G-buffer took 4.8 s.
//! Timed as `vertex_values`, before the G-buffer.

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

/// Texels per row of the values image (`AR_VERTEX_VALUES_WIDTH` in common.glsl).
pub const WIDTH: u32 = 1024;

/// The values image's extent for `vertices` shared vertices: rows of [`WIDTH`].
pub fn extent(vertices: usize) -> (u32, u32) {
    let n = vertices.max(1) as u32;
    (n.min(WIDTH), n.div_ceil(WIDTH))
}

/// The vertex-values pass: its pipeline, a full-screen triangle without vertex input.
pub struct VertexValues {
    pipeline: Owned<vk::Pipeline>,
}

impl VertexValues {
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
            "vertex values",
            "compose.vert",
            "vertex_values.frag",
            &targets,
            specialization,
        );
        Ok(Self {
            pipeline: create(ctx, layout, &desc)?,
        })
    }

    /// Records the pass: reads I_total and the shared-vertex lists, writes `vertex_values`
    /// (left sampled for the G-buffer's vertex shader).
    pub fn record(&self, p: &FramePass<'_>, im: &mut FrameImages<Image>) {
        transition(
            p.ctx,
            p.cmd,
            &mut [(&mut im.vertex_values, Access::Attachment)],
        );
        begin_rendering(p.ctx, p.cmd, &[(&im.vertex_values, Load::Clear)]);
        p.bind(&self.pipeline, &p.constants);
        p.draw(vk::Buffer::null(), 3, 1);
        end_rendering(p.ctx, p.cmd);
        transition(
            p.ctx,
            p.cmd,
            &mut [(&mut im.vertex_values, Access::Sampled)],
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_vertex_has_a_texel() {
        for n in [0usize, 1, 1023, 1024, 1025, 135_000] {
            let (w, h) = extent(n);
            assert!((w * h) as usize >= n.max(1), "{n}: {w}×{h}");
            assert!(
                w <= WIDTH && (h as usize) < n.max(1) / WIDTH as usize + 2,
                "{n}: {w}×{h}"
            );
        }
    }
}

//! Push (§4.2): every node that gathered radiance adds its L_in row to all rows of its subtree,
//! a contiguous range in pre-order, drawn as one quad per column block.

use super::{begin_rendering, end_rendering, Load, Pass, PipelineSpec};
use crate::error::Result;
use crate::gpu::barrier::{transition, Access};
use crate::gpu::handle::Owned;
use crate::gpu::layout::QuadInstance;
use crate::gpu::pipelines::{create, PipelineDesc};
use crate::gpu::resources::Resources;
use ash::vk;

/// Quads over whole rows with fragment shader `frag` (push and local passes share the vertex
/// stage and its instance record).
pub fn quad_desc<'a>(
    name: &'a str,
    frag: &'a str,
    targets: &'a [crate::gpu::pipelines::Target],
    specialization: &'a [u32],
) -> PipelineDesc<'a> {
    PipelineDesc {
        name,
        vert: "quad.vert",
        frag,
        topology: vk::PrimitiveTopology::TRIANGLE_STRIP,
        stride: std::mem::size_of::<QuadInstance>() as u32,
        attributes: &[(vk::Format::R32G32B32_UINT, 0)],
        targets,
        specialization,
        per_vertex: false,
        depth: false,
    }
}

/// The push pass's pipeline: additive into L_push.
pub fn pipeline(spec: &PipelineSpec<'_>) -> Result<Owned<vk::Pipeline>> {
    let targets = [spec.accumulate()];
    create(
        spec.ctx,
        spec.layout,
        &quad_desc("push", "push.frag", &targets, &[]),
    )
}

/// Records the push pass (L_in → L_push).
pub fn record(p: &Pass<'_>, res: &mut Resources) {
    let im = &mut res.images;
    transition(
        p.ctx,
        p.cmd,
        &mut [
            (&mut im.l_in, Access::Sampled),
            (&mut im.l_push, Access::Attachment),
        ],
    );
    begin_rendering(p.ctx, p.cmd, &[(&im.l_push, Load::Clear)]);
    p.bind(&p.pipes.push, im.l_push.extent, res.plan.layout.bins);
    p.draw(
        res.buffers.push_quads.raw,
        4,
        res.plan.draw.push_quads.len(),
    );
    end_rendering(p.ctx, p.cmd);
}

/// Clears L_push (the state before the first propagation).
pub fn clear(p: &Pass<'_>, res: &mut Resources) {
    super::clear(p, &mut res.images.l_push);
}

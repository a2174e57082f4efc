//! Global pass (eq. 16, §4.2): every link is one line primitive across its receiver's bins in
//! L_in; the fragment shader multiplies the sender's I_ex by the form factor and the cone-filter
//! weight, and additive blending sums all links of a receiver.

use super::{begin_rendering, end_rendering, Load, Pass, PipelineSpec};
use crate::error::Result;
use crate::gpu::barrier::{transition, Access};
use crate::gpu::handle::Owned;
use crate::gpu::layout::GpuLink;
use crate::gpu::pipelines::{create, PipelineDesc, Target};
use crate::gpu::resources::Resources;
use ash::vk;

/// The line pipeline of link records with fragment shader `frag` into `targets` (the global
/// pass, and the diagnostics that check which texels a line covers).
pub fn desc<'a>(frag: &'a str, targets: &'a [Target]) -> PipelineDesc<'a> {
    PipelineDesc {
        name: if frag == "global.frag" {
            "global"
        } else {
            frag
        },
        vert: "global.vert",
        frag,
        topology: vk::PrimitiveTopology::LINE_LIST,
        stride: std::mem::size_of::<GpuLink>() as u32,
        attributes: &[
            (vk::Format::R32G32B32A32_UINT, 0),
            (vk::Format::R32_SFLOAT, 16),
        ],
        targets,
        specialization: &[],
        per_vertex: false,
        depth: false,
    }
}

/// The global pass's pipeline: additive into L_in.
pub fn pipeline(spec: &PipelineSpec<'_>) -> Result<Owned<vk::Pipeline>> {
    create(
        spec.ctx,
        spec.layout,
        &desc("global.frag", &[spec.accumulate()]),
    )
}

/// Records the global pass reading `leaf_ex(cur)` and the cluster image.
pub fn record(p: &Pass<'_>, res: &mut Resources, cur: usize) {
    let im = &mut res.images;
    let leaf = if cur == 0 {
        &mut im.leaf_ex0
    } else {
        &mut im.leaf_ex1
    };
    transition(
        p.ctx,
        p.cmd,
        &mut [
            (leaf, Access::Sampled),
            (&mut im.cluster_ex, Access::Sampled),
            (&mut im.filter, Access::Sampled),
            (&mut im.l_in, Access::Attachment),
        ],
    );
    begin_rendering(p.ctx, p.cmd, &[(&im.l_in, Load::Clear)]);
    p.bind(&p.pipes.global, im.l_in.extent, res.plan.layout.bins);
    p.draw(res.buffers.links.raw, 2, res.plan.draw.links.len());
    end_rendering(p.ctx, p.cmd);
}

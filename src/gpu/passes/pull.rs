//! Pull (§4.2): one textured line per (leaf, ancestor) adds the leaf's new I_ex into the
//! ancestor's row of the cluster image (intensities are area-weighted, so no scaling).

use super::{begin_rendering, end_rendering, Load, Pass, PipelineSpec};
use crate::error::Result;
use crate::gpu::barrier::{transition, Access};
use crate::gpu::handle::Owned;
use crate::gpu::layout::PullLine;
use crate::gpu::pipelines::{create, PipelineDesc, Target};
use crate::gpu::resources::{Resources, CLUSTER_FORMAT};
use ash::vk;

/// The pull pass's pipeline: lines additive into the float32 cluster image.
pub fn pipeline(spec: &PipelineSpec<'_>) -> Result<Owned<vk::Pipeline>> {
    create(
        spec.ctx,
        spec.layout,
        &PipelineDesc {
            name: "pull",
            vert: "pull.vert",
            frag: "pull.frag",
            topology: vk::PrimitiveTopology::LINE_LIST,
            stride: std::mem::size_of::<PullLine>() as u32,
            attributes: &[(vk::Format::R32G32_UINT, 0)],
            targets: &[Target {
                format: CLUSTER_FORMAT,
                additive: true,
                write: true,
            }],
            specialization: &[],
            per_vertex: false,
            depth: false,
        },
    )
}

/// Records the pull pass reading `leaf_ex(next)`.
pub fn record(p: &Pass<'_>, res: &mut Resources, next: usize) {
    let im = &mut res.images;
    let leaf = if next == 0 {
        &mut im.leaf_ex0
    } else {
        &mut im.leaf_ex1
    };
    transition(
        p.ctx,
        p.cmd,
        &mut [
            (leaf, Access::Sampled),
            (&mut im.cluster_ex, Access::Attachment),
        ],
    );
    begin_rendering(p.ctx, p.cmd, &[(&im.cluster_ex, Load::Clear)]);
    p.bind(&p.pipes.pull, im.cluster_ex.extent, res.plan.layout.bins);
    p.draw(
        res.buffers.pull_lines.raw,
        2,
        res.plan.draw.pull_lines.len(),
    );
    end_rendering(p.ctx, p.cmd);
}

//! Global pass (eq. 16, §4.2): every link is drawn as line primitives — one per run of receiver
//! bins its cone filter reaches and the receiver reads — into the receiver's row of L_in; the
//! sender's I_ex times the form factor is fetched once per line, the fragment shader weights it
//! by the filter table, and additive blending sums all links of a receiver. Links are drawn in
//! one draw per sender image and run count (`DrawData::link_buckets`), so the vertex shader
//! fetches I_ex from one image instead of summing the leaves' and both cluster parities'.

use super::{begin_rendering, end_rendering, Load, Pass, PipelineSpec};
use crate::error::Result;
use crate::gpu::barrier::{transition, Access};
use crate::gpu::handle::Owned;
use crate::gpu::layout::GpuLink;
use crate::gpu::pipelines::{create, PipelineDesc};
use crate::gpu::resources::Resources;
use ash::vk;

/// The global pass's pipeline: link records as instances, additive into L_in.
pub fn pipeline(spec: &PipelineSpec<'_>) -> Result<Owned<vk::Pipeline>> {
    let targets = [spec.accumulate()];
    let desc = PipelineDesc {
        name: "global",
        vert: "global.vert",
        frag: "global.frag",
        topology: vk::PrimitiveTopology::LINE_LIST,
        stride: std::mem::size_of::<GpuLink>() as u32,
        attributes: &[(vk::Format::R32G32_UINT, 0), (vk::Format::R32_SFLOAT, 8)],
        targets: &targets,
        specialization: &[],
        per_vertex: false,
        depth: false,
    };
    create(spec.ctx, spec.layout, &desc)
}

/// Records the global pass reading `leaf_ex(cur)` and both cluster images.
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
            (&mut im.cluster_ex_odd, Access::Sampled),
            (&mut im.filter, Access::Sampled),
            (&mut im.l_in, Access::Attachment),
        ],
    );
    begin_rendering(p.ctx, p.cmd, &[(&im.l_in, Load::Clear)]);
    let mut bound = None;
    for &(sender, runs, first, count) in &res.plan.draw.link_buckets {
        if bound != Some(sender) {
            p.bind_sender(
                &p.pipes.global,
                im.l_in.extent,
                res.plan.layout.bins,
                sender,
            );
            bound = Some(sender);
        }
        p.draw_range(res.buffers.links.raw, 2 * runs, first, count);
    }
    end_rendering(p.ctx, p.cmd);
}

//! Global pass (eq. 16, §4.2): every link is drawn as line primitives into the receiver's tile
//! of L_in, one per rectangle of the bins' grid that its cone filter's footprint covers
//! (`tables::bin_rects`: usually one, more where the octahedral map's seam cuts it), each line
//! as wide as its rectangle is tall. The sender's I_ex times the form factor is fetched once
//! per line, the fragment shader weights it by the filter table (discarding the rectangle's
//! bins without weight or that a leaf receiver never reads), and additive blending sums all
//! links of a receiver. Lines are drawn in one draw per sender image and line width
//! (`DrawData::link_buckets`), so the vertex shader fetches I_ex from one image instead of
//! summing the leaves' and both cluster parities'. It pulls its record by vertex index (no
//! vertex input, no instances), one descriptor range of records at a time (`gpu::links`).

use super::{begin_rendering, end_rendering, Load, Pass, PipelineSpec};
use crate::error::Result;
use crate::gpu::barrier::{transition, Access};
use crate::gpu::handle::Owned;
use crate::gpu::pipelines::{create, PipelineDesc};
use crate::gpu::resources::Resources;
use ash::vk;

/// The global pass: its pipeline (link records pulled by vertex index, additive into L_in).
pub struct Global {
    pipeline: Owned<vk::Pipeline>,
}

impl Global {
    /// Creates the pipeline.
    pub fn new(spec: &PipelineSpec<'_>) -> Result<Self> {
        Ok(Self {
            pipeline: pipeline(spec)?,
        })
    }

    /// Records the global pass reading `leaf_ex(cur)` and both cluster images into L_in.
    pub fn record(&self, p: &Pass<'_>, res: &mut Resources, cur: usize) {
        record(&self.pipeline, p, res, cur)
    }
}

fn pipeline(spec: &PipelineSpec<'_>) -> Result<Owned<vk::Pipeline>> {
    let targets = [spec.accumulate()];
    let constants = spec.constants(crate::gpu::layout::mode::BOTH, false);
    let desc = PipelineDesc {
        name: "global",
        vert: "global.vert",
        frag: "global.frag",
        topology: vk::PrimitiveTopology::LINE_LIST,
        stride: 0,
        attributes: &[],
        targets: &targets,
        specialization: &constants,
        per_vertex: true,
        depth: false,
        wide_lines: true,
    };
    create(spec.ctx, spec.layout, &desc)
}

fn record(pipeline: &Owned<vk::Pipeline>, p: &Pass<'_>, res: &mut Resources, cur: usize) {
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
    if res.plan.round_f16 {
        crate::gpu::blend16::clear(p.ctx, p.cmd, res);
    }
    let im = &mut res.images;
    begin_rendering(p.ctx, p.cmd, &[(&im.l_in, Load::Clear)]);
    let extent = im.l_in.extent;
    let mut bound = None;
    // Records beyond one descriptor's range are drawn chunk by chunk (`gpu::links`).
    for d in res.link_chunks.pieces(&res.plan.draw.link_buckets) {
        if bound != Some((d.chunk, d.sender)) {
            let set = res.set_for_chunk(cur, d.chunk);
            p.bind_global(pipeline, extent, d.sender, set);
            bound = Some((d.chunk, d.sender));
        }
        // Record k of the chunk is pulled by vertex index 2k + … (fits 32 bits: a chunk
        // holds fewer than 2^31 records).
        unsafe {
            p.ctx.device.cmd_set_line_width(p.cmd, d.width as f32);
            p.ctx.device.cmd_draw(p.cmd, 2 * d.count, 1, 2 * d.first, 0);
        }
    }
    end_rendering(p.ctx, p.cmd);
    if res.plan.round_f16 {
        crate::gpu::blend16::store(p.ctx, p.cmd, res);
    }
}

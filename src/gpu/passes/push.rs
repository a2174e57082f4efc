//! Push (§4.2), top-down, one draw per depth of one quad per node over its tile: every node's
//! L_push is its parent's plus its own gathered L_in, so O(nodes × bins) fragments. Even depths
//! are written into the L_push image
//! (`push_even.frag`, reading the L_in image); odd depths are added onto their own L_in tiles
//! (`push_odd.frag`, reading the L_push image), so no pass reads the image it draws into and
//! no extra table is needed. The local pass reads a leaf's incident light from the image of its
//! depth's parity.

use super::{begin_rendering, end_rendering, Load, Pass, PipelineSpec};
use crate::error::Result;
use crate::gpu::barrier::{transition, Access};
use crate::gpu::handle::Owned;
use crate::gpu::layout::{QuadInstance, RowPair};
use crate::gpu::pipelines::{create, PipelineDesc, Target};
use crate::gpu::resources::Resources;
use ash::vk;

/// Quads over whole rows with fragment shader `frag` (the local pass's vertex stage and
/// instance record).
pub fn quad_desc<'a>(
    name: &'a str,
    frag: &'a str,
    targets: &'a [Target],
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
        wide_lines: false,
    }
}

/// One quad per node over its tile of an incident table (push), with the row it reads besides
/// its own.
pub fn tile_desc<'a>(
    name: &'a str,
    frag: &'a str,
    targets: &'a [Target],
    specialization: &'a [u32],
) -> PipelineDesc<'a> {
    PipelineDesc {
        vert: "tile.vert",
        topology: vk::PrimitiveTopology::TRIANGLE_STRIP,
        ..row_desc(name, frag, targets, specialization)
    }
}

/// One line per node across its row (pull), with the row it reads besides its own.
pub fn row_desc<'a>(
    name: &'a str,
    frag: &'a str,
    targets: &'a [Target],
    specialization: &'a [u32],
) -> PipelineDesc<'a> {
    PipelineDesc {
        name,
        vert: "row.vert",
        frag,
        topology: vk::PrimitiveTopology::LINE_LIST,
        stride: std::mem::size_of::<RowPair>() as u32,
        attributes: &[(vk::Format::R32G32_UINT, 0)],
        targets,
        specialization,
        per_vertex: false,
        depth: false,
        wide_lines: false,
    }
}

/// The push pass: its pipelines, even depths written into L_push, odd depths added onto L_in.
pub struct Push {
    pipelines: [Owned<vk::Pipeline>; 2],
}

impl Push {
    /// Creates the pipelines.
    pub fn new(spec: &PipelineSpec<'_>) -> Result<Self> {
        Ok(Self {
            pipelines: pipelines(spec)?,
        })
    }

    /// Records the push pass, depth by depth (L_in → L_push / L_in by parity).
    pub fn record(&self, p: &Pass<'_>, res: &mut Resources) {
        record(&self.pipelines, p, res)
    }
}

fn pipelines(spec: &PipelineSpec<'_>) -> Result<[Owned<vk::Pipeline>; 2]> {
    let put = [Target {
        additive: false,
        ..spec.accumulate()
    }];
    let add = [spec.accumulate()];
    let constants = spec.constants(crate::gpu::layout::mode::BOTH, false);
    Ok([
        create(
            spec.ctx,
            spec.layout,
            &tile_desc("push (even depths)", "push_even.frag", &put, &constants),
        )?,
        create(
            spec.ctx,
            spec.layout,
            &tile_desc("push (odd depths)", "push_odd.frag", &add, &constants),
        )?,
    ])
}

fn record(pipelines: &[Owned<vk::Pipeline>; 2], p: &Pass<'_>, res: &mut Resources) {
    let bins = res.plan.layout.bins;
    for d in 0..res.plan.draw.push_levels.len() {
        let range = res.plan.draw.push_levels[d].clone();
        let im = &mut res.images;
        let odd = d % 2 == 1;
        let (source, target) = if odd {
            (&mut im.l_push, &mut im.l_in)
        } else {
            (&mut im.l_in, &mut im.l_push)
        };
        transition(
            p.ctx,
            p.cmd,
            &mut [
                (source, Access::Sampled),
                (&mut *target, Access::Attachment),
            ],
        );
        // The leaves' normals and push factors (push.glsl).
        transition(
            p.ctx,
            p.cmd,
            &mut [
                (&mut im.attr_normal_area, Access::Sampled),
                (&mut im.attr_leaf, Access::Sampled),
            ],
        );
        begin_rendering(p.ctx, p.cmd, &[(&*target, Load::Keep)]);
        p.bind(&pipelines[odd as usize], target.extent, bins);
        p.draw_range(
            res.buffers.push.raw,
            4,
            range.start,
            range.end - range.start,
        );
        end_rendering(p.ctx, p.cmd);
        // The odd depths added into the emulated float16 sums, which hold L_in.
        if odd && res.plan.round_f16 {
            crate::gpu::blend16::store(p.ctx, p.cmd, res);
        }
    }
}

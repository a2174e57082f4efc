//! Pull (§4.2), bottom-up, one draw per depth: every cluster's I_ex is the sum of its two
//! children's (O(clusters × bins) fragments, no long blends). Clusters at even and odd depths
//! live in two float32 images, so each level reads the other parity's image while it writes
//! its own; leaf children are read from the new leaf I_ex.

use super::push::row_desc;
use super::{begin_rendering, end_rendering, Load, Pass, PipelineSpec};
use crate::error::Result;
use crate::gpu::barrier::{transition, Access};
use crate::gpu::handle::Owned;
use crate::gpu::pipelines::{create, Target};
use crate::gpu::resources::{Resources, CLUSTER_FORMAT};
use ash::vk;

/// The pull pass: its pipelines, into even-depth clusters (children odd), into odd-depth ones.
pub struct Pull {
    pipelines: [Owned<vk::Pipeline>; 2],
}

impl Pull {
    /// Creates the pipelines.
    pub fn new(spec: &PipelineSpec<'_>) -> Result<Self> {
        Ok(Self {
            pipelines: pipelines(spec)?,
        })
    }

    /// Records the pull pass reading `leaf_ex(next)`, deepest clusters first.
    pub fn record(&self, p: &Pass<'_>, res: &mut Resources, next: usize) {
        record(&self.pipelines, p, res, next)
    }
}

fn pipelines(spec: &PipelineSpec<'_>) -> Result<[Owned<vk::Pipeline>; 2]> {
    let put = [Target {
        format: CLUSTER_FORMAT,
        additive: false,
        write: true,
    }];
    let constants = spec.constants(crate::gpu::layout::mode::BOTH, false);
    Ok([
        create(
            spec.ctx,
            spec.layout,
            &row_desc("pull (even depths)", "pull_even.frag", &put, &constants),
        )?,
        create(
            spec.ctx,
            spec.layout,
            &row_desc("pull (odd depths)", "pull_odd.frag", &put, &constants),
        )?,
    ])
}

fn record(pipelines: &[Owned<vk::Pipeline>; 2], p: &Pass<'_>, res: &mut Resources, next: usize) {
    let im = &mut res.images;
    let bins = res.plan.layout.bins;
    let leaf = if next == 0 {
        &mut im.leaf_ex0
    } else {
        &mut im.leaf_ex1
    };
    transition(p.ctx, p.cmd, &mut [(leaf, Access::Sampled)]);
    for (range, depth) in &res.plan.draw.pull_levels {
        let odd = depth % 2 == 1;
        let (children, target) = if odd {
            (&mut im.cluster_ex, &mut im.cluster_ex_odd)
        } else {
            (&mut im.cluster_ex_odd, &mut im.cluster_ex)
        };
        transition(
            p.ctx,
            p.cmd,
            &mut [
                (children, Access::Sampled),
                (&mut *target, Access::Attachment),
            ],
        );
        begin_rendering(p.ctx, p.cmd, &[(&*target, Load::Keep)]);
        p.bind(&pipelines[odd as usize], target.extent, bins);
        p.draw_range(
            res.buffers.pull.raw,
            2,
            range.start,
            range.end - range.start,
        );
        end_rendering(p.ctx, p.cmd);
    }
}

//! Pull (§4.2): one textured line per (leaf, ancestor) adds the leaf's new I_ex into the
//! ancestor's row of the cluster image (intensities are area-weighted, so no scaling).

use super::{begin_rendering, end_rendering, Load, Pass};
use crate::gpu::barrier::{transition, Access};
use crate::gpu::resources::Resources;

/// Records the pull pass reading `leaf_ex[next]`.
pub fn record(p: &Pass<'_>, res: &mut Resources, next: usize) {
    let im = &mut res.images;
    let [a, b] = &mut im.leaf_ex;
    let leaf = if next == 0 { a } else { b };
    transition(
        p.ctx,
        p.cmd,
        &mut [
            (leaf, Access::Sampled),
            (&mut im.cluster_ex, Access::Attachment),
        ],
    );
    begin_rendering(p.ctx, p.cmd, &[(&im.cluster_ex, Load::Clear)]);
    p.bind(p.pipes.pull, im.cluster_ex.extent, res.layout.bins);
    p.draw(res.buffers.pull_lines.raw, 2, res.draw.pull_lines.len());
    end_rendering(p.ctx, p.cmd);
}

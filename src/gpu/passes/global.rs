//! Global pass (eq. 16, §4.2): every link is one line primitive across its receiver's bins in
//! L_in; the fragment shader multiplies the sender's I_ex by the form factor and the cone-filter
//! weight, and additive blending sums all links of a receiver.

use super::{begin_rendering, end_rendering, Load, Pass};
use crate::gpu::barrier::{transition, Access};
use crate::gpu::resources::Resources;

/// Records the global pass reading `leaf_ex[cur]` and the cluster image.
pub fn record(p: &Pass<'_>, res: &mut Resources, cur: usize) {
    let im = &mut res.images;
    let [a, b] = &mut im.leaf_ex;
    let leaf = if cur == 0 { a } else { b };
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
    p.bind(p.pipes.global, im.l_in.extent, res.layout.bins);
    p.draw(res.buffers.links.raw, 2, res.draw.links.len());
    end_rendering(p.ctx, p.cmd);
}

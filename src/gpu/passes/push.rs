//! Push (§4.2): every node that gathered radiance adds its L_in row to all rows of its subtree,
//! a contiguous range in pre-order, drawn as one quad per column block.

use super::{begin_rendering, end_rendering, Load, Pass};
use crate::gpu::barrier::{transition, Access};
use crate::gpu::resources::Resources;

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
    p.bind(p.pipes.push, im.l_push.extent, res.layout.bins);
    p.draw(res.buffers.push_quads.raw, 4, res.draw.push_quads.len());
    end_rendering(p.ctx, p.cmd);
}

/// Clears L_push (the state before the first propagation).
pub fn clear(p: &Pass<'_>, res: &mut Resources) {
    let im = &mut res.images;
    transition(p.ctx, p.cmd, &mut [(&mut im.l_push, Access::Attachment)]);
    begin_rendering(p.ctx, p.cmd, &[(&im.l_push, Load::Clear)]);
    end_rendering(p.ctx, p.cmd);
}

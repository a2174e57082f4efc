//! Local pass (eqs. 18–19, §4.2) on the leaf rows: first the diffuse fast path's irradiance
//! image (one texel per leaf), then reflection + antiradiance into the other image of the I_ex
//! ping-pong pair and I_total, with the Lambertian runs and the glossy (Phong sum) runs drawn by
//! their own pipelines.

use super::{begin_rendering, end_rendering, Load, Pass};
use crate::gpu::barrier::{transition, Access};
use crate::gpu::layout::mode;
use crate::gpu::profiler::{label_begin, label_end};
use crate::gpu::resources::Resources;

/// Records the local pass in `m` (a [`mode`] value), reading `leaf_ex[cur]`, writing `leaf_ex[1-cur]`.
pub fn record(p: &Pass<'_>, res: &mut Resources, cur: usize, m: u32) {
    let im = &mut res.images;
    label_begin(p.ctx, p.cmd, "local_irradiance");
    transition(
        p.ctx,
        p.cmd,
        &mut [
            (&mut im.l_push, Access::Sampled),
            (&mut im.attr_normal_area, Access::Sampled),
            (&mut im.attr_leaf, Access::Sampled),
            (&mut im.direct, Access::Sampled),
            (&mut im.irradiance_t, Access::Attachment),
            (&mut im.irradiance_d, Access::Attachment),
        ],
    );
    begin_rendering(
        p.ctx,
        p.cmd,
        &[
            (&im.irradiance_t, Load::Clear),
            (&im.irradiance_d, Load::Clear),
        ],
    );
    p.bind(p.pipes.irradiance, im.irradiance_t.extent, 1);
    p.draw(res.buffers.leaf_quads.raw, 4, res.draw.leaf_quads.len());
    end_rendering(p.ctx, p.cmd);
    label_end(p.ctx, p.cmd);

    let [a, b] = &mut im.leaf_ex;
    let (old, new) = if cur == 0 { (a, b) } else { (b, a) };
    transition(
        p.ctx,
        p.cmd,
        &mut [
            (&mut im.irradiance_t, Access::Sampled),
            (&mut im.irradiance_d, Access::Sampled),
            (old, Access::Sampled),
            (&mut *new, Access::Attachment),
            (&mut im.i_total, Access::Attachment),
        ],
    );
    // The antiradiance step keeps I_total (write-masked); the others rewrite it.
    let total_load = if m == mode::ANTIRADIANCE {
        Load::Keep
    } else {
        Load::Clear
    };
    begin_rendering(
        p.ctx,
        p.cmd,
        &[(&*new, Load::Clear), (&im.i_total, total_load)],
    );
    let extent = new.extent;
    if let Some(pipe) = p.pipes.diffuse[m as usize] {
        label_begin(p.ctx, p.cmd, "local_diffuse");
        p.bind(pipe, extent, res.layout.bins);
        p.draw(
            res.buffers.diffuse_quads.raw,
            4,
            res.draw.diffuse_quads.len(),
        );
        label_end(p.ctx, p.cmd);
    }
    if let Some(pipe) = p.pipes.glossy[m as usize] {
        label_begin(p.ctx, p.cmd, "local_glossy");
        p.bind(pipe, extent, res.layout.bins);
        p.draw(res.buffers.glossy_quads.raw, 4, res.draw.glossy_quads.len());
        label_end(p.ctx, p.cmd);
    }
    end_rendering(p.ctx, p.cmd);
}

/// Clears an image as an attachment (initial state of the ping-pong pair and cluster image).
pub fn clear(p: &Pass<'_>, img: &mut crate::gpu::memory::Image) {
    transition(p.ctx, p.cmd, &mut [(&mut *img, Access::Attachment)]);
    begin_rendering(p.ctx, p.cmd, &[(&*img, Load::Clear)]);
    end_rendering(p.ctx, p.cmd);
}

//! Local pass (eqs. 18–19, §4.2) on the leaf rows: first the diffuse fast path's irradiance
//! image (one texel per leaf), then reflection + antiradiance into the other image of the I_ex
//! ping-pong pair and I_total, with the Lambertian runs and the glossy (Phong sum) runs drawn by
//! their own pipelines. One shader (`glsl/local.frag`) is specialized per pipeline.

use super::push::quad_desc;
use super::{begin_rendering, end_rendering, Load, Pass, PipelineSpec};
use crate::error::Result;
use crate::gpu::barrier::{transition, Access};
use crate::gpu::handle::Owned;
use crate::gpu::layout::mode;
use crate::gpu::pipelines::{create, Target};
use crate::gpu::profiler::{label_begin, label_end};
use crate::gpu::resources::Resources;
use ash::vk;

/// The local pass: the irradiance step's pipeline, and the reflection + antiradiance
/// pipelines by mode for the Lambertian and the glossy runs (made for the modes and materials in
/// use, by [`Local::ensure`]).
pub struct Local {
    irradiance: Owned<vk::Pipeline>,
    diffuse: [Option<Owned<vk::Pipeline>>; 3],
    glossy: [Option<Owned<vk::Pipeline>>; 3],
}

impl Local {
    /// Creates the irradiance step's pipeline; the others come with [`Local::ensure`].
    pub fn new(spec: &PipelineSpec<'_>) -> Result<Self> {
        Ok(Self {
            irradiance: irradiance_pipeline(spec)?,
            diffuse: [None, None, None],
            glossy: [None, None, None],
        })
    }

    /// Creates the variants for `m` (a [`mode`] value) that `res` will draw.
    pub fn ensure(&mut self, spec: &PipelineSpec<'_>, res: &Resources, m: u32) -> Result<()> {
        let draw = res.draw();
        for (glossy, slot, needed) in [
            (
                false,
                &mut self.diffuse[m as usize],
                !draw.diffuse_quads.is_empty(),
            ),
            (
                true,
                &mut self.glossy[m as usize],
                !draw.glossy_quads.is_empty(),
            ),
        ] {
            if slot.is_none() && needed {
                *slot = Some(pipeline(spec, m, glossy)?);
            }
        }
        Ok(())
    }

    /// Records the local pass in `m` (a [`mode`] value), reading `leaf_ex(cur)`, writing
    /// `leaf_ex(1-cur)` and I_total.
    pub fn record(&self, p: &Pass<'_>, res: &mut Resources, cur: usize, m: u32) {
        record(self, p, res, cur, m)
    }
}

/// The irradiance step's pipeline: one texel per row into the irradiance image.
fn irradiance_pipeline(s: &PipelineSpec<'_>) -> Result<Owned<vk::Pipeline>> {
    let targets = [s.put()];
    let constants = s.constants(mode::BOTH, false);
    let desc = quad_desc(
        "local_irradiance",
        "local_irradiance.frag",
        &targets,
        &constants,
    );
    create(s.ctx, s.layout, &desc)
}

/// The local pass's pipeline for `m` (a [`mode`] value) over Lambertian or glossy runs.
fn pipeline(s: &PipelineSpec<'_>, m: u32, glossy: bool) -> Result<Owned<vk::Pipeline>> {
    // The antiradiance step leaves I_total as it is: write mask off, attachment loaded.
    let targets = [
        s.put(),
        Target {
            write: m != mode::ANTIRADIANCE,
            ..s.put()
        },
    ];
    let kind = if glossy { "glossy" } else { "diffuse" };
    let names = ["both", "reflect", "antiradiance"];
    let name = format!("local_{kind} ({})", names[m as usize]);
    let constants = s.constants(m, glossy);
    create(
        s.ctx,
        s.layout,
        &quad_desc(&name, "local.frag", &targets, &constants),
    )
}

fn record(pass: &Local, p: &Pass<'_>, res: &mut Resources, cur: usize, m: u32) {
    let im = &mut res.images;
    let draw = &res.plan.draw;
    let bins = res.plan.layout.bins;
    label_begin(p.ctx, p.cmd, "local_irradiance");
    transition(
        p.ctx,
        p.cmd,
        &mut [
            (&mut im.l_push, Access::Sampled),
            (&mut im.l_in, Access::Sampled),
            (&mut im.attr_normal_area, Access::Sampled),
            (&mut im.attr_leaf, Access::Sampled),
            (&mut im.irradiance_t, Access::Attachment),
        ],
    );
    begin_rendering(p.ctx, p.cmd, &[(&im.irradiance_t, Load::Clear)]);
    p.bind(&pass.irradiance, im.irradiance_t.extent, 1);
    p.draw(res.buffers.leaf_quads.raw, 4, draw.leaf_quads.len());
    end_rendering(p.ctx, p.cmd);
    label_end(p.ctx, p.cmd);

    let (old, new) = if cur == 0 {
        (&mut im.leaf_ex0, &mut im.leaf_ex1)
    } else {
        (&mut im.leaf_ex1, &mut im.leaf_ex0)
    };
    transition(
        p.ctx,
        p.cmd,
        &mut [
            (&mut im.irradiance_t, Access::Sampled),
            (&mut im.direct, Access::Sampled),
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
    let runs = [
        (
            &pass.diffuse,
            "local_diffuse",
            &res.buffers.diffuse_quads,
            draw.diffuse_quads.len(),
        ),
        (
            &pass.glossy,
            "local_glossy",
            &res.buffers.glossy_quads,
            draw.glossy_quads.len(),
        ),
    ];
    for (pipes, label, buffer, count) in runs {
        if let Some(pipe) = &pipes[m as usize] {
            label_begin(p.ctx, p.cmd, label);
            p.bind(pipe, extent, bins);
            p.draw(buffer.raw, 4, count);
            label_end(p.ctx, p.cmd);
        }
    }
    end_rendering(p.ctx, p.cmd);
}

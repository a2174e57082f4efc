//! The four operations of §4.2 as raster passes — [`global`], [`push`], [`local`], [`pull`] —
//! and what they share: the pipelines, attachment load/clear, push constants. The frame passes
//! (§3.3, §4.3) — [`shadow`], [`gbuffer`], [`splat`], [`compose`] — use [`FramePass`].

pub mod compose;
pub mod gbuffer;
pub mod global;
pub mod local;
pub mod pull;
pub mod push;
pub mod shadow;
pub mod splat;

use super::context::Context;
use super::layout::{mode, spec, FrameConstants, PassConstants, PullLine, QuadInstance};
use super::memory::Image;
use super::pipelines::{create, PipelineDesc, Target};
use super::resources::Resources;
use crate::error::Result;
use ash::vk;

/// What a render pass does with an attachment's previous contents.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Load {
    /// Clear to zero (accumulation starts from nothing).
    Clear,
    /// Clear every channel to this value (shadow maps start at "nothing seen"; depth at 1).
    ClearTo(f32),
    /// Keep (accumulate onto, or leave write-masked texels as they are).
    Keep,
}

/// The pass pipelines; local variants exist only for the modes and materials in use.
pub struct Pipelines {
    /// Global lines, additive into L_in.
    pub global: vk::Pipeline,
    /// Push quads, additive into L_push.
    pub push: vk::Pipeline,
    /// Irradiance quads (one texel per row).
    pub irradiance: vk::Pipeline,
    /// Local pass, Lambertian runs, by mode.
    pub diffuse: [Option<vk::Pipeline>; 3],
    /// Local pass, glossy runs, by mode.
    pub glossy: [Option<vk::Pipeline>; 3],
    /// Pull lines, additive into the cluster image.
    pub pull: vk::Pipeline,
    format: vk::Format,
    features: crate::plan::Features,
}

const UINT4: vk::Format = vk::Format::R32G32B32A32_UINT;

impl Pipelines {
    /// Creates the pipelines every solve needs (local variants are added by [`Pipelines::ensure_local`]).
    pub fn new(
        ctx: &Context,
        layout: vk::PipelineLayout,
        format: vk::Format,
        accum_format: vk::Format,
        features: crate::plan::Features,
    ) -> Result<Self> {
        let accumulate = [Target {
            format: accum_format,
            additive: true,
            write: true,
        }];
        let quad = [(vk::Format::R32G32B32_UINT, 0)];
        let global = create(
            ctx,
            layout,
            &PipelineDesc {
                name: "global",
                vert: "global.vert",
                frag: "global.frag",
                topology: vk::PrimitiveTopology::LINE_LIST,
                stride: std::mem::size_of::<super::layout::GpuLink>() as u32,
                attributes: &[(UINT4, 0), (vk::Format::R32_SFLOAT, 16)],
                targets: &accumulate,
                specialization: &[],
                per_vertex: false,
                depth: false,
            },
        )?;
        let push = create(
            ctx,
            layout,
            &PipelineDesc {
                name: "push",
                vert: "quad.vert",
                frag: "push.frag",
                topology: vk::PrimitiveTopology::TRIANGLE_STRIP,
                stride: std::mem::size_of::<QuadInstance>() as u32,
                attributes: &quad,
                targets: &accumulate,
                specialization: &[],
                per_vertex: false,
                depth: false,
            },
        )?;
        let put = Target {
            format,
            additive: false,
            write: true,
        };
        let irradiance = create(
            ctx,
            layout,
            &PipelineDesc {
                name: "local_irradiance",
                vert: "quad.vert",
                frag: "local_irradiance.frag",
                topology: vk::PrimitiveTopology::TRIANGLE_STRIP,
                stride: std::mem::size_of::<QuadInstance>() as u32,
                attributes: &quad,
                targets: &[put, put],
                specialization: &spec::values(&features, mode::BOTH, false),
                per_vertex: false,
                depth: false,
            },
        )?;
        let pull = create(
            ctx,
            layout,
            &PipelineDesc {
                name: "pull",
                vert: "pull.vert",
                frag: "pull.frag",
                topology: vk::PrimitiveTopology::LINE_LIST,
                stride: std::mem::size_of::<PullLine>() as u32,
                attributes: &[(vk::Format::R32G32_UINT, 0)],
                targets: &[Target {
                    format: super::resources::CLUSTER_FORMAT,
                    additive: true,
                    write: true,
                }],
                specialization: &[],
                per_vertex: false,
                depth: false,
            },
        )?;
        Ok(Self {
            global,
            push,
            irradiance,
            diffuse: [None; 3],
            glossy: [None; 3],
            pull,
            format,
            features,
        })
    }

    /// Creates the local-pass variants for `m` (a [`mode`] value) that `res` will draw.
    pub fn ensure_local(
        &mut self,
        ctx: &Context,
        layout: vk::PipelineLayout,
        res: &Resources,
        m: u32,
    ) -> Result<()> {
        let format = self.format;
        // The antiradiance step leaves I_total as it is: write mask off, attachment loaded.
        let targets = [
            Target {
                format,
                additive: false,
                write: true,
            },
            Target {
                format,
                additive: false,
                write: m != mode::ANTIRADIANCE,
            },
        ];
        let quad = [(vk::Format::R32G32B32_UINT, 0)];
        let names = ["both", "reflect", "antiradiance"];
        let features = self.features;
        for (glossy, slot) in [
            (false, &mut self.diffuse[m as usize]),
            (true, &mut self.glossy[m as usize]),
        ] {
            let needed = if glossy {
                !res.draw.glossy_quads.is_empty()
            } else {
                !res.draw.diffuse_quads.is_empty()
            };
            if slot.is_some() || !needed {
                continue;
            }
            let kind = if glossy { "glossy" } else { "diffuse" };
            let name = format!("local_{kind} ({})", names[m as usize]);
            *slot = Some(create(
                ctx,
                layout,
                &PipelineDesc {
                    name: &name,
                    vert: "quad.vert",
                    frag: "local.frag",
                    topology: vk::PrimitiveTopology::TRIANGLE_STRIP,
                    stride: std::mem::size_of::<QuadInstance>() as u32,
                    attributes: &quad,
                    targets: &targets,
                    specialization: &spec::values(&features, m, glossy),
                    per_vertex: false,
                    depth: false,
                },
            )?);
        }
        Ok(())
    }

    /// Frees the pipelines.
    pub fn destroy(&self, ctx: &Context) {
        let all = [self.global, self.push, self.irradiance, self.pull]
            .into_iter()
            .chain(self.diffuse.iter().flatten().copied())
            .chain(self.glossy.iter().flatten().copied());
        for p in all {
            unsafe { ctx.device.destroy_pipeline(p, None) };
        }
    }
}

fn attachment(
    img: &Image,
    load: Load,
    layout: vk::ImageLayout,
) -> vk::RenderingAttachmentInfo<'static> {
    let value = match load {
        Load::ClearTo(v) => v,
        _ => 0.0,
    };
    vk::RenderingAttachmentInfo::default()
        .image_view(img.view)
        .image_layout(layout)
        .load_op(match load {
            Load::Clear | Load::ClearTo(_) => vk::AttachmentLoadOp::CLEAR,
            Load::Keep => vk::AttachmentLoadOp::LOAD,
        })
        .store_op(vk::AttachmentStoreOp::STORE)
        .clear_value(if layout == vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL {
            vk::ClearValue {
                depth_stencil: vk::ClearDepthStencilValue {
                    depth: value,
                    stencil: 0,
                },
            }
        } else {
            vk::ClearValue {
                color: vk::ClearColorValue {
                    float32: [value; 4],
                },
            }
        })
}

/// Begins dynamic rendering into `targets` (all of `extent`), with viewport and scissor set.
pub fn begin_rendering(ctx: &Context, cmd: vk::CommandBuffer, targets: &[(&Image, Load)]) {
    begin_rendering_with_depth(ctx, cmd, targets, None)
}

/// [`begin_rendering`] with an optional depth attachment.
pub fn begin_rendering_with_depth(
    ctx: &Context,
    cmd: vk::CommandBuffer,
    targets: &[(&Image, Load)],
    depth: Option<(&Image, Load)>,
) {
    let extent = targets[0].0.extent;
    let atts: Vec<_> = targets
        .iter()
        .map(|(img, load)| attachment(img, *load, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL))
        .collect();
    let depth_att =
        depth.map(|(img, load)| attachment(img, load, vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL));
    let area = vk::Rect2D {
        offset: vk::Offset2D::default(),
        extent,
    };
    let mut info = vk::RenderingInfo::default()
        .render_area(area)
        .layer_count(1)
        .color_attachments(&atts);
    if let Some(d) = depth_att.as_ref() {
        info = info.depth_attachment(d);
    }
    unsafe {
        ctx.device.cmd_begin_rendering(cmd, &info);
        ctx.device.cmd_set_viewport(
            cmd,
            0,
            &[vk::Viewport {
                x: 0.0,
                y: 0.0,
                width: extent.width as f32,
                height: extent.height as f32,
                min_depth: 0.0,
                max_depth: 1.0,
            }],
        );
        ctx.device.cmd_set_scissor(cmd, 0, &[area]);
    }
}

/// Ends dynamic rendering.
pub fn end_rendering(ctx: &Context, cmd: vk::CommandBuffer) {
    unsafe { ctx.device.cmd_end_rendering(cmd) };
}

/// Binds `pipeline` and set 0 of `layout`, and pushes `constants` to both stages.
fn bind_with_constants(
    ctx: &Context,
    cmd: vk::CommandBuffer,
    layout: vk::PipelineLayout,
    set: vk::DescriptorSet,
    pipeline: vk::Pipeline,
    constants: &[u8],
) {
    let d = &ctx.device;
    unsafe {
        d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, pipeline);
        d.cmd_bind_descriptor_sets(cmd, vk::PipelineBindPoint::GRAPHICS, layout, 0, &[set], &[]);
        d.cmd_push_constants(
            cmd,
            layout,
            vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT,
            0,
            constants,
        );
    }
}

/// Everything a pass records with.
pub struct Pass<'a> {
    /// Device.
    pub ctx: &'a Context,
    /// Command buffer being recorded.
    pub cmd: vk::CommandBuffer,
    /// Pipeline layout.
    pub layout: vk::PipelineLayout,
    /// Pipelines.
    pub pipes: &'a Pipelines,
    /// Descriptor set of the current ping-pong parity.
    pub set: vk::DescriptorSet,
    /// Push constants with the scene-wide fields filled in.
    pub constants: PassConstants,
}

impl Pass<'_> {
    /// Binds `pipeline`, the set and the push constants for a target of `extent` with rows
    /// `quad_width` texels wide.
    pub fn bind(&self, pipeline: vk::Pipeline, extent: vk::Extent2D, quad_width: u32) {
        let c = PassConstants {
            target_width: extent.width,
            target_height: extent.height,
            quad_width,
            ..self.constants
        };
        bind_with_constants(
            self.ctx,
            self.cmd,
            self.layout,
            self.set,
            pipeline,
            super::layout::as_bytes(std::slice::from_ref(&c)),
        );
    }

    /// Draws `instances` primitives of `vertices` vertices from `buffer`.
    pub fn draw(&self, buffer: vk::Buffer, vertices: u32, instances: usize) {
        if instances == 0 {
            return;
        }
        unsafe {
            self.ctx
                .device
                .cmd_bind_vertex_buffers(self.cmd, 0, &[buffer], &[0]);
            self.ctx
                .device
                .cmd_draw(self.cmd, vertices, instances as u32, 0, 0);
        }
    }
}

/// What a frame pass records with (the frame's own layout and set, [`FrameConstants`] pushes).
pub struct FramePass<'a> {
    /// Device.
    pub ctx: &'a Context,
    /// Command buffer being recorded.
    pub cmd: vk::CommandBuffer,
    /// Frame pipeline layout.
    pub layout: vk::PipelineLayout,
    /// Frame descriptor set.
    pub set: vk::DescriptorSet,
}

impl FramePass<'_> {
    /// Binds `pipeline`, the frame set and `constants`.
    pub fn bind(&self, pipeline: vk::Pipeline, constants: &FrameConstants) {
        bind_with_constants(
            self.ctx,
            self.cmd,
            self.layout,
            self.set,
            pipeline,
            super::layout::as_bytes(std::slice::from_ref(constants)),
        );
    }

    /// Updates the push constants only.
    pub fn push(&self, constants: &FrameConstants) {
        unsafe {
            self.ctx.device.cmd_push_constants(
                self.cmd,
                self.layout,
                vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT,
                0,
                super::layout::as_bytes(std::slice::from_ref(constants)),
            )
        };
    }

    /// Draws `vertices` × `instances` from `buffer` (bound when not null).
    pub fn draw(&self, buffer: vk::Buffer, vertices: u32, instances: u32) {
        if vertices == 0 || instances == 0 {
            return;
        }
        unsafe {
            if buffer != vk::Buffer::null() {
                self.ctx
                    .device
                    .cmd_bind_vertex_buffers(self.cmd, 0, &[buffer], &[0]);
            }
            self.ctx
                .device
                .cmd_draw(self.cmd, vertices, instances, 0, 0);
        }
    }
}

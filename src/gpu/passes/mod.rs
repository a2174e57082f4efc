//! The four operations of §4.2 as raster passes — [`global`], [`push`], [`local`], [`pull`] —
//! and what they share: attachment load/clear, push constants, [`SolverPasses`]. Each pass is a
//! struct that owns its pipelines (made from its own description in `new`) and records itself
//! (`record`) from a small context ([`Pass`]; [`FramePass`] for the frame passes of §3.3 and
//! §4.3 — [`shadow`], [`gbuffer`], [`splat`], [`compose`] — with the image set of [`targets`]);
//! dropping the struct frees its pipelines.

pub mod compose;
pub mod direct_blocks;
pub mod eye_bins;
pub mod gbuffer;
pub mod global;
pub mod local;
pub mod pull;
pub mod push;
pub mod shadow;
pub mod splat;
pub mod targets;
pub mod vertex_values;

use super::context::Context;
use super::handle::Owned;
use super::layout::{FrameConstants, PassConstants};
use super::memory::Image;
use super::pipelines::Target;
use crate::error::Result;
use crate::plan::Features;
use ash::vk;
use std::sync::Arc;

/// What a pipeline is made for: device, layout, table formats and the plan's features.
pub struct PipelineSpec<'a> {
    /// Device.
    pub ctx: &'a Arc<Context>,
    /// Pipeline layout (the solver's or the frame's).
    pub layout: &'a Owned<vk::PipelineLayout>,
    /// Table texel format.
    pub format: vk::Format,
    /// Format of the additive targets L_in and L_push.
    pub accum_format: vk::Format,
    /// What the scene needs (specialization constants).
    pub features: Features,
    /// The tables' layout (specialization constants of every solver shader).
    pub table: super::tables::TableLayout,
    /// Float16 blending rounded to nearest is emulated ([`crate::gpu::blend16`]).
    pub round_f16: bool,
}

impl PipelineSpec<'_> {
    /// The specialization constants of a solver pipeline in local-pass mode `mode`
    /// ([`super::layout::spec::solver_values`]).
    pub fn constants(&self, mode: u32, glossy: bool) -> [u32; super::layout::spec::SOLVER_COUNT] {
        super::layout::spec::solver_values(
            &self.features,
            mode,
            glossy,
            &self.table,
            self.round_f16,
        )
    }

    /// An additive target in the accumulation format (global, push).
    pub fn accumulate(&self) -> Target {
        Target {
            format: self.accum_format,
            additive: true,
            write: true,
        }
    }

    /// An overwritten target in the table format.
    pub fn put(&self) -> Target {
        Target {
            format: self.format,
            additive: false,
            write: true,
        }
    }
}

/// A frame-pass pipeline: triangles, no vertex input, no depth; each pass sets what differs.
pub fn frame_desc<'a>(
    name: &'a str,
    vert: &'a str,
    frag: &'a str,
    targets: &'a [Target],
    specialization: &'a [u32],
) -> super::pipelines::PipelineDesc<'a> {
    super::pipelines::PipelineDesc {
        name,
        vert,
        frag,
        topology: vk::PrimitiveTopology::TRIANGLE_LIST,
        stride: 0,
        attributes: &[],
        targets,
        specialization,
        per_vertex: true,
        depth: false,
        wide_lines: false,
    }
}

/// What a pass does with an attachment's previous contents.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Load {
    /// Clear to zero (accumulation starts from nothing).
    Clear,
    /// Clear every channel to this value (shadow maps start at "nothing seen"; depth at 1).
    ClearTo(f32),
    /// Keep (accumulate onto, or leave write-masked texels as they are).
    Keep,
}

/// The solver's passes, each owning its pipelines (the local pass's variants exist only for the
/// modes and materials in use).
pub struct SolverPasses {
    /// Global lines, additive into L_in.
    pub global: global::Global,
    /// Push quads (one per node tile): even depths into L_push, odd depths added onto L_in.
    pub push: push::Push,
    /// Irradiance quads, then reflection + antiradiance by mode.
    pub local: local::Local,
    /// Pull lines: into even-depth clusters, into odd-depth clusters.
    pub pull: pull::Pull,
}

impl SolverPasses {
    /// Creates the passes every solve needs (local variants are added by
    /// [`local::Local::ensure`]).
    pub fn new(spec: &PipelineSpec<'_>) -> Result<Self> {
        Ok(Self {
            global: global::Global::new(spec)?,
            push: push::Push::new(spec)?,
            local: local::Local::new(spec)?,
            pull: pull::Pull::new(spec)?,
        })
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
    /// Descriptor set of the current ping-pong parity.
    pub set: vk::DescriptorSet,
    /// Push constants with the scene-wide fields filled in.
    pub constants: PassConstants,
}

impl Pass<'_> {
    /// Binds `pipeline`, the set and the push constants for a target of `extent` with rows
    /// `quad_width` texels wide.
    pub fn bind(&self, pipeline: &Owned<vk::Pipeline>, extent: vk::Extent2D, quad_width: u32) {
        self.bind_with(pipeline, extent, quad_width, 0, self.set);
    }

    /// As [`Pass::bind`] for the global draws of senders in one image
    /// ([`PassConstants::sender`]) with `set` (the pass's set with one chunk of link records).
    pub fn bind_global(
        &self,
        pipeline: &Owned<vk::Pipeline>,
        extent: vk::Extent2D,
        sender: u32,
        set: vk::DescriptorSet,
    ) {
        self.bind_with(pipeline, extent, 0, sender, set);
    }

    fn bind_with(
        &self,
        pipeline: &Owned<vk::Pipeline>,
        extent: vk::Extent2D,
        quad_width: u32,
        sender: u32,
        set: vk::DescriptorSet,
    ) {
        let c = PassConstants {
            target_width: extent.width,
            target_height: extent.height,
            quad_width,
            sender,
            ..self.constants
        };
        bind_with_constants(
            self.ctx,
            self.cmd,
            self.layout,
            set,
            pipeline.raw(),
            super::layout::as_bytes(std::slice::from_ref(&c)),
        );
    }

    /// Draws `instances` primitives of `vertices` vertices from `buffer`.
    pub fn draw(&self, buffer: vk::Buffer, vertices: u32, instances: usize) {
        self.draw_range(buffer, vertices, 0, instances as u32);
    }

    /// Draws `count` primitives of `vertices` vertices from the records of `buffer` starting
    /// at instance `first`.
    pub fn draw_range(&self, buffer: vk::Buffer, vertices: u32, first: u32, count: u32) {
        if count == 0 {
            return;
        }
        unsafe {
            self.ctx
                .device
                .cmd_bind_vertex_buffers(self.cmd, 0, &[buffer], &[0]);
            self.ctx
                .device
                .cmd_draw(self.cmd, vertices, count, 0, first);
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
    /// Push constants of this recording (each pass sets the fields that are its own).
    pub constants: FrameConstants,
}

/// Vertices (or instances) a frame pass draws: a vertex buffer and how many records it holds.
#[derive(Clone, Copy)]
pub struct Source {
    /// The buffer.
    pub buffer: vk::Buffer,
    /// Its records.
    pub count: u32,
}

impl FramePass<'_> {
    /// Binds `pipeline`, the frame set and `constants`.
    pub fn bind(&self, pipeline: &Owned<vk::Pipeline>, constants: &FrameConstants) {
        bind_with_constants(
            self.ctx,
            self.cmd,
            self.layout,
            self.set,
            pipeline.raw(),
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

/// Clears an image as an attachment (initial states: the ping-pong pair, cluster image, L_push).
pub fn clear(p: &Pass<'_>, img: &mut Image) {
    use super::barrier::{transition, Access};
    transition(p.ctx, p.cmd, &mut [(&mut *img, Access::Attachment)]);
    begin_rendering(p.ctx, p.cmd, &[(&*img, Load::Clear)]);
    end_rendering(p.ctx, p.cmd);
}

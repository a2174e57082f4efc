//! The GPU side of progressive refinement (`glsl/pr_*`): radiosity and unshot radiosity in a
//! storage buffer, and per shot three recorded passes — `select` (compute, one workgroup: the
//! element with the most unshot power, the state's figures into a host-visible slot), `hemicube`
//! (every element's triangle rasterized into the five faces of the shooter's hemicube: an item
//! buffer of element ids and distances, depth-tested) and `gather` (compute, one invocation per
//! receiver). A batch of shots is one submission; nothing is read back between shots.

use super::{Elements, State};
use crate::error::Result;
use crate::gpu::barrier::{transition, Access};
use crate::gpu::handle::Owned;
use crate::gpu::layout::as_bytes;
use crate::gpu::memory::{Buffer, Image, ImageDesc, Purpose, DEPTH_FORMAT};
use crate::gpu::passes::{begin_rendering_with_depth, end_rendering, Load};
use crate::gpu::pipelines::{self, Layouts, PipelineDesc, Target};
use crate::gpu::profiler::Profiler;
use crate::gpu::Context;
use crate::methods::MethodSettings;
use ash::vk;
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

/// Push constants (`PrConstants` in `glsl/pr_common.glsl`).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PrConstants {
    /// Elements.
    pub leaves: u32,
    /// Hemicube face being drawn.
    pub face: u32,
    /// Texels per face side.
    pub size: u32,
    /// Deepest receiver subdivision level.
    pub subdivision: u32,
    /// Relative spread of samples that triggers the next level.
    pub gradient: f32,
    /// Offset of the shooter's eye off its surface.
    pub eps: f32,
    /// Near plane of the hemicube faces.
    pub near: f32,
    /// Figures slot written by the selection.
    pub slot: u32,
}

/// One element (`PrLeaf`).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PrLeaf {
    /// First corner, area in w.
    pub c0_area: [f32; 4],
    /// Second corner.
    pub c1: [f32; 4],
    /// Third corner.
    pub c2: [f32; 4],
    /// Unit normal.
    pub normal: [f32; 4],
    /// Albedo of reflection (kd + ks).
    pub albedo: [f32; 4],
    /// Centroid.
    pub center: [f32; 4],
}

/// One element's state (`PrState`).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PrState {
    /// Gathered irradiance.
    pub gathered: [f32; 4],
    /// Unshot radiosity.
    pub unshot: [f32; 4],
    /// Emission + reflected direct light.
    pub base: [f32; 4],
}

/// The current shot (`PrShot`).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PrShot {
    /// Shooter, or `PR_NONE`.
    pub shooter: u32,
    /// Padding.
    pub pad: [u32; 3],
    /// Its unshot radiosity (rgb) and power (w).
    pub unshot: [f32; 4],
}

/// A corner of an element's triangle as vertex input: position and leaf slot.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PrVertex {
    /// World position.
    pub position: [f32; 3],
    /// Leaf slot.
    pub leaf: u32,
}

/// Descriptor bindings (`PR_BINDING_*`).
pub mod binding {
    /// Elements (storage).
    pub const LEAVES: u32 = 0;
    /// State (storage).
    pub const STATE: u32 = 1;
    /// The current shot (storage).
    pub const SHOT: u32 = 2;
    /// Figures per slot (storage, host-visible).
    pub const FIGURES: u32 = 3;
    /// Item buffer: element ids.
    pub const ITEM_ID: u32 = 4;
    /// Item buffer: distances.
    pub const ITEM_DIST: u32 = 5;
    /// Bindings.
    pub const COUNT: u32 = 6;
    /// The storage-buffer bindings.
    pub const BUFFERS: [u32; 4] = [LEAVES, STATE, SHOT, FIGURES];
}

/// Named pass timings (ms), in recording order.
pub type Timings = Vec<(String, f64)>;

/// "No shooter" (`PR_NONE`).
pub const NONE: u32 = u32::MAX;

/// What the selection found before one shot (a figures slot).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Slot {
    /// Unshot power of all elements (W, mean of RGB).
    pub unshot: f64,
    /// The shooter's power.
    pub power: f64,
    /// The shooter, or `None` when nothing was left.
    pub shooter: Option<u32>,
    /// Exitant flux of all elements.
    pub flux: f64,
}

fn v4(v: glam::DVec3, w: f64) -> [f32; 4] {
    [v.x as f32, v.y as f32, v.z as f32, w as f32]
}

/// The shooter's buffers, item buffer, pipelines and descriptor set.
pub struct Shooter {
    ctx: Arc<Context>,
    layouts: Layouts,
    _pool: Owned<vk::DescriptorPool>,
    _sampler: Owned<vk::Sampler>,
    set: vk::DescriptorSet,
    select: Owned<vk::Pipeline>,
    gather: Owned<vk::Pipeline>,
    hemicube: Owned<vk::Pipeline>,
    _leaves: Buffer,
    state: Buffer,
    _shot: Buffer,
    figures: Buffer,
    vertices: Buffer,
    staging: Buffer,
    item_id: Image,
    item_dist: Image,
    depth: Image,
    profiler: Profiler,
    constants: PrConstants,
    slots: usize,
}

impl Shooter {
    /// Buffers, images and pipelines for `els`, with room for `slots` selections per submission.
    pub fn new(
        ctx: &Arc<Context>,
        els: &Elements,
        settings: &MethodSettings,
        eps: f64,
        slots: usize,
    ) -> Result<Self> {
        let n = els.len();
        let leaves: Vec<PrLeaf> = (0..n)
            .map(|i| {
                let c = &els.corners[i];
                PrLeaf {
                    c0_area: v4(c[0], els.area[i]),
                    c1: v4(c[1], 0.0),
                    c2: v4(c[2], 0.0),
                    normal: v4(els.normal[i], 0.0),
                    albedo: v4(els.albedo[i], 0.0),
                    center: v4(els.center[i], 0.0),
                }
            })
            .collect();
        let vertices: Vec<PrVertex> = (0..n)
            .flat_map(|i| {
                els.corners[i].map(|p| PrVertex {
                    position: [p.x as f32, p.y as f32, p.z as f32],
                    leaf: i as u32,
                })
            })
            .collect();
        let sb = vk::BufferUsageFlags::STORAGE_BUFFER;
        let leaves = Buffer::upload(ctx, "pr elements", as_bytes(&leaves), sb)?;
        let vertices = Buffer::upload(
            ctx,
            "pr element corners",
            as_bytes(&vertices),
            vk::BufferUsageFlags::VERTEX_BUFFER,
        )?;
        let state_bytes = (n * std::mem::size_of::<PrState>()) as u64;
        let state = Buffer::new(
            ctx,
            "pr state",
            state_bytes,
            sb | vk::BufferUsageFlags::TRANSFER_DST | vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::GpuOnly,
        )?;
        // One host-visible buffer carries the initial state in and the state back out.
        let staging = Buffer::new(
            ctx,
            "pr state (host)",
            state_bytes,
            vk::BufferUsageFlags::TRANSFER_SRC | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuToCpu,
        )?;
        let shot = Buffer::new(
            ctx,
            "pr shot",
            std::mem::size_of::<PrShot>() as u64,
            sb,
            MemoryLocation::GpuOnly,
        )?;
        let figures = Buffer::new(
            ctx,
            "pr figures",
            slots as u64 * 16,
            sb,
            MemoryLocation::GpuToCpu,
        )?;
        let size = settings.hemicube;
        let image = |name: &str, format| {
            ImageDesc::new(name, 5 * size, size, format, Purpose::Tables).create(ctx)
        };
        let item_id = image("pr item buffer ids", vk::Format::R32_UINT)?;
        let item_dist = image("pr item buffer distances", vk::Format::R32_SFLOAT)?;
        let depth = image("pr item buffer depth", DEPTH_FORMAT)?;
        let kinds = pipelines::descriptor_kinds(binding::COUNT, &binding::BUFFERS);
        let layouts = Layouts::with_stages(
            ctx,
            "progressive refinement",
            &kinds,
            std::mem::size_of::<PrConstants>() as u32,
            stages(),
        )?;
        let pool = pipelines::descriptor_pool(ctx, &kinds, 1, "pr descriptor pool")?;
        let set = pipelines::allocate_set(ctx, &pool, &layouts.set, "pr set")?;
        let sampler = pipelines::texel_sampler(ctx, "pr sampler")?;
        pipelines::write_set(
            ctx,
            set,
            sampler.raw(),
            &[
                (binding::ITEM_ID, item_id.view),
                (binding::ITEM_DIST, item_dist.view),
            ],
            &[
                (binding::LEAVES, leaves.raw),
                (binding::STATE, state.raw),
                (binding::SHOT, shot.raw),
                (binding::FIGURES, figures.raw),
            ],
        );
        let targets = [
            Target {
                format: vk::Format::R32_UINT,
                additive: false,
                write: true,
            },
            Target {
                format: vk::Format::R32_SFLOAT,
                additive: false,
                write: true,
            },
        ];
        let hemicube = pipelines::create(
            ctx,
            &layouts.pipeline,
            &PipelineDesc {
                name: "hemicube",
                vert: "pr_hemicube.vert",
                frag: "pr_hemicube.frag",
                topology: vk::PrimitiveTopology::TRIANGLE_LIST,
                stride: std::mem::size_of::<PrVertex>() as u32,
                attributes: &[
                    (vk::Format::R32G32B32_SFLOAT, 0),
                    (vk::Format::R32_UINT, 12),
                ],
                targets: &targets,
                specialization: &[],
                per_vertex: true,
                depth: true,
                wide_lines: false,
            },
        )?;
        let select = pipelines::create_compute(ctx, &layouts.pipeline, "pr_select.comp")?;
        let gather = pipelines::create_compute(ctx, &layouts.pipeline, "pr_gather.comp")?;
        // Three timed scopes per shot.
        let profiler = Profiler::new(ctx, 3 * slots as u32 + 4)?;
        Ok(Self {
            ctx: ctx.clone(),
            layouts,
            _pool: pool,
            _sampler: sampler,
            set,
            select,
            gather,
            hemicube,
            _leaves: leaves,
            state,
            _shot: shot,
            figures,
            vertices,
            staging,
            item_id,
            item_dist,
            depth,
            profiler,
            constants: PrConstants {
                leaves: n as u32,
                face: 0,
                size,
                subdivision: settings.subdivision,
                gradient: settings.gradient as f32,
                eps: eps as f32,
                near: (0.5 * eps) as f32,
                slot: 0,
            },
            slots,
        })
    }

    /// Selections one submission can record (shots + 1).
    pub fn slots(&self) -> usize {
        self.slots
    }

    /// Bytes of GPU memory of the buffers and item buffer.
    pub fn bytes(&self) -> u64 {
        let images = [&self.item_id, &self.item_dist, &self.depth];
        images.iter().map(|i| i.bytes()).sum::<u64>()
            + self._leaves.size
            + self.state.size
            + self.vertices.size
    }

    /// Replaces the state on the device with `state` (waits).
    pub fn upload(&mut self, state: &State) -> Result<()> {
        let records: Vec<PrState> = (0..state.unshot.len())
            .map(|i| PrState {
                gathered: v4(state.gathered[i], 0.0),
                unshot: v4(state.unshot[i], 0.0),
                base: v4(state.base[i], 0.0),
            })
            .collect();
        self.staging.mapped_mut()?[..].copy_from_slice(as_bytes(&records));
        let (src, dst, size) = (self.staging.raw, self.state.raw, self.state.size);
        let ctx = self.ctx.clone();
        ctx.submit_and_wait(|cmd| unsafe {
            ctx.device
                .cmd_copy_buffer(cmd, src, dst, &[vk::BufferCopy::default().size(size)]);
        })
    }

    /// The gathered irradiance of every element (waits).
    pub fn gathered(&mut self) -> Result<Vec<glam::DVec3>> {
        let (src, dst, size) = (self.state.raw, self.staging.raw, self.state.size);
        let ctx = self.ctx.clone();
        ctx.submit_and_wait(|cmd| unsafe {
            ctx.device
                .cmd_copy_buffer(cmd, src, dst, &[vk::BufferCopy::default().size(size)]);
        })?;
        let bytes = self.staging.mapped()?;
        let f = |o: usize| f32::from_le_bytes(bytes[o..o + 4].try_into().unwrap()) as f64;
        let stride = std::mem::size_of::<PrState>();
        Ok((0..self.constants.leaves as usize)
            .map(|i| glam::DVec3::new(f(i * stride), f(i * stride + 4), f(i * stride + 8)))
            .collect())
    }

    /// Records and submits `shots` shots (at most `slots() - 1`), then one more selection for
    /// the state after them; returns every slot and the pass timings.
    pub fn shoot(&mut self, shots: usize) -> Result<(Vec<Slot>, Timings)> {
        let shots = shots.min(self.slots - 1);
        let ctx = self.ctx.clone();
        ctx.submit_and_wait(|cmd| {
            self.profiler.reset(&ctx, cmd);
            for k in 0..shots {
                self.record_select(cmd, k);
                self.record_hemicube(cmd);
                self.record_gather(cmd);
            }
            self.record_select(cmd, shots);
        })?;
        let timings = self.profiler.results(&ctx)?;
        let bytes = self.figures.mapped()?;
        let word = |o: usize| u32::from_le_bytes(bytes[o..o + 4].try_into().unwrap());
        let f = |o: usize| f32::from_bits(word(o)) as f64;
        let slots = (0..=shots)
            .map(|k| {
                let o = 16 * k;
                let s = word(o + 8);
                Slot {
                    unshot: f(o),
                    power: f(o + 4),
                    shooter: (s != NONE).then_some(s),
                    flux: f(o + 12),
                }
            })
            .collect();
        Ok((slots, timings))
    }

    fn push(&self, cmd: vk::CommandBuffer, c: &PrConstants) {
        unsafe {
            self.ctx.device.cmd_push_constants(
                cmd,
                self.layouts.pipeline.raw(),
                stages(),
                0,
                as_bytes(std::slice::from_ref(c)),
            )
        };
    }

    fn bind(&self, cmd: vk::CommandBuffer, point: vk::PipelineBindPoint, p: &Owned<vk::Pipeline>) {
        let d = &self.ctx.device;
        unsafe {
            d.cmd_bind_pipeline(cmd, point, p.raw());
            d.cmd_bind_descriptor_sets(
                cmd,
                point,
                self.layouts.pipeline.raw(),
                0,
                &[self.set],
                &[],
            );
        }
    }

    fn record_select(&mut self, cmd: vk::CommandBuffer, slot: usize) {
        let ctx = self.ctx.clone();
        self.profiler.begin(&ctx, cmd, "select");
        self.bind(cmd, vk::PipelineBindPoint::COMPUTE, &self.select);
        self.push(
            cmd,
            &PrConstants {
                slot: slot as u32,
                ..self.constants
            },
        );
        unsafe { ctx.device.cmd_dispatch(cmd, 1, 1, 1) };
        storage_barrier(&ctx, cmd);
        self.profiler.end(&ctx, cmd);
    }

    fn record_hemicube(&mut self, cmd: vk::CommandBuffer) {
        let ctx = self.ctx.clone();
        let d = &ctx.device;
        self.profiler.begin(&ctx, cmd, "hemicube");
        transition(
            &ctx,
            cmd,
            &mut [
                (&mut self.item_id, Access::Attachment),
                (&mut self.item_dist, Access::Attachment),
                (&mut self.depth, Access::Depth),
            ],
        );
        begin_rendering_with_depth(
            &ctx,
            cmd,
            &[(&self.item_id, Load::Clear), (&self.item_dist, Load::Clear)],
            Some((&self.depth, Load::Clear)),
        );
        self.bind(cmd, vk::PipelineBindPoint::GRAPHICS, &self.hemicube);
        let size = self.constants.size;
        unsafe { d.cmd_bind_vertex_buffers(cmd, 0, &[self.vertices.raw], &[0]) };
        for face in 0..5u32 {
            // The side faces keep only their upper half (rows [0, size/2)): the hemisphere.
            let rows = if face == 0 { size } else { size / 2 };
            unsafe {
                d.cmd_set_viewport(
                    cmd,
                    0,
                    &[vk::Viewport {
                        x: (face * size) as f32,
                        y: 0.0,
                        width: size as f32,
                        height: size as f32,
                        min_depth: 0.0,
                        max_depth: 1.0,
                    }],
                );
                d.cmd_set_scissor(
                    cmd,
                    0,
                    &[vk::Rect2D {
                        offset: vk::Offset2D {
                            x: (face * size) as i32,
                            y: 0,
                        },
                        extent: vk::Extent2D {
                            width: size,
                            height: rows,
                        },
                    }],
                );
            }
            self.push(
                cmd,
                &PrConstants {
                    face,
                    ..self.constants
                },
            );
            unsafe { d.cmd_draw(cmd, 3 * self.constants.leaves, 1, 0, 0) };
        }
        end_rendering(&ctx, cmd);
        transition(
            &ctx,
            cmd,
            &mut [
                (&mut self.item_id, Access::Sampled),
                (&mut self.item_dist, Access::Sampled),
            ],
        );
        self.profiler.end(&ctx, cmd);
    }

    fn record_gather(&mut self, cmd: vk::CommandBuffer) {
        let ctx = self.ctx.clone();
        self.profiler.begin(&ctx, cmd, "gather");
        self.bind(cmd, vk::PipelineBindPoint::COMPUTE, &self.gather);
        self.push(cmd, &self.constants);
        unsafe {
            ctx.device
                .cmd_dispatch(cmd, self.constants.leaves.div_ceil(64), 1, 1)
        };
        storage_barrier(&ctx, cmd);
        self.profiler.end(&ctx, cmd);
    }
}

/// Shader stages of the one layout (the hemicube draw and the two compute passes).
fn stages() -> vk::ShaderStageFlags {
    vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT | vk::ShaderStageFlags::COMPUTE
}

/// Storage writes of a pass visible to every later read or write (vertex, compute, host).
fn storage_barrier(ctx: &Context, cmd: vk::CommandBuffer) {
    let mb = [vk::MemoryBarrier2::default()
        .src_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
        .src_access_mask(vk::AccessFlags2::SHADER_STORAGE_WRITE)
        .dst_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
        .dst_access_mask(
            vk::AccessFlags2::SHADER_STORAGE_READ
                | vk::AccessFlags2::SHADER_STORAGE_WRITE
                | vk::AccessFlags2::HOST_READ,
        )];
    unsafe {
        ctx.device
            .cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(&mb))
    };
}

#[cfg(test)]
mod tests;

//! The hemicubes rasterized (the paper's §4.1 on graphics hardware): every face slot's triangle
//! drawn into the five faces of each VPL's hemicube, an item buffer of face slots and distances
//! (`glsl/ibr_hemicube.vert`, `glsl/pr_hemicube.frag`), depth-tested; a batch of VPLs side by side
//! in one image, read back and shaded and warped on the CPU as the paper warps on the host, with
//! the same code as the CPU backend's ray-cast hemicubes ([`super::hemicube`]).

use super::hemicube::{frame_of, shade, texels, Sample};
use crate::error::Result;
use crate::frame::surfaces::Surfaces;
use crate::gpu::barrier::{transition, Access};
use crate::gpu::handle::Owned;
use crate::gpu::layout::as_bytes;
use crate::gpu::memory::{Buffer, Image, ImageDesc, Purpose, DEPTH_FORMAT};
use crate::gpu::passes::{begin_rendering_with_depth, end_rendering, Load};
use crate::gpu::pipelines::{self, Layouts, PipelineDesc, Target};
use crate::gpu::Context;
use crate::reference::sampling::basis;
use crate::scene::Light;
use ash::vk;
use glam::DVec3;
use std::sync::Arc;

/// Push constants (`IbrFace` in `glsl/ibr_hemicube.vert`).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default)]
struct IbrFace {
    eye: [f32; 4],
    forward: [f32; 4],
    right: [f32; 4],
    up: [f32; 4],
}

/// A face slot's corner (`glsl/ibr_hemicube.vert`): its normal tells the shader which of two
/// back-to-back twins faces the VPL.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default)]
struct IbrVertex {
    position: [f32; 3],
    slot: u32,
    normal: [f32; 3],
}

fn v4(v: DVec3, w: f32) -> [f32; 4] {
    [v.x as f32, v.y as f32, v.z as f32, w]
}

/// The hemicube rasterizer: the scene's triangles, an item buffer for `batch` VPLs, a pipeline.
pub struct GpuHemicubes {
    ctx: Arc<Context>,
    layouts: Layouts,
    pipeline: Owned<vk::Pipeline>,
    vertices: Buffer,
    triangles: u32,
    item_id: Image,
    item_dist: Image,
    depth: Image,
    size: u32,
    batch: usize,
}

impl GpuHemicubes {
    /// For `surf`'s face slots, hemicubes of side `size` (even), `batch` at a time.
    pub fn new(ctx: &Arc<Context>, surf: &Surfaces, size: u32, batch: usize) -> Result<Self> {
        let size = size.max(2) & !1;
        let vertices: Vec<IbrVertex> = surf
            .corners
            .iter()
            .zip(&surf.normal)
            .enumerate()
            .flat_map(|(i, (c, n))| {
                c.map(|p| IbrVertex {
                    position: [p.x as f32, p.y as f32, p.z as f32],
                    slot: i as u32,
                    normal: [n.x as f32, n.y as f32, n.z as f32],
                })
            })
            .collect();
        let vertices = Buffer::upload(
            ctx,
            "ibr face-slot corners",
            as_bytes(&vertices),
            vk::BufferUsageFlags::VERTEX_BUFFER,
        )?;
        // Each VPL a column of H texels, 3H rows (front H, four sides H/2).
        let image = |name: &str, format| {
            ImageDesc::new(name, batch as u32 * size, 3 * size, format, Purpose::Tables).create(ctx)
        };
        let item_id = image("ibr item buffer ids", vk::Format::R32_UINT)?;
        let item_dist = image("ibr item buffer distances", vk::Format::R32_SFLOAT)?;
        let depth = image("ibr item buffer depth", DEPTH_FORMAT)?;
        let stages = vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT;
        let layouts = Layouts::with_stages(
            ctx,
            "ibr hemicube",
            &[],
            std::mem::size_of::<IbrFace>() as u32,
            stages,
        )?;
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
        let pipeline = pipelines::create(
            ctx,
            &layouts.pipeline,
            &PipelineDesc {
                name: "ibr hemicube",
                vert: "ibr_hemicube.vert",
                frag: "pr_hemicube.frag",
                topology: vk::PrimitiveTopology::TRIANGLE_LIST,
                stride: std::mem::size_of::<IbrVertex>() as u32,
                attributes: &[
                    (vk::Format::R32G32B32_SFLOAT, 0),
                    (vk::Format::R32_UINT, 12),
                    (vk::Format::R32G32B32_SFLOAT, 16),
                ],
                targets: &targets,
                specialization: &[],
                per_vertex: true,
                depth: true,
                wide_lines: false,
            },
        )?;
        Ok(Self {
            ctx: ctx.clone(),
            layouts,
            pipeline,
            vertices,
            triangles: surf.corners.len() as u32,
            item_id,
            item_dist,
            depth,
            size,
            batch,
        })
    }

    /// Bytes of GPU memory (corners and item buffer).
    pub fn bytes(&self) -> u64 {
        self.vertices.size + self.item_id.bytes() + self.item_dist.bytes() + self.depth.bytes()
    }

    /// The samples of each of `lights`' hemicubes (at most `batch`), rays leaving `lift` off
    /// their surfaces: rasterized, read back, shaded on the CPU.
    pub fn cast(
        &mut self,
        lights: &[Light],
        surf: &Surfaces,
        lift: f64,
    ) -> Result<Vec<Vec<Sample>>> {
        let lights = &lights[..lights.len().min(self.batch)];
        let h = self.size;
        let ctx = self.ctx.clone();
        let near = (0.5 * lift) as f32;
        ctx.submit_and_wait(|cmd| {
            let d = &ctx.device;
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
            unsafe {
                d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, self.pipeline.raw());
                d.cmd_bind_vertex_buffers(cmd, 0, &[self.vertices.raw], &[0]);
            }
            for (k, light) in lights.iter().enumerate() {
                let Some((x, n)) = frame_of(light) else {
                    continue;
                };
                let eye = x + n * lift;
                let (t, b) = basis(n);
                // The faces in the CPU's order (hemicube.rs `texels`): front, then the sides.
                let faces = [(n, t, b), (t, b, n), (-t, -b, n), (b, -t, n), (-b, t, n)];
                for (f, &(fw, rt, up)) in faces.iter().enumerate() {
                    let (y, rows) = if f == 0 {
                        (0, h)
                    } else {
                        (h + (f as u32 - 1) * h / 2, h / 2)
                    };
                    let rect = vk::Rect2D {
                        offset: vk::Offset2D {
                            x: (k as u32 * h) as i32,
                            y: y as i32,
                        },
                        extent: vk::Extent2D {
                            width: h,
                            height: rows,
                        },
                    };
                    let c = IbrFace {
                        eye: v4(eye, near),
                        forward: v4(fw, if f == 0 { 0.0 } else { 1.0 }),
                        right: v4(rt, 0.0),
                        up: v4(up, 0.0),
                    };
                    unsafe {
                        d.cmd_set_viewport(
                            cmd,
                            0,
                            &[vk::Viewport {
                                x: rect.offset.x as f32,
                                y: y as f32,
                                width: h as f32,
                                height: rows as f32,
                                min_depth: 0.0,
                                max_depth: 1.0,
                            }],
                        );
                        d.cmd_set_scissor(cmd, 0, &[rect]);
                        d.cmd_push_constants(
                            cmd,
                            self.layouts.pipeline.raw(),
                            vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT,
                            0,
                            as_bytes(std::slice::from_ref(&c)),
                        );
                        d.cmd_draw(cmd, 3 * self.triangles, 1, 0, 0);
                    }
                }
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
        })?;
        let ids = self.item_id.read()?;
        let dists = self.item_dist.read()?;
        let width = (self.batch as u32 * h) as usize;
        let word = |bytes: &[u8], i: usize| {
            u32::from_le_bytes(bytes[4 * i..4 * i + 4].try_into().unwrap())
        };
        Ok(lights
            .iter()
            .enumerate()
            .map(|(k, light)| {
                let Some((x, n)) = frame_of(light) else {
                    return Vec::new();
                };
                let origin = x + n * lift;
                let h = h as usize;
                // Texel q of the CPU's order is row q / H, column q % H of this VPL's column.
                texels(n, h as u32)
                    .iter()
                    .enumerate()
                    .filter_map(|(q, texel)| {
                        let i = (q / h) * width + k * h + q % h;
                        let id = word(&ids, i);
                        if id == 0 {
                            return None;
                        }
                        let t = f32::from_bits(word(&dists, i)) as f64;
                        shade(light, origin, texel, t, surf.normal[id as usize - 1])
                    })
                    .collect()
            })
            .collect())
    }
}

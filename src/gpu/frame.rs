//! The frame on the GPU (§3.3, §4.3): shadow maps rasterized per light view, a G-buffer at 2×2
//! samples per pixel (vertex-interpolated indirect light computed per vertex), splat fans
//! accumulated with additive blending, and a compose pass adding emission, per-pixel direct
//! light and the environment and resolving the samples. `src/frame/cpu.rs` is the same image
//! formation on the CPU; the passes are recorded by `passes/{shadow,gbuffer,splat,compose}.rs`.

use super::context::Context;
use super::layout::{
    as_bytes, bin_centers, frame_binding as fb, spec, CornerVertex, FrameConstants,
    GpuFrameElement, GpuLight, GpuMaterial, GpuShadowView,
};
use super::memory::{Buffer, Image, DEPTH_FORMAT};
use super::passes::{self, FramePass};
use super::pipelines::{
    create, descriptor_kinds, descriptor_pool, texel_sampler, Layouts, PipelineDesc, Target,
};
use super::profiler::Profiler;
use super::resources::decode;
use super::solver::GpuSolver;
use crate::error::{Result, VkContext};
use crate::frame::camera::{View, SUPERSAMPLE};
use crate::frame::shadow::ShadowMaps;
use crate::frame::surfaces::{Surfaces, MODE_SPLAT};
use crate::frame::Image as Frame;
use crate::plan::Features;
use crate::scene::{Light, Scene};
use crate::system::System;
use ash::vk;
use glam::DMat4;
use std::sync::Arc;

const RGBA32F: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

/// `CornerVertex::leaf` bit of crack-filling input triangles (`AR_FILLER` in gbuffer.vert).
pub const FILLER: u32 = 0x8000_0000;

/// Pipelines of the frame passes.
pub struct FramePipelines {
    /// Shadow-map views: linear distance, depth-tested.
    pub shadow: vk::Pipeline,
    /// G-buffer: position + leaf, vertex-interpolated indirect light.
    pub gbuffer: vk::Pipeline,
    /// Splat fans, additive.
    pub splat: vk::Pipeline,
    /// Full-screen compose and 2×2 resolve.
    pub compose: vk::Pipeline,
}

/// Images of the frame passes.
pub struct FrameImages {
    /// Shadow maps, views stacked vertically (R32F linear distances).
    pub shadow_map: Image,
    /// Depth for the shadow-map views.
    pub shadow_depth: Image,
    /// G-buffer position + leaf (2W × 2H).
    pub gbuf_position: Image,
    /// G-buffer vertex-interpolated radiance.
    pub gbuf_vertex: Image,
    /// G-buffer depth.
    pub gbuf_depth: Image,
    /// Splat sums (Σ w·L, Σ w).
    pub splat: Image,
    /// Final linear radiance (W × H).
    pub output: Image,
}

struct FrameBuffers {
    corners: Buffer,
    splats: Buffer,
    storage: Vec<(u32, Buffer)>,
}

/// Draws frames of a solved scene from its camera.
pub struct GpuFrame {
    ctx: Arc<Context>,
    layouts: Layouts,
    pipes: FramePipelines,
    images: FrameImages,
    buffers: FrameBuffers,
    sampler: vk::Sampler,
    pool: vk::DescriptorPool,
    set: vk::DescriptorSet,
    profiler: Profiler,
    constants: FrameConstants,
    corner_count: u32,
    splat_count: u32,
    features: Features,
    views: u32,
    shadow_size: u32,
    timings: Vec<(String, f64)>,
}

/// An overwritten (not blended) color target.
fn put_target(format: vk::Format) -> Target {
    Target {
        format,
        additive: false,
        write: true,
    }
}

fn mat(m: DMat4) -> [[f32; 4]; 4] {
    m.to_cols_array_2d().map(|c| c.map(|v| v as f32))
}

fn v4(v: glam::DVec3, w: f32) -> [f32; 4] {
    [v.x as f32, v.y as f32, v.z as f32, w]
}

fn gpu_lights(lights: &[Light], maps: &ShadowMaps) -> Vec<GpuLight> {
    lights
        .iter()
        .zip(&maps.light_views)
        .map(|(l, &(first, count))| {
            let (kind, pos, dir, power, cutoff, beam) = match *l {
                Light::Directional {
                    direction,
                    irradiance,
                } => (0, glam::DVec3::ZERO, direction, irradiance, 0.0, 0.0),
                Light::Point {
                    position,
                    intensity,
                } => (1, position, glam::DVec3::Z, intensity, 0.0, 0.0),
                Light::Spot {
                    position,
                    axis,
                    intensity,
                    cutoff,
                    beam_width,
                } => (2, position, axis, intensity, cutoff, beam_width),
            };
            GpuLight {
                kind_views: [kind, first, count, 0],
                position: v4(pos, 0.0),
                direction: v4(dir, 0.0),
                power: v4(power, cutoff as f32),
                params: [beam as f32, 0.0, 0.0, 0.0],
            }
        })
        .collect()
}

impl GpuFrame {
    /// Uploads the geometry, lights and shadow views and creates the frame's images and
    /// pipelines for `scene`'s camera.
    pub fn new(
        ctx: Arc<Context>,
        scene: &Scene,
        sys: &System,
        surf: &Surfaces,
        maps: &ShadowMaps,
        features: &Features,
    ) -> Result<Self> {
        let c = &ctx;
        let vb = vk::BufferUsageFlags::VERTEX_BUFFER;
        let sb = vk::BufferUsageFlags::STORAGE_BUFFER;
        let corners: Vec<CornerVertex> = (0..sys.leaves.len())
            .flat_map(|li| {
                let e =
                    &sys.elements[sys.hierarchy.element(sys.leaves[li].node).unwrap_or(0) as usize];
                (0..3).map(move |k| (li, e.corners[k], k))
            })
            .map(|(li, p, k)| CornerVertex {
                position: [p.x as f32, p.y as f32, p.z as f32],
                leaf: li as u32,
                vertex: surf.corner_vertex[li][k],
            })
            .collect();
        // The input triangles again, flagged, behind the elements: bisection leaves T-junctions
        // whose float rounding opens pinhole cracks between elements; these fill them.
        let mut corners = corners;
        let mut tri = 0usize;
        for m in &scene.meshes {
            for t in &m.triangles {
                let leaf = surf.triangle_leaf[tri];
                if leaf != u32::MAX {
                    for k in 0..3 {
                        let p = m.positions[t[k] as usize];
                        corners.push(CornerVertex {
                            position: [p.x as f32, p.y as f32, p.z as f32],
                            leaf: leaf | FILLER,
                            vertex: surf.triangle_vertices[tri][k],
                        });
                    }
                }
                tri += 1;
            }
        }
        let splats: Vec<u32> = (0..sys.leaves.len() as u32)
            .filter(|&li| features.splat && surf.mode[li as usize] == MODE_SPLAT)
            .collect();
        // Shared-vertex adjacency only where smooth meshes are interpolated.
        let (adj_offsets, adj_list) = if features.vertex {
            (surf.adjacency_offsets.clone(), surf.adjacency.clone())
        } else {
            (Vec::new(), Vec::new())
        };
        let elements: Vec<GpuFrameElement> = sys
            .leaves
            .iter()
            .enumerate()
            .map(|(li, l)| GpuFrameElement {
                center_radius: v4(surf.center[li], surf.radius[li] as f32),
                normal_area: v4(l.normal, l.area as f32),
                ids: [l.node, surf.surface[li], surf.mode[li], l.material],
                cos_norm: [l.cos_norm as f32, 0.0, 0.0, 0.0],
            })
            .collect();
        let materials: Vec<GpuMaterial> = sys.materials.iter().map(GpuMaterial::new).collect();
        let views: Vec<GpuShadowView> = maps
            .views
            .iter()
            .map(|v| GpuShadowView {
                view_proj: mat(v.view_proj),
                origin: v4(v.origin, if v.ortho { 1.0 } else { 0.0 }),
                forward: v4(v.forward, v.half as f32),
            })
            .collect();
        // Storage buffers may not be empty: pad with one unused record.
        fn padded<T: Copy + Default>(v: Vec<T>) -> Vec<T> {
            if v.is_empty() {
                vec![T::default()]
            } else {
                v
            }
        }
        let storage = vec![
            (
                fb::MATERIALS,
                c.upload_buffer("frame materials", as_bytes(&padded(materials)), sb)?,
            ),
            (
                fb::BIN_CENTERS,
                c.upload_buffer("frame bin centers", as_bytes(&bin_centers(&sys.bins)), sb)?,
            ),
            (
                fb::ELEMENTS,
                c.upload_buffer("frame elements", as_bytes(&padded(elements)), sb)?,
            ),
            (
                fb::ADJ_OFFSETS,
                c.upload_buffer("shared-vertex offsets", as_bytes(&padded(adj_offsets)), sb)?,
            ),
            (
                fb::ADJ_LIST,
                c.upload_buffer("shared-vertex elements", as_bytes(&padded(adj_list)), sb)?,
            ),
            (
                fb::LIGHTS,
                c.upload_buffer(
                    "lights",
                    as_bytes(&padded(gpu_lights(&scene.lights, maps))),
                    sb,
                )?,
            ),
            (
                fb::SHADOW_VIEWS,
                c.upload_buffer("shadow views", as_bytes(&padded(views)), sb)?,
            ),
        ];
        let buffers = FrameBuffers {
            corners: c.upload_buffer("element corners", as_bytes(&corners), vb)?,
            splats: c.upload_buffer("splat instances", as_bytes(&padded(splats.clone())), vb)?,
            storage,
        };
        let s = maps.size;
        let nviews = maps.views.len() as u32;
        let (w, h) = (scene.camera.width, scene.camera.height);
        let (sw, sh) = (w * SUPERSAMPLE, h * SUPERSAMPLE);
        let images = FrameImages {
            shadow_map: c.create_image(
                "shadow maps",
                s.max(1),
                (s * nviews).max(1),
                vk::Format::R32_SFLOAT,
            )?,
            shadow_depth: c.create_image(
                "shadow depth",
                s.max(1),
                (s * nviews).max(1),
                DEPTH_FORMAT,
            )?,
            gbuf_position: c.create_image("G-buffer position", sw, sh, RGBA32F)?,
            // Scenes without smooth meshes / flat surfaces get 1×1 placeholders (never read).
            gbuf_vertex: if features.vertex {
                c.create_image("G-buffer vertex radiance", sw, sh, RGBA32F)?
            } else {
                c.create_image("G-buffer vertex radiance (none)", 1, 1, RGBA32F)?
            },
            gbuf_depth: c.create_image("G-buffer depth", sw, sh, DEPTH_FORMAT)?,
            splat: if features.splat {
                c.create_image("splat sums", sw, sh, RGBA32F)?
            } else {
                c.create_image("splat sums (none)", 1, 1, RGBA32F)?
            },
            output: c.create_image("frame", w, h, RGBA32F)?,
        };
        let kinds = descriptor_kinds(fb::COUNT, &fb::BUFFERS);
        let layouts = Layouts::with(
            c,
            "frame",
            &kinds,
            std::mem::size_of::<FrameConstants>() as u32,
        )?;
        let pipes = Self::pipelines(c, layouts.pipeline, features)?;
        let sampler = texel_sampler(c, "frame sampler")?;
        let pool = descriptor_pool(c, &kinds, 1, "frame descriptor pool")?;
        let set = unsafe {
            c.device.allocate_descriptor_sets(
                &vk::DescriptorSetAllocateInfo::default()
                    .descriptor_pool(pool)
                    .set_layouts(&[layouts.set]),
            )
        }
        .vk("allocating the frame descriptor set")?[0];
        c.name(set, "frame set");
        let view = View::new(&scene.camera);
        let (lo, hi) = scene.bounds();
        let far = ((lo + hi) * 0.5 - view.eye).length() + (hi - lo).length() + 1e-6;
        let env = scene.environment;
        let grid = sys.bins.nu as u32 | (sys.bins.nv as u32) << 16;
        let constants = FrameConstants {
            view_proj: mat(view.view_proj(far * 1e-5, far)),
            eye: v4(view.eye, 1.0),
            environment: v4(env, 0.0),
            sizes: [sw, sh, grid, 0],
            misc: [scene.lights.len() as u32, 0, s, SUPERSAMPLE],
        };
        let profiler = Profiler::new(c, 16)?;
        let frame = Self {
            corner_count: corners.len() as u32,
            splat_count: splats.len() as u32,
            features: *features,
            views: nviews,
            shadow_size: s,
            ctx: ctx.clone(),
            layouts,
            pipes,
            images,
            buffers,
            sampler,
            pool,
            set,
            profiler,
            constants,
            timings: Vec::new(),
        };
        frame.write_set(None);
        let mut frame = frame;
        // Images the scene does not need are still bound (the shaders skip them by
        // specialization): give them a defined layout and content once.
        let ctx = frame.ctx.clone();
        let im = &mut frame.images;
        let mut unused: Vec<(&mut Image, f32)> = Vec::new();
        if frame.views == 0 {
            unused.push((&mut im.shadow_map, crate::frame::shadow::EMPTY));
        }
        if !features.vertex {
            unused.push((&mut im.gbuf_vertex, 0.0));
        }
        if !features.splat {
            unused.push((&mut im.splat, 0.0));
        }
        if !unused.is_empty() {
            ctx.submit_and_wait(|cmd| {
                for (img, value) in unused {
                    let access = super::barrier::Access::Attachment;
                    super::barrier::transition(&ctx, cmd, &mut [(&mut *img, access)]);
                    let load = passes::Load::ClearTo(value);
                    passes::begin_rendering(&ctx, cmd, &[(&*img, load)]);
                    passes::end_rendering(&ctx, cmd);
                    let access = super::barrier::Access::Sampled;
                    super::barrier::transition(&ctx, cmd, &mut [(&mut *img, access)]);
                }
            })?;
        }
        Ok(frame)
    }

    fn pipelines(
        c: &Context,
        layout: vk::PipelineLayout,
        features: &Features,
    ) -> Result<FramePipelines> {
        let specialization = spec::values(features, 0, false);
        let gbuffer_targets: &[Target] = if features.vertex {
            &[put_target(RGBA32F), put_target(RGBA32F)]
        } else {
            &[put_target(RGBA32F)]
        };
        let stride = std::mem::size_of::<CornerVertex>() as u32;
        let put = put_target;
        let position = (vk::Format::R32G32B32_SFLOAT, 0);
        let desc = |name, vert, frag| PipelineDesc {
            name,
            vert,
            frag,
            topology: vk::PrimitiveTopology::TRIANGLE_LIST,
            stride: 0,
            attributes: &[],
            targets: &[],
            specialization: &specialization,
            per_vertex: true,
            depth: false,
        };
        Ok(FramePipelines {
            shadow: create(
                c,
                layout,
                &PipelineDesc {
                    stride,
                    attributes: &[position],
                    targets: &[put(vk::Format::R32_SFLOAT)],
                    depth: true,
                    ..desc("shadow", "shadow.vert", "shadow.frag")
                },
            )?,
            gbuffer: create(
                c,
                layout,
                &PipelineDesc {
                    stride,
                    attributes: &[
                        position,
                        (vk::Format::R32_UINT, 12),
                        (vk::Format::R32_UINT, 16),
                    ],
                    targets: gbuffer_targets,
                    depth: true,
                    ..desc("gbuffer", "gbuffer.vert", "gbuffer.frag")
                },
            )?,
            splat: create(
                c,
                layout,
                &PipelineDesc {
                    stride: 4,
                    attributes: &[(vk::Format::R32_UINT, 0)],
                    targets: &[Target {
                        format: RGBA32F,
                        additive: true,
                        write: true,
                    }],
                    per_vertex: false,
                    ..desc("splat", "splat.vert", "splat.frag")
                },
            )?,
            compose: create(
                c,
                layout,
                &PipelineDesc {
                    targets: &[put(RGBA32F)],
                    ..desc("compose", "compose.vert", "compose.frag")
                },
            )?,
        })
    }

    /// Writes the descriptor set; `i_total` is the solver's display table (a placeholder until
    /// the first frame).
    fn write_set(&self, i_total: Option<(vk::ImageView, u32)>) {
        let im = &self.images;
        let image = |b: u32| -> vk::ImageView {
            match b {
                fb::I_TOTAL => i_total.map_or(im.output.view, |t| t.0),
                fb::SHADOW_MAP => im.shadow_map.view,
                fb::GBUF_POSITION => im.gbuf_position.view,
                fb::GBUF_VERTEX => im.gbuf_vertex.view,
                _ => im.splat.view,
            }
        };
        let image_infos: Vec<(u32, [vk::DescriptorImageInfo; 1])> = (0..fb::COUNT)
            .filter(|b| !fb::BUFFERS.contains(b))
            .map(|b| {
                (
                    b,
                    [vk::DescriptorImageInfo::default()
                        .sampler(self.sampler)
                        .image_view(image(b))
                        .image_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)],
                )
            })
            .collect();
        let buf_infos: Vec<(u32, [vk::DescriptorBufferInfo; 1])> = self
            .buffers
            .storage
            .iter()
            .map(|(b, buf)| {
                (
                    *b,
                    [vk::DescriptorBufferInfo::default()
                        .buffer(buf.raw)
                        .range(vk::WHOLE_SIZE)],
                )
            })
            .collect();
        let mut writes: Vec<vk::WriteDescriptorSet> = image_infos
            .iter()
            .map(|(b, info)| {
                vk::WriteDescriptorSet::default()
                    .dst_set(self.set)
                    .dst_binding(*b)
                    .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
                    .image_info(info)
            })
            .collect();
        writes.extend(buf_infos.iter().map(|(b, info)| {
            vk::WriteDescriptorSet::default()
                .dst_set(self.set)
                .dst_binding(*b)
                .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                .buffer_info(info)
        }));
        unsafe { self.ctx.device.update_descriptor_sets(&writes, &[]) };
    }

    /// Records the shadow maps of every light view.
    pub fn record_shadow_maps(&mut self, cmd: vk::CommandBuffer) {
        if self.views == 0 {
            return;
        }
        self.profiler.begin(&self.ctx, cmd, "shadow");
        let p = FramePass {
            ctx: &self.ctx,
            cmd,
            layout: self.layouts.pipeline,
            set: self.set,
        };
        passes::shadow::record(
            &p,
            self.pipes.shadow,
            &mut self.images,
            self.buffers.corners.raw,
            self.corner_count,
            self.views,
            self.shadow_size,
            self.constants,
        );
        self.profiler.end(&self.ctx, cmd);
    }

    /// Renders the shadow maps and waits.
    pub fn render_shadow_maps(&mut self) -> Result<()> {
        let ctx = self.ctx.clone();
        ctx.submit_and_wait(|cmd| {
            self.profiler.reset(&ctx, cmd);
            self.record_shadow_maps(cmd);
        })?;
        self.timings = self.profiler.results(&ctx)?;
        Ok(())
    }

    /// Reads the shadow maps back (the layout of [`ShadowMaps::data`]); the leaves' direct light
    /// is computed from them on the host, so leaves and pixels see the same maps.
    pub fn read_shadow_maps(&mut self) -> Result<Vec<f32>> {
        let ctx = self.ctx.clone();
        let bytes = ctx.read_image(&mut self.images.shadow_map)?;
        Ok(bytes
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect())
    }

    /// Records G-buffer, splat and compose passes reading `solver`'s I_total.
    pub fn record_frame(&mut self, cmd: vk::CommandBuffer, solver: &mut GpuSolver) {
        let layout = solver.images().layout;
        let mut constants = self.constants;
        constants.eye[3] = (1.0 / solver.scale()) as f32;
        constants.sizes[3] = layout.rows_per_column;
        solver.prepare_display(cmd);
        let ctx = self.ctx.clone();
        let p = FramePass {
            ctx: &ctx,
            cmd,
            layout: self.layouts.pipeline,
            set: self.set,
        };
        self.profiler.begin(&ctx, cmd, "gbuffer");
        passes::gbuffer::record(
            &p,
            self.pipes.gbuffer,
            &mut self.images,
            self.buffers.corners.raw,
            self.corner_count,
            constants,
            self.features.vertex,
        );
        self.profiler.end(&ctx, cmd);
        if self.features.splat {
            self.profiler.begin(&ctx, cmd, "splat");
            passes::splat::record(
                &p,
                self.pipes.splat,
                &mut self.images,
                self.buffers.splats.raw,
                self.splat_count,
                constants,
            );
            self.profiler.end(&ctx, cmd);
        }
        self.profiler.begin(&ctx, cmd, "compose");
        passes::compose::record(&p, self.pipes.compose, &mut self.images, constants);
        self.profiler.end(&ctx, cmd);
    }

    /// Draws the frame from `solver`'s current I_total, waits, and reads it back.
    pub fn render(&mut self, solver: &mut GpuSolver) -> Result<Frame> {
        self.write_set(Some((solver.images().i_total.1, 0)));
        let ctx = self.ctx.clone();
        ctx.submit_and_wait(|cmd| {
            self.profiler.reset(&ctx, cmd);
            self.record_frame(cmd, solver);
        })?;
        self.timings = self.profiler.results(&ctx)?;
        let out = &mut self.images.output;
        let (w, h) = (out.extent.width, out.extent.height);
        let texels = decode(RGBA32F, &ctx.read_image(out)?);
        Ok(Frame {
            width: w,
            height: h,
            pixels: texels.iter().map(|t| [t[0], t[1], t[2]]).collect(),
        })
    }

    /// Pass timings (ms) of the last submission.
    pub fn timings(&self) -> &[(String, f64)] {
        &self.timings
    }

    /// The frame's images (for hosts that present the output themselves).
    pub fn images(&self) -> &FrameImages {
        &self.images
    }
}

impl Drop for GpuFrame {
    fn drop(&mut self) {
        let ctx = self.ctx.clone();
        ctx.wait_idle();
        unsafe {
            for p in [
                self.pipes.shadow,
                self.pipes.gbuffer,
                self.pipes.splat,
                self.pipes.compose,
            ] {
                ctx.device.destroy_pipeline(p, None);
            }
            ctx.device.destroy_descriptor_pool(self.pool, None);
            ctx.device.destroy_sampler(self.sampler, None);
        }
        self.layouts.destroy(&ctx);
        self.profiler.destroy(&ctx);
        let im = &mut self.images;
        for i in [
            &mut im.shadow_map,
            &mut im.shadow_depth,
            &mut im.gbuf_position,
            &mut im.gbuf_vertex,
            &mut im.gbuf_depth,
            &mut im.splat,
            &mut im.output,
        ] {
            ctx.destroy_image(i);
        }
        ctx.destroy_buffer(&mut self.buffers.corners);
        ctx.destroy_buffer(&mut self.buffers.splats);
        for (_, b) in self.buffers.storage.iter_mut() {
            ctx.destroy_buffer(b);
        }
    }
}

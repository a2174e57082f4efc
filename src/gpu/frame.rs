//! The frame on the GPU (§3.3, §4.3): shadow maps rasterized per light view, a G-buffer at 2×2
//! samples per pixel (vertex-interpolated indirect light computed per vertex), splat fans
//! accumulated with additive blending, and a compose pass adding emission, per-pixel direct
//! light and the environment and resolving the samples. `src/frame/cpu.rs` is the same image
//! formation on the CPU; the passes are recorded by `passes/{shadow,gbuffer,splat,compose}.rs`,
//! and the image set is `passes/targets.rs`.

use super::context::Context;
use super::handle::Owned;
use super::layout::{frame_binding as fb, spec, FrameConstants};
use super::memory::{Buffer, Image, ImageDesc, MemoryReport, Purpose};
use super::pack;
use super::passes::targets::{FrameBuffers, FrameImages, RGBA32F};
use super::passes::{self, FramePass, Source};
use super::pipelines::{self, descriptor_kinds, Layouts};
use super::profiler::Profiler;
use super::solver::GpuSolver;
use crate::error::Result;
use crate::frame::shadow::ShadowMaps;
use crate::frame::surfaces::Surfaces;
use crate::frame::Image as Frame;
use crate::plan::Features;
use crate::scene::{Camera, Light, Scene};
use crate::system::System;
use ash::vk;
use std::sync::Arc;

mod constants;
mod data;
mod follow;

use constants::constants;
use data::FrameData;

/// The frame passes, each owning its pipeline.
struct FramePasses {
    /// Shadow-map views: linear distance, depth-tested.
    shadow: passes::shadow::Shadow,
    /// G-buffer: position + leaf, vertex-interpolated indirect light.
    gbuffer: passes::gbuffer::GBuffer,
    /// The splat texels' bins toward the eye, then the splat fans, additive.
    eye_bins: passes::eye_bins::EyeBins,
    splat: passes::splat::Splat,
    /// The area emitters' shared direct light at the blocks' corner pixels, then the
    /// full-screen compose and 2×2 resolve.
    direct_blocks: passes::direct_blocks::DirectBlocks,
    compose: passes::compose::Compose,
    /// The shared vertices' values, before the G-buffer reads them.
    vertex_values: passes::vertex_values::VertexValues,
}

/// What a frame is drawn from: the scene, its lights (the scene's and its emitter samples) and
/// their shadow views, the camera, the discretized system and its surfaces, and the plan's
/// features.
#[derive(Clone, Copy)]
pub struct FrameScene<'a> {
    /// The scene (geometry, materials, environment).
    pub scene: &'a Scene,
    /// The lights the frame shades with.
    pub lights: &'a [Light],
    /// The lights `start..end` whose direct light a pixel's samples share
    /// (`Prepared::shared_lights`; `(0, 0)`: none).
    pub shared_lights: (usize, usize),
    /// The camera (its size is the frame's).
    pub camera: &'a Camera,
    /// The discretized scene.
    pub sys: &'a System,
    /// Which surfaces are splatted or interpolated, and their shared vertices.
    pub surf: &'a Surfaces,
    /// The lights' shadow views.
    pub maps: &'a ShadowMaps,
    /// What the plan computes.
    pub features: &'a Features,
}

/// Draws frames of a solved scene from its camera.
pub struct GpuFrame {
    ctx: Arc<Context>,
    images: FrameImages<Image>,
    buffers: FrameBuffers<Buffer>,
    passes: FramePasses,
    set: vk::DescriptorSet,
    profiler: Profiler,
    constants: FrameConstants,
    corner_count: u32,
    splat_count: u32,
    features: Features,
    /// Pixels per side of the blocks sharing the area emitters' direct light (1: none;
    /// `frame::direct`), fixed with the images.
    direct_block: u32,
    /// Each shadow view's map in the atlas: x, y, side.
    shadow_rects: Vec<[u32; 3]>,
    /// The shadow views the maps are (to be) rendered for.
    views: Vec<crate::frame::shadow::ShadowView>,
    /// After a follow: the views the next shadow render draws (the others' maps are kept);
    /// `None`: every view.
    only: Option<Vec<bool>>,
    /// Whether the atlas holds every view's map (a partial render keeps the others).
    rendered: bool,
    /// Staging buffers of the last follow's uploads.
    staged: super::staged::Staged,
    /// The solver's I_total the set points at ([`GpuFrame::bind_solver`]).
    i_total: Option<vk::ImageView>,
    /// Factor on the output radiance ([`GpuFrame::set_exposure`]; 1: radiance as computed).
    exposure: f32,
    timings: Vec<(String, f64)>,
    setup: super::solver::SetupTimes,
    sampler: Owned<vk::Sampler>,
    _pool: Owned<vk::DescriptorPool>,
    layouts: Layouts,
}

impl GpuFrame {
    /// The frame's images for `camera` and `maps` under `features`, as data (what `info`
    /// reports as `frame_images` and `shadow_maps`); from `surf` its splat setting and shared
    /// vertices; `direct_block`: the blocks sharing the direct light
    /// ([`crate::frame::direct::block_for`]).
    pub fn describe(
        camera: &Camera,
        features: &Features,
        maps: &ShadowMaps,
        surf: &Surfaces,
        direct_block: u32,
    ) -> FrameImages<ImageDesc> {
        FrameImages::describe(
            camera.width,
            camera.height,
            features,
            maps.atlas,
            surf.splat_per_sample,
            direct_block,
            surf.vertices.len(),
        )
    }

    /// Memory of the frame's images, by purpose.
    pub fn planned_memory(
        camera: &Camera,
        features: &Features,
        maps: &ShadowMaps,
        surf: &Surfaces,
        direct_block: u32,
    ) -> MemoryReport {
        let images = Self::describe(camera, features, maps, surf, direct_block);
        MemoryReport::default().images(images.iter())
    }

    /// Uploads the geometry, the lights and their shadow views of `f` and creates the frame's
    /// images and pipelines for its camera.
    pub fn new(ctx: Arc<Context>, f: &FrameScene<'_>) -> Result<Self> {
        let FrameScene {
            scene,
            lights,
            shared_lights,
            camera,
            sys,
            surf,
            maps,
            features,
        } = *f;
        let c = &ctx;
        let t = std::time::Instant::now();
        let data = FrameData::new(f);
        let buffers = data.upload(c)?;
        let shared = shared_lights.0..shared_lights.1;
        let size = (camera.width, camera.height);
        let direct_block = crate::frame::direct::block_for(surf.direct_block, &shared, size);
        let images =
            Self::describe(camera, features, maps, surf, direct_block).try_map(|d| d.create(c))?;
        let uploads_ms = t.elapsed().as_secs_f64() * 1e3;
        let t = std::time::Instant::now();
        let kinds = descriptor_kinds(fb::COUNT, &fb::BUFFERS);
        let layouts = Layouts::with(
            c,
            "frame",
            &kinds,
            std::mem::size_of::<FrameConstants>() as u32,
        )?;
        let specialization = spec::values(features, 0, false);
        let frame_passes = FramePasses {
            shadow: passes::shadow::Shadow::new(c, &layouts.pipeline, &specialization)?,
            gbuffer: passes::gbuffer::GBuffer::new(
                c,
                &layouts.pipeline,
                &specialization,
                features,
            )?,
            eye_bins: passes::eye_bins::EyeBins::new(c, &layouts.pipeline, &specialization)?,
            splat: passes::splat::Splat::new(c, &layouts.pipeline, &specialization)?,
            direct_blocks: passes::direct_blocks::DirectBlocks::new(
                c,
                &layouts.pipeline,
                &specialization,
            )?,
            compose: passes::compose::Compose::new(c, &layouts.pipeline, &specialization)?,
            vertex_values: passes::vertex_values::VertexValues::new(
                c,
                &layouts.pipeline,
                &specialization,
            )?,
        };
        let setup = super::solver::SetupTimes {
            uploads_ms,
            pipelines_ms: t.elapsed().as_secs_f64() * 1e3,
        };
        let sampler = pipelines::texel_sampler(c, "frame sampler")?;
        let pool = pipelines::descriptor_pool(c, &kinds, 1, "frame descriptor pool")?;
        let set = pipelines::allocate_set(c, &pool, &layouts.set, "frame set")?;
        let mut frame = Self {
            corner_count: data.corners.len() as u32,
            splat_count: pack::splat_instances(surf, features.splat).len() as u32,
            features: *features,
            direct_block,
            shadow_rects: maps
                .views
                .iter()
                .map(|v| [v.atlas.0, v.atlas.1, v.size])
                .collect(),
            views: maps.views.clone(),
            only: None,
            rendered: false,
            i_total: None,
            exposure: 1.0,
            staged: super::staged::Staged::new(c),
            constants: constants(
                scene,
                lights.len(),
                (shared_lights, direct_block),
                camera,
                sys,
            ),
            profiler: Profiler::new(c, 16)?,
            ctx: ctx.clone(),
            images,
            buffers,
            passes: frame_passes,
            set,
            timings: Vec::new(),
            setup,
            sampler,
            _pool: pool,
            layouts,
        };
        frame.write_set(None);
        frame.clear_unused()?;
        Ok(frame)
    }

    /// Images the scene does not need are still bound (the shaders skip them by
    /// specialization): give them a defined layout and content once.
    fn clear_unused(&mut self) -> Result<()> {
        let ctx = self.ctx.clone();
        let im = &mut self.images;
        let mut unused: Vec<(&mut Image, f32)> = Vec::new();
        if self.shadow_rects.is_empty() {
            unused.push((&mut im.shadow_map, crate::frame::shadow::EMPTY));
        }
        if !self.features.vertex && !self.features.normals {
            unused.push((&mut im.gbuf_vertex, 0.0));
        }
        if !self.features.normals {
            unused.push((&mut im.gbuf_normal, 0.0));
        }
        if !self.features.splat {
            unused.push((&mut im.splat, 0.0));
            unused.push((&mut im.splat_bins, -1.0));
        }
        if self.direct_block <= 1 {
            unused.push((&mut im.direct_blocks, 0.0));
        }
        if !self.features.vertex {
            unused.push((&mut im.vertex_values, 0.0));
        }
        if unused.is_empty() {
            return Ok(());
        }
        ctx.submit_and_wait(|cmd| {
            use super::barrier::{transition, Access};
            for (img, value) in unused {
                transition(&ctx, cmd, &mut [(&mut *img, Access::Attachment)]);
                let load = passes::Load::ClearTo(value);
                passes::begin_rendering(&ctx, cmd, &[(&*img, load)]);
                passes::end_rendering(&ctx, cmd);
                transition(&ctx, cmd, &mut [(&mut *img, Access::Sampled)]);
            }
        })
    }

    /// Writes the descriptor set; `i_total` is the solver's display table (a placeholder until
    /// the first frame).
    fn write_set(&self, i_total: Option<vk::ImageView>) {
        let im = &self.images;
        let images: Vec<(u32, vk::ImageView)> = (0..fb::COUNT)
            .filter(|b| !fb::BUFFERS.contains(b))
            .map(|b| {
                let view = match b {
                    fb::I_TOTAL => i_total.unwrap_or(im.output.view),
                    fb::SHADOW_MAP => im.shadow_map.view,
                    fb::GBUF_POSITION => im.gbuf_position.view,
                    fb::GBUF_VERTEX => im.gbuf_vertex.view,
                    fb::GBUF_NORMAL => im.gbuf_normal.view,
                    fb::SPLAT_BINS => im.splat_bins.view,
                    fb::DIRECT_BLOCKS => im.direct_blocks.view,
                    fb::VERTEX_VALUES => im.vertex_values.view,
                    _ => im.splat.view,
                };
                (b, view)
            })
            .collect();
        let b = &self.buffers;
        let buffers = [
            (fb::MATERIALS, b.materials.raw),
            (fb::BIN_CENTERS, b.bin_centers.raw),
            (fb::ELEMENTS, b.elements.raw),
            (fb::ADJ_OFFSETS, b.adj_offsets.raw),
            (fb::ADJ_LIST, b.adj_list.raw),
            (fb::LIGHTS, b.lights.raw),
            (fb::SHADOW_VIEWS, b.shadow_views.raw),
            (fb::EMITTERS, b.emitters.raw),
            (fb::VERTEX_POSITIONS, b.vertex_positions.raw),
        ];
        pipelines::write_set(&self.ctx, self.set, self.sampler.raw(), &images, &buffers);
    }

    /// Records the shadow maps of every light view (after [`GpuFrame::follow`]: of the views
    /// it found changed).
    pub fn record_shadow_maps(&mut self, cmd: vk::CommandBuffer) {
        if self.shadow_rects.is_empty() || self.shadow_views_to_render() == 0 {
            self.only = None;
            return;
        }
        let ctx = self.ctx.clone();
        let p = FramePass {
            ctx: &ctx,
            cmd,
            layout: self.layouts.pipeline.raw(),
            set: self.set,
            constants: self.constants,
        };
        let only = self.only.take().filter(|_| self.rendered);
        let corners = Source {
            buffer: self.buffers.corners.raw,
            count: self.corner_count,
        };
        let (shadow, images, prof) = (&self.passes.shadow, &mut self.images, &mut self.profiler);
        prof.scope(&ctx, cmd, "shadow", || {
            shadow.record(&p, images, corners, &self.shadow_rects, only.as_deref())
        });
        self.rendered = true;
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

    /// Reads the shadow-map atlas back (row-major; [`ShadowMaps::set_from_atlas`] takes it); the
    /// leaves' direct light is computed from it on the host, so leaves and pixels see the same
    /// maps.
    pub fn read_shadow_maps(&mut self) -> Result<Vec<crate::frame::shadow::Texel>> {
        let v = pack::decode_r32(&self.images.shadow_map.read()?);
        Ok(v.chunks_exact(2).map(|t| [t[0], t[1]]).collect())
    }

    /// Records G-buffer, splat and compose passes reading `solver`'s I_total (bind it first
    /// with [`GpuFrame::bind_solver`]).
    pub fn record_frame(&mut self, cmd: vk::CommandBuffer, solver: &mut GpuSolver) {
        let layout = solver.images().layout;
        let mut constants = self.constants;
        constants.eye[3] = (1.0 / solver.scale()) as f32;
        constants.environment[3] = self.exposure;
        constants.sizes[3] = layout.rows_per_column;
        solver.prepare_display(cmd);
        let ctx = self.ctx.clone();
        let corners = Source {
            buffer: self.buffers.corners.raw,
            count: self.corner_count,
        };
        let splats = Source {
            buffer: self.buffers.splats.raw,
            count: self.splat_count,
        };
        let p = FramePass {
            ctx: &ctx,
            cmd,
            layout: self.layouts.pipeline.raw(),
            set: self.set,
            constants,
        };
        let (ps, images, prof) = (&self.passes, &mut self.images, &mut self.profiler);
        if self.features.vertex {
            prof.scope(&ctx, cmd, "vertex_values", || {
                ps.vertex_values.record(&p, images)
            });
        }
        prof.scope(&ctx, cmd, "gbuffer", || {
            ps.gbuffer.record(&p, images, corners)
        });
        if self.features.splat {
            prof.scope(&ctx, cmd, "splat", || {
                ps.eye_bins.record(&p, images);
                ps.splat.record(&p, images, splats)
            });
        }
        if self.direct_block > 1 {
            prof.scope(&ctx, cmd, "direct_blocks", || {
                ps.direct_blocks.record(&p, images)
            });
        }
        prof.scope(&ctx, cmd, "compose", || ps.compose.record(&p, images));
    }

    /// Starts a command buffer's frame timestamps (a host's; [`GpuFrame::render`] does it
    /// itself); call before [`GpuFrame::record_frame`].
    pub fn begin_frame(&mut self, cmd: vk::CommandBuffer) {
        self.profiler.reset(&self.ctx, cmd);
    }

    /// Points the frame's set at `solver`'s I_total (once per solver; the image does not move).
    pub fn bind_solver(&mut self, solver: &GpuSolver) {
        self.i_total = Some(solver.images().i_total.1);
        self.write_set(self.i_total);
    }

    /// Draws the frame from `solver`'s current I_total, waits, and reads it back.
    pub fn render(&mut self, solver: &mut GpuSolver) -> Result<Frame> {
        self.bind_solver(solver);
        let ctx = self.ctx.clone();
        ctx.submit_and_wait(|cmd| {
            self.profiler.reset(&ctx, cmd);
            self.record_frame(cmd, solver);
        })?;
        self.timings = self.profiler.results(&ctx)?;
        let out = &mut self.images.output;
        let (w, h) = (out.extent.width, out.extent.height);
        let texels = pack::decode(RGBA32F, &out.read()?);
        Ok(Frame {
            width: w,
            height: h,
            pixels: texels.iter().map(|t| [t[0], t[1], t[2]]).collect(),
        })
    }

    /// Draws the next frames from `camera` (its size must be the one the images were made
    /// for: they are not reallocated); `lights` is the number of lights the frame shades
    /// (the shared ones stay those the frame was made or last followed with).
    pub fn set_camera(
        &mut self,
        scene: &Scene,
        lights: usize,
        camera: &Camera,
        sys: &System,
    ) -> Result<()> {
        let out = &self.images.output.extent;
        if (camera.width, camera.height) != (out.width, out.height) {
            return Err(crate::error::Error::Invalid(format!(
                "camera: the frame is {}×{} pixels; a new camera must keep that size (got {}×{})",
                out.width, out.height, camera.width, camera.height
            )));
        }
        let m = self.constants.misc;
        let shared = (m[1] as usize, m[2] as usize);
        self.constants = constants(scene, lights, (shared, self.direct_block), camera, sys);
        Ok(())
    }

    /// Multiplies the output by `factor` from the next frame on (a viewer's exposure; 1 by
    /// default, the output then being the radiance `render` writes).
    pub fn set_exposure(&mut self, factor: f32) {
        self.exposure = factor;
    }

    /// Reads the frame's timestamps of a host-submitted command buffer (after it completed).
    pub fn read_timings(&mut self) -> Result<&[(String, f64)]> {
        self.timings = self.profiler.results(&self.ctx)?;
        Ok(&self.timings)
    }

    /// How long creating the frame's resources and pipelines took.
    pub fn setup_times(&self) -> super::solver::SetupTimes {
        self.setup
    }

    /// Pass timings (ms) of the last submission.
    pub fn timings(&self) -> &[(String, f64)] {
        &self.timings
    }

    /// The frame's images (for hosts that present the output themselves).
    pub fn images(&self) -> &FrameImages<Image> {
        &self.images
    }

    /// GPU memory of the frame's images and buffers, by purpose.
    pub fn memory(&self) -> MemoryReport {
        let mut r = MemoryReport::default().images(self.images.iter().map(|i| &i.desc));
        for b in self.buffers.iter() {
            r.add(Purpose::FrameBuffers, b.size);
        }
        r
    }
}

impl Drop for GpuFrame {
    fn drop(&mut self) {
        // The fields free themselves once the GPU no longer uses them.
        self.ctx.wait_idle();
    }
}

//! Image-based radiosity's backends: the cube is built when the lights are prepared (VPLs
//! traced, hemicubes ray cast on the CPU backend or rasterized on the GPU backend, warped on the
//! host as the paper warps), iterations do nothing, and the frame reconstructs from the cube
//! per sample ([`super::CubeIndirect`], the CPU frame on both backends) with the direct light of
//! the shadow-mapped lights.

use super::cube::Cube;
use super::gpu::GpuHemicubes;
use crate::backend::{Backend, Draw, HostFrame, Prepared, Solve};
use crate::error::Result;
use crate::frame::Image;
use crate::gpu::barrier::{transition, Access};
use crate::gpu::memory::{Buffer, Image as GpuImage, ImageDesc, Purpose};
use crate::gpu::Context;
use crate::methods::instant::backend::idle_figures;
use crate::methods::{MethodReport, MethodSettings};
use crate::raycast::RayCaster;
use crate::scene::Scheme;
use crate::settings::BackendKind;
use crate::solver::convergence::Figures;
use crate::solver::Table;
use ash::vk;
use gpu_allocator::MemoryLocation;
use std::sync::Arc;
use std::time::Instant;

/// Image-based radiosity on either backend.
pub struct ImageBased {
    caster: RayCaster,
    raster: Option<(Arc<Context>, GpuHemicubes)>,
    display: Table,
    settings: MethodSettings,
    cube: Option<Cube>,
    report: MethodReport,
    timings: Vec<(String, f64)>,
    /// The frame handed to a host's command buffer (GPU backend): image, staging, exposure.
    host: Option<(GpuImage, Buffer)>,
    exposure: f32,
}

impl ImageBased {
    /// For `prep`, with hemicubes rasterized on `ctx` where one is given, else ray cast; the
    /// cube comes with the lights.
    pub fn new(
        prep: &Prepared,
        settings: MethodSettings,
        ctx: Option<Arc<Context>>,
    ) -> Result<Self> {
        let raster = match ctx {
            Some(ctx) => {
                let h = GpuHemicubes::new(
                    &ctx,
                    &prep.surfaces,
                    settings.hemicube,
                    super::chunk(settings.hemicube),
                )?;
                Some((ctx, h))
            }
            None => None,
        };
        Ok(Self {
            caster: RayCaster::new(&prep.system),
            raster,
            display: Table::zeros(prep.system.rows(), prep.system.bins.count),
            settings,
            cube: None,
            report: MethodReport::default(),
            timings: Vec::new(),
            host: None,
            exposure: 1.0,
        })
    }

    /// The cube (built by [`Solve::prepare_lights`]).
    pub fn cube(&self) -> Option<&Cube> {
        self.cube.as_ref()
    }
}

impl Solve for ImageBased {
    fn prepare_lights(&mut self, prep: &mut Prepared) -> Result<()> {
        let t = Instant::now();
        if !prep.maps.views.is_empty() {
            prep.maps.render_cpu(&self.caster);
        }
        self.timings
            .push(("shadow".into(), t.elapsed().as_secs_f64() * 1e3));
        let lift = super::lift(&prep.system);
        let surf = &prep.surfaces;
        let mut built = match &mut self.raster {
            Some((_, raster)) => {
                let mut cast = |lights: &[crate::scene::Light]| raster.cast(lights, surf, lift);
                super::build(&prep.scene, &prep.system, surf, &self.settings, &mut cast)?
            }
            None => {
                let mut cast = super::ray_cast(&self.caster, surf, self.settings.hemicube, lift);
                super::build(&prep.scene, &prep.system, surf, &self.settings, &mut cast)?
            }
        };
        let near = super::near::NearField {
            caster: &self.caster,
            surf,
            sys: &prep.system,
            lights: &prep.lights,
            maps: &prep.maps,
            lift,
        };
        let restored = super::near::restore(
            &mut built.cube,
            &near,
            built.clamp_area,
            self.settings.near_rays,
        );
        for (k, v) in [
            ("near_rays", self.settings.near_rays as f64),
            ("near_hits", restored.hits as f64),
            ("near_share", restored.share),
            ("near_ms", restored.ms),
        ] {
            built.report.figures.insert(k.into(), v);
        }
        built.report.setup_ms += restored.ms;
        for k in ["hemicube_ms", "warp_ms", "near_ms"] {
            self.timings
                .push((k.trim_end_matches("_ms").into(), built.report.figures[k]));
        }
        self.cube = Some(built.cube);
        self.report = built.report;
        Ok(())
    }
    fn iterate_batch(
        &mut self,
        _: &Prepared,
        _: Scheme,
        _: usize,
        n: usize,
    ) -> Result<Vec<Figures>> {
        Ok(idle_figures(&self.report, n))
    }
    fn i_ex(&mut self) -> Result<Table> {
        Ok(self.display.clone())
    }
    fn i_total(&mut self) -> Result<Table> {
        Ok(self.display.clone())
    }
    fn method_report(&self) -> Option<MethodReport> {
        Some(self.report.clone())
    }
}

impl Draw for ImageBased {
    fn draw(&mut self, prep: &Prepared) -> Result<Image> {
        let t = Instant::now();
        let image = match &self.cube {
            Some(cube) => {
                let store = super::CubeIndirect(cube);
                prep.render_cpu_with(&self.display, &self.caster, Some(&store))
            }
            None => prep.render_cpu(&self.display, &self.caster),
        };
        self.timings
            .push(("frame".into(), t.elapsed().as_secs_f64() * 1e3));
        Ok(image)
    }
}

impl Backend for ImageBased {
    fn kind(&self) -> BackendKind {
        if self.raster.is_some() {
            BackendKind::Gpu
        } else {
            BackendKind::Cpu
        }
    }
    fn device(&self) -> String {
        match &self.raster {
            Some((ctx, _)) => ctx.info.name.clone(),
            None => "cpu".into(),
        }
    }
    fn take_timings(&mut self) -> Vec<(String, f64)> {
        std::mem::take(&mut self.timings)
    }
    fn host_frame(&mut self) -> Option<&mut dyn HostFrame> {
        if self.raster.is_some() {
            Some(self)
        } else {
            None
        }
    }
    fn fallbacks(&self) -> Vec<String> {
        self.raster
            .as_ref()
            .map(|_| {
                "image-based-radiosity: hemicubes rasterized on the GPU; the warp into the cube and \
                 the frame's reconstruction run on the CPU (the paper warps on the host)"
                    .to_string()
            })
            .into_iter()
            .collect()
    }
}

impl HostFrame for ImageBased {
    fn record_draw(&mut self, prep: &Prepared, cmd: vk::CommandBuffer) -> Result<()> {
        let image = self.draw(prep)?;
        let Some((ctx, _)) = &self.raster else {
            return Err(crate::error::Error::Invalid(
                "recording into a command buffer needs the GPU backend".into(),
            ));
        };
        let ctx = ctx.clone();
        let (w, h) = (image.width, image.height);
        let bytes = w as u64 * h as u64 * 16;
        if self
            .host
            .as_ref()
            .map(|(i, _)| (i.extent.width, i.extent.height))
            != Some((w, h))
        {
            let out = ImageDesc::new(
                "ibr output",
                w,
                h,
                vk::Format::R32G32B32A32_SFLOAT,
                Purpose::FrameImages,
            )
            .create(&ctx)?;
            let staging = Buffer::new(
                &ctx,
                "ibr output (staging)",
                bytes,
                vk::BufferUsageFlags::TRANSFER_SRC,
                MemoryLocation::CpuToGpu,
            )?;
            self.host = Some((out, staging));
        }
        let (out, staging) = self.host.as_mut().expect("made above");
        let k = self.exposure;
        for (dst, p) in staging
            .mapped_mut()?
            .chunks_exact_mut(16)
            .zip(&image.pixels)
        {
            for (c, v) in [p[0] * k, p[1] * k, p[2] * k, 1.0].iter().enumerate() {
                dst[4 * c..4 * c + 4].copy_from_slice(&v.to_le_bytes());
            }
        }
        transition(&ctx, cmd, &mut [(&mut *out, Access::TransferDst)]);
        unsafe {
            ctx.device.cmd_copy_buffer_to_image(
                cmd,
                staging.raw,
                out.raw,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &[crate::gpu::memory::copy_region(out.extent)],
            )
        };
        transition(&ctx, cmd, &mut [(&mut *out, Access::Sampled)]);
        Ok(())
    }
    fn output(&self) -> Option<&GpuImage> {
        self.host.as_ref().map(|(i, _)| i)
    }
    fn set_exposure(&mut self, factor: f32) {
        self.exposure = factor;
    }
}

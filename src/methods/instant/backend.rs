//! Instant radiosity's backends. The VPLs are lights of the prepared scene (traced when it is
//! prepared, [`super::trace`]), so both backends only render every light's shadow map and draw
//! the frame: per-pixel light from the analytic lights, the emitter samples and the VPLs, with
//! an I_total of zero (nothing goes through the bins). The CPU backend ray-casts the maps and
//! the frame ([`crate::frame::cpu`]), the GPU backend rasterizes them ([`GpuFrame`]) and reads
//! I_total from a link-less [`GpuSolver`] holding zeros. An iteration does nothing: the solve is
//! the tracing.

use crate::backend::{Backend, Draw, Prepared, Solve};
use crate::error::Result;
use crate::frame::Image;
use crate::gpu::frame::GpuFrame;
use crate::gpu::memory::MemoryReport;
use crate::gpu::{Context, GpuOptions, GpuSolver};
use crate::methods::MethodReport;
use crate::plan::Features;
use crate::raycast::RayCaster;
use crate::scene::{Precision, Scheme};
use crate::settings::BackendKind;
use crate::solver::convergence::{Change, Figures};
use crate::solver::Table;
use std::sync::Arc;
use std::time::Instant;

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// `n` iterations that change nothing (the VPLs' flux, mean of RGB, as the energy).
pub(crate) fn idle_figures(report: &MethodReport, n: usize) -> Vec<Figures> {
    let flux = report.figures.get("vpl_flux").copied().unwrap_or(0.0);
    vec![
        Figures {
            change: Change {
                relative: 0.0,
                absolute: 0.0,
            },
            flux,
            peak: 0.0,
        };
        n
    ]
}

fn zeros(prep: &Prepared) -> Table {
    Table::zeros(prep.system.rows(), prep.system.bins.count)
}

/// Instant radiosity with ray-cast shadow maps and frame.
pub struct CpuInstant {
    caster: RayCaster,
    display: Table,
    report: MethodReport,
    timings: Vec<(String, f64)>,
}

impl CpuInstant {
    /// The ray caster over `prep`'s elements; `report` is the tracing's.
    pub fn new(prep: &Prepared, report: MethodReport) -> Self {
        Self {
            caster: RayCaster::new(&prep.system),
            display: zeros(prep),
            report,
            timings: Vec::new(),
        }
    }
}

impl Solve for CpuInstant {
    fn prepare_lights(&mut self, prep: &mut Prepared) -> Result<()> {
        let t = Instant::now();
        if !prep.maps.views.is_empty() {
            prep.maps.render_cpu(&self.caster);
        }
        self.timings.push(("shadow".into(), ms(t)));
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

impl Draw for CpuInstant {
    fn draw(&mut self, prep: &Prepared) -> Result<Image> {
        let t = Instant::now();
        let image = prep.render_cpu(&self.display, &self.caster);
        self.timings.push(("frame".into(), ms(t)));
        Ok(image)
    }
}

impl Backend for CpuInstant {
    fn kind(&self) -> BackendKind {
        BackendKind::Cpu
    }
    fn take_timings(&mut self) -> Vec<(String, f64)> {
        std::mem::take(&mut self.timings)
    }
}

/// Instant radiosity with rasterized shadow maps and the raster frame.
pub struct GpuInstant {
    ctx: Arc<Context>,
    display: GpuSolver,
    frame: GpuFrame,
    shape: (usize, usize),
    report: MethodReport,
    pending: Vec<(String, f64)>,
}

impl GpuInstant {
    /// The frame (every light's shadow-map view in its atlas) and a display table of zeros.
    pub fn new(ctx: Arc<Context>, prep: &Prepared, report: MethodReport) -> Result<Self> {
        // The display table only: no sources, no antiradiance (its passes never run).
        let features = Features {
            antiradiance: false,
            direct: false,
            environment: false,
            emission: false,
            ..prep.plan.features
        };
        let mut display = GpuSolver::new(
            ctx.clone(),
            &prep.system,
            GpuOptions {
                precision: prep.plan.precision,
                features: Some(features),
                ..Default::default()
            },
        )?;
        display.upload_i_total(&zeros(prep))?;
        let frame = crate::methods::antiradiance::gpu::frame_for(&ctx, prep, &display)?;
        Ok(Self {
            ctx,
            display,
            frame,
            shape: (prep.system.rows(), prep.system.bins.count),
            report,
            pending: Vec::new(),
        })
    }
}

impl Solve for GpuInstant {
    fn prepare_lights(&mut self, prep: &mut Prepared) -> Result<()> {
        if !prep.maps.views.is_empty() {
            self.frame.render_shadow_maps()?;
            self.pending.extend(self.frame.timings().iter().cloned());
        }
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
        Ok(Table::zeros(self.shape.0, self.shape.1))
    }
    fn i_total(&mut self) -> Result<Table> {
        Ok(Table::zeros(self.shape.0, self.shape.1))
    }
    fn precision(&self) -> Precision {
        self.display.precision()
    }
    fn method_report(&self) -> Option<MethodReport> {
        Some(self.report.clone())
    }
}

impl Draw for GpuInstant {
    fn draw(&mut self, _: &Prepared) -> Result<Image> {
        let image = self.frame.render(&mut self.display)?;
        self.pending.extend(self.frame.timings().iter().cloned());
        Ok(image)
    }
    fn set_camera(&mut self, prep: &Prepared) -> Result<()> {
        // The VPLs are lights of `prep`, so its light count includes them.
        crate::methods::antiradiance::gpu::take_camera(&mut self.frame, prep)
    }
}

impl Backend for GpuInstant {
    fn kind(&self) -> BackendKind {
        BackendKind::Gpu
    }
    fn device(&self) -> String {
        self.ctx.info.name.clone()
    }
    fn take_timings(&mut self) -> Vec<(String, f64)> {
        std::mem::take(&mut self.pending)
    }
    fn memory(&self) -> MemoryReport {
        self.display.memory()
    }
}

//! The GPU backend: the raster passes of §4 ([`GpuSolver`]) and the raster frame
//! ([`GpuFrame`]) on one Vulkan context, submitted by themselves or recorded into a command
//! buffer an embedding host gives them.

use super::backend::Backend;
use super::prepared::Prepared;
use super::GpuTuning;
use crate::error::Result;
use crate::frame::lights::direct_in_table;
use crate::frame::Image;
use crate::gpu::frame::GpuFrame;
use crate::gpu::memory::MemoryReport;
use crate::gpu::solver::SetupTimes;
use crate::gpu::work::Work;
use crate::gpu::{Context, GpuOptions, GpuSolver};
use crate::scene::{Precision, Scheme};
use crate::settings::BackendKind;
use crate::solver::convergence::Figures;
use crate::solver::Table;
use ash::vk;
use std::sync::Arc;

/// The GPU solver and frame; keeps what a restart in float32 needs.
pub struct GpuBackend {
    ctx: Arc<Context>,
    solver: GpuSolver,
    frame: GpuFrame,
    direct: Option<Table>,
    tuning: GpuTuning,
    pending: Vec<(String, f64)>,
}

impl GpuBackend {
    /// Creates the solver's and the frame's resources for `prep` on `ctx`.
    pub fn new(ctx: Arc<Context>, prep: &Prepared, tuning: GpuTuning) -> Result<Self> {
        let solver = Self::make_solver(&ctx, prep, prep.plan.precision, tuning)?;
        let frame = GpuFrame::new(
            ctx.clone(),
            &prep.scene,
            &prep.lights,
            &prep.camera,
            &prep.system,
            &prep.surfaces,
            &prep.maps,
            &prep.plan.features,
        )?;
        frame.bind_solver(&solver);
        Ok(Self {
            ctx,
            solver,
            frame,
            direct: None,
            tuning,
            pending: Vec::new(),
        })
    }

    fn make_solver(
        ctx: &Arc<Context>,
        prep: &Prepared,
        precision: Precision,
        tuning: GpuTuning,
    ) -> Result<GpuSolver> {
        GpuSolver::new(
            ctx.clone(),
            &prep.system,
            GpuOptions {
                precision,
                column_height: tuning.column_height,
                force_table_accumulation: tuning.force_table_accumulation,
                features: Some(prep.plan.features),
            },
        )
    }

    /// Sets the environment and direct light on the solver.
    fn set_sources(&mut self, prep: &Prepared) -> Result<()> {
        self.solver.set_environment(prep.scene.environment)?;
        if let Some(d) = &self.direct {
            self.solver.set_direct(d)?;
        }
        Ok(())
    }

    fn collect(&mut self, timings: &[(String, f64)]) {
        self.pending.extend(timings.iter().cloned());
    }

    /// The solver (for hosts reading its images, and for tests).
    pub fn solver(&mut self) -> &mut GpuSolver {
        &mut self.solver
    }

    /// The frame (for hosts presenting its output image, and reading its timestamps).
    pub fn frame(&mut self) -> &mut GpuFrame {
        &mut self.frame
    }

    /// The context.
    pub fn context(&self) -> &Arc<Context> {
        &self.ctx
    }

    /// The raster work of one propagation.
    pub fn work(&self) -> Work {
        self.solver.work()
    }

    /// How long creating the solver's and the frame's resources and pipelines took.
    pub fn setup_times(&self) -> SetupTimes {
        self.solver.setup_times() + self.frame.setup_times()
    }

    /// Starts a host command buffer's timestamps; call once per command buffer before the
    /// `record_*` calls.
    pub fn begin(&mut self, cmd: vk::CommandBuffer) {
        self.solver.begin_frame(cmd);
        self.frame.begin_frame(cmd);
    }

    /// Records the initial state into `cmd`.
    pub fn record_initialize(&mut self, cmd: vk::CommandBuffer) -> Result<()> {
        self.solver.record_initialize(cmd)
    }

    /// Records `n` iterations of `scheme` into `cmd`.
    pub fn record_iterations(
        &mut self,
        cmd: vk::CommandBuffer,
        scheme: Scheme,
        antiradiance_steps: usize,
        n: usize,
    ) -> Result<()> {
        for _ in 0..n {
            self.solver
                .record_iteration(cmd, scheme, antiradiance_steps)?;
        }
        Ok(())
    }

    /// Records the frame (G-buffer, splat, compose) from the current I_total into `cmd`; the
    /// result is [`GpuFrame::images`]' `output`, in shader-read layout.
    pub fn record_draw(&mut self, cmd: vk::CommandBuffer) {
        self.frame.record_frame(cmd, &mut self.solver);
    }
}

impl Backend for GpuBackend {
    fn kind(&self) -> BackendKind {
        BackendKind::Gpu
    }

    fn device(&self) -> String {
        self.ctx.info.name.clone()
    }

    fn follow(&mut self, before: &Prepared, prep: &Prepared) -> Result<bool> {
        // Only lights moved (the geometry, hence the system and its tables, is the same) and
        // the solver was planned for the same passes and precision: keep the solver and its
        // tables, make only the frame (lights, shadow views) anew. Moved objects change the
        // link records: the backend is made anew for them.
        let still = before
            .scene
            .meshes
            .iter()
            .zip(&prep.scene.meshes)
            .all(|(a, b)| a.positions == b.positions)
            && before.scene.meshes.len() == prep.scene.meshes.len();
        if !still
            || before.plan.features != prep.plan.features
            || before.plan.precision != prep.plan.precision
        {
            return Ok(false);
        }
        self.frame = GpuFrame::new(
            self.ctx.clone(),
            &prep.scene,
            &prep.lights,
            &prep.camera,
            &prep.system,
            &prep.surfaces,
            &prep.maps,
            &prep.plan.features,
        )?;
        self.frame.bind_solver(&self.solver);
        Ok(true)
    }

    fn prepare_lights(&mut self, prep: &mut Prepared) -> Result<()> {
        self.direct = None;
        if !prep.maps.views.is_empty() {
            self.frame.render_shadow_maps()?;
            let t = self.frame.timings().to_vec();
            self.collect(&t);
            let atlas = self.frame.read_shadow_maps()?;
            prep.maps.set_from_atlas(&atlas);
            self.direct = Some(direct_in_table(&prep.system, &prep.lights, &prep.maps));
        }
        self.set_sources(prep)
    }

    fn initialize(&mut self, _: &Prepared) -> Result<()> {
        self.solver.initialize()?;
        let t = self.solver.timings().to_vec();
        self.collect(&t);
        Ok(())
    }

    fn iterate_batch(
        &mut self,
        _: &Prepared,
        scheme: Scheme,
        steps: usize,
        n: usize,
    ) -> Result<Vec<Figures>> {
        let figures = self.solver.iterate_batch(scheme, steps, n)?;
        let t = self.solver.timings().to_vec();
        self.collect(&t);
        Ok(figures)
    }

    fn warm_start(&mut self, prep: &Prepared, i_ex: &Table) -> Result<()> {
        self.solver.upload_i_ex(&prep.system, i_ex)
    }

    fn i_ex(&mut self) -> Result<Table> {
        self.solver.read_i_ex()
    }

    fn i_total(&mut self) -> Result<Table> {
        self.solver.read_i_total()
    }

    fn overflow_limit(&self) -> f64 {
        self.solver.overflow_limit()
    }

    fn widen(&mut self, prep: &Prepared) -> Result<Option<String>> {
        if self.solver.precision() == Precision::F32 {
            return Ok(None);
        }
        self.solver = Self::make_solver(&self.ctx, prep, Precision::F32, self.tuning)?;
        self.set_sources(prep)?;
        self.frame.bind_solver(&self.solver);
        Ok(Some("tables switched to float32".into()))
    }

    fn draw(&mut self, _: &Prepared) -> Result<Image> {
        let image = self.frame.render(&mut self.solver)?;
        let t = self.frame.timings().to_vec();
        self.collect(&t);
        Ok(image)
    }

    fn set_camera(&mut self, prep: &Prepared) -> Result<()> {
        self.frame
            .set_camera(&prep.scene, prep.lights.len(), &prep.camera, &prep.system)
    }

    fn take_timings(&mut self) -> Vec<(String, f64)> {
        std::mem::take(&mut self.pending)
    }

    fn precision(&self) -> Precision {
        self.solver.precision()
    }

    fn fallbacks(&self) -> Vec<String> {
        self.solver.fallbacks().to_vec()
    }

    fn memory(&self) -> MemoryReport {
        self.solver.memory()
    }

    fn as_gpu(&mut self) -> Option<&mut GpuBackend> {
        Some(self)
    }
}

//! The GPU backend: the raster passes of §4 ([`GpuSolver`]) and the raster frame
//! ([`GpuFrame`]) on one Vulkan context, submitted by themselves or recorded into a command
//! buffer an embedding host gives them.

use crate::backend::GpuTuning;
use crate::backend::{Backend, Draw, Prepared, Solve};
use crate::error::Result;
use crate::frame::lights::direct_in_table;
use crate::frame::Image;
use crate::gpu::frame::{FrameScene, GpuFrame};
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

/// What the frame of `prep` is drawn from.
pub(crate) fn frame_scene(prep: &Prepared) -> FrameScene<'_> {
    FrameScene {
        scene: &prep.scene,
        lights: &prep.lights,
        shared_lights: (prep.shared_lights.start, prep.shared_lights.end),
        camera: &prep.camera,
        sys: &prep.system,
        surf: &prep.surfaces,
        maps: &prep.maps,
        features: &prep.plan.features,
    }
}

/// Points `frame` at `prep.camera` (same size) with `prep`'s lights, VPLs among them.
pub(crate) fn take_camera(frame: &mut GpuFrame, prep: &Prepared) -> Result<()> {
    frame.set_camera(&prep.scene, prep.lights.len(), &prep.camera, &prep.system)
}

/// The raster frame of `prep` on `ctx`, reading `solver`'s I_total.
pub(crate) fn frame_for(
    ctx: &Arc<Context>,
    prep: &Prepared,
    solver: &GpuSolver,
) -> Result<GpuFrame> {
    let mut frame = GpuFrame::new(ctx.clone(), &frame_scene(prep))?;
    frame.bind_solver(solver);
    Ok(frame)
}

/// The GPU solver and frame; keeps what a restart in float32 needs.
pub struct GpuBackend {
    ctx: Arc<Context>,
    solver: GpuSolver,
    frame: GpuFrame,
    direct: Option<Table>,
    /// The environment's shadowed incident table of the last light preparation (kept for a
    /// solver made anew at another precision, [`Solve::widen`]).
    sky: Option<std::sync::Arc<Table>>,
    tuning: GpuTuning,
    pending: Vec<(String, f64)>,
    /// After a follow that left every shadow view as it was: the maps' distances, reused
    /// instead of rendered and read back.
    kept_maps: Option<Vec<crate::frame::shadow::Texel>>,
    /// Where [`Solve::follow`] records the solver's uploads (an embedding host's command
    /// buffer, [`crate::engine::Engine::record_update`]); `None`: submitted at once.
    record_into: Option<vk::CommandBuffer>,
    last_follow: FollowReport,
}

/// What the last [`Solve::follow`] of the GPU backend did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct FollowReport {
    /// The solver kept its tables and solution and took the moved links in place.
    pub in_place: bool,
    /// Bytes of link records, attributes and lobe factors uploaded (0 where only lights moved).
    pub uploaded_bytes: u64,
    /// Shadow views drawn again, of all views.
    pub shadow_views: (usize, usize),
}

impl GpuBackend {
    /// Creates the solver's and the frame's resources for `prep` on `ctx`.
    pub fn new(ctx: Arc<Context>, prep: &Prepared, tuning: GpuTuning) -> Result<Self> {
        let solver = Self::make_solver(&ctx, prep, prep.plan.precision, tuning)?;
        let frame = frame_for(&ctx, prep, &solver)?;
        Ok(Self {
            ctx,
            solver,
            frame,
            direct: None,
            sky: None,
            tuning,
            pending: Vec::new(),
            kept_maps: None,
            record_into: None,
            last_follow: FollowReport::default(),
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
                max_line_width: None,
                force_table_accumulation: tuning.force_table_accumulation,
                emulate_f16_rounding: tuning.emulate_f16_rounding,
                features: Some(prep.plan.features),
                link_range: tuning.link_range,
            },
        )
    }

    /// Sets the environment (shadowed by rays on the host) and direct light on the solver.
    fn set_sources(&mut self, prep: &Prepared) -> Result<()> {
        let env = prep.scene.environment;
        self.solver
            .set_environment(&prep.system, env, self.sky.as_deref())?;
        if let Some(d) = &self.direct {
            self.solver.set_direct(&prep.system, d)?;
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

    /// What the last update's follow did ([`FollowReport`]).
    pub fn last_follow(&self) -> FollowReport {
        self.last_follow
    }

    /// Records the solver's uploads of the next follow into `cmd` (a host's command buffer,
    /// submitted after this update) instead of submitting them; `None` submits them at once.
    pub fn record_follow_into(&mut self, cmd: Option<vk::CommandBuffer>) {
        self.record_into = cmd;
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

impl Solve for GpuBackend {
    fn follow(&mut self, before: &Prepared, prep: &Prepared) -> Result<bool> {
        // The solver was planned for these passes and precision: it keeps its tables and
        // solution. Where objects moved along the bound it takes the new link records,
        // normals and lobe factors in place; where only lights moved, nothing of it changes.
        if before.plan.features != prep.plan.features
            || before.plan.precision != prep.plan.precision
        {
            return Ok(false);
        }
        let still = before.scene.meshes.len() == prep.scene.meshes.len()
            && before
                .scene
                .meshes
                .iter()
                .zip(&prep.scene.meshes)
                .all(|(a, b)| a.positions == b.positions);
        let mut report = FollowReport {
            in_place: true,
            ..Default::default()
        };
        let mut moved = Vec::new();
        if !still {
            let uploads = match self.record_into {
                Some(cmd) => self.solver.record_follow(cmd, &prep.system)?,
                None => self.solver.follow(&prep.system)?,
            };
            let Some(u) = uploads else {
                return Ok(false);
            };
            report.uploaded_bytes = u.bytes;
            moved = before.system.moving_spheres();
            moved.extend(prep.system.moving_spheres());
        }
        let kept = self.frame.follow(&frame_scene(prep), &moved)?;
        if !kept {
            self.frame = frame_for(&self.ctx, prep, &self.solver)?;
        }
        self.kept_maps = (before.maps.views == prep.maps.views && !before.maps.data.is_empty())
            .then(|| before.maps.data.clone());
        report.shadow_views = (self.frame.shadow_views_to_render(), prep.maps.views.len());
        self.last_follow = report;
        Ok(true)
    }
    fn keep_solution(&mut self, _: &Prepared) -> Result<()> {
        // The images hold the solution; a new source scale has rescaled it (set_direct).
        Ok(())
    }
    fn prepare_lights(&mut self, prep: &mut Prepared) -> Result<()> {
        self.direct = None;
        // The sky's rays once per geometry (`Prepared::sky`: kept where only lights moved).
        let t = std::time::Instant::now();
        self.sky = prep.sky(None);
        if self.sky.is_some() {
            self.pending
                .push(("environment".into(), t.elapsed().as_secs_f64() * 1e3));
        }
        let kept = self.kept_maps.take();
        if !prep.maps.views.is_empty() {
            match kept {
                // No view can have changed: the last maps hold.
                Some(data) if self.frame.shadow_views_to_render() == 0 => prep.maps.data = data,
                _ => {
                    self.frame.render_shadow_maps()?;
                    let t = self.frame.timings().to_vec();
                    self.collect(&t);
                    let atlas = self.frame.read_shadow_maps()?;
                    prep.maps.set_from_atlas(&atlas);
                }
            }
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
    fn resumable(&self) -> bool {
        true
    }
    fn damp(&mut self, weight: f64) -> bool {
        self.solver.set_damping(weight);
        true
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
    fn precision(&self) -> Precision {
        self.solver.precision()
    }
}

impl Draw for GpuBackend {
    fn draw(&mut self, _: &Prepared) -> Result<Image> {
        let image = self.frame.render(&mut self.solver)?;
        let t = self.frame.timings().to_vec();
        self.collect(&t);
        Ok(image)
    }
    fn set_camera(&mut self, prep: &Prepared) -> Result<()> {
        take_camera(&mut self.frame, prep)
    }
}

impl Backend for GpuBackend {
    fn kind(&self) -> BackendKind {
        BackendKind::Gpu
    }
    fn device(&self) -> String {
        self.ctx.info.name.clone()
    }
    fn take_timings(&mut self) -> Vec<(String, f64)> {
        std::mem::take(&mut self.pending)
    }
    fn fallbacks(&self) -> Vec<String> {
        self.solver.fallbacks().to_vec()
    }
    fn memory(&self) -> MemoryReport {
        self.solver.memory()
    }
}

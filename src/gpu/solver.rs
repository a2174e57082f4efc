//! The GPU solver: the same iterations as [`crate::solver::CpuSolver`], recorded as raster
//! passes. It can submit to its own queue or record into a command buffer a host gives it.

use super::context::Context;
use super::diagnostics::BlendRounding;
use super::layout::{mode, PassConstants, FLAG_HALF};
use super::passes::{self, Pass, PipelineSpec, SolverPasses};
use super::pipelines::Layouts;
use super::profiler::Profiler;
use super::reduce::{Reducer, Start};
use super::resources::{ResourcePlan, Resources};
use crate::error::{Error, Result};
use crate::plan::range::Range;
use crate::plan::Features;
use crate::scene::{Precision, Scheme};
use crate::solver::convergence::{Change, Figures};
use crate::solver::{LocalMode, Table};
use crate::system::System;
use ash::vk;
use glam::DVec3;
use std::sync::Arc;

mod access;
mod follow;
mod options;
mod transfer;

pub use follow::FollowUploads;
pub use options::{GpuOptions, SetupTimes};

/// Images a host application may read (all in `SHADER_READ_ONLY_OPTIMAL` after a recorded
/// iteration), with the layout that addresses them.
#[derive(Debug, Clone, Copy)]
pub struct HostImages {
    /// Leaves' current I_ex.
    pub leaf_ex: (vk::Image, vk::ImageView),
    /// Clusters' I_ex.
    pub cluster_ex: (vk::Image, vk::ImageView),
    /// Display intensity I_total (attachment layout after the local pass).
    pub i_total: (vk::Image, vk::ImageView),
    /// Row/bin → texel layout.
    pub layout: super::tables::TableLayout,
}

/// Antiradiance solver on Vulkan raster passes.
pub struct GpuSolver {
    ctx: Arc<Context>,
    res: Resources,
    layouts: Layouts,
    passes: SolverPasses,
    profiler: Profiler,
    parity: usize,
    constants: PassConstants,
    timings: Vec<(String, f64)>,
    fallbacks: Vec<String>,
    sys_range: Range,
    precision: Precision,
    environment: DVec3,
    /// The leaves' first bounce of the direct light
    /// ([`crate::solver::local::direct_exitant`]), uploaded at the source scale.
    direct: Option<Table>,
    /// The leaves' first bounce of the shadowed environment, uploaded at the source scale.
    environment_ex: Option<Table>,
    /// The brightest direct incident radiance (it sets the source scale with the other sources).
    direct_max: f64,
    scale: f64,
    features: Features,
    /// Whether each row's depth is odd (where push leaves its L_push).
    depth_parity: Vec<bool>,
    /// Whether each row is a leaf's (its I_ex is in the ping-pong pair).
    leaf_rows: Vec<bool>,
    /// Whether the images hold a solution's I_ex and its I_total (initialized, uploaded or
    /// iterated): a new source scale then rescales them.
    held: Held,
    /// Staging buffers of the last recorded follow.
    staged: super::staged::Staged,
    reducer: Reducer,
    work: super::work::Work,
    setup: SetupTimes,
    /// Weight of a symmetric iteration's new iterate ([`crate::solver::CpuState::damping`]).
    damping: f64,
}

/// Which tables hold values a new source scale must rescale.
#[derive(Debug, Clone, Copy, Default)]
struct Held {
    i_ex: bool,
    i_total: bool,
}

impl GpuSolver {
    /// Creates every image, buffer and pipeline `sys` needs and uploads the links and tables.
    pub fn new(ctx: Arc<Context>, sys: &System, opts: GpuOptions) -> Result<Self> {
        let format = super::resources::table_format(opts.precision);
        let precision = match opts.precision {
            Precision::F16 => Precision::F16,
            _ => Precision::F32,
        };
        let features = opts.features.unwrap_or_else(|| Features::for_system(sys));
        let mut fallbacks = Vec::new();
        let round_f16 = opts.precision == Precision::F16 && opts.emulate_f16_rounding;
        if round_f16 && !ctx.info.fragment_stores {
            return Err(Error::Device(format!(
                "{} lacks fragmentStoresAndAtomics, which emulated float16 blending needs",
                ctx.info.name
            )));
        }
        let accum_format = if round_f16 {
            fallbacks.push(
                "float16 blending rounded to nearest, emulated in the shaders: L_in and L_push are float32 rounded to float16 at every addition (tables stay float16)".to_string(),
            );
            vk::Format::R32G32B32A32_SFLOAT
        } else if opts.precision == Precision::F16
            && !opts.force_table_accumulation
            && super::diagnostics::f16_blend_rounding(&ctx)? == BlendRounding::TowardZero
        {
            fallbacks.push(format!(
                "{} truncates float16 blending; L_in and L_push accumulate in float32 (tables stay float16)",
                ctx.info.driver
            ));
            vk::Format::R32G32B32A32_SFLOAT
        } else {
            format
        };
        let plan = ResourcePlan::new(
            sys,
            &features,
            precision,
            accum_format,
            opts.column_height.unwrap_or(u32::MAX),
            ctx.info.max_image_dimension,
            opts.max_line_width
                .map_or(ctx.info.max_line_width, |w| w.min(ctx.info.max_line_width)),
        )?;
        let plan = if round_f16 {
            plan.with_round_f16()
        } else {
            plan
        };
        // Shaders read the storage buffers whole, except the link records: the global pass
        // reads those one descriptor range at a time (`gpu::links`).
        let range = ctx.info.max_storage_buffer_range as u64;
        let link_range = opts.link_range.map_or(range, |r| r.min(range));
        if let Some(b) = plan.buffers.iter().find(|b| {
            b.usage.contains(vk::BufferUsageFlags::STORAGE_BUFFER)
                && b.size > range
                && b.name != "links"
        }) {
            return Err(Error::TooLarge {
                what: format!(
                    "GPU buffer '{}' (maxStorageBufferRange; solver.element_size, solver.oracle)",
                    b.name,
                ),
                needed_bytes: b.size,
                limit_bytes: range,
            });
        }
        let work = super::work::Work::of(sys, &plan);
        let t = std::time::Instant::now();
        let layouts = Layouts::new(&ctx)?;
        let res = Resources::new(&ctx, plan, sys, layouts.set.raw(), link_range)?;
        let uploads_ms = t.elapsed().as_secs_f64() * 1e3;
        let t = std::time::Instant::now();
        let spec = PipelineSpec {
            ctx: &ctx,
            layout: &layouts.pipeline,
            format,
            accum_format,
            features,
            table: res.plan.layout,
            round_f16: res.plan.round_f16,
        };
        let mut passes = SolverPasses::new(&spec)?;
        // Every local variant now, so no pipeline is built during the iterations.
        for m in [mode::BOTH, mode::REFLECT, mode::ANTIRADIANCE] {
            passes.local.ensure(&spec, &res, m)?;
        }
        let profiler = Profiler::new(&ctx, 1024)?;
        let reducer = Reducer::new(&ctx, &res)?;
        let setup = SetupTimes {
            uploads_ms,
            pipelines_ms: t.elapsed().as_secs_f64() * 1e3,
        };
        let constants = PassConstants {
            line_offset: ctx.info.line_mode.endpoint_offset(),
            omega: sys.bins.omega as f32,
            flags: if precision == Precision::F16 {
                FLAG_HALF
            } else {
                0
            },
            ..Default::default()
        };
        let staged = super::staged::Staged::new(&ctx);
        Ok(Self {
            ctx,
            res,
            layouts,
            passes,
            profiler,
            parity: 0,
            constants,
            timings: Vec::new(),
            fallbacks,
            sys_range: Range::of(sys, DVec3::ZERO, 0.0),
            precision,
            environment: DVec3::ZERO,
            direct: None,
            environment_ex: None,
            direct_max: 0.0,
            scale: 1.0,
            features,
            depth_parity: sys
                .hierarchy
                .nodes
                .iter()
                .map(|n| n.depth % 2 == 1)
                .collect(),
            leaf_rows: sys.leaf_slot.iter().map(|&s| s != u32::MAX).collect(),
            held: Held::default(),
            staged,
            reducer,
            work,
            setup,
            damping: 1.0,
        })
        .and_then(|mut s| {
            s.update_scale()?;
            Ok(s)
        })
    }

    /// How long creating this solver took.
    pub fn setup_times(&self) -> SetupTimes {
        self.setup
    }

    /// Departures from the requested configuration, each a sentence for stderr and the stats JSON.
    pub fn fallbacks(&self) -> &[String] {
        &self.fallbacks
    }

    /// The context.
    pub fn context(&self) -> &Arc<Context> {
        &self.ctx
    }

    /// What this solver computes and allocates.
    pub fn features(&self) -> &Features {
        &self.features
    }

    /// The constant environment: its radiance `radiance` (which sets the source scale with the
    /// other sources) and its shadowed incident table for `sys`
    /// ([`crate::frame::environment::environment_in_table`]; `None` without an environment),
    /// whose first bounce is reflected here once on the host and added to I_ex and I_total by
    /// every local pass, as the CPU solver does.
    pub fn set_environment(
        &mut self,
        sys: &System,
        radiance: DVec3,
        table: Option<&Table>,
    ) -> Result<()> {
        if (radiance != DVec3::ZERO || table.is_some()) && !self.features.environment {
            return Err(Error::Invalid(
                "an environment was set on a solver planned without one".into(),
            ));
        }
        self.environment = radiance;
        self.environment_ex = table.map(|t| crate::solver::local::direct_exitant(sys, t));
        let before = self.scale;
        self.update_scale()?;
        if self.scale == before {
            self.upload_direct()?;
        }
        Ok(())
    }

    /// Direct incident radiance of `sys` per node and bin (reflected only), e.g. from
    /// [`crate::solver::CpuState::direct_in`]. Its first bounce is reflected here, once, on the
    /// host ([`crate::solver::local::direct_exitant`], as the CPU solver does), and the local
    /// pass adds it to I_ex every iteration.
    pub fn set_direct(&mut self, sys: &System, table: &Table) -> Result<()> {
        if !self.features.direct {
            return Err(Error::Invalid(
                "direct light was set on a solver planned without lights".into(),
            ));
        }
        self.direct_max = table
            .data
            .iter()
            .map(|v| v.max_element())
            .fold(0.0, f64::max);
        self.direct = Some(crate::solver::local::direct_exitant(sys, table));
        let before = self.scale;
        self.update_scale()?;
        // update_scale uploads it when the scale changes; otherwise upload it here, once.
        if self.scale == before {
            self.upload_direct()?;
        }
        Ok(())
    }

    /// The power-of-two factor applied to every source (results are divided by it on readback).
    pub fn scale(&self) -> f64 {
        self.scale
    }

    /// Table precision.
    pub fn precision(&self) -> Precision {
        self.precision
    }

    /// The largest |I_ex| (unscaled, as read back) before float16 overflow is near.
    pub fn overflow_limit(&self) -> f64 {
        Range::overflow_limit(self.precision, self.scale)
    }

    /// Starts a frame's timestamps; call once per command buffer before the `record_*` calls.
    pub fn begin_frame(&mut self, cmd: vk::CommandBuffer) {
        self.profiler.reset(&self.ctx, cmd);
    }

    fn prepare(&mut self, modes: &[u32]) -> Result<()> {
        let spec = PipelineSpec {
            ctx: &self.ctx,
            layout: &self.layouts.pipeline,
            format: self.res.plan.format,
            accum_format: self.res.plan.accum_format,
            features: self.features,
            table: self.res.plan.layout,
            round_f16: self.res.plan.round_f16,
        };
        for &m in modes {
            self.passes.local.ensure(&spec, &self.res, m)?;
        }
        Ok(())
    }

    /// Records the initial state: emission, reflected direct light and environment, the
    /// environment's antiradiance, then pull (as [`crate::solver::CpuSolver::initialize`]).
    pub fn record_initialize(&mut self, cmd: vk::CommandBuffer) -> Result<()> {
        self.prepare(&[mode::BOTH])?;
        // The initial state writes I_ex and I_total (the local pass).
        self.held = Held {
            i_ex: true,
            i_total: true,
        };
        self.record(cmd, None, mode::BOTH);
        Ok(())
    }

    /// Records one propagation: global, push, local (in `local_mode`), pull.
    pub fn record_propagation(
        &mut self,
        cmd: vk::CommandBuffer,
        local_mode: LocalMode,
    ) -> Result<()> {
        let m = match local_mode {
            LocalMode::Both => mode::BOTH,
            LocalMode::Reflect => mode::REFLECT,
            LocalMode::Antiradiance => mode::ANTIRADIANCE,
        };
        self.prepare(&[m])?;
        self.record(cmd, Some(()), m);
        Ok(())
    }

    /// Records global + push (or, for the initial state, the clears), then local and pull, and
    /// swaps the ping-pong pair.
    fn record(&mut self, cmd: vk::CommandBuffer, propagate: Option<()>, m: u32) {
        let Self {
            ctx,
            res,
            layouts,
            passes: ps,
            profiler: prof,
            parity,
            constants,
            ..
        } = self;
        let cur = *parity;
        let p = Pass {
            ctx,
            cmd,
            layout: layouts.pipeline.raw(),
            set: res.sets[cur],
            constants: *constants,
        };
        if propagate.is_some() {
            prof.scope(ctx, cmd, "global", || ps.global.record(&p, res, cur));
            prof.scope(ctx, cmd, "push", || ps.push.record(&p, res));
        } else {
            prof.scope(ctx, cmd, "initialize", || {
                let im = &mut res.images;
                // Push leaves odd depths' incident light in L_in: both start at zero.
                for img in [
                    &mut im.cluster_ex,
                    &mut im.cluster_ex_odd,
                    &mut im.i_total,
                    &mut im.leaf_ex0,
                    &mut im.leaf_ex1,
                    &mut im.l_in,
                    &mut im.l_push,
                ] {
                    passes::clear(&p, img);
                }
            });
        }
        prof.scope(ctx, cmd, "local", || ps.local.record(&p, res, cur, m));
        prof.scope(ctx, cmd, "pull", || ps.pull.record(&p, res, 1 - cur));
        *parity = 1 - cur;
    }

    /// Damps the symmetric iterations from now on ([`crate::solver::CpuState::damping`]).
    pub fn set_damping(&mut self, weight: f64) {
        self.damping = weight;
    }

    /// Records one iteration of `scheme` (as [`crate::solver::CpuSolver::iterate`]).
    pub fn record_iteration(
        &mut self,
        cmd: vk::CommandBuffer,
        scheme: Scheme,
        antiradiance_steps: usize,
    ) -> Result<()> {
        match scheme {
            Scheme::Symmetric => {
                // A damped iteration keeps 1 − ω of the last iterate (CpuState::damping).
                self.constants.keep = (1.0 - self.damping) as f32;
                let r = self.record_propagation(cmd, LocalMode::Both);
                self.constants.keep = 0.0;
                r
            }
            Scheme::Asymmetric => {
                self.record_propagation(cmd, LocalMode::Reflect)?;
                // Without antiradiance its steps would change nothing (as in the CPU solver).
                let steps = if self.features.antiradiance {
                    antiradiance_steps
                } else {
                    0
                };
                for _ in 0..steps {
                    self.record_propagation(cmd, LocalMode::Antiradiance)?;
                }
                Ok(())
            }
        }
    }

    fn submit(
        &mut self,
        record: impl FnOnce(&mut Self, vk::CommandBuffer) -> Result<()>,
    ) -> Result<()> {
        let ctx = self.ctx.clone();
        let mut inner = Ok(());
        ctx.submit_and_wait(|cmd| {
            self.begin_frame(cmd);
            inner = record(self, cmd);
        })?;
        inner?;
        self.timings = self.profiler.results(&ctx)?;
        Ok(())
    }

    /// Submits the initial state and waits.
    pub fn initialize(&mut self) -> Result<()> {
        self.submit(|s, cmd| s.record_initialize(cmd))
    }

    /// Submits one iteration and waits.
    pub fn iterate(&mut self, scheme: Scheme, antiradiance_steps: usize) -> Result<()> {
        self.iterate_batch(scheme, antiradiance_steps, 1)
            .map(|_| ())
    }

    /// Propagations in one iteration of `scheme` (the asymmetric scheme's antiradiance steps
    /// run only where antiradiance is planned).
    fn propagations(&self, scheme: Scheme, antiradiance_steps: usize) -> usize {
        match scheme {
            Scheme::Asymmetric if self.features.antiradiance => 1 + antiradiance_steps,
            _ => 1,
        }
    }

    /// Records `n` iterations, each followed by the reduction of its convergence figures into
    /// slot `i` of the result buffer (read by [`GpuSolver::iterate_batch`]).
    pub fn record_batch(
        &mut self,
        cmd: vk::CommandBuffer,
        scheme: Scheme,
        antiradiance_steps: usize,
        n: usize,
    ) -> Result<()> {
        let several = self.propagations(scheme, antiradiance_steps) > 1;
        for i in 0..n.min(super::reduce::MAX_BATCH) {
            // Several propagations overwrite both ping-pong images: keep the start.
            let start = if several {
                self.reducer
                    .record_snapshot(cmd, &mut self.res, self.parity)?;
                Start::Snapshot
            } else {
                Start::PingPong
            };
            self.record_iteration(cmd, scheme, antiradiance_steps)?;
            let (reducer, res, parity) = (&mut self.reducer, &mut self.res, self.parity);
            self.profiler.scope(&self.ctx, cmd, "reduce", || {
                reducer.record(cmd, res, start, parity, i)
            });
        }
        Ok(())
    }

    /// Submits `n` iterations (at most [`super::reduce::MAX_BATCH`]) at once and waits once;
    /// returns each one's convergence figures, reduced on the device (unscaled).
    pub fn iterate_batch(
        &mut self,
        scheme: Scheme,
        antiradiance_steps: usize,
        n: usize,
    ) -> Result<Vec<Figures>> {
        let n = n.min(super::reduce::MAX_BATCH);
        self.submit(|s, cmd| s.record_batch(cmd, scheme, antiradiance_steps, n))?;
        let inv = 1.0 / self.scale;
        let omega = self.constants.omega as f64;
        Ok(self
            .reducer
            .read(n)?
            .into_iter()
            .map(|r| {
                let (diff, norm) = (r.diff2.sqrt(), r.norm2.sqrt());
                Figures {
                    change: Change {
                        relative: if norm > 0.0 { diff / norm } else { diff * inv },
                        absolute: diff * inv,
                    },
                    flux: r.flux * omega * inv,
                    peak: if r.peak >= 3.0e38 {
                        f64::INFINITY
                    } else {
                        r.peak * inv
                    },
                }
            })
            .collect())
    }

    /// Initializes and runs `iterations` iterations in one submission.
    pub fn solve(
        &mut self,
        scheme: Scheme,
        iterations: usize,
        antiradiance_steps: usize,
    ) -> Result<()> {
        self.submit(|s, cmd| {
            s.record_initialize(cmd)?;
            for _ in 0..iterations {
                s.record_iteration(cmd, scheme, antiradiance_steps)?;
            }
            Ok(())
        })
    }
}

impl Drop for GpuSolver {
    fn drop(&mut self) {
        // The fields free themselves once the GPU no longer uses them.
        self.ctx.wait_idle();
    }
}

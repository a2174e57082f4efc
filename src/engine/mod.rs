//! The engine: one long-lived object that owns a prepared scene and one backend, and that every
//! command, the tests and an embedding host drive the same way. A frame is: update what moved
//! ([`Engine::new`] prepares the lights; between frames [`Engine::set_time`],
//! [`Engine::set_light`], [`Engine::set_object_transform`] then [`Engine::update`], `motion.rs`), iterate
//! ([`Engine::initialize`], [`Engine::iterate`], or [`Engine::render`] with the convergence
//! monitor and its fallbacks), draw ([`Engine::draw`]). A host that owns the Vulkan device records
//! the same steps into its own command buffers ([`Engine::record_initialize`],
//! [`Engine::record_iterations`], [`Engine::record_draw`]).

pub mod drive;
mod host;
pub mod motion;
mod passes;
pub mod planned;
pub mod stats;
mod tail;

pub use crate::backend::{options, prepared, Backend, Draw, Solve};
pub use crate::methods::antiradiance::{cpu, gpu};
pub use drive::BATCH;
pub use host::OutputImage;
pub use options::{GpuTuning, Options, SolverOverrides, DEFAULT_MAX_LINKS};
pub use prepared::{fit_system, Prepared};
pub use stats::{IterationFrame, RenderStats, Rendered, Setup};

use crate::error::{Error, Result};
use crate::frame::Image;
use crate::gpu::memory::MemoryReport;
use crate::gpu::work::Work;
use crate::gpu::{Context, ContextOptions};
use crate::progress::Progress;
use crate::scene::{Camera, Precision, Scene};
use crate::settings::BackendKind;
use crate::solver::Table;
use ash::vk;
use passes::draw_frame;
pub use passes::pass_jitter;
use std::cell::Cell;
use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::Instant;

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// A prepared scene and the backend that solves and draws it.
pub struct Engine {
    prep: Prepared,
    backend: Box<dyn Backend>,
    fallbacks: Vec<String>,
    /// When the engine was asked for (start of the first render's `total_ms`).
    created: Option<Instant>,
    /// When the backend's setup began (start of the first render's `setup_ms`).
    setup_start: Option<Instant>,
    setup: Setup,
    method: crate::settings::Method,
    /// The options the engine was made with (an update prepares the moved scene with them).
    options: Options,
    /// The scene with the moves made since the last update ([`Engine::update`]).
    next: Option<Scene>,
    /// Scene time last set.
    time: f64,
    /// Parts of the last update.
    update_times: motion::UpdateTimes,
    /// Whether the last update carried the solution over.
    warm: bool,
    /// Whether the last update linked again.
    relinked: bool,
    /// Whether a host placed an object since the last update ([`Engine::set_object_transform`]):
    /// a pose the bounded link mesh may not cover, so the update prepares anew.
    placed: bool,
    /// Residual of the last iteration [`Engine::iterate`] ran.
    last_residual: Option<f64>,
}

/// The Vulkan context `options` ask for: the host's, or a new headless one.
pub fn context_for(options: &Options) -> Result<Arc<Context>> {
    match &options.context {
        Some(c) => Ok(c.clone()),
        None => Context::headless(&ContextOptions {
            validation: options.validation,
            device_name: options.device.clone(),
            no_pipeline_cache: false,
        }),
    }
}

impl Engine {
    /// Prepares `scene` with `options` (on the GPU backend the device comes first: its memory
    /// bounds the discretization before linking), creates the backend and prepares the lights
    /// (shadow maps, direct light, environment). Then [`Engine::initialize`] or
    /// [`Engine::render`].
    pub fn new(scene: &Scene, options: &Options, progress: &dyn Progress) -> Result<Self> {
        let created = Instant::now();
        let ctx = match options.backend {
            BackendKind::Cpu => None,
            BackendKind::Gpu => Some(context_for(options)?),
        };
        let memory = ctx.as_ref().map(|c| c.info.device_local_bytes);
        // The link records are read in chunks of maxStorageBufferRange (`gpu::links`): the
        // device's memory is the only bound, which the preparation fits.
        let prep = Prepared::new(scene, options, memory, progress)?;
        let mut engine = Self::with_context(prep, options, ctx, progress)?;
        engine.created = Some(created);
        Ok(engine)
    }

    /// An engine for an already prepared scene (e.g. [`Prepared::with_every_pass`]); the GPU
    /// backend uses `options.context` or a new headless context.
    pub fn from_prepared(
        prep: Prepared,
        options: &Options,
        progress: &dyn Progress,
    ) -> Result<Self> {
        let ctx = match options.backend {
            BackendKind::Cpu => None,
            BackendKind::Gpu => Some(context_for(options)?),
        };
        Self::with_context(prep, options, ctx, progress)
    }

    fn with_context(
        mut prep: Prepared,
        options: &Options,
        ctx: Option<Arc<Context>>,
        progress: &dyn Progress,
    ) -> Result<Self> {
        let setup_start = Instant::now();
        let mut backend = crate::methods::create(options, &mut prep, ctx)?;
        let created_ms = ms(setup_start);
        let method_ms = backend.method_report().map_or(0.0, |r| r.setup_ms);
        let mut fallbacks = prep.fallbacks.clone();
        if options.backend == BackendKind::Gpu {
            fallbacks.extend(prep.plan.precision_fallback.clone());
        }
        fallbacks.extend(backend.fallbacks());
        let lights = !prep.maps.views.is_empty();
        if lights {
            progress.begin("shadow maps", 1);
        }
        let t = Instant::now();
        backend.prepare_lights(&mut prep)?;
        if lights {
            progress.end();
        }
        let gpu = gpu_of(&mut backend)
            .map(|g| g.setup_times())
            .unwrap_or_default();
        let setup = Setup {
            linking_ms: prep.system.meshing_ms + prep.system.links.linking_ms,
            uploads_ms: gpu.uploads_ms,
            pipelines_ms: gpu.pipelines_ms,
            method_ms,
            other_ms: (created_ms - gpu.uploads_ms - gpu.pipelines_ms - method_ms).max(0.0),
            lights_ms: ms(t),
        };
        Ok(Self {
            prep,
            backend,
            fallbacks,
            created: Some(setup_start),
            setup_start: Some(setup_start),
            setup,
            method: options.method,
            options: options.clone(),
            next: None,
            time: 0.0,
            update_times: motion::UpdateTimes::default(),
            warm: false,
            relinked: false,
            placed: false,
            last_residual: None,
        })
    }

    /// The prepared scene: settings, camera, system, plan, surfaces, shadow maps.
    pub fn prepared(&self) -> &Prepared {
        &self.prep
    }

    /// How global illumination is computed.
    pub fn method(&self) -> crate::settings::Method {
        self.method
    }

    /// Which backend solves and draws.
    pub fn backend_kind(&self) -> BackendKind {
        self.backend.kind()
    }

    /// The device (`cpu` or the Vulkan device name).
    pub fn device(&self) -> String {
        self.backend.device()
    }

    /// Table precision now (after any widening).
    pub fn precision(&self) -> Precision {
        self.backend.precision()
    }

    /// Departures from the requested configuration made while setting up.
    pub fn fallbacks(&self) -> &[String] {
        &self.fallbacks
    }

    /// GPU memory of the solver by purpose (empty for the CPU backend).
    pub fn memory(&self) -> MemoryReport {
        self.backend.memory()
    }

    /// The raster work of one GPU propagation (`None` for the CPU backend).
    pub fn work(&mut self) -> Option<Work> {
        gpu_of(&mut self.backend).map(|g| g.work())
    }

    /// How long preparing this engine took, by part.
    pub fn setup(&self) -> Setup {
        self.setup
    }

    /// The initial state: emission, direct light and environment reflected once, no
    /// propagation (submitted and waited for).
    pub fn initialize(&mut self) -> Result<()> {
        self.backend.initialize(&self.prep)
    }

    /// `n` iterations of the settings' scheme (submitted and waited for), without the
    /// convergence monitor: what `profile` times and what a host runs per frame.
    pub fn iterate(&mut self, n: usize) -> Result<()> {
        let s = &self.prep.settings;
        let mut done = 0;
        while done < n {
            let k = (n - done).min(drive::BATCH_LIMIT);
            let figures =
                self.backend
                    .iterate_batch(&self.prep, s.scheme, s.antiradiance_steps, k)?;
            if let Some(f) = figures.last() {
                self.last_residual = Some(f.change.relative);
            }
            done += k;
        }
        Ok(())
    }

    /// The relative change of I_ex in the last iteration [`Engine::iterate`] ran.
    pub fn last_residual(&self) -> Option<f64> {
        self.last_residual
    }

    /// Draws the current state from the camera into host memory.
    pub fn draw(&mut self) -> Result<Image> {
        draw_frame(self.backend.as_mut(), &mut self.prep)
    }

    /// Draws the next frames from `camera` (a pose, target or field of view; the image size
    /// is fixed when the engine is made). The solution is view-independent: nothing is
    /// re-solved, the next [`Engine::draw`] / [`Engine::record_draw`] uses the camera.
    /// The camera's `supersample` is the engine's (fixed with the size).
    pub fn set_camera(&mut self, mut camera: Camera) -> Result<()> {
        let old = &self.prep.camera;
        let k = old.supersample;
        let (w, h) = (old.width / k, old.height / k);
        if (camera.width, camera.height) != (w, h) {
            return Err(Error::Invalid(format!(
                "camera: the image is {w}×{h} pixels; set_camera must keep that size (got {}×{})",
                camera.width, camera.height
            )));
        }
        (camera.width, camera.height, camera.supersample) = (w * k, h * k, k);
        let forward = camera.target - camera.eye;
        let finite = [camera.eye, camera.target, camera.up]
            .iter()
            .all(|v| v.is_finite());
        if !finite
            || forward.length() <= 0.0
            || forward.cross(camera.up).length() <= 1e-12 * forward.length() * camera.up.length()
            || !(camera.fov_y_deg > 0.0 && camera.fov_y_deg < 180.0)
        {
            return Err(Error::Invalid(format!(
                "camera: eye, target and up must be finite, eye ≠ target, up not along the view, \
                 0 < fov_y_deg < 180 (got eye {:?}, target {:?}, up {:?}, fov {})",
                camera.eye, camera.target, camera.up, camera.fov_y_deg
            )));
        }
        self.prep.camera = camera;
        self.backend.set_camera(&self.prep)
    }

    /// The current I_ex (unscaled).
    pub fn i_ex(&mut self) -> Result<Table> {
        self.backend.i_ex()
    }

    /// The current display intensity I_total (unscaled).
    pub fn i_total(&mut self) -> Result<Table> {
        self.backend.i_total()
    }

    /// Pass timings (ms, in order) since the last call: GPU timestamps of every pass, or the
    /// CPU backend's wall times.
    pub fn take_timings(&mut self) -> Vec<(String, f64)> {
        self.backend.take_timings()
    }

    /// The GPU backend's internals, for this project's own tests of them (its shadow atlas,
    /// its source scale). Not the host surface: hosts use [`Engine::output_image`],
    /// [`Engine::recorded_timings`], [`Engine::last_update`] and the `record_*` calls.
    #[doc(hidden)]
    pub fn gpu_internals(&mut self) -> Result<&mut gpu::GpuBackend> {
        gpu_of(&mut self.backend).ok_or_else(|| {
            Error::Invalid("recording into a command buffer needs the GPU backend".into())
        })
    }

    /// Records the initial state (emission, the reflected direct light and environment) into
    /// `cmd`, a host's command buffer in the recording state, after
    /// [`Engine::begin_recording`]; the solver's images are left for the next iteration. The
    /// command buffer must be submitted and complete before the engine is used otherwise.
    pub fn record_initialize(&mut self, cmd: vk::CommandBuffer) -> Result<()> {
        if self.backend.host_frame().is_some() {
            return Ok(()); // solved when the lights were prepared
        }
        self.gpu_internals()?.record_initialize(cmd)
    }

    /// Records `n` iterations of the settings' scheme into `cmd` (after
    /// [`Engine::record_initialize`] or an earlier frame's iterations, in this or an earlier
    /// completed command buffer). The convergence monitor does not run: the host decides the
    /// count (the scene's `iterations_per_frame` is the paper's 4).
    pub fn record_iterations(&mut self, cmd: vk::CommandBuffer, n: usize) -> Result<()> {
        let (scheme, steps) = (
            self.prep.settings.scheme,
            self.prep.settings.antiradiance_steps,
        );
        if self.backend.host_frame().is_some() {
            return Ok(()); // nothing iterates
        }
        self.gpu_internals()?
            .record_iterations(cmd, scheme, steps, n)
    }

    /// Records the frame (G-buffer, splat, compose) from the current solution into `cmd`; it
    /// leaves [`Engine::output_image`] in the layout and state that names, for the host's
    /// barrier before it copies, blits or samples it.
    pub fn record_draw(&mut self, cmd: vk::CommandBuffer) -> Result<()> {
        if let Some(h) = self.backend.host_frame() {
            return h.record_draw(&self.prep, cmd);
        }
        self.gpu_internals()?.record_draw(cmd);
        Ok(())
    }

    /// Solves with the convergence monitor and its fallbacks (the scene's `iterations`, or
    /// until `tolerance`) and draws the result.
    pub fn render(&mut self, progress: &dyn Progress) -> Result<Rendered> {
        let mut last = None;
        let (stats, i_total) = self.run(false, progress, &mut |f| {
            last = Some(f.image);
            Ok(())
        })?;
        Ok(Rendered {
            image: last.ok_or_else(|| Error::Numerical("no frame was drawn".into()))?,
            stats,
            i_total,
        })
    }

    /// As [`Engine::render`], drawing a frame after every iteration (1..=`iterations`, or only
    /// the initial state when that is 0) and handing each to `each`: one solve gives the whole
    /// error-per-iteration curve (`study`). Returns the statistics and the final display table.
    pub fn render_each_iteration(
        &mut self,
        progress: &dyn Progress,
        each: &mut dyn FnMut(IterationFrame) -> Result<()>,
    ) -> Result<(RenderStats, Table)> {
        self.run(true, progress, each)
    }

    fn run(
        &mut self,
        every_iteration: bool,
        progress: &dyn Progress,
        each: &mut dyn FnMut(IterationFrame) -> Result<()>,
    ) -> Result<(RenderStats, Table)> {
        let start = self.created.take().unwrap_or_else(Instant::now);
        let setup_start = self.setup_start.take().unwrap_or_else(Instant::now);
        // Solve time excludes the frames and the callback (they are not part of solving).
        let setup_ms = Cell::new(0.0);
        let solve_start = Cell::new(Instant::now());
        let mut excluded_ms = 0.0;
        let mut initialized = || {
            setup_ms.set(ms(setup_start));
            solve_start.set(Instant::now());
        };
        let mut on_frame =
            |k: usize, backend: &mut dyn Backend, prep: &mut Prepared| -> Result<()> {
                let t = Instant::now();
                let image = draw_frame(backend, prep)?;
                if !image.is_finite() {
                    return Err(Error::Numerical(format!(
                        "the frame after iteration {k} has non-finite pixels"
                    )));
                }
                let frame_ms = ms(t);
                excluded_ms += frame_ms;
                let t = Instant::now();
                each(IterationFrame {
                    iteration: k,
                    image,
                    setup_ms: setup_ms.get(),
                    solve_ms: ms(solve_start.get()) - excluded_ms,
                    frame_ms,
                })?;
                excluded_ms += ms(t);
                Ok(())
            };
        let outcome = drive::drive(
            &mut self.prep,
            self.backend.as_mut(),
            every_iteration,
            progress,
            &mut initialized,
            &mut on_frame,
        )?;
        let prep = &self.prep;
        let mut pass_ms = BTreeMap::new();
        for (k, v) in self.backend.take_timings() {
            *pass_ms.entry(k).or_insert(0.0) += v;
        }
        let sys = &prep.system;
        let mut fallbacks = self.fallbacks.clone();
        fallbacks.extend(outcome.fallbacks);
        let stats = RenderStats {
            method: self.method,
            backend: self.backend.kind(),
            device: self.backend.device(),
            elements: sys.leaves.len(),
            links: sys.links.links.len(),
            bins: sys.bins.count,
            iterations: outcome.residuals.len(),
            scheme: outcome.scheme.unwrap_or(prep.settings.scheme),
            precision: self.backend.precision(),
            width: prep.camera.width / prep.camera.supersample,
            height: prep.camera.height / prep.camera.supersample,
            passes: prep.plan.passes(),
            decisions: prep.plan.decisions.clone(),
            all_passes: prep.plan.all_passes,
            target: prep.target.clone(),
            pass_ms,
            linking_ms: sys.meshing_ms + sys.links.linking_ms,
            total_ms: 0.0,
            residuals: outcome.residuals,
            energies: outcome.energies,
            estimated_error: outcome.estimated_error,
            extrapolations: outcome.extrapolations,
            fallbacks,
            warnings: outcome.warnings,
            method_report: self.backend.method_report(),
        };
        let i_total = self.backend.i_total()?;
        Ok((
            RenderStats {
                total_ms: ms(start),
                ..stats
            },
            i_total,
        ))
    }
}

/// Renders `scene` from its camera with its settings and `options`: [`Engine::new`] then
/// [`Engine::render`].
pub fn render(scene: &Scene, options: &Options, progress: &dyn Progress) -> Result<Rendered> {
    Engine::new(scene, options, progress)?.render(progress)
}

/// The GPU antiradiance backend behind `b`, if that is what it is (or wraps).
fn gpu_of(b: &mut Box<dyn Backend>) -> Option<&mut gpu::GpuBackend> {
    b.recorder().downcast_mut::<gpu::GpuBackend>()
}

//! `render`: scene → image with either backend. Linking and meshing (CPU), shadow maps, the
//! leaves' direct light, the iterations (GPU passes or the f64 CPU solver), then the frame.
//! Progress is reported through [`Progress`] so the CLI can draw bars on stderr.

mod backends;
mod drive;

use crate::error::{Error, Result};
use crate::frame::lights::direct_in_table;
use crate::frame::shadow::ShadowMaps;
use crate::frame::surfaces::Surfaces;
use crate::frame::Image;
use crate::raycast::RayCaster;
use crate::scene::Scene;
use crate::solver::Table;
use crate::system::System;
use crate::CpuSolver;
use drive::Iterative;
use serde::Serialize;
use std::collections::BTreeMap;
use std::time::Instant;

/// Which implementation solves and draws the frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Backend {
    /// Vulkan raster passes (§4).
    Gpu,
    /// The f64 CPU solver and a ray-cast frame: the reference the GPU is checked against.
    Cpu,
}

/// Options of [`render`] beyond the scene's own settings.
#[derive(Clone)]
pub struct RenderOptions {
    /// Device to render on (GPU backend); `None` creates a headless context.
    pub context: Option<std::sync::Arc<crate::gpu::Context>>,
    /// Backend.
    pub backend: Backend,
    /// Side of each shadow map (texels).
    pub shadow_map_size: u32,
    /// Vulkan device name filter (GPU backend).
    pub device: Option<String>,
    /// Enable the Vulkan validation layer (tests).
    pub validation: bool,
    /// Run every pass and create every table whether the scene needs it or not, with float32
    /// tables (`--all-passes`: the reference the scene-adaptive plan is checked against).
    pub all_passes: bool,
    /// Choose bins, element size and iterations for this relative RMSE from the measured
    /// error-vs-time data ([`crate::plan::target`]), replacing the scene's.
    pub target_error: Option<f64>,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            context: None,
            backend: Backend::Gpu,
            shadow_map_size: 1024,
            device: None,
            validation: false,
            all_passes: false,
            target_error: None,
        }
    }
}

/// Progress of the long steps.
pub trait Progress {
    /// A step with `total` units of work begins.
    fn begin(&self, step: &str, total: u64);
    /// `n` more units are done.
    fn advance(&self, n: u64);
    /// The current step is done.
    fn end(&self);
}

/// Reports nothing.
pub struct Silent;

impl Progress for Silent {
    fn begin(&self, _: &str, _: u64) {}
    fn advance(&self, _: u64) {}
    fn end(&self) {}
}

/// Statistics of a render (the `--json` file).
#[derive(Debug, Clone, Serialize)]
pub struct RenderStats {
    /// Backend used.
    pub backend: Backend,
    /// Device (GPU backend) or "cpu".
    pub device: String,
    /// Leaf elements.
    pub elements: usize,
    /// Links.
    pub links: usize,
    /// Bins.
    pub bins: usize,
    /// Iterations run (of the run that produced the image, after any restart).
    pub iterations: usize,
    /// Scheme of the result (`symmetric` or `asymmetric`; differs from the scene's after a fallback).
    pub scheme: String,
    /// Table precision of the result (`f16`, `f32`; `f64` for the CPU backend).
    pub precision: String,
    /// Image size.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// The passes the scene's plan runs, in order (names in the README, "Passes a scene needs").
    pub passes: Vec<String>,
    /// What the scene analysis decided and why, one sentence per rule.
    pub decisions: Vec<String>,
    /// True when `--all-passes` forced every pass on.
    pub all_passes: bool,
    /// The setting `--target-error` chose, if given.
    pub target: Option<crate::plan::target::TargetChoice>,
    /// Milliseconds per timed scope, summed over the render (GPU timestamps for GPU passes).
    pub pass_ms: BTreeMap<String, f64>,
    /// Meshing + linking time (ms).
    pub linking_ms: f64,
    /// Wall time of the whole render (ms).
    pub total_ms: f64,
    /// Relative change of the leaves' I_ex at each iteration.
    pub residuals: Vec<f64>,
    /// Flux (W, mean of RGB) leaving the leaves' front bins after each iteration.
    pub energies: Vec<f64>,
    /// Estimated relative distance to the fixed point after the last iteration.
    pub estimated_error: Option<f64>,
    /// Departures from the requested configuration.
    pub fallbacks: Vec<String>,
    /// Things the user should know about the result (e.g. the iteration cap was reached).
    pub warnings: Vec<String>,
}

/// A rendered frame.
#[derive(Debug, Clone)]
pub struct Rendered {
    /// Linear radiance.
    pub image: Image,
    /// Statistics.
    pub stats: RenderStats,
    /// Display intensities the frame was drawn from (for checks).
    pub i_total: Table,
}

/// Rows of the stacked shadow-map image (maxImageDimension2D of lavapipe and most GPUs).
const MAX_SHADOW_ROWS: u32 = 16384;

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// A frame drawn after some iterations, handed to the callback of [`render_each_iteration`].
#[derive(Debug, Clone)]
pub struct IterationFrame {
    /// Iterations done (0: only the initialization).
    pub iteration: usize,
    /// The frame.
    pub image: Image,
    /// Wall time (ms) of the one-time setup after linking: device resources and pipelines, shadow
    /// maps, direct light, and the initialization (emission, environment, direct light reflected).
    pub setup_ms: f64,
    /// Wall time (ms) of the iterations up to this one (after the setup), without the frames
    /// drawn for earlier ones.
    pub solve_ms: f64,
    /// Wall time (ms) of drawing this frame.
    pub frame_ms: f64,
}

/// Renders `scene` from its camera with its `[solver]` settings.
pub fn render(scene: &Scene, opts: &RenderOptions, progress: &dyn Progress) -> Result<Rendered> {
    let mut last = None;
    let (stats, i_total) = run(scene, opts, progress, false, &mut |f| {
        last = Some(f.image);
        Ok(())
    })?;
    Ok(Rendered {
        image: last.expect("a frame is drawn after the last iteration"),
        stats,
        i_total,
    })
}

/// Renders a frame after every iteration (1..=`solver.iterations`, or only after the
/// initialization when that is 0), handing each to `each`: one solve gives the whole
/// error-per-iteration curve (`study`). Returns the statistics and the final display table.
pub fn render_each_iteration(
    scene: &Scene,
    opts: &RenderOptions,
    progress: &dyn Progress,
    each: &mut dyn FnMut(IterationFrame) -> Result<()>,
) -> Result<(RenderStats, Table)> {
    run(scene, opts, progress, true, each)
}

/// Hands a frame drawn since `drawn` to `each`; the drawing and the callback are kept out of
/// the solve time (`excluded_ms`).
fn deliver(
    each: &mut dyn FnMut(IterationFrame) -> Result<()>,
    iteration: usize,
    image: Image,
    drawn: Instant,
    setup_ms: f64,
    solve_start: Instant,
    excluded_ms: &mut f64,
) -> Result<()> {
    let frame_ms = ms(drawn);
    *excluded_ms += frame_ms;
    let t = Instant::now();
    each(IterationFrame {
        iteration,
        image,
        setup_ms,
        solve_ms: ms(solve_start) - *excluded_ms,
        frame_ms,
    })?;
    *excluded_ms += ms(t);
    Ok(())
}

fn run(
    scene: &Scene,
    opts: &RenderOptions,
    progress: &dyn Progress,
    every_iteration: bool,
    each: &mut dyn FnMut(IterationFrame) -> Result<()>,
) -> Result<(RenderStats, Table)> {
    let t0 = Instant::now();
    let target = opts
        .target_error
        .map(|e| crate::plan::target::choose(scene, e));
    let targeted;
    let scene = match &target {
        Some(choice) => {
            let mut s = scene.clone();
            crate::plan::target::apply(&mut s, choice);
            targeted = s;
            &targeted
        }
        None => scene,
    };
    // The device comes first: its memory bounds the discretization before linking.
    let ctx = match (opts.backend, &opts.context) {
        (Backend::Cpu, _) => None,
        (Backend::Gpu, Some(c)) => Some(c.clone()),
        (Backend::Gpu, None) => Some(crate::gpu::Context::headless(
            &crate::gpu::ContextOptions {
                validation: opts.validation,
                device_name: opts.device.clone(),
            },
        )?),
    };
    progress.begin("linking", 1);
    let sys = System::build_within(scene, ctx.as_ref().map(|c| c.info.device_local_bytes))?;
    progress.end();
    let surfaces = Surfaces::new(scene, &sys);
    let plan = crate::plan::Plan::new(scene, &sys, &surfaces, opts.all_passes);
    let mut maps = ShadowMaps::new(scene, opts.shadow_map_size);
    // All views share one image of side × (side · views) texels; keep it within 16384 rows.
    let views = maps.views.len().max(1) as u32;
    let mut fallbacks = Vec::new();
    if opts.shadow_map_size * views > MAX_SHADOW_ROWS {
        let size = MAX_SHADOW_ROWS / views;
        fallbacks.push(format!(
            "{views} shadow-map views do not fit {} texels each; using {size}",
            opts.shadow_map_size
        ));
        maps = ShadowMaps::new(scene, size);
    }
    let mut passes = BTreeMap::new();
    let mut stats = RenderStats {
        backend: opts.backend,
        device: "cpu".into(),
        elements: sys.leaves.len(),
        links: sys.links.links.len(),
        bins: sys.bins.count,
        iterations: 0,
        scheme: String::new(),
        precision: String::new(),
        width: scene.camera.width,
        height: scene.camera.height,
        passes: plan.passes(),
        decisions: plan.decisions.clone(),
        all_passes: plan.all_passes,
        target,
        pass_ms: BTreeMap::new(),
        linking_ms: sys.meshing_ms + sys.links.linking_ms,
        total_ms: 0.0,
        residuals: Vec::new(),
        energies: Vec::new(),
        estimated_error: None,
        fallbacks,
        warnings: Vec::new(),
    };
    // Solve time excludes the frames and the callback (they are not part of solving).
    let setup_start = Instant::now();
    let mut setup_ms = None;
    let mut solve_start = Instant::now();
    let mut excluded_ms = 0.0;
    let mut last: Option<Image> = None;
    // Called by the loop for every wanted frame: draw, time, hand on.
    let mut on_frame = |k: usize, solver: &mut dyn Iterative| -> Result<()> {
        let setup = *setup_ms.get_or_insert_with(|| {
            solve_start = Instant::now();
            ms(setup_start)
        });
        let t = Instant::now();
        let image = solver.draw()?;
        if !image.is_finite() {
            return Err(Error::Numerical(format!(
                "the frame after iteration {k} has non-finite pixels"
            )));
        }
        last = Some(image.clone());
        deliver(each, k, image, t, setup, solve_start, &mut excluded_ms)
    };
    let (outcome, i_total, precision) = match opts.backend {
        Backend::Cpu => {
            let t = Instant::now();
            let caster = RayCaster::new(&sys);
            if !maps.views.is_empty() {
                progress.begin("shadow maps", 1);
                maps.render_cpu(&caster);
                progress.end();
            }
            passes.insert("shadow".to_string(), ms(t));
            let t = Instant::now();
            let mut solver = CpuSolver::new(&sys);
            solver.antiradiance = plan.features.antiradiance;
            solver.set_environment(scene.environment);
            if !scene.lights.is_empty() {
                solver.direct_in = Some(direct_in_table(&sys, &scene.lights, &maps));
            }
            passes.insert("direct".to_string(), ms(t));
            let mut cpu = backends::Cpu {
                solver,
                scene,
                maps: &maps,
                surfaces: &surfaces,
                caster: &caster,
                solve_ms: 0.0,
                frame_ms: 0.0,
            };
            let outcome = drive::drive(
                &sys,
                &scene.solver,
                &mut cpu,
                every_iteration,
                progress,
                &mut on_frame,
            )?;
            cpu.timings(&mut passes);
            (outcome, cpu.solver.i_total.clone(), "f64".to_string())
        }
        Backend::Gpu => {
            let ctx = ctx.clone().expect("created above for the GPU backend");
            stats.device = ctx.info.name.clone();
            stats.fallbacks.extend(plan.precision_fallback.clone());
            let mut solver = crate::gpu::GpuSolver::new(
                ctx.clone(),
                &sys,
                crate::gpu::GpuOptions {
                    precision: plan.precision,
                    features: Some(plan.features),
                    ..Default::default()
                },
            )?;
            stats.fallbacks.extend(solver.fallbacks().iter().cloned());
            solver.set_environment(scene.environment)?;
            let mut frame = crate::gpu::frame::GpuFrame::new(
                ctx.clone(),
                scene,
                &sys,
                &surfaces,
                &maps,
                &plan.features,
            )?;
            let mut direct = None;
            if !maps.views.is_empty() {
                progress.begin("shadow maps", 1);
                frame.render_shadow_maps()?;
                for (k, v) in frame.timings() {
                    *passes.entry(k.clone()).or_insert(0.0) += v;
                }
                maps.data = frame.read_shadow_maps()?;
                progress.end();
                let d = direct_in_table(&sys, &scene.lights, &maps);
                solver.set_direct(&d)?;
                direct = Some(d);
            }
            let mut gpu = backends::Gpu {
                solver,
                frame,
                sys: &sys,
                scene,
                direct,
                pending: Vec::new(),
            };
            let outcome = drive::drive(
                &sys,
                &scene.solver,
                &mut gpu,
                every_iteration,
                progress,
                &mut on_frame,
            )?;
            gpu.timings(&mut passes);
            let p = match gpu.solver.precision() {
                crate::scene::Precision::F16 => "f16",
                crate::scene::Precision::F32 => "f32",
            };
            (outcome, gpu.solver.read_i_total()?, p.to_string())
        }
    };
    drop(on_frame);
    stats.iterations = outcome.residuals.len();
    stats.scheme = match outcome.scheme {
        Some(crate::scene::Scheme::Asymmetric) => "asymmetric".into(),
        _ => "symmetric".into(),
    };
    stats.precision = precision;
    stats.residuals = outcome.residuals;
    stats.energies = outcome.energies;
    stats.estimated_error = outcome.estimated_error;
    stats.fallbacks.extend(outcome.fallbacks);
    stats.warnings.extend(outcome.warnings);
    stats.pass_ms = passes;
    stats.total_ms = ms(t0);
    if last.is_none() {
        return Err(Error::Numerical("no frame was drawn".into()));
    }
    Ok((stats, i_total))
}

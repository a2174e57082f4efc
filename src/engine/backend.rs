//! The one public trait both backends implement, and the one factory that makes them: the f64
//! CPU solver with a ray-cast frame ([`super::cpu::CpuBackend`]), and the Vulkan raster passes
//! with their raster frame ([`super::gpu::GpuBackend`]). The engine drives either the same way.

use super::prepared::Prepared;
use crate::error::Result;
use crate::frame::Image;
use crate::gpu::memory::MemoryReport;
use crate::gpu::Context;
use crate::scene::{Precision, Scheme};
use crate::settings::{BackendKind, Method};
use crate::solver::convergence::Figures;
use crate::solver::Table;
use std::sync::Arc;

/// A solver and its frame drawing, as the engine sees them.
pub trait Backend {
    /// Which backend this is.
    fn kind(&self) -> BackendKind;
    /// The device it runs on (`cpu` or the Vulkan device name).
    fn device(&self) -> String;
    /// Shadow maps for the scene's lights (into `prep.maps`), the leaves' direct light from
    /// them, and the environment: everything the initial state is made from.
    fn prepare_lights(&mut self, prep: &mut Prepared) -> Result<()>;
    /// The initial state (emission, environment, direct light; no propagation).
    fn initialize(&mut self, prep: &Prepared) -> Result<()>;
    /// `n` iterations of `scheme` with `antiradiance_steps` (asymmetric), as one batch (the GPU
    /// submits them at once and reduces the convergence figures on the device), returning the
    /// figures of each.
    fn iterate_batch(
        &mut self,
        prep: &Prepared,
        scheme: Scheme,
        antiradiance_steps: usize,
        n: usize,
    ) -> Result<Vec<Figures>>;
    /// The current I_ex (unscaled).
    fn i_ex(&mut self) -> Result<Table>;
    /// The current display intensity I_total (unscaled).
    fn i_total(&mut self) -> Result<Table>;
    /// Largest |I_ex| before the table format overflows (infinite for f64/f32).
    fn overflow_limit(&self) -> f64;
    /// Switches to wider tables (float32) and says so, or `None` when already as wide as it gets.
    fn widen(&mut self, prep: &Prepared) -> Result<Option<String>>;
    /// Draws the frame of the current state from `prep.camera`.
    fn draw(&mut self, prep: &Prepared) -> Result<Image>;
    /// Takes `prep.camera` (same size, new pose or field of view) for the next frames; the
    /// solution does not depend on the camera, so nothing is re-solved.
    fn set_camera(&mut self, prep: &Prepared) -> Result<()>;
    /// Pass timings (ms, in order) since the last call.
    fn take_timings(&mut self) -> Vec<(String, f64)>;
    /// Precision of the tables now.
    fn precision(&self) -> Precision;
    /// Departures from the requested configuration made when the backend was set up.
    fn fallbacks(&self) -> Vec<String>;
    /// GPU memory by purpose (empty for the CPU backend).
    fn memory(&self) -> MemoryReport;
    /// The GPU backend, for recording into a host's command buffers.
    fn as_gpu(&mut self) -> Option<&mut super::gpu::GpuBackend>;
    /// Continues from `i_ex` (unscaled, one row per node of `prep.system`, clusters pulled)
    /// instead of the initial state: the previous frame's solution after objects or lights
    /// moved (§3.3). Baseline methods keep no such state and refuse.
    fn warm_start(&mut self, _prep: &Prepared, _i_ex: &Table) -> Result<()> {
        Err(crate::error::Error::Invalid(
            "moving objects and lights need the antiradiance method".into(),
        ))
    }
    /// Whether [`Backend::warm_start`] continues from any table of the system's shape (the
    /// antiradiance backends): the drive loop's tail extrapolation needs it.
    fn resumable(&self) -> bool {
        false
    }
    /// Continues from the solution the backend holds after it followed a move
    /// ([`Backend::follow`] returned true): the next iterations start from it (§3.3), as
    /// [`Backend::warm_start`] with the same table would, without handing it over.
    fn keep_solution(&mut self, _prep: &Prepared) -> Result<()> {
        Err(crate::error::Error::Invalid(
            "moving objects and lights need the antiradiance method".into(),
        ))
    }
    /// Follows `prep` after its objects moved from where `before` had them along a bounded
    /// link mesh (same nodes, links and table shapes; new geometry and form factors,
    /// [`crate::bound`]), or after only its lights moved (same system), keeping its state; or
    /// returns false where the backend must be made anew (the default). The next [`Backend::prepare_lights`] may reuse what the motion
    /// cannot have changed.
    fn follow(&mut self, _before: &Prepared, _prep: &Prepared) -> Result<bool> {
        Ok(false)
    }
    /// What a baseline method reports of its own (`None` for antiradiance).
    fn method_report(&self) -> Option<crate::methods::MethodReport> {
        None
    }
}

/// Makes the backend of `options.method` on `options.backend` for `prep`; GPU backends use
/// `ctx`. A method may first transform the prepared system (hierarchical radiosity puts its
/// visibility into the links and turns antiradiance off; instant radiosity adds its VPLs to the
/// lights).
pub fn create(
    options: &super::Options,
    prep: &mut Prepared,
    ctx: Option<Arc<Context>>,
) -> Result<Box<dyn Backend>> {
    let gpu = || {
        ctx.clone().ok_or_else(|| {
            crate::error::Error::Device("the GPU backend needs a Vulkan context".into())
        })
    };
    use crate::methods::{hierarchical, instant, progressive};
    Ok(match (options.method, options.backend) {
        (Method::Antiradiance, BackendKind::Cpu) => Box::new(super::cpu::CpuBackend::new(prep)),
        (Method::Antiradiance, BackendKind::Gpu) => {
            Box::new(super::gpu::GpuBackend::new(gpu()?, prep, options.gpu)?)
        }
        (Method::HierarchicalRadiosity, kind) => {
            let report = hierarchical::prepare(prep, &options.baseline)?;
            let inner: Box<dyn Backend> = match kind {
                BackendKind::Cpu => Box::new(super::cpu::CpuBackend::new(prep)),
                BackendKind::Gpu => {
                    Box::new(super::gpu::GpuBackend::new(gpu()?, prep, options.gpu)?)
                }
            };
            Box::new(hierarchical::HierarchicalBackend::new(inner, report))
        }
        (Method::ProgressiveRadiosity, BackendKind::Cpu) => {
            Box::new(progressive::cpu::CpuShooting::new(prep, &options.baseline)?)
        }
        (Method::ProgressiveRadiosity, BackendKind::Gpu) => Box::new(
            progressive::gpu::GpuShooting::new(gpu()?, prep, &options.baseline)?,
        ),
        (Method::InstantRadiosity, kind) => {
            let report = instant::prepare(prep, options)?;
            match kind {
                BackendKind::Cpu => Box::new(instant::backend::CpuInstant::new(prep, report)),
                BackendKind::Gpu => {
                    Box::new(instant::backend::GpuInstant::new(gpu()?, prep, report)?)
                }
            }
        }
    })
}

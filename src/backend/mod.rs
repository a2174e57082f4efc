//! What every method implements and what it is made from, below both the engine and the
//! methods: the [`Solve`] and [`Draw`] interfaces (one [`Backend`] is both), the prepared scene
//! ([`Prepared`]), the options ([`Options`]) and the methods' settings ([`method`]). The methods
//! make themselves ([`crate::methods::create`]); the engine drives any of them the same way.

pub mod method;
pub mod options;
pub mod prepared;

pub use options::{GpuTuning, Options, Resolved, SolverOverrides, DEFAULT_MAX_LINKS};
pub use prepared::{fit_system, Prepared};

use crate::error::{Error, Result};
use crate::frame::Image;
use crate::gpu::memory::MemoryReport;
use crate::scene::{Precision, Scheme};
use crate::settings::BackendKind;
use crate::solver::convergence::Figures;
use crate::solver::Table;
use std::any::Any;

/// How a method computes the light: from the prepared scene to the tables the frame reads.
/// Only the lights, the iterations and the two tables are required; the rest has the answer of
/// a method with nothing to say (no initial state, no wider tables, no warm start).
pub trait Solve {
    /// Shadow maps for the scene's lights (into `prep.maps`), the leaves' direct light from
    /// them, and the environment: everything the initial state is made from.
    fn prepare_lights(&mut self, prep: &mut Prepared) -> Result<()>;
    /// The initial state (emission, environment, direct light; no propagation).
    fn initialize(&mut self, _prep: &Prepared) -> Result<()> {
        Ok(())
    }
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
    /// Damps the symmetric scheme's iterations from now on: each new iterate weighted by
    /// `weight` against the last ([`crate::solver::CpuState::damping`]); false where the
    /// method has no such iteration.
    fn damp(&mut self, _weight: f64) -> bool {
        false
    }
    /// The current I_ex (unscaled).
    fn i_ex(&mut self) -> Result<Table>;
    /// The current display intensity I_total (unscaled).
    fn i_total(&mut self) -> Result<Table>;
    /// Largest |I_ex| before the table format overflows (infinite for f64/f32).
    fn overflow_limit(&self) -> f64 {
        f64::MAX
    }
    /// Switches to wider tables (float32) and says so, or `None` when already as wide as it gets.
    fn widen(&mut self, _prep: &Prepared) -> Result<Option<String>> {
        Ok(None)
    }
    /// Precision of the tables now.
    fn precision(&self) -> Precision {
        Precision::F64
    }
    /// Continues from `i_ex` (unscaled, one row per node of `prep.system`, clusters pulled)
    /// instead of the initial state: the previous frame's solution after objects or lights
    /// moved (§3.3). Baseline methods keep no such state and refuse.
    fn warm_start(&mut self, _prep: &Prepared, _i_ex: &Table) -> Result<()> {
        Err(needs_antiradiance())
    }
    /// Whether [`Solve::warm_start`] continues from any table of the system's shape (the
    /// antiradiance backends): the drive loop's tail extrapolation needs it.
    fn resumable(&self) -> bool {
        false
    }
    /// Continues from the solution the backend holds after it followed a move
    /// ([`Solve::follow`] returned true): the next iterations start from it (§3.3), as
    /// [`Solve::warm_start`] with the same table would, without handing it over.
    fn keep_solution(&mut self, _prep: &Prepared) -> Result<()> {
        Err(needs_antiradiance())
    }
    /// Follows `prep` after its objects moved from where `before` had them along a bounded
    /// link mesh (same nodes, links and table shapes; new geometry and form factors,
    /// [`crate::bound`]), or after only its lights moved (same system), keeping its state; or
    /// returns false where the backend must be made anew (the default). The next
    /// [`Solve::prepare_lights`] may reuse what the motion cannot have changed.
    fn follow(&mut self, _before: &Prepared, _prep: &Prepared) -> Result<bool> {
        Ok(false)
    }
    /// What a baseline method reports of its own (`None` for antiradiance).
    fn method_report(&self) -> Option<method::MethodReport> {
        None
    }
}

fn needs_antiradiance() -> Error {
    Error::Invalid("moving objects and lights need the antiradiance method".into())
}

/// How a method draws its solution: the frame from `prep.camera`.
pub trait Draw {
    /// Draws the frame of the current state from `prep.camera`.
    fn draw(&mut self, prep: &Prepared) -> Result<Image>;
    /// Takes `prep.camera` (same size, new pose or field of view) for the next frames; the
    /// solution does not depend on the camera, so nothing is re-solved. The default suits a
    /// frame that reads `prep.camera` at every draw (the ray-cast frames).
    fn set_camera(&mut self, _prep: &Prepared) -> Result<()> {
        Ok(())
    }
}

/// A method on one backend, as the engine holds it: it solves and draws, says where it runs and
/// what it took.
pub trait Backend: Solve + Draw + AsAny {
    /// Which backend this is.
    fn kind(&self) -> BackendKind;
    /// The device it runs on: the Vulkan device's name, or `cpu` (the default).
    fn device(&self) -> String {
        "cpu".into()
    }
    /// Pass timings (ms, in order) since the last call.
    fn take_timings(&mut self) -> Vec<(String, f64)>;
    /// Departures from the requested configuration made when the backend was set up.
    fn fallbacks(&self) -> Vec<String> {
        Vec::new()
    }
    /// GPU memory by purpose (empty for the CPU backends).
    fn memory(&self) -> MemoryReport {
        MemoryReport::default()
    }
    /// The backend that records the GPU work, as [`Any`]: the engine downcasts it to the GPU
    /// antiradiance backend to record into a host's command buffers. A method that wraps
    /// another returns what it wraps.
    fn recorder(&mut self) -> &mut dyn Any {
        self.as_any_mut()
    }
    /// A frame drawn on the host but handed to a host's command buffer as a GPU image (a method
    /// whose reconstruction runs on the CPU, on the GPU backend); `None` where the GPU
    /// antiradiance backend records its own passes, or on the CPU backend.
    fn host_frame(&mut self) -> Option<&mut dyn HostFrame> {
        None
    }
}

/// What [`Backend::host_frame`] gives: the draw, uploaded by commands recorded into a host's
/// command buffer, into an output image the host then copies, blits or samples.
pub trait HostFrame {
    /// Draws the frame of `prep` and records its upload into `cmd`, leaving [`Self::output`]
    /// shader-readable. `cmd` must complete before the next call (its staging is reused).
    fn record_draw(&mut self, prep: &Prepared, cmd: ash::vk::CommandBuffer) -> Result<()>;
    /// The output image (RGBA32F, the camera's size); None before the first draw.
    fn output(&self) -> Option<&crate::gpu::memory::Image>;
    /// Multiplies the radiance the next draws upload by `factor` (a viewer's exposure).
    fn set_exposure(&mut self, factor: f32);
}

/// The concrete backend behind a `dyn Backend` (the engine finds the GPU antiradiance backend
/// this way to record into a host's command buffers); implemented for every type.
pub trait AsAny: Any {
    /// `self` as [`Any`].
    fn as_any_mut(&mut self) -> &mut dyn Any;
}

impl<T: Any> AsAny for T {
    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}

//! What a run uses beyond the scene file: the backend, device, solver and camera overrides from
//! the command line or an embedding host. Options are resolved against a scene into the
//! effective settings; they are never written into the scene.

use crate::error::{Error, Result};
use crate::gpu::Context;
use crate::plan::target::{self, TargetChoice};
use crate::scene::{Camera, Precision, Scene, Scheme, SolverSettings};
use crate::settings::{BackendKind, Method};
use std::sync::Arc;

/// Solver settings that replace the scene's `[solver]` values where given.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SolverOverrides {
    /// Directional bins.
    pub bins: Option<usize>,
    /// Iterations (0: the initial state only, direct light and emission).
    pub iterations: Option<usize>,
    /// Iteration scheme.
    pub scheme: Option<Scheme>,
    /// GPU table precision.
    pub precision: Option<Precision>,
    /// Longest edge of a leaf element (scene units).
    pub element_size: Option<f64>,
    /// Oracle threshold τ.
    pub oracle: Option<f64>,
    /// Antiradiance steps per radiance step (asymmetric).
    pub antiradiance_steps: Option<usize>,
    /// Iterate until the estimated error is below this.
    pub tolerance: Option<f64>,
    /// Iteration cap with a tolerance.
    pub max_iterations: Option<usize>,
    /// Truncation of the cone filters.
    pub filter_cutoff: Option<f64>,
    /// Shadow-mapped samples of the area emitters (0: emission through the bins).
    pub emitter_samples: Option<usize>,
    /// Iterations per animated frame (warm-started).
    pub iterations_per_frame: Option<usize>,
}

impl SolverOverrides {
    /// `base` with these overrides applied.
    pub fn apply(&self, base: &SolverSettings) -> SolverSettings {
        let mut s = base.clone();
        s.bins = self.bins.unwrap_or(s.bins);
        s.iterations = self.iterations.unwrap_or(s.iterations);
        s.scheme = self.scheme.unwrap_or(s.scheme);
        s.precision = self.precision.unwrap_or(s.precision);
        s.element_size = self.element_size.unwrap_or(s.element_size);
        s.oracle = self.oracle.unwrap_or(s.oracle);
        s.antiradiance_steps = self.antiradiance_steps.unwrap_or(s.antiradiance_steps);
        // A count asked for here runs exactly (the scene's tolerance, its own or the file
        // default, gives way), unless a tolerance is asked for too.
        s.tolerance = match (self.tolerance, self.iterations) {
            (Some(t), _) => Some(t),
            (None, Some(_)) => None,
            (None, None) => s.tolerance,
        };
        s.max_iterations = self.max_iterations.unwrap_or(s.max_iterations);
        s.filter_cutoff = self.filter_cutoff.unwrap_or(s.filter_cutoff);
        s.emitter_samples = self.emitter_samples.or(s.emitter_samples);
        s.iterations_per_frame = self.iterations_per_frame.unwrap_or(s.iterations_per_frame);
        s
    }
}

/// GPU knobs for tests and diagnostics.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct GpuTuning {
    /// Caps the rows per column block below maxImageDimension2D (exercises the column split).
    pub column_height: Option<u32>,
    /// Accumulate L_in and L_push in the table format even where the device truncates float16
    /// blending.
    pub force_table_accumulation: bool,
    /// Accumulate L_in and L_push rounded to nearest float16, emulated in the shaders
    /// ([`crate::gpu::GpuOptions::emulate_f16_rounding`]).
    pub emulate_f16_rounding: bool,
    /// Caps the bytes of link records one descriptor reads (exercises the chunked global pass).
    pub link_range: Option<u64>,
}

/// Options of an [`crate::engine::Engine`] beyond the scene's own settings.
#[derive(Clone)]
pub struct Options {
    /// Which implementation solves and draws.
    pub backend: BackendKind,
    /// How global illumination is computed.
    pub method: Method,
    /// Solver settings replacing the scene's.
    pub solver: SolverOverrides,
    /// Image width replacing the camera's.
    pub width: Option<u32>,
    /// Image height replacing the camera's.
    pub height: Option<u32>,
    /// Supersampling replacing the camera's ([`crate::scene::Camera::supersample`]).
    pub supersample: Option<u32>,
    /// Shifted passes of the frame replacing the camera's ([`crate::scene::Camera::passes`]).
    pub passes: Option<u32>,
    /// Side of each shadow map (texels).
    pub shadow_map_size: u32,
    /// Side of each emitter sample's cube-face maps (texels; default
    /// [`crate::frame::emitters::SAMPLE_MAP_SIZE`]): finer maps narrow the band a shadow's
    /// filter reaches across a contact (docs/measurements.md, the lamp's direct light).
    pub emitter_map_size: u32,
    /// Device to render on (GPU backend; a host's device when embedding); `None` creates a
    /// headless context.
    pub context: Option<Arc<Context>>,
    /// Vulkan device name filter (GPU backend, headless).
    pub device: Option<String>,
    /// Enable the Vulkan validation layer (tests).
    pub validation: bool,
    /// Run every pass and create every table whether the scene needs it or not, with float32
    /// tables (`--all-passes`: the reference the scene-adaptive plan is checked against).
    pub all_passes: bool,
    /// Choose bins, element size and iterations for this relative RMSE from the measured
    /// error-vs-time data ([`crate::plan::target`]), replacing the scene's and the overrides.
    pub target_error: Option<f64>,
    /// GPU knobs for tests.
    pub gpu: GpuTuning,
    /// Settings of the baseline methods (rays per link, hemicube, subdivision, shots).
    pub baseline: super::method::MethodSettings,
    /// Link budget (`--max-links`; `None`: [`DEFAULT_MAX_LINKS`]): a scene whose links at its
    /// settings would pass it is linked coarser (a larger τ, then a larger element size) until
    /// it fits, each step stated in the plan's decisions.
    pub max_links: Option<u64>,
    /// Memory budget in bytes for the tables (`--memory-budget`; `None`: the device's memory
    /// on the GPU backend, none on the CPU): a scene whose tables would pass it gets a larger
    /// element size until they fit, stated in the decisions.
    pub memory_budget: Option<u64>,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            backend: BackendKind::Gpu,
            method: Method::Antiradiance,
            solver: SolverOverrides::default(),
            width: None,
            height: None,
            supersample: None,
            passes: None,
            shadow_map_size: 1024,
            emitter_map_size: crate::frame::emitters::SAMPLE_MAP_SIZE,
            context: None,
            device: None,
            validation: false,
            all_passes: false,
            target_error: None,
            gpu: GpuTuning::default(),
            baseline: super::method::MethodSettings::default(),
            max_links: None,
            memory_budget: None,
        }
    }
}

/// The default link budget ([`Options::max_links`]): a few times the paper's scale (its office
/// had 632K links). Measured on lavapipe (docs/measurements.md): the breakfast room's 2.55M
/// links iterate in 5.8× the Cornell box's 0.70M; no GPU figure has been taken for it yet.
pub const DEFAULT_MAX_LINKS: u64 = 4_000_000;

/// The settings a run uses: the scene's, with the options applied.
#[derive(Debug, Clone)]
pub struct Resolved {
    /// Effective solver settings.
    pub settings: SolverSettings,
    /// Effective camera.
    pub camera: Camera,
    /// The setting `target_error` chose, if given.
    pub target: Option<TargetChoice>,
}

impl Options {
    /// Options for `backend`, everything else default.
    pub fn backend(backend: BackendKind) -> Self {
        Self {
            backend,
            ..Self::default()
        }
    }

    /// Checks the option values themselves (ranges that do not depend on the scene).
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(Error::Invalid(m));
        if let Some(e) = self.target_error {
            if !(e > 0.0 && e.is_finite()) {
                return bad(format!(
                    "--target-error must be positive and finite, got {e}"
                ));
            }
        }
        if let Some(t) = self.solver.tolerance {
            if !(t > 0.0 && t < 1.0) {
                return bad(format!("--tolerance must be in (0, 1), got {t}"));
            }
        }
        use crate::scene::{MAX_ANTIRADIANCE_STEPS, MAX_ITERATIONS};
        if let Some(n) = self.solver.iterations.filter(|&n| n > MAX_ITERATIONS) {
            return bad(format!(
                "--iterations must be 0..={MAX_ITERATIONS} (a cap against typos, not a convergence limit), got {n}"
            ));
        }
        if let Some(n) = self
            .solver
            .iterations_per_frame
            .filter(|n| !(1..=MAX_ITERATIONS).contains(n))
        {
            return bad(format!(
                "--iterations-per-frame must be 1..={MAX_ITERATIONS}, got {n}"
            ));
        }
        if let Some(n) = self
            .solver
            .max_iterations
            .filter(|n| !(1..=MAX_ITERATIONS).contains(n))
        {
            return bad(format!(
                "--max-iterations must be 1..={MAX_ITERATIONS}, got {n}"
            ));
        }
        if let Some(n) = self
            .solver
            .antiradiance_steps
            .filter(|n| !(1..=MAX_ANTIRADIANCE_STEPS).contains(n))
        {
            return bad(format!(
                "antiradiance steps must be 1..={MAX_ANTIRADIANCE_STEPS}, got {n}"
            ));
        }
        if let Some(c) = self
            .solver
            .filter_cutoff
            .filter(|c| !(1e-9..=0.5).contains(c))
        {
            return bad(format!("--filter-cutoff must be in [1e-9, 0.5], got {c}"));
        }
        if let Some(n) = self
            .solver
            .emitter_samples
            .filter(|&n| n > crate::scene::MAX_EMITTER_SAMPLES)
        {
            return bad(format!(
                "--emitter-samples must be 0..={}, got {n}",
                crate::scene::MAX_EMITTER_SAMPLES
            ));
        }
        if let Some(o) = self.solver.oracle.filter(|o| !(*o > 0.0 && o.is_finite())) {
            return bad(format!("the oracle τ must be positive and finite, got {o}"));
        }
        for (flag, v) in [("--width", self.width), ("--height", self.height)] {
            if let Some(v) = v {
                if !(1..=16384).contains(&v) {
                    return bad(format!("{flag} must be 1..=16384, got {v}"));
                }
            }
        }
        if !(16..=8192).contains(&self.shadow_map_size) {
            return bad(format!(
                "--shadow-map-size must be 16..=8192, got {}",
                self.shadow_map_size
            ));
        }
        if !(16..=2048).contains(&self.emitter_map_size) {
            return bad(format!(
                "--emitter-map-size must be 16..=2048, got {}",
                self.emitter_map_size
            ));
        }
        if let Some(b) = self.solver.bins {
            crate::bins::Bins::new(b).map_err(|e| Error::Invalid(format!("--bins: {e}")))?;
        }
        self.baseline.validate()?;
        if let Some(e) = self.solver.element_size {
            if !(e > 0.0 && e.is_finite()) {
                return bad(format!("element size must be positive and finite, got {e}"));
            }
        }
        Ok(())
    }

    /// The effective settings and camera for `scene`.
    pub fn resolve(&self, scene: &Scene) -> Result<Resolved> {
        self.validate()?;
        let mut settings = self.solver.apply(&scene.solver);
        let target = self.target_error.map(|e| target::choose(scene, e));
        if let Some(c) = &target {
            settings.bins = c.bins;
            settings.element_size = c.element_size;
            settings.iterations = c.iterations;
            settings.tolerance = None;
        }
        let mut camera = scene.camera.clone();
        // A file's field of view stays fixed along its own axis (Mitsuba's `fov_axis`).
        camera = camera.resized(
            self.width.unwrap_or(camera.width),
            self.height.unwrap_or(camera.height),
        );
        camera.supersample = self.supersample.unwrap_or(camera.supersample);
        let k = camera.supersample;
        let max = crate::scene::MAX_SUPERSAMPLE;
        if !(1..=max).contains(&k) {
            return Err(Error::Invalid(format!(
                "--supersample must be in 1..={max}, got {k}"
            )));
        }
        camera.passes = self.passes.unwrap_or(camera.passes);
        let max = crate::scene::MAX_PASSES;
        if !(1..=max).contains(&camera.passes) {
            return Err(Error::Invalid(format!(
                "--passes must be in 1..={max}, got {}",
                camera.passes
            )));
        }
        // The frame is drawn at k× the image and reduced by the engine when read back.
        let (w, h) = (
            camera.width as u64 * k as u64,
            camera.height as u64 * k as u64,
        );
        if w.max(h) > 16384 {
            return Err(Error::Invalid(format!(
                "the image {}×{} supersampled {k}× is {w}×{h} frame pixels, more than 16384 on a side",
                camera.width, camera.height
            )));
        }
        camera.width = w as u32;
        camera.height = h as u32;
        Ok(Resolved {
            settings,
            camera,
            target,
        })
    }
}

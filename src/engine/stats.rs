//! What a render reports: the statistics of the `--json` file, the rendered frame, and the
//! frames handed out after every iteration for the error-per-iteration curves of `study`.

use crate::frame::Image;
use crate::plan::target::TargetChoice;
use crate::scene::{Precision, Scheme};
use crate::settings::BackendKind;
use crate::solver::Table;
use serde::Serialize;
use std::collections::BTreeMap;

/// Statistics of a render (the `--json` file).
#[derive(Debug, Clone, Serialize)]
pub struct RenderStats {
    /// Method used.
    pub method: crate::settings::Method,
    /// Backend used.
    pub backend: BackendKind,
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
    /// Scheme of the result (differs from the scene's after a fallback).
    pub scheme: Scheme,
    /// Table precision of the result (`f64` for the CPU backend).
    pub precision: Precision,
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
    pub target: Option<TargetChoice>,
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
    /// Estimated relative distance to the discrete system's fixed point after the last
    /// iteration ([`crate::solver::convergence::Monitor::error_estimate`]): the iteration error,
    /// not the error against the true answer (the discretization's own error is not in it).
    pub estimated_error: Option<f64>,
    /// Tail extrapolations the solve applied and kept ([`crate::solver::extrapolate`]; only
    /// where the iteration is stiff and one mode dominates).
    pub extrapolations: usize,
    /// Departures from the requested configuration.
    pub fallbacks: Vec<String>,
    /// Things the user should know about the result (e.g. the iteration cap was reached).
    pub warnings: Vec<String>,
    /// A baseline method's own figures: rays and time of its setup, its settings, the shots of
    /// progressive refinement (`None` for antiradiance).
    pub method_report: Option<crate::methods::MethodReport>,
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

/// A frame drawn after some iterations, handed to the callback of
/// [`super::Engine::render_each_iteration`].
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

/// How long preparing an engine took, by part (what `profile` reports as setup).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Setup {
    /// Meshing and linking on the CPU.
    pub linking_ms: f64,
    /// Creating and filling the GPU's images and buffers (with the CPU packing).
    pub uploads_ms: f64,
    /// Creating the GPU pipelines (from the pipeline cache when it holds them).
    pub pipelines_ms: f64,
    /// A baseline method's own preparation (hierarchical radiosity's visibility rays,
    /// progressive refinement's environment rays).
    pub method_ms: f64,
    /// The rest of the backend's creation (layouts, descriptor sets, the float16 probe; the
    /// CPU backend's ray caster).
    pub other_ms: f64,
    /// Shadow maps, the leaves' direct light and the sources' upload.
    pub lights_ms: f64,
}

impl Setup {
    /// Everything but linking.
    pub fn after_linking_ms(&self) -> f64 {
        self.uploads_ms + self.pipelines_ms + self.method_ms + self.other_ms + self.lights_ms
    }
}

//! What a [`super::GpuSolver`] is built with, and what building it took.

use crate::plan::Features;
use crate::scene::Precision;

/// GPU solver options.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GpuOptions {
    /// Table texel format.
    pub precision: Precision,
    /// Caps the rows per column block below maxImageDimension2D (tests use it to exercise
    /// the column split on small scenes).
    pub column_height: Option<u32>,
    /// Caps the global pass's line width below the device's
    /// ([`super::context::DeviceInfo::max_line_width`];
    /// tests use 1 to exercise the one-line-per-bin-row path of devices without wide lines).
    pub max_line_width: Option<u32>,
    /// Accumulate L_in and L_push in the table format even where the device truncates
    /// float16 blending (by default such devices accumulate in float32; see [`GpuSolver::fallbacks`]).
    pub force_table_accumulation: bool,
    /// Test-only: accumulate L_in and L_push in float32 rounded to the nearest float16 at every
    /// addition, in the shaders ([`crate::gpu::blend16`]): float16 tables' accumulation as a
    /// device that rounds its float16 blending performs it, on any device (lavapipe's
    /// truncates). Ignored for float32 tables; needs `fragmentStoresAndAtomics`.
    pub emulate_f16_rounding: bool,
    /// What to compute and allocate (a scene's [`crate::plan::Plan`]); `None`:
    /// [`Features::for_system`] (the system's local passes, antiradiance and every source on).
    pub features: Option<Features>,
    /// Caps the bytes of link records one descriptor reads below maxStorageBufferRange (tests
    /// use it to draw a small scene's links in several chunks).
    pub link_range: Option<u64>,
}

impl Default for GpuOptions {
    fn default() -> Self {
        Self {
            precision: Precision::F16,
            column_height: None,
            max_line_width: None,
            force_table_accumulation: false,
            emulate_f16_rounding: false,
            features: None,
            link_range: None,
        }
    }
}

/// Wall time of a GPU object's creation, split as `profile` reports it.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct SetupTimes {
    /// Creating images and buffers and uploading their contents (with the CPU packing).
    pub uploads_ms: f64,
    /// Creating pipelines (from the pipeline cache when it holds them).
    pub pipelines_ms: f64,
}

impl std::ops::Add for SetupTimes {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Self {
            uploads_ms: self.uploads_ms + o.uploads_ms,
            pipelines_ms: self.pipelines_ms + o.pipelines_ms,
        }
    }
}

//! The TOML scene file as written on disk (serde structs). `load.rs` validates and resolves it.

use serde::Deserialize;
use std::collections::BTreeMap;

/// An RGB value written either as one number (grey) or as `[r, g, b]`.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(untagged)]
pub enum Rgb {
    /// Same value in all three channels.
    Grey(f64),
    /// Per-channel value.
    Rgb([f64; 3]),
}

impl Rgb {
    /// The three channels.
    pub fn channels(self) -> [f64; 3] {
        match self {
            Rgb::Grey(g) => [g; 3],
            Rgb::Rgb(c) => c,
        }
    }
}

/// A uniform or per-axis scale.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(untagged)]
pub enum Scale {
    /// Same factor on every axis.
    Uniform(f64),
    /// Per-axis factors.
    Axes([f64; 3]),
}

/// Root of a scene file.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// Meshes placed in the scene.
    #[serde(default)]
    pub object: Vec<ObjectDesc>,
    /// Analytic lights.
    #[serde(default)]
    pub light: Vec<LightDesc>,
    /// Constant environment.
    pub environment: Option<EnvironmentDesc>,
    /// Pinhole camera.
    pub camera: Option<CameraDesc>,
    /// Discretization and iteration settings.
    pub solver: Option<SolverDesc>,
}

/// One `[[object]]`: an OBJ file, its placement and material overrides.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectDesc {
    /// OBJ path, relative to the scene file.
    pub mesh: String,
    /// Scale applied first.
    pub scale: Option<Scale>,
    /// Rotation applied second.
    pub rotate: Option<RotateDesc>,
    /// Translation applied last.
    pub translate: Option<[f64; 3]>,
    /// Full 4×4 row-major object-to-world matrix; excludes scale/rotate/translate.
    pub matrix: Option<[[f64; 4]; 4]>,
    /// Overrides of MTL materials by name.
    #[serde(default)]
    pub materials: BTreeMap<String, MaterialOverride>,
}

/// Rotation by `angle_deg` degrees about `axis` (right-handed).
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RotateDesc {
    /// Rotation axis (normalized on load).
    pub axis: [f64; 3],
    /// Angle in degrees.
    pub angle_deg: f64,
}

/// Replaces fields of a named MTL material.
#[derive(Debug, Clone, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct MaterialOverride {
    /// Diffuse albedo.
    pub kd: Option<Rgb>,
    /// Phong specular albedo.
    pub ks: Option<Rgb>,
    /// Phong exponent.
    pub ns: Option<f64>,
    /// Emitted radiance (one-sided, front face).
    pub ke: Option<Rgb>,
}

/// One `[[light]]`.
#[derive(Debug, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase")]
pub enum LightDesc {
    /// Parallel light.
    Directional {
        /// Direction in which light travels.
        direction: [f64; 3],
        /// Irradiance (W/m²) on a surface facing the light.
        irradiance: Rgb,
    },
    /// Isotropic point light.
    Point {
        /// Position.
        position: [f64; 3],
        /// Radiant intensity (W/sr).
        intensity: Rgb,
    },
    /// Spot light with a linear angular fall-off.
    Spot {
        /// Position.
        position: [f64; 3],
        /// Point on the axis.
        target: [f64; 3],
        /// Intensity on the axis (W/sr).
        intensity: Rgb,
        /// Full angle from the axis at which intensity reaches zero.
        cutoff_deg: f64,
        /// Angle from the axis inside which intensity is full.
        beam_width_deg: f64,
    },
}

/// `[environment]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EnvironmentDesc {
    /// Constant radiance arriving from every direction not blocked by geometry.
    pub radiance: Rgb,
}

/// `[camera]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraDesc {
    /// Eye position.
    pub eye: [f64; 3],
    /// Point looked at.
    pub target: [f64; 3],
    /// Up vector.
    pub up: Option<[f64; 3]>,
    /// Vertical field of view in degrees.
    pub fov_y_deg: Option<f64>,
    /// Image width in pixels.
    pub width: Option<i64>,
    /// Image height in pixels.
    pub height: Option<i64>,
}

/// `[solver]`.
#[derive(Debug, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct SolverDesc {
    /// Number of directional bins `m`.
    pub bins: Option<i64>,
    /// Number of iterations.
    pub iterations: Option<i64>,
    /// `"symmetric"` or `"asymmetric"`.
    pub scheme: Option<String>,
    /// Longest edge of a leaf element (scene units).
    pub element_size: Option<f64>,
    /// Link oracle threshold τ: refine while a node subtends more than τ·ω_bin.
    pub oracle: Option<f64>,
    /// Antiradiance steps per radiance step in the asymmetric scheme.
    pub antiradiance_steps: Option<i64>,
    /// `"f16"` or `"f32"` GPU tables.
    pub precision: Option<String>,
    /// Upper bound on leaf elements (refuses scenes that would exceed it).
    pub max_elements: Option<i64>,
    /// Residual target (iterate until the estimated error is below it).
    pub tolerance: Option<f64>,
    /// Iteration cap when a tolerance is given.
    pub max_iterations: Option<i64>,
}

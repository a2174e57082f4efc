//! The settings every method is made with and the report a baseline gives back: what the
//! command line, the scene analysis and the study pass to [`crate::methods`] without depending
//! on any one of them.

use crate::error::{Error, Result};
use serde::Serialize;
use std::collections::BTreeMap;

/// Side (texels) of a VPL's shadow-map faces: VPLs are many and their light is soft, so their
/// maps can be smaller than an emitter sample's (README, "Instant radiosity").
pub const VPL_MAP_SIZE: u32 = 64;

/// Settings of the baseline methods (antiradiance ignores them).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MethodSettings {
    /// Hierarchical radiosity: visibility rays per link (the paper used 141).
    pub rays_per_link: u32,
    /// Progressive refinement: side of a hemicube face of the item buffer, texels.
    pub hemicube: u32,
    /// Progressive refinement: deepest receiver subdivision (0: the centroid only; `L`: up to
    /// 4^L sub-triangles where the received light varies across the element).
    pub subdivision: u32,
    /// Progressive refinement: a receiver is subdivided further when its samples of one shot
    /// spread by more than this fraction of their largest.
    pub gradient: f64,
    /// Progressive refinement: shots per iteration; `None`: a quarter of the elements.
    pub shots_per_iteration: Option<u32>,
    /// Instant radiosity: light paths traced (each leaves a VPL at its first hit, Russian
    /// roulette about `ρ/(1−ρ)` more).
    pub vpls: u32,
    /// Instant radiosity: the clamp's disc area in units of the scene's surface area per VPL
    /// (0: no clamp, the bare `1/r²`).
    pub vpl_clamp: f64,
    /// Image-based radiosity: cells of the layered depth cube along the scene's longest side
    /// (its hemicubes are `hemicube` texels a side).
    pub cube: u32,
    /// Image-based radiosity: rays per cube layer that gather back the light the clamp takes
    /// from the VPLs' near field (0: the clamped cube, as the paper has it).
    pub near_rays: u32,
}

impl Default for MethodSettings {
    fn default() -> Self {
        Self {
            rays_per_link: DEFAULT_RAYS_PER_LINK,
            hemicube: DEFAULT_HEMICUBE,
            subdivision: DEFAULT_SUBDIVISION,
            gradient: DEFAULT_GRADIENT,
            shots_per_iteration: None,
            vpls: DEFAULT_VPLS,
            vpl_clamp: DEFAULT_VPL_CLAMP,
            cube: DEFAULT_CUBE,
            near_rays: DEFAULT_NEAR_RAYS,
        }
    }
}

/// Default light paths of instant radiosity (README, "Instant radiosity": chosen by
/// measurement on the Cornell box).
pub const DEFAULT_VPLS: u32 = 256;

/// Default resolution of image-based radiosity's layered depth cube (cells along the longest
/// side); the paper keeps the hemicubes' faces about as fine.
pub const DEFAULT_CUBE: u32 = 128;

/// Default rays per cube layer restoring image-based radiosity's near field (README,
/// "Baselines"; docs/measurements.md, "Image-based radiosity").
pub const DEFAULT_NEAR_RAYS: u32 = 16;

/// Default clamp of instant radiosity: a VPL's disc is the surface area it stands for.
pub const DEFAULT_VPL_CLAMP: f64 = 1.0;

/// Default visibility rays per link of hierarchical radiosity (README, "Baselines": chosen by
/// measurement on the Cornell box).
pub const DEFAULT_RAYS_PER_LINK: u32 = 16;

/// Default side of a hemicube face of progressive refinement's item buffer (texels).
pub const DEFAULT_HEMICUBE: u32 = 128;

/// Default deepest receiver subdivision of progressive refinement (up to 16 samples).
pub const DEFAULT_SUBDIVISION: u32 = 2;

/// Default spread of a receiver's samples above which progressive refinement subdivides it.
pub const DEFAULT_GRADIENT: f64 = 0.25;

/// Largest receiver subdivision level (4^4 = 256 samples per element and shot).
pub const MAX_SUBDIVISION: u32 = 4;

impl MethodSettings {
    /// Checks the ranges (flags name themselves in the message).
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(Error::Invalid(m));
        if !(1..=4096).contains(&self.rays_per_link) {
            return bad(format!(
                "--rays-per-link must be 1..=4096, got {}",
                self.rays_per_link
            ));
        }
        if !(8..=2048).contains(&self.hemicube) {
            return bad(format!(
                "--hemicube must be 8..=2048 texels, got {}",
                self.hemicube
            ));
        }
        if self.subdivision > MAX_SUBDIVISION {
            return bad(format!(
                "--subdivision must be 0..={MAX_SUBDIVISION}, got {}",
                self.subdivision
            ));
        }
        if !(self.gradient >= 0.0 && self.gradient.is_finite()) {
            return bad(format!(
                "--gradient must be non-negative and finite, got {}",
                self.gradient
            ));
        }
        // The GPU frame loops over every light per pixel; llvmpipe caps a loop at 65535
        // iterations, and paths leave up to ~2 VPLs each in the bundled scenes.
        if !(1..=16384).contains(&self.vpls) {
            return bad(format!("--vpls must be 1..=16384, got {}", self.vpls));
        }
        if !(self.vpl_clamp >= 0.0 && self.vpl_clamp.is_finite()) {
            return bad(format!(
                "--vpl-clamp must be non-negative and finite, got {}",
                self.vpl_clamp
            ));
        }
        if !(4..=2048).contains(&self.cube) {
            return bad(format!("--cube must be 4..=2048, got {}", self.cube));
        }
        if self.near_rays > 4096 {
            return bad(format!(
                "--near-rays must be 0..=4096, got {}",
                self.near_rays
            ));
        }
        if let Some(0) = self.shots_per_iteration {
            return bad("--shots-per-iteration must be at least 1".into());
        }
        Ok(())
    }
}

/// One shot of progressive refinement: what was left to shoot before it, and what leaves the
/// surfaces after it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Shot {
    /// Leaf slot of the shooter.
    pub shooter: u32,
    /// Unshot power (W, mean of RGB) of all elements before the shot.
    pub unshot: f64,
    /// The shooter's unshot power (W, mean of RGB).
    pub power: f64,
}

/// What a baseline method reports beyond the engine's per-iteration figures (the `method_report`
/// of the render's statistics).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct MethodReport {
    /// One-time work of the method itself (ms), part of the setup: hierarchical radiosity's
    /// visibility rays, progressive refinement's environment rays.
    pub setup_ms: f64,
    /// Rays traced in that setup.
    pub rays: u64,
    /// Named settings and counts (e.g. `rays_per_link`, `occluded_links`, `shots`).
    pub figures: BTreeMap<String, f64>,
    /// Progressive refinement: every shot of the last solve, in order.
    pub shots: Vec<Shot>,
}

//! The related systems the paper compares with, as further methods of the same engine (each a
//! [`crate::engine::Backend`]): hierarchical radiosity with explicit visibility on the same links
//! ([`hierarchical`], the paper's Fig. 14f) and progressive refinement radiosity with a hemicube
//! item buffer ([`progressive`], Coombe and Harris, GPU Gems 2 ch. 39). They take the same scene,
//! the same direct light (analytic lights by shadow maps through
//! [`crate::engine::Backend::prepare_lights`], area emitters through the method) and the same frame
//! formation, so their images differ from antiradiance's only by the method.

pub mod hierarchical;
pub mod instant;
pub mod progressive;
pub mod visibility;

use crate::error::{Error, Result};
use glam::DVec3;
use serde::Serialize;
use std::collections::BTreeMap;

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
        }
    }
}

/// Default light paths of instant radiosity (README, "Instant radiosity": chosen by
/// measurement on the Cornell box).
pub const DEFAULT_VPLS: u32 = 256;

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

/// Golden-ratio generalization for `d` dimensions (Roberts' R_d sequence): the root of
/// x^(d+1) = x + 1; `α_k = φ^-(k+1)` make a low-discrepancy Kronecker sequence.
fn kronecker_alphas<const D: usize>() -> [f64; D] {
    let mut phi = 2.0f64;
    for _ in 0..64 {
        phi = (1.0 + phi).powf(1.0 / (D as f64 + 1.0));
    }
    std::array::from_fn(|k| phi.powi(-(k as i32 + 1)).fract())
}

/// SplitMix64: a well-mixed 64-bit hash (per-link and per-element sequence offsets).
pub fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Points `0..n` of a `D`-dimensional Kronecker sequence shifted by a random offset drawn from
/// `seed` (Cranley–Patterson rotation: unbiased, stratified, and uncorrelated between seeds).
pub struct Sequence<const D: usize> {
    alpha: [f64; D],
    offset: [f64; D],
}

impl<const D: usize> Sequence<D> {
    /// The sequence for `seed`.
    pub fn new(seed: u64) -> Self {
        let mut h = seed;
        Self {
            alpha: kronecker_alphas::<D>(),
            offset: std::array::from_fn(|_| {
                h = mix64(h);
                (h >> 11) as f64 / (1u64 << 53) as f64
            }),
        }
    }

    /// Point `k`, each coordinate in [0, 1).
    pub fn point(&self, k: usize) -> [f64; D] {
        std::array::from_fn(|d| (self.offset[d] + (k as f64 + 1.0) * self.alpha[d]).fract())
    }
}

/// A point of triangle `c` from two uniform numbers (area-uniform).
pub fn triangle_point(c: &[DVec3; 3], u: f64, v: f64) -> DVec3 {
    let s = u.sqrt();
    c[0] * (1.0 - s) + c[1] * (s * (1.0 - v)) + c[2] * (s * v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kronecker_points_are_uniform() {
        let s = Sequence::<6>::new(7);
        let n = 4096;
        let mut mean = [0.0; 6];
        for k in 0..n {
            for (m, x) in mean.iter_mut().zip(s.point(k)) {
                assert!((0.0..1.0).contains(&x));
                *m += x / n as f64;
            }
        }
        for m in mean {
            assert!((m - 0.5).abs() < 5e-3, "{m}");
        }
        // φ_1 is the golden ratio.
        let a = kronecker_alphas::<1>()[0];
        assert!((a - 0.618_033_988_749_895).abs() < 1e-12, "{a}");
    }

    #[test]
    fn triangle_points_stay_inside() {
        let c = [DVec3::ZERO, DVec3::X, DVec3::Y];
        let s = Sequence::<2>::new(3);
        let mut centroid = DVec3::ZERO;
        for k in 0..2000 {
            let [u, v] = s.point(k);
            let p = triangle_point(&c, u, v);
            assert!(p.x >= 0.0 && p.y >= 0.0 && p.x + p.y <= 1.0 + 1e-12);
            centroid += p / 2000.0;
        }
        assert!((centroid - DVec3::new(1.0, 1.0, 0.0) / 3.0).length() < 2e-3);
    }

    #[test]
    fn settings_are_checked() {
        assert!(MethodSettings::default().validate().is_ok());
        let e = MethodSettings {
            rays_per_link: 0,
            ..Default::default()
        }
        .validate()
        .unwrap_err();
        assert!(e.to_string().contains("--rays-per-link"), "{e}");
        let e = MethodSettings {
            subdivision: 9,
            ..Default::default()
        }
        .validate()
        .unwrap_err();
        assert!(e.to_string().contains("--subdivision"), "{e}");
    }
}

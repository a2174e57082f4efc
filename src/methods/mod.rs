//! The methods, each a [`crate::backend::Backend`] that makes itself here ([`create`]): the
//! paper's antiradiance ([`antiradiance`], on the f64 CPU solver or the Vulkan passes) and the
//! related systems it compares with: hierarchical radiosity with explicit visibility on the same
//! links ([`hierarchical`], the paper's Fig. 14f), progressive refinement radiosity with a
//! hemicube item buffer ([`progressive`], Coombe and Harris, GPU Gems 2 ch. 39) and instant
//! radiosity ([`instant`]). They take the same scene, the same direct light (analytic lights by
//! shadow maps through [`crate::backend::Solve::prepare_lights`], area emitters through the
//! method) and the same frame formation, so their images differ only by the method.

pub mod antiradiance;
pub mod hierarchical;
pub mod ibr;
pub mod instant;
pub mod progressive;
pub mod visibility;

pub use crate::backend::method::*;

use crate::backend::{Backend, Options, Prepared};
use crate::error::{Error, Result};
use crate::gpu::Context;
use crate::settings::{BackendKind, Method};
use glam::DVec3;
use std::sync::Arc;

/// Makes the backend of `options.method` on `options.backend` for `prep`; GPU backends use
/// `ctx`. A method may first transform the prepared system (hierarchical radiosity puts its
/// visibility into the links and turns antiradiance off; instant radiosity adds its VPLs to the
/// lights).
pub fn create(
    options: &Options,
    prep: &mut Prepared,
    ctx: Option<Arc<Context>>,
) -> Result<Box<dyn Backend>> {
    let gpu = || {
        ctx.clone()
            .ok_or_else(|| Error::Device("the GPU backend needs a Vulkan context".into()))
    };
    use antiradiance::{cpu::CpuBackend, gpu::GpuBackend};
    Ok(match (options.method, options.backend) {
        (Method::Antiradiance, BackendKind::Cpu) => Box::new(CpuBackend::new(prep)),
        (Method::Antiradiance, BackendKind::Gpu) => {
            Box::new(GpuBackend::new(gpu()?, prep, options.gpu)?)
        }
        (Method::HierarchicalRadiosity, kind) => {
            let report = hierarchical::prepare(prep, &options.baseline)?;
            let inner: Box<dyn Backend> = match kind {
                BackendKind::Cpu => Box::new(CpuBackend::new(prep)),
                BackendKind::Gpu => Box::new(GpuBackend::new(gpu()?, prep, options.gpu)?),
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
        (Method::ImageBasedRadiosity, kind) => {
            let ctx = match kind {
                BackendKind::Cpu => None,
                BackendKind::Gpu => Some(gpu()?),
            };
            Box::new(ibr::backend::ImageBased::new(prep, options.baseline, ctx)?)
        }
    })
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
/// `seed` (Cranley–Patterson rotation: unbiased and stratified). Points of equal index under two
/// seeds differ by a constant shift: draws that must be independent take different dimensions.
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

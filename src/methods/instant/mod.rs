//! Instant radiosity (Keller 1997; the paper's Fig. 14e): light paths traced from the lights
//! leave virtual point lights (VPLs) where they hit surfaces, and every pixel gathers from them
//! through their shadow maps, the same maps and lookup as the analytic lights and the area
//! emitters' samples ([`crate::frame::shadow`]). Direct light stays as for antiradiance (the
//! shadow-mapped lights and emitter samples); the VPLs carry the indirect light, so the frame
//! passes of either backend draw the method unchanged: a VPL is a [`Light::EmitterSample`].
//!
//! **Paths.** The scene's lights and its area emitters are sources; `vpls` paths are shared
//! among them by power (largest remainders, at least one per source that has power). The starts
//! of a source's paths are the points of a low-discrepancy sequence (Kronecker,
//! [`super::Sequence`]), and so are each bounce's directions and roulette draws, over the paths
//! in an order shuffled per bounce ("padding"): the same index in two bounces' sequences would
//! give points a constant shift apart, deciding a survivor's next roulette by its last.
//! Point lights start uniformly over the sphere, spots uniformly in the cone of their cut-off
//! (weighted by the fall-off), directional lights on a disc across the scene's bounding sphere,
//! area emitters at stratified points ([`crate::frame::emitters::sample`]) into the
//! cosine-weighted hemisphere. At every front-side hit the path leaves a VPL with the flux the
//! surface reflects diffusely (`flux · kd`), then continues by Russian roulette with the
//! probability of `kd`'s largest channel (at most [`MAX_BOUNCES`] hits). A path that hits a
//! surface's back ends there: one-sided surfaces reflect nothing from behind.
//!
//! **Glossy materials**: a VPL radiates diffusely (cosine-weighted, flux × `kd`); the Phong part
//! of a bounce is dropped, so light reflected by a glossy lobe toward another surface is missing
//! (a bias on the glossy box). The receiver, a pixel, applies its full BRDF toward the eye, lobe
//! included, as for the lights.
//!
//! **Clamp.** A point light's `1/r²` makes bright splotches where a VPL sits next to a receiver
//! (room corners). Each VPL is the emitter samples' disc: it delivers `Φ·cos/(π(r² + A/π))`
//! ([`crate::frame::lights::incident`]), which is bounded by `Φ/A` as `r → 0`, with `A` the
//! surface area the VPL stands for: `clamp` × the scene's surface area over the VPL count. The
//! bound shrinks as VPLs are added (the method stays consistent); the energy it removes is
//! measured in `tests/instant.rs` and the README.

pub mod backend;

use super::{MethodReport, MethodSettings, Sequence};
use crate::backend::{Options, Prepared};
use crate::error::{Error, Result};
use crate::frame::emitters;
use crate::raycast::RayCaster;
use crate::reference::sampling::sample_power_cosine;
use crate::scene::{Light, Scene};
use crate::system::System;
use glam::DVec3;
use std::f64::consts::PI;
use std::time::Instant;

/// Most surface hits of one light path (Russian roulette ends nearly all paths before).
pub const MAX_BOUNCES: usize = 16;

pub use crate::backend::method::VPL_MAP_SIZE;

/// The traced VPLs and what tracing them cost.
#[derive(Debug, Clone, Default)]
pub struct Vpls {
    /// The VPLs, as cosine-weighted one-sided point lights.
    pub lights: Vec<Light>,
    /// Light paths started.
    pub paths: usize,
    /// Flux the VPLs carry (W per channel): the indirect light leaving the surfaces.
    pub flux: DVec3,
    /// Clamp area of every VPL (m²; see the module's documentation).
    pub clamp_area: f64,
    /// Wall time of the tracing (ms).
    pub ms: f64,
}

/// Traces the VPLs of `prep`'s scene with `options.baseline`'s settings, appends them to
/// `prep.lights` (after the analytic lights and the emitter samples), and re-plans and re-fits
/// the shadow maps for them. Returns the method's report (the tracing is its setup).
pub fn prepare(prep: &mut Prepared, options: &Options) -> Result<MethodReport> {
    let settings = &options.baseline;
    let vpls = trace(&prep.scene, &prep.system, settings)?;
    let first = prep.lights.len();
    let count = vpls.lights.len();
    prep.lights.extend(vpls.lights);
    let t = Instant::now();
    prep.relight(options, first)?;
    prep.plan.decisions.push(format!(
        "instant radiosity: {} light paths left {count} VPLs ({:.0} ms), each a cosine point light with a {}² shadow map per face, clamped as a disc of {:.3e} m²; no links, nothing through the bins",
        vpls.paths,
        vpls.ms,
        prep.maps.views.get(prep.maps.light_views.get(first).map_or(0, |v| v.0 as usize)).map_or(0, |v| v.size),
        vpls.clamp_area
    ));
    let mut report = MethodReport {
        setup_ms: vpls.ms + t.elapsed().as_secs_f64() * 1e3,
        rays: 0,
        ..Default::default()
    };
    let flux = vpls.flux;
    for (k, v) in [
        ("vpl_paths", vpls.paths as f64),
        ("vpls", count as f64),
        ("vpl_flux", (flux.x + flux.y + flux.z) / 3.0),
        ("vpl_clamp", settings.vpl_clamp),
        ("vpl_clamp_area", vpls.clamp_area),
    ] {
        report.figures.insert(k.into(), v);
    }
    Ok(report)
}

/// Rec. 709 luminance (the weight that shares paths among sources).
fn luminance(c: DVec3) -> f64 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// A source of light paths: where a path starts and with what flux, from two uniform numbers.
enum Source {
    Light(Light),
    /// The area emitters: their stratified samples, one per path.
    Emitters(Vec<Light>),
}

/// Power of a light (W per channel) over the scene's bounding sphere of `radius` (directional
/// lights deliver their irradiance over its cross-section).
fn power(light: &Light, radius: f64) -> DVec3 {
    match *light {
        Light::Directional { irradiance, .. } => irradiance * (PI * radius * radius),
        Light::Point { intensity, .. } => intensity * (4.0 * PI),
        Light::Spot {
            intensity,
            cutoff,
            beam_width,
            ..
        } => {
            // ∫ falloff(θ) sin θ dθ · 2π, by the midpoint rule (the fall-off is linear in θ).
            let n = 256;
            let sum: f64 = (0..n)
                .map(|k| {
                    let t = (k as f64 + 0.5) / n as f64 * cutoff;
                    crate::frame::lights::spot_falloff(t, beam_width, cutoff) * t.sin()
                })
                .sum();
            intensity * (2.0 * PI * sum * cutoff / n as f64)
        }
        Light::EmitterSample { radiance, area, .. } => radiance * (PI * area),
    }
}

/// Shares `total` paths among sources of luminance powers `w` by largest remainders, at least
/// one per source with power (when there are enough paths).
fn share(w: &[f64], total: usize) -> Vec<usize> {
    let sum: f64 = w.iter().sum();
    if sum <= 0.0 || total == 0 {
        return vec![0; w.len()];
    }
    let ideal: Vec<f64> = w.iter().map(|x| x / sum * total as f64).collect();
    let mut n: Vec<usize> = ideal
        .iter()
        .zip(w)
        .map(|(i, &x)| {
            let f = i.floor() as usize;
            if x > 0.0 && f == 0 && total >= w.len() {
                1
            } else {
                f
            }
        })
        .collect();
    let mut order: Vec<usize> = (0..w.len()).collect();
    order.sort_by(|&a, &b| (ideal[b] - ideal[b].floor()).total_cmp(&(ideal[a] - ideal[a].floor())));
    let mut k = 0;
    while n.iter().sum::<usize>() < total {
        n[order[k % order.len()]] += 1;
        k += 1;
    }
    n
}

/// Traces `settings.vpls` light paths from `lights`' analytic lights and `scene`'s area
/// emitters through `sys`, and returns their VPLs.
pub fn trace(scene: &Scene, sys: &System, settings: &MethodSettings) -> Result<Vpls> {
    let start = Instant::now();
    if scene.environment != DVec3::ZERO {
        return Err(Error::Invalid(
            "instant-radiosity and image-based-radiosity do not support an [environment]: its \
             light would need VPLs from the sky, which this implementation does not trace"
                .into(),
        ));
    }
    let (lo, hi) = scene.bounds();
    let (center, radius) = ((lo + hi) * 0.5, ((hi - lo).length() * 0.5).max(1e-6));
    let caster = RayCaster::new(sys);
    let eps = super::progressive::surface_offset(sys);
    let lift = (hi - lo).length() * 1e-6;
    // Sources and their powers; the emitters are one source (their samples share its paths).
    let mut sources: Vec<(Source, DVec3)> = scene
        .lights
        .iter()
        .map(|l| (Source::Light(l.clone()), power(l, radius)))
        .collect();
    let emitter_power: DVec3 = emitters::sample(scene, 1024)
        .iter()
        .map(|l| power(l, radius))
        .sum();
    if luminance(emitter_power) > 0.0 {
        sources.push((Source::Emitters(Vec::new()), emitter_power));
    }
    let weights: Vec<f64> = sources
        .iter()
        .map(|(_, p)| luminance(*p).max(0.0))
        .collect();
    let counts = share(&weights, settings.vpls as usize);
    let area: f64 = sys.leaves.iter().map(|l| l.area).sum();
    let expected = settings.vpls as f64 * 2.0;
    let mut vpls = Vpls {
        paths: counts.iter().sum(),
        ..Default::default()
    };
    // Each VPL's clamp area: its share of the surface (fixed below from the VPL count).
    let mut raw: Vec<(DVec3, DVec3, DVec3)> = Vec::with_capacity(expected as usize);
    for (si, ((source, _), &n)) in sources.iter_mut().zip(&counts).enumerate() {
        if n == 0 {
            continue;
        }
        if let Source::Emitters(samples) = source {
            *samples = emitters::sample(scene, n);
        }
        let seq = Sequence::<2>::new(0x1f5d_0000 + si as u64);
        let bounces: Vec<(Sequence<3>, Vec<u32>)> = (0..MAX_BOUNCES as u64)
            .map(|b| {
                let seed = super::mix64((si as u64) << 32 | (b + 1));
                (Sequence::<3>::new(seed), shuffled(n, seed))
            })
            .collect();
        for k in 0..n {
            let [u1, u2] = seq.point(k);
            let (origin, dir, flux) = match source {
                Source::Light(light) => match *light {
                    Light::Directional {
                        direction,
                        irradiance,
                    } => {
                        let (t, b) = crate::reference::sampling::basis(direction);
                        let (r, phi) = (radius * 1.02 * u1.sqrt(), 2.0 * PI * u2);
                        let o = center - direction * (radius * 1.02)
                            + t * (r * phi.cos())
                            + b * (r * phi.sin());
                        let flux = irradiance * (PI * (radius * 1.02).powi(2) / n as f64);
                        (o, direction, flux)
                    }
                    Light::Point {
                        position,
                        intensity,
                    } => {
                        let z = 1.0 - 2.0 * u1;
                        let s = (1.0 - z * z).max(0.0).sqrt();
                        let phi = 2.0 * PI * u2;
                        let d = DVec3::new(s * phi.cos(), s * phi.sin(), z);
                        (position, d, intensity * (4.0 * PI / n as f64))
                    }
                    Light::Spot {
                        position,
                        axis,
                        intensity,
                        cutoff,
                        beam_width,
                    } => {
                        // Uniform in the cone's solid angle 2π(1 − cos cutoff).
                        let cos = 1.0 - u1 * (1.0 - cutoff.cos());
                        let sin = (1.0 - cos * cos).max(0.0).sqrt();
                        let phi = 2.0 * PI * u2;
                        let (t, b) = crate::reference::sampling::basis(axis);
                        let d = (t * (sin * phi.cos()) + b * (sin * phi.sin()) + axis * cos)
                            .normalize();
                        let f = crate::frame::lights::spot_falloff(cos.acos(), beam_width, cutoff);
                        let omega = 2.0 * PI * (1.0 - cutoff.cos());
                        (position, d, intensity * (f * omega / n as f64))
                    }
                    Light::EmitterSample { .. } => unreachable!("scene lights are analytic"),
                },
                Source::Emitters(samples) => {
                    let Light::EmitterSample {
                        position,
                        normal,
                        radiance,
                        area,
                        ..
                    } = samples[k]
                    else {
                        unreachable!("emitters::sample makes emitter samples")
                    };
                    let d = sample_power_cosine(normal, 1.0, u1, u2);
                    (position, d, radiance * (PI * area))
                }
            };
            follow(
                sys, &caster, eps, lift, origin, dir, flux, &bounces, k, &mut raw,
            );
        }
    }
    let clamp_area = if settings.vpl_clamp > 0.0 {
        settings.vpl_clamp * area / raw.len().max(1) as f64
    } else {
        // No clamp: a disc far below any distance the frame resolves.
        (hi - lo).length_squared() * 1e-12
    };
    vpls.clamp_area = clamp_area;
    vpls.flux = raw.iter().map(|r| r.2).sum();
    vpls.lights = raw
        .into_iter()
        .map(|(position, normal, flux)| Light::EmitterSample {
            position,
            normal,
            radiance: flux / (PI * clamp_area),
            area: clamp_area,
            cell: None,
        })
        .collect();
    vpls.ms = start.elapsed().as_secs_f64() * 1e3;
    Ok(vpls)
}

/// Follows one light path from `origin` along `dir` carrying `flux`, appending a VPL
/// (position, normal, reflected flux) at every front-side hit. Bounce `b` of path `k` takes
/// point `bounces[b].1[k]` of `bounces[b].0`.
#[allow(clippy::too_many_arguments)]
fn follow(
    sys: &System,
    caster: &RayCaster,
    eps: f64,
    lift: f64,
    mut origin: DVec3,
    mut dir: DVec3,
    mut flux: DVec3,
    bounces: &[(Sequence<3>, Vec<u32>)],
    k: usize,
    out: &mut Vec<(DVec3, DVec3, DVec3)>,
) {
    for (seq, order) in bounces.iter().take(MAX_BOUNCES) {
        let Some(hit) = caster.closest(origin, dir, eps, f64::INFINITY) else {
            return;
        };
        let leaf = &sys.leaves[hit.leaf as usize];
        let n = leaf.normal;
        if dir.dot(n) >= 0.0 {
            return; // the back of a one-sided surface: opaque, reflects nothing
        }
        let c = caster.corners(hit.shape);
        let p = c[0] * (1.0 - hit.u - hit.v) + c[1] * hit.u + c[2] * hit.v;
        let kd = sys.materials[leaf.material as usize].kd;
        let reflected = flux * kd;
        if reflected.max_element() <= 0.0 {
            return;
        }
        out.push((p + n * lift, n, reflected));
        let [u1, u2, u3] = seq.point(order[k] as usize);
        let q = kd.max_element().min(1.0);
        if u3 >= q {
            return;
        }
        flux = reflected / q;
        dir = sample_power_cosine(n, 1.0, u1, u2);
        origin = p + n * eps;
    }
}

/// A permutation of `0..n` drawn from `seed` (Fisher–Yates).
fn shuffled(n: usize, seed: u64) -> Vec<u32> {
    let mut order: Vec<u32> = (0..n as u32).collect();
    for i in (1..n).rev() {
        let r = super::mix64(seed ^ (i as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15));
        order.swap(i, (r % (i as u64 + 1)) as usize);
    }
    order
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_are_shared_by_power() {
        assert_eq!(share(&[3.0, 1.0], 8), vec![6, 2]);
        assert_eq!(share(&[1000.0, 1.0], 8), vec![7, 1]);
        assert_eq!(share(&[1.0, 0.0], 5), vec![5, 0]);
        assert_eq!(share(&[1.0, 1.0, 1.0], 10).iter().sum::<usize>(), 10);
        assert_eq!(share(&[0.0], 10), vec![0]);
    }

    #[test]
    fn spot_power_is_the_cone_integral() {
        // Without fall-off (beam = cut-off) a spot radiates I·2π(1 − cos c).
        let c: f64 = 0.6;
        let spot = Light::Spot {
            position: DVec3::ZERO,
            axis: DVec3::NEG_Y,
            intensity: DVec3::ONE,
            cutoff: c,
            beam_width: c,
        };
        let want = 2.0 * PI * (1.0 - c.cos());
        assert!((power(&spot, 1.0).x - want).abs() < 1e-4 * want);
    }
}

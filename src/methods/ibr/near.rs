//! The VPLs' near field, restored in the cube. A VPL's light is bounded as from a disc of area
//! `A` (instant radiosity's clamp): at distance `r` it delivers `r²/(r² + A/π)` of a point
//! light's, so every receiver misses `a/(r² + a)` (`a = A/π`) of the light the surfaces within a
//! few `√a` reflect toward it: along a room's edges and in its corners, a tenth of the indirect
//! light (the closed uniform box's worst pixel, 16% at 256 paths). This is Kollig and Keller's
//! bias compensation ("Illumination in the presence of weak singularities", 2004), done once per
//! layer of the cube instead of per pixel and frame: from each layer's point, `rays`
//! cosine-distributed rays; where one meets a surface's front at distance `r`, it adds
//! `kd·E·a/(r² + a)/rays` of irradiance, `E` the total irradiance the cube holds there (the
//! direct light, the VPLs' and the near field restored so far). [`SWEEPS`] Jacobi sweeps give the
//! near field's own interreflection in a corner; each sweep casts its rays anew (keeping their
//! hits would take 30 times the cube's memory). Both backends warp on the host, so both run
//! this same code on the same cube.

use super::cube::Cube;
use crate::frame::lights::direct_irradiance;
use crate::frame::shadow::ShadowMaps;
use crate::frame::surfaces::Surfaces;
use crate::raycast::RayCaster;
use crate::reference::sampling::basis;
use crate::scene::Light;
use crate::system::System;
use glam::DVec3;
use rayon::prelude::*;
use std::f64::consts::PI;
use std::time::Instant;

/// Jacobi sweeps of the restored near field, each one more reflection within it (the closed
/// uniform box at ρ = 0.5: mean −1.420 / −1.305 / −1.288 / −1.286% after 1 / 2 / 3 / 4, worst
/// pixel 10.0 / 9.56 / 9.52 / 9.51%).
pub const SWEEPS: usize = 3;

/// Rays stop where the clamp takes less than this fraction of a point light's light
/// (`a/(r² + a)`): farther surfaces miss less than it, the ray would cost without adding.
pub const LEAST_WEIGHT: f64 = 0.001;

/// What the near field is restored from: the scene's surfaces and the frame's lights.
pub struct NearField<'a> {
    /// Rays between surfaces.
    pub caster: &'a RayCaster,
    /// The surfaces' normals and materials (by the caster's shape).
    pub surf: &'a Surfaces,
    /// The leaves' materials.
    pub sys: &'a System,
    /// The frame's lights and their shadow maps: the direct light each layer reflects.
    pub lights: &'a [Light],
    /// Their shadow maps.
    pub maps: &'a ShadowMaps,
    /// How far the rays leave a layer's surface.
    pub lift: f64,
}

/// What restoring cost and found.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Restored {
    /// Rays cast.
    pub rays: u64,
    /// Rays that met a surface within reach.
    pub hits: u64,
    /// The restored irradiance over the VPLs' own, summed over layers (mean of channels).
    pub share: f64,
    /// Milliseconds, all of it.
    pub ms: f64,
}

/// `rays` directions of the cosine-weighted hemisphere around +z, stratified (rings of equal
/// measure, golden-angle turns), the same for every layer: a layer's neighbours see nearly the
/// same surfaces through them, so what is left of the sampling varies smoothly, not as grain.
pub fn directions(rays: u32) -> Vec<DVec3> {
    let golden = PI * (3.0 - 5f64.sqrt());
    (0..rays)
        .map(|k| {
            let u = (k as f64 + 0.5) / rays as f64;
            let (s, phi) = (u.sqrt(), k as f64 * golden);
            DVec3::new(s * phi.cos(), s * phi.sin(), (1.0 - u).sqrt())
        })
        .collect()
}

/// Restores the near field that a clamp disc of `clamp_area` takes from the VPLs in `cube`,
/// with `rays` rays per layer (0: nothing).
pub fn restore(cube: &mut Cube, nf: &NearField<'_>, clamp_area: f64, rays: u32) -> Restored {
    let t = Instant::now();
    let a = clamp_area / PI;
    if rays == 0 || a <= 0.0 || cube.layers() == 0 {
        return Restored::default();
    }
    let reach = (a * (1.0 / LEAST_WEIGHT - 1.0)).sqrt();
    let dirs = directions(rays);
    let frames: Vec<(DVec3, DVec3)> = cube.layers_iter().map(|l| (l.point, l.normal)).collect();
    let direct: Vec<DVec3> = frames
        .par_iter()
        .map(|&(p, n)| direct_irradiance(nf.lights, nf.maps, p, n))
        .collect();
    cube.set_layers(&direct, |l, e| l.direct = e);
    // Each sweep casts the rays again rather than keeping their hits: at 16 rays a layer those
    // would take about 70 bytes a ray (110 MB for the Cornell box's 114K layers), 30 times the
    // cube.
    let mut count = 0;
    for _ in 0..SWEEPS {
        let gathered: Vec<(DVec3, u64)> = frames
            .par_iter()
            .map(|&(p, n)| gather(cube, nf, p, n, &dirs, a, reach))
            .collect();
        count = gathered.iter().map(|g| g.1).sum();
        let near: Vec<DVec3> = gathered.iter().map(|g| g.0).collect();
        cube.set_layers(&near, |l, e| l.near = e);
    }
    let (vpl, near) = cube.layers_iter().fold((0.0, 0.0), |(v, n), l| {
        (v + l.irradiance.element_sum(), n + l.near.element_sum())
    });
    Restored {
        rays: frames.len() as u64 * rays as u64,
        hits: count,
        share: near / vpl.max(1e-300),
        ms: t.elapsed().as_secs_f64() * 1e3,
    }
}

/// The near field a layer at `p` (unit normal `n`) misses, from the light the cube holds where
/// its rays `dirs` (around +z) meet a surface's front within `reach`; and how many did.
fn gather(
    cube: &Cube,
    nf: &NearField<'_>,
    p: DVec3,
    n: DVec3,
    dirs: &[DVec3],
    a: f64,
    reach: f64,
) -> (DVec3, u64) {
    let (t1, t2) = basis(n);
    let o = p + n * nf.lift;
    let (mut sum, mut hits) = (DVec3::ZERO, 0);
    for d in dirs {
        let d = t1 * d.x + t2 * d.y + n * d.z;
        let Some(hit) = nf.caster.closest(o, d, 0.0, reach) else {
            continue;
        };
        let slot = hit.shape as usize;
        let ny = nf.surf.normal[slot];
        if d.dot(ny) >= 0.0 {
            continue;
        }
        let leaf = nf.surf.leaf[slot] as usize;
        let kd = nf.sys.materials[nf.sys.leaves[leaf].material as usize].kd;
        let e = cube.lookup(o + d * hit.t, ny, |l| l.direct + l.irradiance + l.near);
        sum += kd * e * (a / (hit.t * hit.t + a));
        hits += 1;
    }
    (sum / dirs.len() as f64, hits)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn directions_are_cosine_distributed() {
        // The mean of cos θ over the cosine-weighted hemisphere is 2/3; of cos² θ, 1/2.
        let d = directions(256);
        let m1 = d.iter().map(|d| d.z).sum::<f64>() / 256.0;
        let m2 = d.iter().map(|d| d.z * d.z).sum::<f64>() / 256.0;
        assert!((m1 - 2.0 / 3.0).abs() < 1e-3, "{m1}");
        assert!((m2 - 0.5).abs() < 1e-6, "{m2}");
        assert!(d
            .iter()
            .all(|d| (d.length() - 1.0).abs() < 1e-12 && d.z > 0.0));
        // Balanced around the axis.
        let xy: DVec3 = d.iter().map(|d| DVec3::new(d.x, d.y, 0.0)).sum();
        assert!(xy.length() / 256.0 < 0.01, "{xy}");
    }
}

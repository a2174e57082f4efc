//! The scene's BRDF: Lambertian `kd/π` plus the normalized modified-Phong lobe
//! `ks·(ns+2)/(2π)·cos^ns(α)`, α between the mirrored incident direction and the outgoing one.
//! Directions follow the travel convention: `incident` points from the light to the surface.

use glam::DVec3;
use std::f64::consts::PI;

/// Mirror of a travel direction about the plane with normal `n`.
pub fn mirror(incident: DVec3, n: DVec3) -> DVec3 {
    incident - 2.0 * incident.dot(n) * n
}

/// The Phong lobe value (per channel) for light travelling along `incident` and leaving along
/// `outgoing` (both unit, travel convention).
pub fn phong_lobe(ks: DVec3, ns: f64, n: DVec3, incident: DVec3, outgoing: DVec3) -> DVec3 {
    let c = mirror(incident, n).dot(outgoing);
    if c <= 0.0 {
        return DVec3::ZERO;
    }
    ks * ((ns + 2.0) / (2.0 * PI) * c.powf(ns))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lobe_peaks_at_mirror_direction_and_is_normalized() {
        let n = DVec3::Z;
        let inc = DVec3::new(1.0, 0.0, -1.0).normalize();
        let refl = DVec3::new(1.0, 0.0, 1.0).normalize();
        let peak = phong_lobe(DVec3::ONE, 20.0, n, inc, refl).x;
        assert!((peak - 22.0 / (2.0 * PI)).abs() < 1e-12);
        // ∫ cos^n(α) (n+2)/(2π) over the hemisphere around the mirror axis, times cos(θ) ≈ 1 at normal incidence.
        let inc = -DVec3::Z;
        let mut s = 0.0;
        let k = 400;
        for i in 0..k {
            for j in 0..4 * k {
                let th = (i as f64 + 0.5) / k as f64 * PI / 2.0;
                let ph = (j as f64 + 0.5) / (4 * k) as f64 * 2.0 * PI;
                let w = DVec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos());
                s += phong_lobe(DVec3::ONE, 20.0, n, inc, w).x
                    * th.cos()
                    * th.sin()
                    * (PI / 2.0 / k as f64)
                    * (2.0 * PI / (4 * k) as f64);
            }
        }
        assert!((s - 1.0).abs() < 0.01, "albedo at normal incidence {s}");
    }
}

//! Emitter edges: pixels that see an emitter take its emission from a dense grid of sub-pixel
//! rays instead of the frame's 2×2 samples. An emitter is often two orders of magnitude
//! brighter than what surrounds it, so a pixel 37% covered drawn as 50% is far off a
//! box-filtered reference; everything else in the pixel keeps the 2×2 samples.
//!
//! A pixel is an *edge pixel* when any 2×2 sample of it or of its 8 neighbours hits an emitting
//! triangle (front or back). Its emission is the mean over [`samples_per_axis`]² sub-pixel rays
//! (centers of a regular grid) of the `Ke` of the nearest emitting triangle each ray meets,
//! front faces only. Occlusion comes from the 2×2 sample of the sub-ray's quadrant: the sub-ray
//! is blocked when that sample hit a non-emitting surface nearer than the emitter by more than
//! [`OCCLUDER_MARGIN`] of the distance (so an occluder's own edge across an emitter is resolved
//! at the 2×2 samples only, and an emitter flush with a surface is not self-occluded). An
//! emitter narrower than about half a pixel that no sample of the 3×3 neighbourhood hits is not
//! seen (as before). The GPU's compose pass (`glsl/compose.frag`) does the same.

use crate::scene::Scene;
use glam::DVec3;

/// Sub-pixel rays per axis for an edge pixel when the scene has at most
/// [`MAX_DENSE_TRIANGLES`] emitting triangles (a coverage step of 1/1024).
pub const DENSE_SAMPLES: u32 = 32;
/// Sub-pixel rays per axis when the scene has more emitting triangles (each sub-ray tests every
/// one of them).
pub const SPARSE_SAMPLES: u32 = 8;
/// Emitting triangles up to which edge pixels use [`DENSE_SAMPLES`].
pub const MAX_DENSE_TRIANGLES: usize = 64;
/// An occluder must be this fraction of the distance nearer than the emitter to block it.
pub const OCCLUDER_MARGIN: f64 = 0.01;

/// The scene's emitting triangles (world space) and their `Ke`.
#[derive(Debug, Clone, Default)]
pub struct EmitterTriangles {
    /// Corners, counter-clockwise seen from the emitting side.
    pub corners: Vec<[DVec3; 3]>,
    /// Emitted radiance of each.
    pub ke: Vec<DVec3>,
}

/// What a frame sample's ray hit, for the occlusion of sub-pixel rays.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SampleHit {
    /// Nothing: the environment.
    Background,
    /// An emitting triangle (either side).
    Emitter,
    /// Another surface at this distance from the eye.
    Surface(f64),
}

impl EmitterTriangles {
    /// The emitting triangles of `scene` (`Ke` above zero in some channel).
    pub fn new(scene: &Scene) -> Self {
        let mut out = Self::default();
        for m in &scene.meshes {
            for (t, &mi) in m.triangles.iter().zip(&m.material) {
                let ke = scene.materials[mi as usize].ke;
                if ke.max_element() > 0.0 {
                    out.corners.push(t.map(|v| m.positions[v as usize]));
                    out.ke.push(ke);
                }
            }
        }
        out
    }

    /// Sub-pixel rays per axis of an edge pixel.
    pub fn samples_per_axis(&self) -> u32 {
        if self.corners.len() <= MAX_DENSE_TRIANGLES {
            DENSE_SAMPLES
        } else {
            SPARSE_SAMPLES
        }
    }

    /// The nearest emitting triangle along the ray `o + t·d` (`d` unit): its distance, whether
    /// the ray meets its front, and its `Ke`.
    pub fn nearest(&self, o: DVec3, d: DVec3) -> Option<(f64, bool, DVec3)> {
        let mut best: Option<(f64, bool, DVec3)> = None;
        for (c, ke) in self.corners.iter().zip(&self.ke) {
            // Möller–Trumbore, both sides.
            let (e1, e2) = (c[1] - c[0], c[2] - c[0]);
            let p = d.cross(e2);
            let det = e1.dot(p);
            if det.abs() < 1e-300 {
                continue;
            }
            let inv = 1.0 / det;
            let s = o - c[0];
            let u = s.dot(p) * inv;
            if !(0.0..=1.0).contains(&u) {
                continue;
            }
            let q = s.cross(e1);
            let v = d.dot(q) * inv;
            if v < 0.0 || u + v > 1.0 {
                continue;
            }
            let t = e2.dot(q) * inv;
            if t > 0.0 && best.is_none_or(|b| t < b.0) {
                best = Some((t, e1.cross(e2).dot(d) < 0.0, *ke));
            }
        }
        best
    }

    /// Emission of the edge pixel `(px, py)`: the mean over the sub-pixel grid of the front
    /// emitters the sub-rays meet, unless the 2×2 sample of their quadrant (`quadrant(sx, sy)`,
    /// `sx, sy` ∈ {0, 1}) saw a nearer surface. `ray(x, y)` is the unit camera ray through
    /// framebuffer position `(x, y)`.
    pub fn edge_emission(
        &self,
        eye: DVec3,
        ray: impl Fn(f64, f64) -> DVec3,
        px: u32,
        py: u32,
        quadrant: impl Fn(usize, usize) -> SampleHit,
    ) -> DVec3 {
        let e = self.samples_per_axis();
        let mut sum = DVec3::ZERO;
        for j in 0..e {
            for i in 0..e {
                let (fx, fy) = ((i as f64 + 0.5) / e as f64, (j as f64 + 0.5) / e as f64);
                let d = ray(px as f64 + fx, py as f64 + fy);
                let Some((t, front, ke)) = self.nearest(eye, d) else {
                    continue;
                };
                let blocked = match quadrant((2 * i / e) as usize, (2 * j / e) as usize) {
                    SampleHit::Surface(dist) => dist < t * (1.0 - OCCLUDER_MARGIN),
                    _ => false,
                };
                if front && !blocked {
                    sum += ke;
                }
            }
        }
        sum / (e * e) as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_half_covered_pixel_gets_half_the_emission() {
        // A square emitter facing +z whose left edge (x = 0) splits a pixel in two; the
        // orthographic-like ray keeps the coverage exactly the fraction of sub-rays.
        let t = EmitterTriangles {
            corners: vec![
                [
                    DVec3::new(0.0, -1.0, 0.0),
                    DVec3::new(1.0, -1.0, 0.0),
                    DVec3::new(1.0, 1.0, 0.0),
                ],
                [
                    DVec3::new(0.0, -1.0, 0.0),
                    DVec3::new(1.0, 1.0, 0.0),
                    DVec3::new(0.0, 1.0, 0.0),
                ],
            ],
            ke: vec![DVec3::splat(4.0); 2],
        };
        let eye = DVec3::new(0.0, 0.0, 5.0);
        // Pixel (0, 0) spans x ∈ [−0.5, 0.5] at the emitter's plane (rays from far away).
        let ray = |x: f64, y: f64| (DVec3::new(x - 0.5, y - 0.5, 0.0) - eye).normalize();
        let e = t.edge_emission(eye, ray, 0, 0, |_, _| SampleHit::Emitter);
        assert!((e.x - 2.0).abs() < 1e-12, "{e}");
        // Seen from behind: nothing (one-sided).
        let back = DVec3::new(0.0, 0.0, -5.0);
        let ray = |x: f64, y: f64| (DVec3::new(x - 0.5, y - 0.5, 0.0) - back).normalize();
        assert_eq!(
            t.edge_emission(back, ray, 0, 0, |_, _| SampleHit::Emitter),
            DVec3::ZERO
        );
        // A nearer surface in the left quadrants blocks those sub-rays, a farther one does not.
        let ray = |x: f64, y: f64| (DVec3::new(x - 0.5, y - 0.5, 0.0) - eye).normalize();
        let near = |sx: usize, _| {
            if sx == 0 {
                SampleHit::Surface(1.0)
            } else {
                SampleHit::Surface(9.0)
            }
        };
        let e = t.edge_emission(eye, ray, 0, 0, near);
        assert!((e.x - 2.0).abs() < 1e-12, "{e}");
        let e = t.edge_emission(eye, ray, 0, 0, |_, _| SampleHit::Surface(1.0));
        assert_eq!(e, DVec3::ZERO);
    }
}

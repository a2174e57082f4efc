//! Shadow maps for the analytic lights (§3.3): one orthographic view for a directional light,
//! one perspective view for a spot light with a cut-off below 75°, six cube faces otherwise.
//! A map stores the *linear* distance to the nearest surface at each texel center (from the light
//! for perspective views, from the near plane for orthographic ones), so the GPU (rasterized,
//! `glsl/shadow.frag`) and the CPU (ray cast at texel centers) build the same map, and one
//! filtered lookup (`visibility`, mirrored in `glsl/frame.glsl`) serves leaves and pixels.

use crate::raycast::RayCaster;
use crate::scene::{Light, Scene};
use glam::{DMat4, DVec3, DVec4};
use rayon::prelude::*;

/// Value of a texel that sees no surface.
pub const EMPTY: f32 = 3.0e38;
/// Receiver offset along its normal, in texels (at the receiver's distance).
pub const NORMAL_OFFSET: f64 = 1.5;
/// Constant depth bias, in texels.
pub const CONSTANT_BIAS: f64 = 1.0;
/// Slope-scaled bias, in texels per unit of tan(θ) (θ between normal and light), capped at 8.
pub const SLOPE_BIAS: f64 = 1.5;
/// Radius (texels) of the tent filter of the percentage-closer lookup.
pub const FILTER_RADIUS: f64 = 1.5;
/// Spot lights wider than this use a cube map.
const SPOT_SINGLE_VIEW_MAX_DEG: f64 = 75.0;

/// One rendered view of a light.
#[derive(Debug, Clone, PartialEq)]
pub struct ShadowView {
    /// World → Vulkan clip space (x right, y down, reversed depth 1..0).
    pub view_proj: DMat4,
    /// Light position (perspective) or a point on the near plane (orthographic).
    pub origin: DVec3,
    /// Unit view axis.
    pub forward: DVec3,
    /// Unit image right.
    pub right: DVec3,
    /// Unit image up.
    pub up: DVec3,
    /// `tan(fov/2)` (perspective) or half the side of the square (orthographic).
    pub half: f64,
    /// Orthographic (directional light) rather than perspective.
    pub ortho: bool,
}

impl ShadowView {
    fn perspective(origin: DVec3, forward: DVec3, half_angle: f64, near: f64, far: f64) -> Self {
        let helper = if forward.y.abs() < 0.9 {
            DVec3::Y
        } else {
            DVec3::Z
        };
        let right = forward.cross(helper).normalize();
        let up = right.cross(forward);
        let half = half_angle.tan();
        let view = basis(origin, forward, right, up);
        let proj = super::camera::reversed_perspective(1.0 / half, 1.0 / half, near, far);
        Self {
            view_proj: proj * view,
            origin,
            forward,
            right,
            up,
            half,
            ortho: false,
        }
    }

    /// Unit ray (origin, direction) through the center of texel (i, j) of a `size`² map.
    pub fn texel_ray(&self, i: u32, j: u32, size: u32) -> (DVec3, DVec3) {
        let x = (i as f64 + 0.5) / size as f64 * 2.0 - 1.0;
        let y = (j as f64 + 0.5) / size as f64 * 2.0 - 1.0;
        if self.ortho {
            let o = self.origin + self.right * (x * self.half) - self.up * (y * self.half);
            (o, self.forward)
        } else {
            let d = self.forward + self.right * (x * self.half) - self.up * (y * self.half);
            (self.origin, d.normalize())
        }
    }

    /// The linear distance the map stores for a surface point `p`.
    pub fn distance(&self, p: DVec3) -> f64 {
        if self.ortho {
            (p - self.origin).dot(self.forward)
        } else {
            (p - self.origin).length()
        }
    }

    /// World size of one texel at `p`.
    pub fn texel_size(&self, p: DVec3, size: u32) -> f64 {
        let scale = if self.ortho {
            1.0
        } else {
            (p - self.origin).length()
        };
        2.0 * self.half * scale / size as f64
    }
}

/// World → view matrix for camera space x right, y down, z forward.
fn basis(o: DVec3, f: DVec3, r: DVec3, u: DVec3) -> DMat4 {
    DMat4::from_cols(
        DVec4::new(r.x, -u.x, f.x, 0.0),
        DVec4::new(r.y, -u.y, f.y, 0.0),
        DVec4::new(r.z, -u.z, f.z, 0.0),
        DVec4::new(-r.dot(o), u.dot(o), -f.dot(o), 1.0),
    )
}

/// Cube faces in the order the lookup selects them: +X, −X, +Y, −Y, +Z, −Z.
const CUBE: [DVec3; 6] = [
    DVec3::X,
    DVec3::NEG_X,
    DVec3::Y,
    DVec3::NEG_Y,
    DVec3::Z,
    DVec3::NEG_Z,
];

/// Cube face of direction `v` (major axis), as indexed in [`CUBE`].
pub fn cube_face(v: DVec3) -> usize {
    let a = v.abs();
    if a.x >= a.y && a.x >= a.z {
        (v.x < 0.0) as usize
    } else if a.y >= a.z {
        2 + (v.y < 0.0) as usize
    } else {
        4 + (v.z < 0.0) as usize
    }
}

/// The shadow maps of every light of a scene.
#[derive(Debug, Clone)]
pub struct ShadowMaps {
    /// Side of every map, texels.
    pub size: u32,
    /// All views, lights in order.
    pub views: Vec<ShadowView>,
    /// First view and view count (1 or 6) per light.
    pub light_views: Vec<(u32, u32)>,
    /// Distances, view after view, row-major (`views.len() × size × size`); empty until rendered.
    pub data: Vec<f32>,
}

impl ShadowMaps {
    /// The views for `scene`'s lights, fitted to its bounds (no map data yet).
    pub fn new(scene: &Scene, size: u32) -> Self {
        let (lo, hi) = scene.bounds();
        let (center, radius) = ((lo + hi) * 0.5, ((hi - lo).length() * 0.5).max(1e-6));
        let mut views = Vec::new();
        let mut light_views = Vec::new();
        for light in &scene.lights {
            let first = views.len() as u32;
            match light {
                Light::Directional { direction, .. } => {
                    let f = *direction;
                    let helper = if f.y.abs() < 0.9 { DVec3::Y } else { DVec3::Z };
                    let r = f.cross(helper).normalize();
                    let u = r.cross(f);
                    let half = radius * 1.02;
                    let origin = center - f * (radius * 1.02);
                    let depth = 2.0 * radius * 1.02;
                    let view = basis(origin, f, r, u);
                    let proj = DMat4::from_cols(
                        DVec4::new(1.0 / half, 0.0, 0.0, 0.0),
                        DVec4::new(0.0, 1.0 / half, 0.0, 0.0),
                        DVec4::new(0.0, 0.0, -1.0 / depth, 0.0),
                        DVec4::new(0.0, 0.0, 1.0, 1.0),
                    );
                    views.push(ShadowView {
                        view_proj: proj * view,
                        origin,
                        forward: f,
                        right: r,
                        up: u,
                        half,
                        ortho: true,
                    });
                }
                Light::Point { position, .. } | Light::Spot { position, .. } => {
                    let far = (*position - center).length() + radius * 1.02;
                    let near = (far * 1e-5).max(1e-7);
                    match light {
                        Light::Spot { axis, cutoff, .. }
                            if cutoff.to_degrees() < SPOT_SINGLE_VIEW_MAX_DEG =>
                        {
                            let half = (cutoff * 1.05 + 0.01).min(80f64.to_radians());
                            views.push(ShadowView::perspective(*position, *axis, half, near, far));
                        }
                        _ => {
                            for f in CUBE {
                                views.push(ShadowView::perspective(
                                    *position,
                                    f,
                                    std::f64::consts::FRAC_PI_4,
                                    near,
                                    far,
                                ));
                            }
                        }
                    }
                }
            }
            light_views.push((first, views.len() as u32 - first));
        }
        Self {
            size,
            views,
            light_views,
            data: Vec::new(),
        }
    }

    /// Fills the maps by casting a ray through every texel center (the CPU backend).
    pub fn render_cpu(&mut self, caster: &RayCaster) {
        let s = self.size as usize;
        let mut data = vec![EMPTY; self.views.len() * s * s];
        data.par_chunks_mut(s).enumerate().for_each(|(row, out)| {
            let (v, j) = (row / s, (row % s) as u32);
            let view = &self.views[v];
            for (i, o) in out.iter_mut().enumerate() {
                let (org, dir) = view.texel_ray(i as u32, j, self.size);
                if let Some(h) = caster.closest(org, dir, 0.0, f64::INFINITY) {
                    *o = view.distance(org + dir * h.t) as f32;
                }
            }
        });
        self.data = data;
    }

    /// The view of light `light` that covers point `p`.
    pub fn view_for(&self, light: usize, p: DVec3) -> usize {
        let (first, count) = self.light_views[light];
        if count == 6 {
            first as usize + cube_face(p - self.views[first as usize].origin)
        } else {
            first as usize
        }
    }

    /// Filtered fraction of light `light` reaching `p`, a surface point with unit normal `n`
    /// facing the light, where `cos` is the cosine between `n` and the direction to the light.
    pub fn visibility(&self, light: usize, p: DVec3, n: DVec3, cos: f64) -> f64 {
        if self.data.is_empty() {
            return 1.0;
        }
        let vi = self.view_for(light, p);
        let view = &self.views[vi];
        let s = self.size as i64;
        let texel = view.texel_size(p, self.size);
        let q = p + n * (NORMAL_OFFSET * texel);
        let c = view.view_proj * q.extend(1.0);
        let (x, y) = (c.x / c.w, c.y / c.w);
        let tx = (x + 1.0) * 0.5 * s as f64 - 0.5;
        let ty = (y + 1.0) * 0.5 * s as f64 - 0.5;
        let tan = ((1.0 - cos * cos).max(0.0).sqrt() / cos.max(1e-6)).min(8.0);
        let d = view.distance(q) - texel * (CONSTANT_BIAS + SLOPE_BIAS * tan);
        let base = &self.data[vi * (s * s) as usize..(vi + 1) * (s * s) as usize];
        let (mut lit, mut total) = (0.0, 0.0);
        let (x0, y0) = (
            (tx - FILTER_RADIUS).floor() as i64 + 1,
            (ty - FILTER_RADIUS).floor() as i64 + 1,
        );
        for ky in y0..y0 + 3 {
            let wy = (1.0 - (ky as f64 - ty).abs() / FILTER_RADIUS).max(0.0);
            for kx in x0..x0 + 3 {
                let wx = (1.0 - (kx as f64 - tx).abs() / FILTER_RADIUS).max(0.0);
                let w = wx * wy;
                let texel = base[(ky.clamp(0, s - 1) * s + kx.clamp(0, s - 1)) as usize];
                total += w;
                if d <= texel as f64 {
                    lit += w;
                }
            }
        }
        if total > 0.0 {
            lit / total
        } else {
            1.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn glsl_uses_the_same_constants() {
        let glsl = include_str!("../../glsl/frame.glsl");
        for (name, v) in [
            ("NORMAL_OFFSET", NORMAL_OFFSET),
            ("CONSTANT_BIAS", CONSTANT_BIAS),
            ("SLOPE_BIAS", SLOPE_BIAS),
            ("FILTER_RADIUS", FILTER_RADIUS),
        ] {
            let line = format!("const float AR_SHADOW_{name} = {v:?};");
            assert!(glsl.contains(&line), "frame.glsl lacks `{line}`");
        }
        let mode = format!(
            "const uint AR_MODE_VERTEX = {}u;",
            crate::frame::surfaces::MODE_VERTEX
        );
        assert!(glsl.contains(&mode), "frame.glsl lacks `{mode}`");
        let gbuffer = include_str!("../../glsl/gbuffer.vert");
        let filler = format!("const uint AR_FILLER = {:#x}u;", crate::gpu::pack::FILLER);
        assert!(gbuffer.contains(&filler), "gbuffer.vert lacks `{filler}`");
    }

    #[test]
    fn texel_rays_project_to_their_texels() {
        let mut scene = Scene::empty();
        let m = scene.add_material(crate::scene::Material::diffuse("w", 0.5));
        scene.add_mesh(
            "t",
            vec![
                DVec3::ZERO,
                DVec3::new(2.0, 0.0, 0.0),
                DVec3::new(0.0, 0.0, 2.0),
            ],
            vec![[0, 2, 1]],
            m,
        );
        scene.lights.push(Light::Directional {
            direction: DVec3::new(0.3, -1.0, 0.2).normalize(),
            irradiance: DVec3::ONE,
        });
        scene.lights.push(Light::Point {
            position: DVec3::new(0.5, 1.0, 0.5),
            intensity: DVec3::ONE,
        });
        let maps = ShadowMaps::new(&scene, 16);
        assert_eq!(maps.light_views, vec![(0, 1), (1, 6)]);
        for v in &maps.views {
            for (i, j) in [(0, 0), (5, 9), (15, 15)] {
                let (o, d) = v.texel_ray(i, j, 16);
                let p = o + d * 0.7;
                let c = v.view_proj * p.extend(1.0);
                let tx = (c.x / c.w + 1.0) * 8.0 - 0.5;
                let ty = (c.y / c.w + 1.0) * 8.0 - 0.5;
                assert!((tx - i as f64).abs() < 1e-9 && (ty - j as f64).abs() < 1e-9);
                assert!((0.0..=1.0).contains(&(c.z / c.w)));
            }
        }
        // Every cube face covers the directions whose major axis it is.
        let d = DVec3::new(0.2, -0.9, 0.3);
        let f = cube_face(d);
        assert_eq!(f, 3);
        let c = maps.views[1 + f].view_proj * (maps.views[1].origin + d).extend(1.0);
        assert!((c.x / c.w).abs() <= 1.0 && (c.y / c.w).abs() <= 1.0);
    }
}

//! The scene's pinhole camera as rays (CPU frame) and as a view-projection matrix (GPU frame).
//! Both agree on the convention of the scene format: pixel (0,0) is the top-left corner, image
//! right is `forward × up`, `fov_y_deg` spans the image height.

use crate::scene::Camera;
use glam::{DMat4, DVec3, DVec4};

/// Supersampling per axis: the frame is rendered at 2×2 samples per pixel (4× anti-aliasing),
/// at sample positions (0.25, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75) within the pixel.
pub const SUPERSAMPLE: u32 = 2;

/// Orthonormal camera frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct View {
    /// Eye position.
    pub eye: DVec3,
    /// Unit viewing direction.
    pub forward: DVec3,
    /// Unit image-right direction.
    pub right: DVec3,
    /// Unit image-up direction.
    pub up: DVec3,
    /// `tan(fov_y / 2)`.
    pub tan_half: f64,
    /// Width / height.
    pub aspect: f64,
    /// Image size in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// The camera's [`Camera::jitter`]: the image shifted by it (pixels).
    pub jitter: [f64; 2],
}

impl View {
    /// The frame of `cam`, at the camera's own resolution.
    pub fn new(cam: &Camera) -> Self {
        let forward = (cam.target - cam.eye).normalize();
        let right = forward.cross(cam.up).normalize();
        let up = right.cross(forward);
        Self {
            eye: cam.eye,
            forward,
            right,
            up,
            tan_half: (cam.fov_y_deg.to_radians() * 0.5).tan(),
            aspect: cam.width as f64 / cam.height as f64,
            width: cam.width,
            height: cam.height,
            jitter: cam.jitter,
        }
    }

    /// Unit direction through image position (`x`, `y`) in pixels (continuous; 0,0 = top-left).
    pub fn ray(&self, x: f64, y: f64) -> DVec3 {
        let (x, y) = (x + self.jitter[0], y + self.jitter[1]);
        let sx = (2.0 * x / self.width as f64 - 1.0) * self.tan_half * self.aspect;
        let sy = (1.0 - 2.0 * y / self.height as f64) * self.tan_half;
        (self.forward + self.right * sx + self.up * sy).normalize()
    }

    /// World → Vulkan clip space (x right, y down, reversed depth: 1 at `near`, 0 at `far`, for
    /// float depth precision), matching [`View::ray`]: a point on the ray through (x, y) lands on
    /// framebuffer position (x, y).
    pub fn view_proj(&self, near: f64, far: f64) -> DMat4 {
        let (r, u, f) = (self.right, self.up, self.forward);
        // Camera space: x right, y down, z forward (depth).
        let view = DMat4::from_cols(
            DVec4::new(r.x, -u.x, f.x, 0.0),
            DVec4::new(r.y, -u.y, f.y, 0.0),
            DVec4::new(r.z, -u.z, f.z, 0.0),
            DVec4::new(-r.dot(self.eye), u.dot(self.eye), -f.dot(self.eye), 1.0),
        );
        let (sx, sy) = (1.0 / (self.tan_half * self.aspect), 1.0 / self.tan_half);
        let proj = reversed_perspective(sx, sy, near, far);
        // The jitter moves what framebuffer position (x, y) shows to image position (x, y) +
        // jitter: clip x and y shift by −2·jitter/size times w.
        let (jx, jy) = (
            -2.0 * self.jitter[0] / self.width as f64,
            -2.0 * self.jitter[1] / self.height as f64,
        );
        let shift = DMat4::from_cols(DVec4::X, DVec4::Y, DVec4::Z, DVec4::new(jx, jy, 0.0, 1.0));
        shift * proj * view
    }
}

/// Perspective projection with reversed depth (1 at `near`, 0 at `far`), camera looking down +z.
pub fn reversed_perspective(sx: f64, sy: f64, near: f64, far: f64) -> DMat4 {
    let a = near / (far - near);
    DMat4::from_cols(
        DVec4::new(sx, 0.0, 0.0, 0.0),
        DVec4::new(0.0, sy, 0.0, 0.0),
        DVec4::new(0.0, 0.0, -a, 1.0),
        DVec4::new(0.0, 0.0, a * far, 0.0),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn projection_matches_rays() {
        let cam = Camera {
            eye: DVec3::new(0.3, 1.0, 4.0),
            target: DVec3::new(0.0, 0.8, 0.0),
            up: DVec3::Y,
            fov_y_deg: 40.0,
            width: 64,
            height: 48,
            supersample: 1,
            jitter: [0.0; 2],
            passes: 1,
            fov_axis: Default::default(),
        };
        for jitter in [[0.0; 2], [0.375, -0.125]] {
            check(&Camera {
                jitter,
                ..cam.clone()
            });
        }
        let v = View::new(&cam);
        // Image right is forward × up; top row looks up.
        assert!(v.ray(64.0, 24.0).dot(v.right) > 0.0);
        assert!(v.ray(32.0, 0.0).y > v.ray(32.0, 48.0).y);
        // A jitter shifts the image: (x, y) of the shifted view looks where (x + jx, y + jy) did.
        let j = View::new(&Camera {
            jitter: [0.375, -0.125],
            ..cam.clone()
        });
        assert!((j.ray(10.0, 3.0) - v.ray(10.375, 2.875)).length() < 1e-12);
    }

    fn check(cam: &Camera) {
        let v = View::new(cam);
        let m = v.view_proj(0.01, 100.0);
        for (x, y) in [(0.0, 0.0), (10.5, 3.25), (64.0, 48.0), (32.0, 24.0)] {
            let p = v.eye + v.ray(x, y) * 3.0;
            let c = m * p.extend(1.0);
            let ndc = c.truncate() / c.w;
            let (fx, fy) = ((ndc.x + 1.0) * 32.0, (ndc.y + 1.0) * 24.0);
            assert!(
                (fx - x).abs() < 1e-9 && (fy - y).abs() < 1e-9,
                "{x},{y} -> {fx},{fy}"
            );
            assert!(ndc.z > 0.0 && ndc.z < 1.0);
            let nearer = m * (v.eye + v.ray(x, y) * 2.0).extend(1.0);
            assert!(nearer.z / nearer.w > ndc.z, "reversed depth");
        }
    }
}

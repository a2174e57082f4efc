//! The frame's push constants (`glsl/common.glsl` FrameConstants) for a camera over a scene.

use super::super::layout::FrameConstants;
use super::super::pack::mat;
use crate::frame::camera::{View, SUPERSAMPLE};
use crate::scene::{Camera, Scene};
use crate::system::System;

/// The frame's push constants for `camera` over `scene` (its bounds set the depth range), the
/// lights `shared` shared by blocks of `block` pixels per side.
pub(super) fn constants(
    scene: &Scene,
    lights: usize,
    (shared, block): ((usize, usize), u32),
    camera: &Camera,
    sys: &System,
) -> FrameConstants {
    let view = View::new(camera);
    let (lo, hi) = scene.bounds();
    let far = ((lo + hi) * 0.5 - view.eye).length() + (hi - lo).length() + 1e-6;
    let env = scene.environment;
    let grid = sys.bins.nu as u32 | (sys.bins.nv as u32) << 16;
    FrameConstants {
        view_proj: mat(view.view_proj(far * 1e-5, far)),
        eye: [view.eye.x as f32, view.eye.y as f32, view.eye.z as f32, 1.0],
        environment: [env.x as f32, env.y as f32, env.z as f32, 1.0],
        sizes: [
            camera.width * SUPERSAMPLE,
            camera.height * SUPERSAMPLE,
            grid,
            0,
        ],
        // y: the shadow pass's view (shadow.rs); for compose, y..z the lights whose direct
        // light a pixel's samples share; w: the supersampling, and the direct light's block
        // (`frame::direct`) above it.
        misc: [
            lights as u32,
            shared.0 as u32,
            shared.1 as u32,
            SUPERSAMPLE | block << 8,
        ],
    }
}

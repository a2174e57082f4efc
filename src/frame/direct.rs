//! The area emitters' direct light shared across pixels. A pixel whose 2×2 samples lie on one
//! flat surface evaluates it once, at their mean (`cpu.rs shared_direct`); with blocks of
//! `solver.direct_block` pixels per side, only each block's corner pixel does (a full-screen
//! pass at the blocks' resolution on the GPU, `glsl/direct_blocks.frag`), and every other pixel
//! interpolates between the corners around it ([`block_direct`]: bilinearly, perspective-correct
//! on their surface, so linearly in the world as a plane's attributes are) where all of them
//! lie on its surface, of its material, and agree within [`SPREAD`]; elsewhere (a surface's edge
//! in the image, a penumbra or a contact shadow sharper than a block) it evaluates its own. That
//! light is a penumbra of 32 shadow-mapped emitter samples, each filtered over 3×3 texels:
//! smooth over a few pixels where it is not refined, and it is most of the frame's cost.
//! The same rules as glsl/compose.frag ar_block_direct.

use glam::DVec3;

/// Frames of at least this many pixels share the direct light in blocks of 2 unless
/// `solver.direct_block` says otherwise: there the compose pass's cost matters, and a block's
/// footprint on a surface is small enough that interpolating across it is exact to ~1e-3
/// (tests/frame.rs). On small frames a block spans so much of a surface that a smooth peak
/// between two corners is missed by a few percent (the closed-form plane under a square emitter
/// at 48²: 2.9% at a pixel, tests/emitters.rs), and the frame is cheap anyway.
pub const MIN_BLOCK_PIXELS: u64 = 250_000;

/// The blocks' side a `width × height` frame uses: 1 (no blocks) where it shares no light's
/// direct light (`shared` empty), else `setting`, or where none is set 2 on frames of at least
/// [`MIN_BLOCK_PIXELS`] pixels and 1 on smaller ones.
pub fn block_for(
    setting: Option<u32>,
    shared: &std::ops::Range<usize>,
    (width, height): (u32, u32),
) -> u32 {
    if shared.is_empty() {
        return 1;
    }
    match setting {
        Some(b) => b.max(1),
        None if width as u64 * height as u64 >= MIN_BLOCK_PIXELS => 2,
        None => 1,
    }
}

/// What a pixel's shared direct light may be interpolated across: the flat surface and the
/// material of its first sample's face slot, and the slot itself where shading normals
/// interpolate over it (`u32::MAX` where not); equal keys interpolate.
pub type Key = (u32, u32, u32);

/// The blocks' grid for an image of `width × height` pixels at `block` pixels per side: one
/// block per corner pixel `(block·i, block·j)` inside the image.
pub fn grid(width: usize, height: usize, block: usize) -> (usize, usize) {
    (width.div_ceil(block), height.div_ceil(block))
}

/// Largest spread of the corners' light (max − min of r + g + b, over the max) that a pixel
/// interpolates; beyond, the light changes faster than the blocks sample it and the pixel
/// evaluates its own.
pub const SPREAD: f64 = 0.1;

/// A block's corner pixel: the key and light of its samples' shared direct light, and the
/// inverse of their mean's depth along the view axis (the perspective-correct weight).
pub type Corner = (Key, DVec3, f64);

/// The shared direct light of pixel `(px, py)`, of key `key`, interpolated bilinearly and
/// perspective-correct between the corners of the blocks around it with a weight:
/// `corner(i, j)` is block `(i, j)`'s ([`Corner`]; `None`: it shares none, or `(i, j)` is off
/// the grid). `None` (the pixel evaluates its own) unless every one of them has the pixel's key
/// and their lights agree within [`SPREAD`]. A corner pixel takes its own block's light.
pub fn block_direct(
    (px, py): (usize, usize),
    block: usize,
    key: Key,
    corner: impl Fn(usize, usize) -> Option<Corner>,
) -> Option<DVec3> {
    let (bx, by) = (px / block, py / block);
    let fx = (px - bx * block) as f64 / block as f64;
    let fy = (py - by * block) as f64 / block as f64;
    let (mut acc, mut wsum, mut lo, mut hi) = (DVec3::ZERO, 0.0, f64::INFINITY, 0f64);
    for (cx, cy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
        let w = if cx == 1 { fx } else { 1.0 - fx } * if cy == 1 { fy } else { 1.0 - fy };
        if w > 0.0 {
            let (k, v, inv_depth) = corner(bx + cx, by + cy)?;
            if k != key {
                return None;
            }
            acc += v * (w * inv_depth);
            wsum += w * inv_depth;
            let s = v.element_sum();
            (lo, hi) = (lo.min(s), hi.max(s));
        }
    }
    (hi - lo <= SPREAD * hi && wsum > 0.0).then(|| acc / wsum)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pixel_interpolates_the_corners_on_its_surface_and_a_corner_keeps_its_own() {
        let (a, b) = ((1, 0, u32::MAX), (2, 0, u32::MAX));
        // Blocks of 2: corners (0, 0) and (1, 0) on surface 1, (0, 1) on surface 2.
        let corner = |i: usize, j: usize| match (i, j) {
            (0, 0) => Some((a, DVec3::splat(1.0), 1.0)),
            (1, 0) => Some((a, DVec3::splat(3.0), 1.0)),
            (0, 1) => Some((b, DVec3::splat(5.0), 1.0)),
            _ => None,
        };
        let at = |p, key| block_direct(p, 2, key, corner);
        // A corner pixel keeps its own, whatever the others.
        assert_eq!(at((0, 0), a), Some(DVec3::splat(1.0)));
        assert_eq!(at((2, 0), a), Some(DVec3::splat(3.0)));
        assert_eq!(at((0, 2), b), Some(DVec3::splat(5.0)));
        // Corners 1 and 3 differ by far more than SPREAD: (1, 0) evaluates its own.
        assert_eq!(at((1, 0), a), None);
        // (1, 1): two of its four corners are on surface 2 or off the grid: its own.
        assert_eq!(at((1, 1), a), None);
        assert_eq!(at((1, 1), b), None);
        // Another material, or a shaded slot, on the same surface does not interpolate.
        assert_eq!(at((1, 0), (1, 1, u32::MAX)), None);
        assert_eq!(at((1, 0), (1, 0, 7)), None);
        // Corners within SPREAD: bilinear.
        let close = |i: usize, j: usize| {
            (i < 2 && j < 2).then(|| (a, DVec3::splat(1.0 + 0.01 * (i + 2 * j) as f64), 1.0))
        };
        let v = block_direct((1, 1), 2, a, close).unwrap();
        assert!((v - DVec3::splat(1.015)).abs().max_element() < 1e-12);
        let v = block_direct((1, 0), 2, a, close).unwrap();
        assert!((v - DVec3::splat(1.005)).abs().max_element() < 1e-12);
        // A spread just beyond SPREAD of the largest is refined.
        let far = |i: usize, j: usize| {
            let s = if i == 1 { 1.0 - SPREAD * 1.01 } else { 1.0 };
            (i < 2 && j < 2).then_some((a, DVec3::splat(s), 1.0))
        };
        assert_eq!(block_direct((1, 0), 2, a, far), None);
        // Perspective-correct: halfway on screen between a corner at depth 1 and one at depth 3
        // is a quarter of the way along the plane (weights 1/1 and 1/3): 1 + 0.25 × 0.04.
        let deep = |i: usize, j: usize| {
            (i < 2 && j == 0).then(|| {
                (
                    a,
                    DVec3::splat(1.0 + 0.04 * i as f64),
                    1.0 / (1.0 + 2.0 * i as f64),
                )
            })
        };
        let v = block_direct((1, 0), 2, a, deep).unwrap();
        assert!((v - DVec3::splat(1.01)).abs().max_element() < 1e-12);
    }

    #[test]
    fn blocks_of_two_by_default_on_large_frames_only() {
        let (some, none) = (0..32, 0..0);
        assert_eq!(block_for(None, &some, (512, 512)), 2);
        assert_eq!(block_for(None, &some, (640, 400)), 2);
        assert_eq!(block_for(None, &some, (480, 360)), 1);
        assert_eq!(block_for(Some(4), &some, (48, 48)), 4);
        assert_eq!(block_for(Some(1), &some, (1024, 1024)), 1);
        assert_eq!(block_for(Some(4), &none, (1024, 1024)), 1);
    }

    #[test]
    fn the_grid_has_a_block_for_every_corner_pixel_inside_the_image() {
        assert_eq!(grid(512, 512, 2), (256, 256));
        assert_eq!(grid(97, 33, 2), (49, 17));
        assert_eq!(grid(9, 4, 4), (3, 1));
        assert_eq!(grid(5, 5, 1), (5, 5));
        for (w, b) in [(97usize, 2usize), (9, 4), (10, 4), (512, 8)] {
            let (g, _) = grid(w, 1, b);
            assert!(b * (g - 1) < w && b * g >= w);
        }
    }
}

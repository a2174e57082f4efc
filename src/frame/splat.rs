//! Splatted indirect light on screen (§4.3): the normalized sum of the leaves' kernels on one
//! flat surface. The GPU draws the sums once per pixel, at the pixel's first 2×2 sample (a
//! quarter of the fragments of a sum per sample); each sample interpolates bilinearly between
//! the sums of the first samples around it that lie on its flat surface ([`pixel_sum`]), takes a
//! neighbouring pixel's where none does, and where there is none (a sliver of a surface) its
//! own leaf's radiance, unsplatted. `solver.splat_per_sample` draws a sum per sample instead.
//! The same rules as glsl/splat.frag and glsl/compose.frag.

use super::surfaces::{display_radiance_in, splat_weight, Surfaces};
use crate::solver::Table;
use crate::system::System;
use glam::DVec3;
use std::collections::HashMap;

/// The pixels whose sums a sample on another surface than its pixel's first sample tries, in
/// order (glsl/compose.frag ar_splat_neighbour).
pub const NEIGHBOURS: [(i64, i64); 8] = [
    (1, 0),
    (0, 1),
    (-1, 0),
    (0, -1),
    (1, 1),
    (-1, 1),
    (1, -1),
    (-1, -1),
];

/// Splatted element centers hashed on a grid of the largest splat radius.
pub struct SplatGrid {
    cell: f64,
    cells: HashMap<(i64, i64, i64), Vec<u32>>,
}

impl SplatGrid {
    /// The grid of `surf`'s splatted slots.
    pub fn new(surf: &Surfaces) -> Self {
        let cell = surf.max_radius.max(1e-12);
        let mut cells: HashMap<_, Vec<u32>> = HashMap::new();
        for li in surf.splat_slots() {
            let k = (surf.center[li as usize] / cell).floor();
            cells
                .entry((k.x as i64, k.y as i64, k.z as i64))
                .or_default()
                .push(li);
        }
        Self { cell, cells }
    }

    fn near(&self, p: DVec3, mut f: impl FnMut(u32)) {
        let k = (p / self.cell).floor();
        let (x, y, z) = (k.x as i64, k.y as i64, k.z as i64);
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    if let Some(v) = self.cells.get(&(x + dx, y + dy, z + dz)) {
                        v.iter().for_each(|&i| f(i));
                    }
                }
            }
        }
    }

    /// The splat sum at `p` on flat surface `surface`, read in display bin `bin` (none: 0),
    /// normalized by its kernels' weight (0 where no kernel reaches `p`).
    pub fn radiance(
        &self,
        surf: &Surfaces,
        sys: &System,
        i_total: &Table,
        p: DVec3,
        surface: u32,
        bin: Option<usize>,
    ) -> DVec3 {
        let (mut acc, mut wsum) = (DVec3::ZERO, 0.0);
        self.near(p, |e| {
            let e = e as usize;
            if surf.surface[e] == surface {
                let wt = splat_weight((p - surf.center[e]).length(), surf.radius[e]);
                if wt > 0.0 {
                    if let Some(b) = bin {
                        acc += display_radiance_in(sys, i_total, surf.leaf[e] as usize, b) * wt;
                    }
                    wsum += wt;
                }
            }
        });
        if wsum > 0.0 {
            acc / wsum
        } else {
            DVec3::ZERO
        }
    }
}

/// The splatted radiance sample `(i, j)` (its index within the pixel, each below `ss`) of pixel
/// `(px, py)` on flat surface `surface` takes: the bilinear interpolation, at the sample, of the
/// sums of the first samples of this pixel and of those after it in x, y and both that lie on
/// its surface; where none with a weight does, the sum of the first neighbour in [`NEIGHBOURS`]
/// whose first sample does; else none. `first(x, y)`: pixel `(x, y)`'s first sample's surface
/// and normalized sum, `None` off the image, on the background or off the splatted surfaces.
pub fn pixel_sum(
    (px, py): (i64, i64),
    (i, j): (i64, i64),
    ss: i64,
    surface: u32,
    first: impl Fn(i64, i64) -> Option<(u32, DVec3)>,
) -> Option<DVec3> {
    let (fx, fy) = (i as f64 / ss as f64, j as f64 / ss as f64);
    let (mut acc, mut wsum) = (DVec3::ZERO, 0.0);
    for (cx, cy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
        let w = if cx == 1 { fx } else { 1.0 - fx } * if cy == 1 { fy } else { 1.0 - fy };
        if w > 0.0 {
            if let Some((s, v)) = first(px + cx, py + cy) {
                if s == surface {
                    acc += v * w;
                    wsum += w;
                }
            }
        }
    }
    if wsum > 0.0 {
        return Some(acc / wsum);
    }
    NEIGHBOURS
        .into_iter()
        .find_map(|(dx, dy)| first(px + dx, py + dy).filter(|f| f.0 == surface))
        .map(|f| f.1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sample_interpolates_the_first_samples_on_its_surface_then_takes_a_neighbours() {
        // Surface 1 on the pixel and its right neighbour, surface 2 below and below-left.
        let first = |x: i64, y: i64| match (x, y) {
            (0, 0) => Some((1, DVec3::splat(1.0))),
            (1, 0) => Some((1, DVec3::splat(2.0))),
            (0, 1) => Some((2, DVec3::splat(3.0))),
            (-1, 1) => Some((2, DVec3::splat(4.0))),
            (1, 1) => Some((3, DVec3::splat(5.0))),
            _ => None,
        };
        let at = |ij, surface| pixel_sum((0, 0), ij, 2, surface, first);
        // The first sample is its own pixel's; the one to its right halfway to the next.
        assert_eq!(at((0, 0), 1), Some(DVec3::splat(1.0)));
        assert_eq!(at((1, 0), 1), Some(DVec3::splat(1.5)));
        // Only the two on surface 1 weigh at (1, 1): the same halfway value.
        assert_eq!(at((1, 1), 1), Some(DVec3::splat(1.5)));
        assert_eq!(at((0, 1), 2), Some(DVec3::splat(3.0)));
        assert_eq!(at((1, 1), 3), Some(DVec3::splat(5.0)));
        // At (1, 0) nothing on surface 2 weighs: the first neighbour in order that has it.
        assert_eq!(at((1, 0), 2), Some(DVec3::splat(3.0)));
        assert_eq!(at((1, 1), 4), None);
    }

    #[test]
    fn the_neighbours_are_the_eight_around_a_pixel_once_each() {
        let mut n = NEIGHBOURS.to_vec();
        n.sort();
        n.dedup();
        assert_eq!(n.len(), 8);
        assert!(n
            .iter()
            .all(|&(x, y)| x.abs() <= 1 && y.abs() <= 1 && (x, y) != (0, 0)));
    }
}

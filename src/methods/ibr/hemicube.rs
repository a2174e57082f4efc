//! A virtual light's hemicube (§4.1 of the image-based radiosity paper): five faces around its
//! normal, the front `H×H`, the four sides `H×H/2` over the upper half, each texel a ray from the
//! light. What a texel sees, shaded by the light (its irradiance there), is one sample for the
//! cube; its footprint on the surface sizes the splat (§4.3). The CPU backend casts the texels'
//! rays here; a rasterized item buffer of the same layout gives the same samples.

use super::cube::{Cube, Insert};
use crate::frame::lights::incident;
use crate::frame::surfaces::Surfaces;
use crate::raycast::RayCaster;
use crate::reference::sampling::basis;
use crate::scene::Light;
use glam::DVec3;

/// Most cells a splat reaches from its sample's own, per side (a footprint seen at a grazing
/// angle is long: beyond this its far cells are left to other lights).
pub const MAX_SPLAT: i64 = 16;

/// One texel of a hemicube: its ray direction, solid angle, and how the direction changes from
/// one texel to the next along the face's rows and columns.
#[derive(Debug, Clone, Copy)]
pub struct Texel {
    /// Unit direction from the light.
    pub dir: DVec3,
    /// Solid angle (sr).
    pub solid_angle: f64,
    /// The direction's change over one texel along the face's right and up.
    pub step: [DVec3; 2],
}

/// The texels of a hemicube of side `h` (even) around unit normal `n`: the front face, then the
/// four sides, row by row.
pub fn texels(n: DVec3, h: u32) -> Vec<Texel> {
    let (t, b) = basis(n);
    let h = h.max(2) & !1;
    let step = 2.0 / h as f64;
    let mut out = Vec::with_capacity((3 * h * h) as usize);
    // A texel of side `step` on the unit face through `axis + x·right + y·up` subtends
    // step²/|(x, y, 1)|³.
    let mut face = |axis: DVec3, right: DVec3, up: DVec3, rows: u32, y0: f64| {
        for j in 0..rows {
            for i in 0..h {
                let x = -1.0 + (i as f64 + 0.5) * step;
                let y = y0 + (j as f64 + 0.5) * step;
                let v = axis + right * x + up * y;
                let len = v.length();
                let dir = v / len;
                let turn = |a: DVec3| (a - dir * dir.dot(a)) * (step / len);
                out.push(Texel {
                    dir,
                    solid_angle: step * step / (len * len * len),
                    step: [turn(right), turn(up)],
                });
            }
        }
    };
    face(n, t, b, h, -1.0);
    // The sides: their `up` is the normal, and only its upper half (0..1) is above the plane.
    for (axis, right) in [(t, b), (-t, -b), (b, -t), (-b, t)] {
        face(axis, right, n, h / 2, 0.0);
    }
    out
}

/// A sample a hemicube texel gave: the surface point, its unit normal, the light's irradiance
/// there, and the texel's footprint on the surface (m²) with its two edges.
#[derive(Debug, Clone, Copy)]
pub struct Sample {
    /// Surface point.
    pub p: DVec3,
    /// Unit face normal.
    pub n: DVec3,
    /// The light's irradiance there (W/m² per channel).
    pub irradiance: DVec3,
    /// The texel's area on the surface (m²).
    pub footprint: f64,
    /// The footprint's edges on the surface: where the next texel's rays along the face's
    /// right and up meet the surface's plane, less `p` (a parallelogram around `p`).
    pub span: [DVec3; 2],
}

/// The position and normal of a cosine light (a VPL).
pub fn frame_of(light: &Light) -> Option<(DVec3, DVec3)> {
    match *light {
        Light::EmitterSample {
            position, normal, ..
        } => Some((position, normal)),
        _ => None,
    }
}

/// The sample a texel's ray gives where it meets a surface's front at distance `t` (`normal`
/// its face normal); None where it meets a back or the light delivers nothing there.
pub fn shade(light: &Light, origin: DVec3, texel: &Texel, t: f64, normal: DVec3) -> Option<Sample> {
    let cos = -texel.dir.dot(normal);
    if cos <= 0.0 {
        return None;
    }
    let p = origin + texel.dir * t;
    let inc = incident(light, p)?;
    let cos_r = -inc.travel.dot(normal);
    if cos_r <= 0.0 {
        return None;
    }
    // A turn δd of the ray moves its hit on the plane by t·(δd − d·(n·δd)/(n·d)).
    let span = texel
        .step
        .map(|dd| (dd - texel.dir * (normal.dot(dd) / -cos)) * t);
    Some(Sample {
        p,
        n: normal,
        irradiance: inc.irradiance * cos_r,
        footprint: texel.solid_angle * t * t / cos,
        span,
    })
}

/// Casts `light`'s hemicube of side `h` through `caster` (rays leave `lift` off its surface).
pub fn cast(light: &Light, h: u32, caster: &RayCaster, surf: &Surfaces, lift: f64) -> Vec<Sample> {
    let Some((x, n)) = frame_of(light) else {
        return Vec::new();
    };
    let origin = x + n * lift;
    texels(n, h)
        .iter()
        .filter_map(|texel| {
            let hit = caster.closest(origin, texel.dir, 0.0, f64::INFINITY)?;
            shade(light, origin, texel, hit.t, surf.normal[hit.shape as usize])
        })
        .collect()
}

/// Warps one light's samples into `cube` (§4): every sample into its cell, then copies into
/// the neighbouring cells whose centres its footprint covers and that the light's own samples
/// did not reach (§4.3's splat, sized by the footprint's parallelogram rather than a square,
/// so that a surface seen at a grazing angle is covered along its length); then the light's
/// layers take their means.
pub fn warp(cube: &mut Cube, samples: &[Sample]) {
    let cell = cube.cell;
    let grid = |axis: usize, p: DVec3| cube.coords(axis, p);
    // Each sample belongs to one LDI: the three take theirs in parallel, in the samples' order
    // (the same cube as one after another).
    let mut by_axis: [Vec<(&Sample, (f64, f64))>; 3] = Default::default();
    for s in samples {
        let axis = super::cube::axis_of(s.n);
        by_axis[axis].push((s, grid(axis, s.p)));
    }
    let mut ldis = cube.ldis_mut();
    rayon::scope(|scope| {
        for (ldi, samples) in ldis.iter_mut().zip(&by_axis) {
            scope.spawn(move |_| {
                for (s, _) in samples {
                    ldi.insert(s.p, s.n, s.irradiance, Insert::Own, 0, 0);
                }
                for &(s, uv) in samples {
                    splat_cells(cell, ldi.axis(), uv, s, |du, dv| {
                        ldi.insert(s.p, s.n, s.irradiance, Insert::Copy, du, dv)
                    });
                }
                ldi.finish_light();
            });
        }
    });
}

/// Calls `each` with the cells (offsets from the sample's own, at cell coordinates `uv` in the
/// LDI along `axis`) other than its own that the sample's footprint overlaps (separating axes:
/// the cell's two and the footprint's two). Testing the cells' centres only, a cell that a
/// crease cuts (the cube's grid is not aligned with the walls) missed every light whose samples
/// fell beside it: the closed box's floor lost 10–40% of its VPLs' light in the cells along
/// the walls.
fn splat_cells(cell: f64, axis: usize, uv: (f64, f64), s: &Sample, mut each: impl FnMut(i64, i64)) {
    let (b, c) = super::cube::image_axes(axis);
    let [e, f] = s.span.map(|v| (v[b] / cell, v[c] / cell));
    let det = e.0 * f.1 - e.1 * f.0;
    if !(det.abs() > 1e-12) {
        return;
    }
    // The footprint's half extents along the grid, in cells; the cell's half extents along the
    // footprint's two edge coordinates.
    let (xu, xv) = ((e.0.abs() + f.0.abs()) * 0.5, (e.1.abs() + f.1.abs()) * 0.5);
    let (ra, rg) = (
        0.5 * (f.1.abs() + f.0.abs()) / det.abs(),
        0.5 * (e.0.abs() + e.1.abs()) / det.abs(),
    );
    let hu = (xu + 0.5).ceil().min(MAX_SPLAT as f64) as i64;
    let hv = (xv + 0.5).ceil().min(MAX_SPLAT as f64) as i64;
    let (u, v) = uv;
    let (fu, fv) = (u - u.floor(), v - v.floor());
    for dv in -hv..=hv {
        for du in -hu..=hu {
            if du == 0 && dv == 0 {
                continue;
            }
            // The cell centre from the sample, in cells; its parallelogram coordinates.
            let (x, y) = (du as f64 + 0.5 - fu, dv as f64 + 0.5 - fv);
            if x.abs() > xu + 0.5 || y.abs() > xv + 0.5 {
                continue;
            }
            let a = (x * f.1 - y * f.0) / det;
            let g = (e.0 * y - e.1 * x) / det;
            if a.abs() <= 0.5 + ra && g.abs() <= 0.5 + rg {
                each(du, dv);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn texels_cover_the_hemisphere() {
        for n in [DVec3::Z, DVec3::new(0.3, -0.5, 0.8).normalize()] {
            let ts = texels(n, 32);
            assert_eq!(ts.len(), 3 * 32 * 32);
            let omega: f64 = ts.iter().map(|t| t.solid_angle).sum();
            // Midpoint solid angles of the cube's texels: 2π to a fraction of a percent.
            assert!((omega / (2.0 * PI) - 1.0).abs() < 2e-3, "{omega}");
            // Cosine-weighted: π.
            let proj: f64 = ts.iter().map(|t| t.solid_angle * t.dir.dot(n)).sum();
            assert!((proj / PI - 1.0).abs() < 2e-3, "{proj}");
            assert!(ts.iter().all(|t| t.dir.dot(n) > 0.0));
        }
    }

    #[test]
    fn a_footprint_reaching_a_cell_splats_into_it_without_covering_its_centre() {
        // A sample at (0.9, 0.5) of its cell, its footprint 0.6 cells wide: it reaches into the
        // cell to its right (x from 1.0 to 1.2 of its own) but not that cell's centre (1.5).
        let cell = 1.0;
        let s = Sample {
            p: DVec3::ZERO,
            n: DVec3::Y,
            irradiance: DVec3::ONE,
            footprint: 0.36,
            span: [DVec3::X * 0.6, DVec3::Z * 0.6],
        };
        let axis = super::super::cube::axis_of(DVec3::Y);
        let (b, c) = super::super::cube::image_axes(axis);
        // The footprint's image coordinates: along the LDI's axes b and c.
        let uv = if b == 0 { (0.9, 0.5) } else { (0.5, 0.9) };
        let mut cells = Vec::new();
        splat_cells(cell, axis, uv, &s, |du, dv| cells.push((du, dv)));
        let right = if b == 0 { (1, 0) } else { (0, 1) };
        assert!(cells.contains(&right), "{cells:?} (axes {b}, {c})");
        // Not the cells it does not reach: two to the right, or the one to the left.
        let far = (2 * right.0, 2 * right.1);
        assert!(
            !cells.contains(&far) && !cells.contains(&(-right.0, -right.1)),
            "{cells:?}"
        );
    }

    #[test]
    fn a_light_over_a_floor_gives_its_irradiance() {
        // A VPL 1 above a floor, facing down; the texel straight below sees the floor at 1.
        let light = Light::EmitterSample {
            position: DVec3::new(0.0, 1.0, 0.0),
            normal: -DVec3::Y,
            radiance: DVec3::splat(2.0),
            area: 1e-6,
            cell: None,
        };
        let texel = Texel {
            dir: -DVec3::Y,
            solid_angle: 1e-4,
            step: [DVec3::X * 1e-2, DVec3::Z * 1e-2],
        };
        let s = shade(&light, DVec3::new(0.0, 1.0, 0.0), &texel, 1.0, DVec3::Y).unwrap();
        // L·A·cos·cos / (r² + A/π): the tiny disc's irradiance.
        let want = 2.0 * 1e-6 / (1.0 + 1e-6 / PI);
        assert!((s.irradiance.x - want).abs() < 1e-15, "{}", s.irradiance.x);
        assert!((s.footprint - 1e-4).abs() < 1e-15);
        // Straight down, the footprint's edges are the turns themselves at distance 1.
        assert!((s.span[0] - DVec3::X * 1e-2).length() < 1e-15);
        // Seen from behind: no sample.
        assert!(shade(&light, DVec3::new(0.0, 1.0, 0.0), &texel, 1.0, -DVec3::Y).is_none());
    }
}

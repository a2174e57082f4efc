//! Direct light from the analytic lights (§3.3): the irradiance a light delivers, the leaves'
//! direct incident radiance that initializes the solve (reflected, never turned into antiradiance:
//! the shadow map already accounted for occlusion), and the per-pixel direct radiance of the frame.
//! `glsl/frame.glsl` mirrors [`direct_radiance`] and [`front_bin`].

use super::shadow::ShadowMaps;
use crate::bins::Bins;
use crate::brdf::phong_lobe;
use crate::scene::{Light, Material};
use crate::solver::Table;
use crate::system::System;
use glam::DVec3;
use std::f64::consts::PI;
use std::ops::Range;

/// Light arriving at a point from one analytic light, before the receiver's cosine and shadowing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Incident {
    /// Unit direction in which the light travels (from the light to the point).
    pub travel: DVec3,
    /// Irradiance on a surface facing the light (W/m²).
    pub irradiance: DVec3,
}

/// Spot fall-off: 1 within the beam width, linear in angle to 0 at the cut-off.
pub fn spot_falloff(angle: f64, beam_width: f64, cutoff: f64) -> f64 {
    if angle <= beam_width {
        1.0
    } else if angle >= cutoff {
        0.0
    } else {
        (cutoff - angle) / (cutoff - beam_width)
    }
}

/// What `light` delivers at `p` (None where it delivers nothing: at the light, outside a cone).
pub fn incident(light: &Light, p: DVec3) -> Option<Incident> {
    match *light {
        Light::Directional {
            direction,
            irradiance,
        } => Some(Incident {
            travel: direction,
            irradiance,
        }),
        Light::Point {
            position,
            intensity,
        } => {
            let v = p - position;
            let r2 = v.length_squared();
            (r2 > 0.0).then(|| Incident {
                travel: v / r2.sqrt(),
                irradiance: intensity / r2,
            })
        }
        Light::Spot {
            position,
            axis,
            intensity,
            cutoff,
            beam_width,
        } => {
            let v = p - position;
            let r2 = v.length_squared();
            if r2 <= 0.0 {
                return None;
            }
            let travel = v / r2.sqrt();
            let angle = travel.dot(axis).clamp(-1.0, 1.0).acos();
            let f = spot_falloff(angle, beam_width, cutoff);
            (f > 0.0).then(|| Incident {
                travel,
                irradiance: intensity * (f / r2),
            })
        }
        Light::EmitterSample {
            position,
            normal,
            radiance,
            area,
            ..
        } => {
            let v = p - position;
            let r2 = v.length_squared();
            if r2 <= 0.0 {
                return None;
            }
            let travel = v / r2.sqrt();
            let cos_e = travel.dot(normal);
            // A disc of the sample's area seen on its axis gives L·A·cos/(r² + A/π) of
            // irradiance, bounded as r → 0 where a point's 1/r² is not.
            (cos_e > 0.0).then(|| Incident {
                travel,
                irradiance: radiance * (area * cos_e / (r2 + area / PI)),
            })
        }
    }
}

/// A bin on the requested side of a surface: the bin of `dir`, or, where its center lies within
/// ~3° of the plane or beyond it, the bin of `dir` tilted toward `side·n` in growing steps.
/// `side` is +1 for exitant directions, −1 for incident travel directions.
pub fn front_bin(bins: &Bins, dir: DVec3, n: DVec3, side: f64) -> usize {
    let mut b = bins.bin_of(dir);
    for k in [0.25, 0.5, 1.0, 2.0, 4.0, 16.0] {
        if side * bins.centers[b].dot(n) > 0.05 {
            break;
        }
        b = bins.bin_of(dir.normalize() + n * (side * k));
    }
    b
}

/// BRDF of `mat` at normal `n` for light travelling along `travel` and leaving along `wo`.
pub fn brdf(mat: &Material, n: DVec3, travel: DVec3, wo: DVec3) -> DVec3 {
    let mut f = mat.kd / PI;
    if mat.is_glossy() {
        f += phong_lobe(mat.ks, mat.ns, n, travel, wo);
    }
    f
}

/// The lights a frame shades with, their shadow maps, and the range of them whose direct light
/// a pixel's 2×2 samples share where they lie on one flat surface (`frame::cpu::shared_direct`;
/// the engine's `Prepared::shared_lights`: the area emitters' samples).
pub struct LightSet<'a> {
    /// Every light.
    pub lights: &'a [Light],
    /// Their shadow maps.
    pub maps: &'a ShadowMaps,
    /// The shared ones (empty: every light per sample).
    pub shared: Range<usize>,
}

/// A surface point receiving light.
#[derive(Clone, Copy, Debug)]
pub struct Receiver {
    /// The point.
    pub p: DVec3,
    /// Its face's unit normal, facing `wo` (front side, shadow lookup).
    pub n: DVec3,
    /// Its unit shading normal (receiver cosine, BRDF).
    pub shading: DVec3,
    /// The unit direction toward the eye.
    pub wo: DVec3,
}

/// The lights of `range` that reach the front of a surface at `p` (face normal `n`, facing
/// the side the light must arrive on): each with its incident light and its shadow-map
/// visibility (> 0).
fn reaching<'a>(
    lights: &'a [Light],
    maps: &'a ShadowMaps,
    p: DVec3,
    n: DVec3,
    range: Range<usize>,
) -> impl Iterator<Item = (&'a Light, Incident, f64)> + 'a {
    lights
        .iter()
        .enumerate()
        .take(range.end)
        .skip(range.start)
        .filter_map(move |(i, light)| {
            let (inc, v) = reach(light, i, maps, p, n)?;
            Some((light, inc, v))
        })
}

/// How light `i` reaches the front of a surface at `p` of face normal `n`: its incident light
/// and shadow-map visibility (> 0), or, where it is an emitter cell ([`irradiance_on`]) whose
/// sample point lies behind the surface's plane while part of the cell lies in front, the light
/// of that part unshadowed ([`straddling`]). `glsl/frame.glsl` ar_direct_radiance mirrors it.
fn reach(
    light: &Light,
    i: usize,
    maps: &ShadowMaps,
    p: DVec3,
    n: DVec3,
) -> Option<(Incident, f64)> {
    let inc = incident(light, p)?;
    let cos_face = -inc.travel.dot(n);
    if cos_face <= 0.0 {
        return straddling(light, p, n).map(|inc| (inc, 1.0));
    }
    let v = maps.visibility(i, p, n, cos_face);
    (v > 0.0).then_some((inc, v))
}

/// An emitter cell within [`CELL_FAR`] of `p`, `p` in front of it, whose sample point lies behind
/// `p`'s plane (normal `n`) but some corner in front: the light arrives from the front corners'
/// mean, and [`irradiance_on`] takes the cell's part in front. Dropping it (the point's cosine
/// says nothing reaches) lost the light of every cell a receiver's plane cuts: in a closed
/// uniform box a block's faces got 7–14% too little direct light. The sample's shadow map cannot
/// say whether that part is hidden (its rays leave from behind the receiver's plane, through
/// it); the part lies beside the plane, so it is taken as unoccluded.
fn straddling(light: &Light, p: DVec3, n: DVec3) -> Option<Incident> {
    let Light::EmitterSample {
        position,
        normal,
        area,
        cell: Some(c),
        ..
    } = *light
    else {
        return None;
    };
    if p.distance_squared(position) > CELL_FAR * area || (p - c[0]).dot(normal) <= 0.0 {
        return None;
    }
    let (sum, k) = c
        .into_iter()
        .filter(|&x| (x - p).dot(n) > 0.0)
        .fold((DVec3::ZERO, 0), |(s, k), x| (s + x, k + 1));
    (k > 0).then(|| Incident {
        travel: (p - sum / k as f64).normalize(),
        irradiance: DVec3::ZERO,
    })
}

/// [`direct_radiance`] from the lights `range` of `lights`.
pub fn direct_radiance_from(
    lights: &[Light],
    maps: &ShadowMaps,
    r: &Receiver,
    mat: &Material,
    range: Range<usize>,
) -> DVec3 {
    let mut l = DVec3::ZERO;
    for (light, inc, v) in reaching(lights, maps, r.p, r.n, range) {
        if -inc.travel.dot(r.shading) > 0.0 {
            l += brdf(mat, r.shading, inc.travel, r.wo)
                * irradiance_on(light, &inc, r.p, r.shading)
                * v;
        }
    }
    l
}

/// The shadowed irradiance every light delivers at `p` on a surface of unit normal `n` (the
/// front): [`direct_radiance`]'s light before a BRDF.
pub fn direct_irradiance(lights: &[Light], maps: &ShadowMaps, p: DVec3, n: DVec3) -> DVec3 {
    reaching(lights, maps, p, n, 0..lights.len())
        .map(|(light, inc, v)| irradiance_on(light, &inc, p, n) * v)
        .sum()
}

/// Irradiance that `light`, arriving as `inc` (from [`incident`]), delivers on a surface at `p`
/// of unit normal `n`: `inc`'s irradiance times the receiver's cosine, except for an emitter
/// sample with a cell, whose light is its cell's (a uniform Lambertian triangle's, by Lambert's
/// edge sum over the part in front of the receiver's plane): exact without occlusion, where a
/// point's 1/r² is right only far from the emitter. Beyond [`CELL_FAR`] the point's is used:
/// the two agree to about `area/r²` there, and the edge sum's terms, each of order the cell's
/// angular size, cancel to its square times the two cosines: in float32 (the GPU) that lost
/// 7·10⁻⁴ of a grazing receiver at r² = 7000 areas, 2·10⁻⁵ at 1000.
pub fn irradiance_on(light: &Light, inc: &Incident, p: DVec3, n: DVec3) -> DVec3 {
    match *light {
        Light::EmitterSample {
            position,
            normal,
            radiance,
            area,
            cell: Some(c),
        } if p.distance_squared(position) <= CELL_FAR * area => {
            if (p - c[0]).dot(normal) <= 0.0 {
                return DVec3::ZERO;
            }
            radiance * projected_solid_angle(&c, p, n)
        }
        _ => inc.irradiance * (-inc.travel.dot(n)).max(0.0),
    }
}

/// Squared distance, in units of a cell's area, beyond which an emitter cell delivers its
/// light as a point ([`irradiance_on`]).
pub const CELL_FAR: f64 = 1e3;

/// Projected solid angle (the integral of the cosine to `n`) of triangle `c` seen from `p`,
/// over its part in front of `p`'s plane of normal `n`: Lambert's ½ Σ θ_e (γ̂_e · n) over the
/// clipped polygon's edges. Each edge contributes its part in front; where the plane cuts the
/// triangle, one closing edge runs along the plane from the point where an edge leaves the front
/// to the point where another enters. `glsl/frame.glsl`'s `ar_cell` is the same sum.
pub fn projected_solid_angle(c: &[DVec3; 3], p: DVec3, n: DVec3) -> f64 {
    // One edge's term; a degenerate edge adds nothing.
    let edge = |x: DVec3, y: DVec3| {
        let cross = x.cross(y);
        let len = cross.length();
        // The angle by atan2: exact for the small angles of a distant cell.
        if len > 0.0 {
            len.atan2(x.dot(y)) * cross.dot(n) / len
        } else {
            0.0
        }
    };
    let q = c.map(|x| x - p);
    let (mut leave, mut enter) = (DVec3::ZERO, DVec3::ZERO);
    let mut sum = 0.0;
    for i in 0..3 {
        let (s, e) = (q[i], q[(i + 1) % 3]);
        let (ds, de) = (s.dot(n), e.dot(n));
        let (fs, fe) = (ds > 0.0, de > 0.0);
        let x = s + (e - s) * (ds / (ds - de));
        if fs && !fe {
            leave = x;
        }
        if !fs && fe {
            enter = x;
        }
        if fs || fe {
            sum += edge(if fs { s } else { x }, if fe { e } else { x });
        }
    }
    0.5 * (sum + edge(leave, enter)).abs()
}

/// Radiance reflected toward `wo` at surface point `p` from every analytic light, shadowed by
/// `maps`. `n` is the face's unit normal (facing `wo`): light must arrive at its front (the
/// surface is opaque from both sides) and the shadow lookup uses it; `shading` is the unit
/// shading normal ([`super::shading`]; `n` itself without `vn`), which gives the receiver's
/// cosine, clamped at 0, and the BRDF.
pub fn direct_radiance(
    lights: &[Light],
    maps: &ShadowMaps,
    p: DVec3,
    n: DVec3,
    shading: DVec3,
    mat: &Material,
    wo: DVec3,
) -> DVec3 {
    let r = Receiver { p, n, shading, wo };
    direct_radiance_from(lights, maps, &r, mat, 0..lights.len())
}

/// Direct incident radiance per node and bin (leaf rows only): each light puts, in the bin of
/// its direction at the leaf's center, the radiance whose bin quadrature gives the exact shadowed
/// irradiance there. This is what [`crate::CpuSolver::set_direct`] and
/// [`crate::gpu::GpuSolver::set_direct`] take.
pub fn direct_in_table(sys: &System, lights: &[Light], maps: &ShadowMaps) -> Table {
    use rayon::prelude::*;
    // Per leaf (in parallel), its lights' (bin, radiance) in light order, summed in that order.
    let per_leaf: Vec<Vec<(usize, DVec3)>> = sys
        .leaves
        .par_iter()
        .map(|leaf| {
            let e = &sys.elements[sys.hierarchy.element(leaf.node).expect("leaf") as usize];
            let mut out = Vec::new();
            if !e.is_cluster() {
                for (i, light) in lights.iter().enumerate() {
                    let Some((inc, v)) = reach(light, i, maps, e.center, leaf.normal) else {
                        continue;
                    };
                    let b = front_bin(&sys.bins, inc.travel, leaf.normal, -1.0);
                    let cb = -sys.bins.centers[b].dot(leaf.normal);
                    out.push((
                        b,
                        irradiance_on(light, &inc, e.center, leaf.normal)
                            * (v / (sys.bins.omega * leaf.cos_norm * cb)),
                    ));
                }
                return out;
            }
            // A face cluster receives each face's shadowed irradiance at the face's centroid
            // (its own centroid may lie off the surface), area-weighted; one face is the leaf.
            let points: Vec<(DVec3, DVec3, f64)> = e
                .faces
                .iter()
                .map(|f| (f.center(), f.normal(), f.area() / e.area))
                .collect();
            for (i, light) in lights.iter().enumerate() {
                let mut sum = DVec3::ZERO;
                let mut travel = None;
                for &(p, n, share) in &points {
                    let Some((inc, v)) = reach(light, i, maps, p, n) else {
                        continue;
                    };
                    travel.get_or_insert(inc.travel);
                    sum += irradiance_on(light, &inc, p, n) * (v * share);
                }
                let Some(travel) = travel else {
                    continue;
                };
                // The bin of the light's direction at the cluster's center; its quadrature gives
                // back the summed irradiance.
                let travel = incident(light, e.center).map_or(travel, |inc| inc.travel);
                let b = front_bin(&sys.bins, travel, leaf.normal, -1.0);
                let cb = -sys.bins.centers[b].dot(leaf.normal);
                out.push((b, sum / (sys.bins.omega * leaf.cos_norm * cb)));
            }
            out
        })
        .collect();
    let mut t = Table::zeros(sys.rows(), sys.bins.count);
    for (leaf, adds) in sys.leaves.iter().zip(per_leaf) {
        let row = t.row_mut(leaf.node as usize);
        for (b, v) in adds {
            row[b] += v;
        }
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spot_falls_off_linearly_in_angle() {
        let (b, c) = (0.3, 0.5);
        assert_eq!(spot_falloff(0.1, b, c), 1.0);
        assert!((spot_falloff(0.4, b, c) - 0.5).abs() < 1e-12);
        assert_eq!(spot_falloff(0.6, b, c), 0.0);
        let light = Light::Point {
            position: DVec3::new(0.0, 2.0, 0.0),
            intensity: DVec3::splat(8.0),
        };
        let inc = incident(&light, DVec3::ZERO).unwrap();
        assert!((inc.irradiance.x - 2.0).abs() < 1e-12);
        assert!((inc.travel - DVec3::NEG_Y).length() < 1e-12);
    }

    /// A cell the receiver's plane cuts, its sample point behind that plane: the part in front
    /// lights the receiver (unshadowed), as the clipped edge sum; nothing where no corner is in
    /// front.
    #[test]
    fn a_cell_cut_by_the_receivers_plane_lights_its_front_part() {
        let scene = crate::scene::test_plane(0.3);
        let c = [
            DVec3::new(-1.0, 1.0, -1.0),
            DVec3::new(1.0, 1.0, -1.0),
            DVec3::new(0.0, 1.0, 1.0),
        ];
        let cell = |c: [DVec3; 3]| Light::EmitterSample {
            position: (c[0] + c[1] + c[2]) / 3.0,
            normal: DVec3::NEG_Y,
            radiance: DVec3::splat(2.0),
            area: 2.0,
            cell: Some(c),
        };
        let lights = vec![cell(c)];
        let maps = ShadowMaps::new(&scene, &lights, 16, 8).unwrap();
        let (p, n) = (DVec3::new(0.0, 0.5, 0.0), DVec3::Z);
        assert!(
            incident(&lights[0], p).unwrap().travel.dot(n) > 0.0,
            "the point is behind"
        );
        let e = direct_irradiance(&lights, &maps, p, n);
        let want = 2.0 * projected_solid_angle(&c, p, n);
        assert!(
            want > 0.01 && (e.x - want).abs() < 1e-12,
            "{e} against {want}"
        );
        let behind = c.map(|x| x - DVec3::Z * 1.5);
        assert_eq!(direct_irradiance(&[cell(behind)], &maps, p, n), DVec3::ZERO);
    }

    #[test]
    fn front_bin_lies_on_the_requested_side() {
        let bins = Bins::new(32).unwrap();
        let n = DVec3::new(0.1, 0.2, 1.0).normalize();
        for i in 0..200 {
            let a = i as f64 * 0.37;
            let d = DVec3::new(a.cos(), a.sin(), 0.01 * (i as f64 - 100.0)).normalize();
            if d.dot(n) > 0.0 {
                assert!(bins.centers[front_bin(&bins, d, n, 1.0)].dot(n) > 0.05);
            }
            if d.dot(n) < 0.0 {
                assert!(bins.centers[front_bin(&bins, d, n, -1.0)].dot(n) < -0.05);
            }
        }
    }
}

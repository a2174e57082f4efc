//! Area emitters as many shadow-mapped point samples (§3.3): the paper initializes the solve
//! from direct light computed with shadow maps and draws direct light per pixel; antiradiance
//! carries indirect light only. The emitting triangles (`Ke` faces) are sampled with N
//! stratified points, chosen by area × luminance of `Ke`, and each point becomes a
//! [`Light::EmitterSample`]: a cosine-weighted one-sided patch with its own shadow map, read
//! with the same filtered lookup as the analytic lights, for the leaves' first bounce and for
//! every pixel. The samples are deterministic: the same scene gives the same points.

use crate::scene::{Light, Scene};
use glam::DVec3;

/// Emitter samples when `solver.emitter_samples` is not given (see the README for the
/// measurement behind it).
pub const DEFAULT_SAMPLES: usize = 32;

/// Side (texels) of each emitter sample's shadow-map faces: many soft samples average the
/// maps' blur away, so they can be far smaller than an analytic light's. Measured against the
/// path tracer (tests/references.rs, relative RMSE): 64 texels cost 2–14% more error than 128
/// (Cornell box 0.118 vs 0.110, slabs 0.235 vs 0.206) for a quarter of the texels.
pub const SAMPLE_MAP_SIZE: u32 = 128;

/// Above this share of the scene's surface area emitting, the automatic choice sends emission
/// through the bins: a few point samples cannot resolve an emitter that surrounds its
/// receivers (a uniformly emitting enclosure), where the bins' spread does no harm.
pub const MAX_SAMPLED_SHARE: f64 = 0.1;

/// How a scene's area emitters are lit, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct Choice {
    /// Emitter samples (0: emission through the bins).
    pub samples: usize,
    /// Why, in a line (for the plan's decisions).
    pub reason: String,
}

/// Share of `scene`'s surface area that emits.
pub fn emitting_share(scene: &Scene) -> f64 {
    let (mut emitting, mut total) = (0.0, 0.0);
    for m in &scene.meshes {
        for (t, &mi) in m.triangles.iter().zip(&m.material) {
            let c = t.map(|v| m.positions[v as usize]);
            let area = 0.5 * (c[1] - c[0]).cross(c[2] - c[0]).length();
            total += area;
            if scene.materials[mi as usize].ke.max_element() > 0.0 {
                emitting += area;
            }
        }
    }
    if total > 0.0 {
        emitting / total
    } else {
        0.0
    }
}

/// The emitter samples for `scene` when `requested` (the setting; `None` chooses
/// [`DEFAULT_SAMPLES`] unless more than [`MAX_SAMPLED_SHARE`] of the surface emits).
pub fn choose(scene: &Scene, requested: Option<usize>) -> Choice {
    let share = emitting_share(scene);
    let pct = share * 100.0;
    if share <= 0.0 {
        return Choice {
            samples: 0,
            reason: "no area emitters".into(),
        };
    }
    match requested {
        Some(0) => Choice {
            samples: 0,
            reason: "emitter_samples = 0: area emitters' light through the bins".into(),
        },
        Some(n) => Choice {
            samples: n,
            reason: format!(
                "area emitters by {n} shadow-mapped samples (as set): direct light per pixel and as the leaves' first bounce, no emission in the bins"
            ),
        },
        None if share > MAX_SAMPLED_SHARE => Choice {
            samples: 0,
            reason: format!(
                "emitters cover {pct:.0}% of the surface (> {:.0}%): their light through the bins",
                MAX_SAMPLED_SHARE * 100.0
            ),
        },
        None => Choice {
            samples: DEFAULT_SAMPLES,
            reason: format!(
                "area emitters ({pct:.2}% of the surface) by {DEFAULT_SAMPLES} shadow-mapped samples: direct light per pixel and as the leaves' first bounce, no emission in the bins"
            ),
        },
    }
}

/// Weight of an emitting triangle's `Ke` when sampling: Rec. 709 luminance, kept above a small
/// share of the mean so a saturated colour is still sampled.
fn weight(ke: DVec3) -> f64 {
    let lum = 0.2126 * ke.x + 0.7152 * ke.y + 0.0722 * ke.z;
    lum.max(1e-3 * ke.element_sum() / 3.0)
}

/// `corners` labelled `[a, b, c]` so that a–c is the longest edge and b the opposite corner.
fn longest_first(corners: [DVec3; 3]) -> [DVec3; 3] {
    let [p, q, r] = corners;
    let (pq, qr, rp) = (p.distance(q), q.distance(r), r.distance(p));
    if qr >= pq && qr >= rp {
        [q, p, r]
    } else if rp >= pq {
        [r, q, p]
    } else {
        [p, r, q]
    }
}

/// `count` cells of triangle `[a, b, c]` (labelled as by [`longest_first`]) in the order of
/// [`curve_cell`]'s curve, halving at the midpoint of a–c with ⌈count/2⌉ cells on the first half:
/// for a power of two, `curve_cell`'s cells.
fn bisect([a, b, c]: [DVec3; 3], count: usize, out: &mut Vec<[DVec3; 3]>) {
    if count <= 1 {
        out.push([a, b, c]);
        return;
    }
    let m = 0.5 * (a + c);
    let first = count.div_ceil(2);
    bisect([a, m, b], first, out);
    bisect([b, m, c], count - first, out);
}

/// Shares `n ≥ w.len()` samples among weights `w`: at least one each, the rest by largest
/// remainders of `w`'s shares of what is left.
fn shares(w: &[f64], n: usize) -> Vec<usize> {
    let sum: f64 = w.iter().sum();
    let rest = (n - w.len()) as f64;
    let ideal: Vec<f64> = w.iter().map(|x| x / sum * rest).collect();
    let mut counts: Vec<usize> = ideal.iter().map(|i| 1 + i.floor() as usize).collect();
    let mut order: Vec<usize> = (0..w.len()).collect();
    order.sort_by(|&a, &b| (ideal[b] - ideal[b].floor()).total_cmp(&(ideal[a] - ideal[a].floor())));
    let mut k = 0;
    while counts.iter().sum::<usize>() < n {
        counts[order[k % order.len()]] += 1;
        k += 1;
    }
    counts
}

/// The centroid of the cell of a triangle that parameter `s` ∈ [0, 1) falls in, after
/// `levels` bisections along a Sierpiński curve (each triangle halved at the midpoint of the edge
/// from its curve's entry to its exit; the first such edge the longest). Consecutive parameter
/// intervals of length 2^−levels are cells of equal area, so evenly spaced `s` give one sample
/// per cell at its centroid: the samples' mean is the triangle's centroid and their spread is
/// even, which a point set warped onto the triangle does not give (measured: 3.9% off a square
/// emitter's closed form at 32 samples, 0.4% with the cells).
fn curve_cell(corners: [DVec3; 3], mut s: f64, levels: u32) -> DVec3 {
    let [mut a, mut b, mut c] = longest_first(corners);
    for _ in 0..levels {
        let m = 0.5 * (a + c);
        if s < 0.5 {
            (a, b, c) = (a, m, b);
            s *= 2.0;
        } else {
            (a, b, c) = (b, m, c);
            s = 2.0 * s - 1.0;
        }
    }
    (a + b + c) / 3.0
}

/// `n` stratified samples of `scene`'s emitting triangles (none when nothing emits or `n` is
/// zero). Where `n` is at least the emitting triangles' count, the samples tile them: each
/// triangle takes its share of `n` by area × luminance (at least one), split by [`bisect`], and
/// each sample is the centroid of its cell, carrying the cell and its area (its light is then
/// the cell's exact unoccluded irradiance, see [`crate::frame::lights::irradiance_on`]).
/// Otherwise sample `k` takes the triangle at `(k + ½)/n` of the cumulative area × luminance and,
/// with the rest of that coordinate, the centroid of its cell of the triangle ([`curve_cell`],
/// cells as many as the triangle's expected samples rounded up to a power of two); its
/// area is the emitters' total weighted area over `n`, divided by its own `Ke`'s weight, so the
/// samples sum to every emitter's power; it stands for its area as a point (no cell).
pub fn sample(scene: &Scene, n: usize) -> Vec<Light> {
    struct Tri {
        corners: [DVec3; 3],
        normal: DVec3,
        ke: DVec3,
        weight: f64,
    }
    let mut tris = Vec::new();
    for m in &scene.meshes {
        for (t, &mi) in m.triangles.iter().zip(&m.material) {
            let ke = scene.materials[mi as usize].ke;
            if ke.max_element() <= 0.0 {
                continue;
            }
            let c = t.map(|v| m.positions[v as usize]);
            let cross = (c[1] - c[0]).cross(c[2] - c[0]);
            let area = 0.5 * cross.length();
            if area > 0.0 {
                tris.push(Tri {
                    corners: c,
                    normal: cross.normalize(),
                    ke,
                    weight: area * weight(ke),
                });
            }
        }
    }
    let total: f64 = tris.iter().map(|t| t.weight).sum();
    if n == 0 || tris.is_empty() || total <= 0.0 {
        return Vec::new();
    }
    let (lo, hi) = scene.bounds();
    // Off the surface by a hair, so the emitter's own face never shadows its sample.
    let lift = (hi - lo).length() * 1e-6;
    if n >= tris.len() {
        // Every triangle its share of the samples (at least one), each sample a cell of a
        // balanced bisection: the cells tile the emitters.
        let counts = shares(&tris.iter().map(|t| t.weight).collect::<Vec<_>>(), n);
        let mut out = Vec::with_capacity(n);
        for (tri, &count) in tris.iter().zip(&counts) {
            let mut cells = Vec::with_capacity(count);
            bisect(longest_first(tri.corners), count, &mut cells);
            out.extend(cells.into_iter().map(|c| Light::EmitterSample {
                position: (c[0] + c[1] + c[2]) / 3.0 + tri.normal * lift,
                normal: tri.normal,
                radiance: tri.ke,
                area: 0.5 * (c[1] - c[0]).cross(c[2] - c[0]).length(),
                cell: Some(c),
            }));
        }
        return out;
    }
    let mut cumulative = Vec::with_capacity(tris.len());
    let mut acc = 0.0;
    for t in &tris {
        acc += t.weight / total;
        cumulative.push(acc);
    }
    (0..n)
        .map(|k| {
            let u = (k as f64 + 0.5) / n as f64;
            let i = cumulative.partition_point(|&c| c <= u).min(tris.len() - 1);
            let start = if i == 0 { 0.0 } else { cumulative[i - 1] };
            let width = cumulative[i] - start;
            let s = ((u - start) / width.max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
            let tri = &tris[i];
            let expected = width * n as f64;
            let levels = expected.max(1.0).log2().ceil().min(30.0) as u32;
            let p = curve_cell(tri.corners, s.min(1.0 - f64::EPSILON), levels);
            Light::EmitterSample {
                position: p + tri.normal * lift,
                normal: tri.normal,
                radiance: tri.ke,
                area: total / (n as f64 * weight(tri.ke)),
                cell: None,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Material;

    #[test]
    fn curve_cells_are_even_and_centred() {
        let t = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(3.0, 0.0, 0.0),
            DVec3::new(0.4, 1.0, 0.0),
        ];
        let centroid = (t[0] + t[1] + t[2]) / 3.0;
        for levels in [0u32, 1, 3, 6] {
            let n = 1usize << levels;
            let cells: Vec<DVec3> = (0..n)
                .map(|j| curve_cell(t, (j as f64 + 0.5) / n as f64, levels))
                .collect();
            let mean = cells.iter().sum::<DVec3>() / n as f64;
            assert!(
                mean.distance(centroid) < 1e-12,
                "{levels}: {mean} vs {centroid}"
            );
            // Every cell centroid inside the triangle (barycentric coordinates positive).
            for p in &cells {
                let area = |a: DVec3, b: DVec3, c: DVec3| (b - a).cross(c - a).z;
                let total = area(t[0], t[1], t[2]);
                for k in 0..3 {
                    let w = area(*p, t[(k + 1) % 3], t[(k + 2) % 3]) / total;
                    assert!(w > 0.0, "{levels}: {p} outside");
                }
            }
            // Distinct cells: no two samples share a point.
            for a in 0..n {
                for b in a + 1..n {
                    assert!(cells[a].distance(cells[b]) > 1e-9);
                }
            }
        }
    }

    #[test]
    fn samples_carry_the_emitters_power_and_lie_on_them() {
        let mut s = Scene::empty();
        let lamp = s.add_material(Material {
            ke: DVec3::new(17.0, 12.0, 4.0),
            ..Material::diffuse("lamp", 0.0)
        });
        let dim = s.add_material(Material {
            ke: DVec3::splat(1.0),
            ..Material::diffuse("dim", 0.0)
        });
        // A 1×1 lamp facing down at y = 1 and a 2×1 dim panel facing +x at x = 0.
        s.add_mesh(
            "lamp",
            vec![
                DVec3::new(0.0, 1.0, 0.0),
                DVec3::new(1.0, 1.0, 0.0),
                DVec3::new(1.0, 1.0, 1.0),
                DVec3::new(0.0, 1.0, 1.0),
            ],
            vec![[0, 1, 2], [0, 2, 3]],
            lamp,
        );
        s.add_mesh(
            "panel",
            vec![
                DVec3::new(0.0, 0.0, 0.0),
                DVec3::new(0.0, 1.0, 0.0),
                DVec3::new(0.0, 1.0, 2.0),
                DVec3::new(0.0, 0.0, 2.0),
            ],
            vec![[0, 1, 2], [0, 2, 3]],
            dim,
        );
        let samples = sample(&s, 64);
        assert_eq!(samples.len(), 64);
        // Power (radiance × area) summed over samples is each emitter's, up to the rounding of
        // each one's share of the n samples (within 1/n of the total).
        let mut power = DVec3::ZERO;
        for l in &samples {
            let Light::EmitterSample {
                position,
                normal,
                radiance,
                area,
                ..
            } = *l
            else {
                panic!("not an emitter sample");
            };
            power += radiance * area;
            let on_lamp = (position.y - 1.0).abs() < 1e-5 && normal.y < -0.99;
            let on_panel = position.x.abs() < 1e-5 && normal.x > 0.99;
            assert!(on_lamp || on_panel, "{position:?} {normal:?}");
        }
        let want = DVec3::new(17.0, 12.0, 4.0) * 1.0 + DVec3::splat(1.0) * 2.0;
        let weighted = |p: DVec3| weight(p);
        assert!(
            (weighted(power) - weighted(want)).abs() < weighted(want) / 64.0,
            "{power:?} vs {want:?}"
        );
        // Deterministic, and none for a scene without emitters.
        assert_eq!(sample(&s, 64), samples);
        assert!(sample(&Scene::empty(), 16).is_empty());
        assert!(sample(&s, 0).is_empty());
        // Fewer samples than triangles: points without cells.
        assert!(sample(&s, 3)
            .iter()
            .all(|l| matches!(l, Light::EmitterSample { cell: None, .. })));
    }

    /// Where the samples tile the emitters, their cells' light summed is the emitters' exact
    /// unoccluded irradiance at any distance (1% to 10 times the panel's size), and that of a
    /// receiver whose plane cuts the panel.
    #[test]
    fn tiling_cells_give_the_exact_irradiance() {
        let mut s = Scene::empty();
        let m = s.add_material(Material {
            ke: DVec3::splat(2.0),
            ..Material::diffuse("panel", 0.0)
        });
        // A 2×2 square at y = 1 facing down, centred over the origin.
        s.add_mesh(
            "panel",
            vec![
                DVec3::new(-1.0, 1.0, -1.0),
                DVec3::new(1.0, 1.0, -1.0),
                DVec3::new(1.0, 1.0, 1.0),
                DVec3::new(-1.0, 1.0, 1.0),
            ],
            vec![[0, 1, 2], [0, 2, 3]],
            m,
        );
        // On the axis at height 1 − h: four 1×1 rectangles with a corner over the point
        // (E = π·L·F, F the corner form factor of a parallel rectangle).
        let exact = |h: f64| {
            let x: f64 = 1.0 / h;
            let a = x / (1.0 + x * x).sqrt() * (x / (1.0 + x * x).sqrt()).atan();
            let f = (a + a) / (2.0 * std::f64::consts::PI);
            4.0 * std::f64::consts::PI * 2.0 * f
        };
        // The samples' light on a receiver at `p` of normal `n`.
        let irradiance = |samples: &[Light], p: DVec3, n: DVec3| -> f64 {
            samples
                .iter()
                .map(|l| {
                    let inc = crate::frame::lights::incident(l, p).unwrap();
                    crate::frame::lights::irradiance_on(l, &inc, p, n).x
                })
                .sum()
        };
        for n in [2, 5, 32] {
            let samples = sample(&s, n);
            let area: f64 = samples
                .iter()
                .map(|l| match *l {
                    Light::EmitterSample { area, .. } => area,
                    _ => 0.0,
                })
                .sum();
            assert!((area - 4.0).abs() < 1e-12, "{n}: {area}");
            for h in [0.01, 0.1, 1.0, 10.0] {
                let p = DVec3::new(0.0, 1.0 - h, 0.0);
                let e = irradiance(&samples, p, DVec3::Y);
                let want = exact(h);
                assert!((e - want).abs() < 1e-9 * want, "{n} at {h}: {e} vs {want}");
            }
        }
        // A receiver whose plane cuts the panel (a wall under its middle, facing +x): the
        // clipped cells against a fine point quadrature of the half in front.
        let (p, nx) = (DVec3::new(0.0, 0.5, 0.0), DVec3::X);
        let e = irradiance(&sample(&s, 8), p, nx);
        let k = 800;
        let mut want = 0.0;
        for i in 0..k {
            for j in 0..k {
                let q = DVec3::new(
                    (i as f64 + 0.5) / k as f64,
                    1.0,
                    2.0 * (j as f64 + 0.5) / k as f64 - 1.0,
                );
                let v = q - p;
                let r2 = v.length_squared();
                want += 2.0 * (v.dot(nx) * 0.5) / (r2 * r2) * (2.0 / (k * k) as f64);
            }
        }
        assert!((e - want).abs() < 1e-4 * want, "clipped: {e} vs {want}");
    }
}

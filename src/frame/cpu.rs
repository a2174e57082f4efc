//! The frame on the CPU: the same image formation as the GPU frame passes (`src/gpu/frame.rs`),
//! by ray casting at the same 2×2 sample positions: emission, per-pixel direct light with the
//! shadow maps (at the interpolated shading normal where the mesh has `vn`, `shading.rs`),
//! indirect light splatted or vertex-interpolated, environment where rays escape;
//! pixels at an emitter's edge take its emission from sub-pixel rays (`edges.rs`).

use super::camera::{View, SUPERSAMPLE};
use super::direct;
use super::edges::{EmitterTriangles, SampleHit};
use super::image::Image;
use super::lights::{direct_radiance_from, LightSet, Receiver};
use super::shading::{eye_direction, shading_normal};
use super::splat::{pixel_sum, SplatGrid};
use super::surfaces::{display_bin, display_radiance_in, vertex_values, Surfaces, MODE_VERTEX};
use crate::raycast::RayCaster;
use crate::scene::{Camera, Material, Scene};
use crate::solver::Table;
use crate::system::System;
use glam::DVec3;
use rayon::prelude::*;

/// A 2×2 sample's surface point facing the eye: what its direct light needs, and its
/// indirect light (splatted or vertex-interpolated).
#[derive(Clone, Copy)]
struct Front {
    p: DVec3,
    slot: usize,
    /// The interpolated shading normal (not normalized; the face normal without `vn`).
    interpolated: DVec3,
    ns: DVec3,
    wo: DVec3,
    indirect: DVec3,
    /// A splatted sample whose indirect light comes from the pixels' sums (`splat.rs`), not yet
    /// taken (meanwhile its own leaf's radiance, what it keeps where no pixel around is on its
    /// surface).
    pending: bool,
}

/// What a 2×2 sample sees: the environment, a face from behind (black), or a face in front.
#[derive(Clone, Copy)]
enum Seen {
    Background,
    Back,
    Front(Front),
}

/// Indirect light per sample from a method's own view-independent store (image-based
/// radiosity's cube) rather than from the elements' bins.
pub trait SampleIndirect: Sync {
    /// Radiance toward the eye at `p`, on a face of unit normal `n` and material `m`.
    fn radiance(&self, p: DVec3, n: DVec3, m: &Material) -> DVec3;
}

/// Renders `camera`'s view of `scene` from the solved display intensities `i_total`, or with
/// the indirect light of `store` where one is given.
#[allow(clippy::too_many_arguments)]
pub fn render(
    scene: &Scene,
    lit: &LightSet<'_>,
    camera: &Camera,
    sys: &System,
    i_total: &Table,
    surf: &Surfaces,
    caster: &RayCaster,
    store: Option<&dyn SampleIndirect>,
) -> Image {
    let (lights, maps) = (lit.lights, lit.maps);
    let view = View::new(camera);
    let verts = vertex_values(surf, sys, i_total, view.eye);
    let grid = SplatGrid::new(surf);
    let (w, h) = (view.width as usize, view.height as usize);
    let ss = SUPERSAMPLE as usize;
    let (sw, sh) = (w * ss, h * ss);
    let emitters = EmitterTriangles::new(scene);
    let per_sample = surf.splat_per_sample;
    // Every 2×2 sample first: what it sees, its emission, and what it hit (for the emitter
    // edges, `edges.rs`); the direct light comes per pixel, below.
    let mut samples = vec![(Seen::Background, DVec3::ZERO, SampleHit::Background); sw * sh];
    samples
        .par_chunks_mut(sw)
        .enumerate()
        .for_each(|(sy, row)| {
            for (sx, out) in row.iter_mut().enumerate() {
                let x = (sx as f64 + 0.5) / SUPERSAMPLE as f64;
                let y = (sy as f64 + 0.5) / SUPERSAMPLE as f64;
                let d = view.ray(x, y);
                *out = match caster.closest(view.eye, d, 0.0, f64::INFINITY) {
                    None => (Seen::Background, DVec3::ZERO, SampleHit::Background),
                    Some(hit) => {
                        // The face slot hit, and its leaf (another where it is a cluster's).
                        let li = hit.shape as usize;
                        let leaf = &sys.leaves[hit.leaf as usize];
                        let normal = surf.normal[li];
                        let c = caster.corners(hit.shape);
                        let p = c[0] * (1.0 - hit.u - hit.v) + c[1] * hit.u + c[2] * hit.v;
                        let mat = &sys.materials[leaf.material as usize];
                        let kind = if mat.ke.max_element() > 0.0 {
                            SampleHit::Emitter
                        } else {
                            SampleHit::Surface((p - view.eye).length())
                        };
                        let wo = -d;
                        if wo.dot(normal) <= 0.0 {
                            (Seen::Back, DVec3::ZERO, kind) // one-sided: the back is black
                        } else {
                            // The shading normal lights the pixel and picks the bin toward
                            // the eye (`shading.rs`); without `vn` it is the face normal.
                            let (interpolated, ns, dir) = if surf.shaded[li] {
                                let n = surf.interpolated_normal(li, hit.u, hit.v);
                                let ns = shading_normal(n, normal, wo);
                                (n, ns, eye_direction(wo, ns, normal))
                            } else {
                                (normal, normal, wo)
                            };
                            let mut pending = false;
                            let indirect = if let Some(store) = store {
                                store.radiance(p, normal, mat)
                            } else if surf.mode[li] == MODE_VERTEX {
                                let cv = surf.corner_vertex[li];
                                verts[cv[0] as usize] * (1.0 - hit.u - hit.v)
                                    + verts[cv[1] as usize] * hit.u
                                    + verts[cv[2] as usize] * hit.v
                            } else if per_sample || (sx % ss == 0 && sy % ss == 0) {
                                let bin = display_bin(sys, dir, normal);
                                grid.radiance(surf, sys, i_total, p, surf.surface[li], bin)
                            } else {
                                // Its own leaf's radiance where no pixel around has its
                                // surface (`splat.rs`); else replaced by a pixel's sum below.
                                pending = true;
                                display_bin(sys, dir, normal).map_or(DVec3::ZERO, |b| {
                                    display_radiance_in(sys, i_total, surf.leaf[li] as usize, b)
                                })
                            };
                            let front = Front {
                                p,
                                slot: li,
                                interpolated,
                                ns,
                                wo,
                                indirect,
                                pending,
                            };
                            (Seen::Front(front), mat.ke, kind)
                        }
                    }
                };
            }
        });
    if !per_sample {
        take_pixel_sums(&mut samples, surf, (w, h));
    }
    let sample =
        |px: usize, py: usize, i: usize, j: usize| &samples[(py * ss + j) * sw + px * ss + i];
    let sees_emitter = |px: usize, py: usize| {
        (py.saturating_sub(1)..(py + 2).min(h)).any(|y| {
            (px.saturating_sub(1)..(px + 2).min(w)).any(|x| {
                (0..ss).any(|j| (0..ss).any(|i| sample(x, y, i, j).2 == SampleHit::Emitter))
            })
        })
    };
    let material =
        |slot: usize| &sys.materials[sys.leaves[surf.leaf[slot] as usize].material as usize];
    // The area emitters' samples, shared among a pixel's samples (empty: none shared).
    let shared_lights = lit.shared.clone();
    let direct_at = |f: &Front, range| {
        let r = Receiver {
            p: f.p,
            n: surf.normal[f.slot],
            shading: f.ns,
            wo: f.wo,
        };
        direct_radiance_from(lights, maps, &r, material(f.slot), range)
    };
    let seen_at = |px: usize, py: usize| -> [Seen; (SUPERSAMPLE * SUPERSAMPLE) as usize] {
        std::array::from_fn(|k| sample(px, py, k % ss, k / ss).0)
    };
    // The shared lights' direct light at a pixel's samples' mean (`shared_direct`).
    let shared_at = |(mid, interpolated, slot): (DVec3, DVec3, usize)| {
        let normal = surf.normal[slot];
        let wo = (view.eye - mid).normalize();
        if wo.dot(normal) <= 0.0 {
            return DVec3::ZERO;
        }
        let ns = if surf.shaded[slot] {
            shading_normal(interpolated, normal, wo)
        } else {
            normal
        };
        let r = Receiver {
            p: mid,
            n: normal,
            shading: ns,
            wo,
        };
        direct_radiance_from(lights, maps, &r, material(slot), shared_lights.clone())
    };
    let key = |slot: usize| -> direct::Key {
        let m = sys.leaves[surf.leaf[slot] as usize].material;
        let shaded = if surf.shaded[slot] {
            slot as u32
        } else {
            u32::MAX
        };
        (surf.surface[slot], m, shaded)
    };
    let share = !shared_lights.is_empty();
    // Only the blocks' corner pixels evaluate it; the others interpolate (`direct.rs`).
    let size = (view.width, view.height);
    let block = direct::block_for(surf.direct_block, &shared_lights, size) as usize;
    let (gw, gh) = direct::grid(w, h, block);
    let blocks: Vec<Option<direct::Corner>> = if share && block > 1 {
        (0..gw * gh)
            .into_par_iter()
            .map(|k| {
                let seen = seen_at(k % gw * block, k / gw * block);
                shared_direct(&seen, surf, sys).map(|s| {
                    let inv_depth = 1.0 / (s.0 - view.eye).dot(view.forward);
                    (key(s.2), shared_at(s), inv_depth)
                })
            })
            .collect()
    } else {
        Vec::new()
    };
    let n = (ss * ss) as f64;
    let mut pixels = vec![[0f32; 3]; w * h];
    pixels.par_chunks_mut(w).enumerate().for_each(|(py, row)| {
        for (px, out) in row.iter_mut().enumerate() {
            let seen = seen_at(px, py);
            let shared = share.then(|| shared_direct(&seen, surf, sys)).flatten();
            let shared = shared.map(|s| {
                let corner = |i: usize, j: usize| {
                    if i < gw && j < gh {
                        blocks[j * gw + i]
                    } else {
                        None
                    }
                };
                (block > 1)
                    .then(|| direct::block_direct((px, py), block, key(s.2), corner))
                    .flatten()
                    .unwrap_or_else(|| shared_at(s))
            });
            let (mut rest, mut emission) = (DVec3::ZERO, DVec3::ZERO);
            for k in 0..ss * ss {
                let s = sample(px, py, k % ss, k / ss);
                match &s.0 {
                    Seen::Background => rest += scene.environment,
                    Seen::Front(f) => {
                        let direct = match shared {
                            Some(d) => {
                                d + direct_at(f, 0..shared_lights.start)
                                    + direct_at(f, shared_lights.end..lights.len())
                            }
                            None => direct_at(f, 0..lights.len()),
                        };
                        // Discretization can leave a slightly negative indirect term
                        // (antiradiance over-cancelling); radiance is never negative.
                        rest += (direct + f.indirect).max(DVec3::ZERO);
                        emission += s.1;
                    }
                    Seen::Back => {}
                }
            }
            let emission = if sees_emitter(px, py) {
                emitters.edge_emission(
                    view.eye,
                    |x, y| view.ray(x, y),
                    px as u32,
                    py as u32,
                    |i, j| sample(px, py, i, j).2,
                )
            } else {
                emission / n
            };
            let v = rest / n + emission;
            *out = [v.x as f32, v.y as f32, v.z as f32];
        }
    });
    Image {
        width: view.width,
        height: view.height,
        pixels,
    }
}

/// Gives each pending splatted sample its value from the sums of the pixels' first samples,
/// which were evaluated (`splat.rs` pixel_sum); `size` is the image's in pixels.
fn take_pixel_sums(
    samples: &mut [(Seen, DVec3, SampleHit)],
    surf: &Surfaces,
    size: (usize, usize),
) {
    let ss = SUPERSAMPLE as usize;
    let (w, h) = size;
    let sw = w * ss;
    let first = |x: i64, y: i64| {
        if x < 0 || y < 0 || x >= w as i64 || y >= h as i64 {
            return None;
        }
        match &samples[y as usize * ss * sw + x as usize * ss].0 {
            Seen::Front(f) if surf.mode[f.slot] != MODE_VERTEX => {
                Some((surf.surface[f.slot], f.indirect))
            }
            _ => None,
        }
    };
    let taken: Vec<(usize, DVec3)> = (0..samples.len())
        .into_par_iter()
        .filter_map(|k| match &samples[k].0 {
            Seen::Front(f) if f.pending => {
                let (sx, sy) = ((k % sw) as i64, (k / sw) as i64);
                let (px, py) = (sx / ss as i64, sy / ss as i64);
                let within = (sx % ss as i64, sy % ss as i64);
                pixel_sum((px, py), within, ss as i64, surf.surface[f.slot], first).map(|v| (k, v))
            }
            _ => None,
        })
        .collect();
    for (k, v) in taken {
        if let Seen::Front(f) = &mut samples[k].0 {
            f.indirect = v;
            f.pending = false;
        }
    }
}

/// Where a pixel's samples share one evaluation of the area emitters' direct light
/// (glsl/compose.frag ar_shares_direct): all hit a face from its front, on one flat surface of
/// one material without shading normals, or on one face slot. Returns their mean position, the
/// sum of their interpolated normals and the first sample's slot. That light is smooth there (a
/// penumbra over 32 emitter samples), so one evaluation at the mean differs from the samples'
/// mean by the curvature of the shading within a pixel; it is most of the frame's cost (32
/// shadow-mapped samples per emitter). Point, spot and directional lights stay per sample:
/// their shadow edges can be sharper than a pixel.
fn shared_direct(seen: &[Seen], surf: &Surfaces, sys: &System) -> Option<(DVec3, DVec3, usize)> {
    let material = |slot: usize| sys.leaves[surf.leaf[slot] as usize].material;
    let first = seen.first()?;
    let slot0 = match first {
        Seen::Front(f) => f.slot,
        _ => return None,
    };
    let (mut mid, mut normal) = (DVec3::ZERO, DVec3::ZERO);
    for s in seen {
        let Seen::Front(f) = s else { return None };
        if f.slot != slot0
            && (surf.surface[f.slot] != surf.surface[slot0]
                || material(f.slot) != material(slot0)
                || surf.shaded[f.slot]
                || surf.shaded[slot0])
        {
            return None;
        }
        mid += f.p;
        normal += f.interpolated;
    }
    Some((mid / seen.len() as f64, normal, slot0))
}

//! Local pass at the leaves: reflection (eq. 18) into front bins, antiradiance (eq. 19) into
//! back bins, and the display intensity `I_total`. A surface is opaque from both sides: light
//! arriving at a leaf's back is not reflected but blocked, so it becomes antiradiance leaving
//! the front, `I_ex = I_L − a·c·cos·L_t` in a front bin. Not on a closed solid's surface
//! ([`crate::solids`]): light inside a solid was already cancelled by its near face.

use super::{CpuSolver, LocalMode};
use crate::brdf::{lobe_shape, mirror};
use glam::DVec3;
use rayon::prelude::*;
use std::f64::consts::PI;

/// Runs the local pass over all leaves, updating `i_ex` (per `mode`) and `i_total`.
pub fn local(s: &mut CpuSolver<'_>, mode: LocalMode) {
    let sys = s.sys;
    let s = &mut s.state;
    let m = sys.bins.count;
    let w = sys.bins.omega;
    let (l_push, direct, env) = (&s.l_push, s.direct_in.as_ref(), s.environment);
    // Without antiradiance (nothing can occlude) the back bins stay zero.
    let antiradiance = s.antiradiance;
    let emission = s.emission;
    s.i_ex
        .data
        .par_chunks_mut(m)
        .zip(s.i_total.data.par_chunks_mut(m))
        .enumerate()
        .for_each(|(node, (ex, tot))| {
            let slot = sys.leaf_slot[node];
            if slot == u32::MAX {
                return;
            }
            let leaf = &sys.leaves[slot as usize];
            let mat = &sys.materials[leaf.material as usize];
            let ke = if emission { mat.ke } else { DVec3::ZERO };
            let (n, c, a) = (leaf.normal, leaf.cos_norm, leaf.area);
            let lp = l_push.row(node);
            let dr = direct.map(|d| d.row(node));
            // Incident bins on the front side, with their quadrature weight (−cos)·ω·c.
            let incoming: Vec<(usize, f64)> = sys
                .bins
                .centers
                .iter()
                .enumerate()
                .filter_map(|(l, d)| {
                    let cos = -d.dot(n);
                    (cos > 0.0).then_some((l, cos * w * c))
                })
                .collect();
            let lt = |l: usize| lp[l] + env;
            let ld = |l: usize| dr.map_or(DVec3::ZERO, |d| d[l]);
            let e_t: DVec3 = incoming.iter().map(|&(l, wt)| lt(l) * wt).sum();
            let e_d: DVec3 = incoming.iter().map(|&(l, wt)| ld(l) * wt).sum();
            // The lobe as the bins sample it (effective exponent, per-bin albedo factors).
            let lobe = sys.lobes[leaf.material as usize]
                .zip(sys.lobe_factors(slot as usize))
                .map(|(lobe, f)| {
                    let mirrored: Vec<DVec3> = incoming
                        .iter()
                        .map(|&(l, _)| mirror(sys.bins.centers[l], n))
                        .collect();
                    (lobe, f, mirrored)
                });
            for (j, dir) in sys.bins.centers.iter().enumerate() {
                let cj = dir.dot(n);
                if cj > 0.0 {
                    if mode == LocalMode::Antiradiance {
                        continue;
                    }
                    let base = a * c * cj;
                    let (mut r_t, mut r_d) = (mat.kd / PI * e_t, mat.kd / PI * e_d);
                    if let Some((lobe, factors, mirrored)) = &lobe {
                        for (&(l, wt), r) in incoming.iter().zip(mirrored) {
                            // The truncated lobe (brdf::LOBE_CUTOFF), as the GPU sums it.
                            let cos_alpha = r.dot(*dir);
                            if !lobe.keeps(cos_alpha) {
                                continue;
                            }
                            let shape = lobe_shape(lobe.exponent, cos_alpha);
                            let f = mat.ks * (shape * factors[l] as f64 * wt);
                            r_t += f * lt(l);
                            r_d += f * ld(l);
                        }
                    }
                    tot[j] = base * r_t;
                    // Light arriving at the back in bin j is blocked: antiradiance out the front.
                    let blocked = if antiradiance && leaf.blocks_back {
                        lt(j)
                    } else {
                        DVec3::ZERO
                    };
                    ex[j] = base * (r_t + r_d + ke - blocked);
                } else if cj < 0.0 {
                    if mode == LocalMode::Reflect {
                        continue;
                    }
                    tot[j] = DVec3::ZERO;
                    ex[j] = if antiradiance {
                        -(a * c * -cj) * lt(j)
                    } else {
                        DVec3::ZERO
                    };
                } else {
                    tot[j] = DVec3::ZERO;
                    ex[j] = DVec3::ZERO;
                }
            }
        });
}

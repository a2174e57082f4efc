//! Local pass at the leaves: reflection (eq. 18) into front bins, antiradiance (eq. 19) into
//! back bins, and the display intensity `I_total`. A surface is opaque from both sides: light
//! arriving at a leaf's back is not reflected but blocked, so it becomes antiradiance leaving
//! the front, `I_ex = I_L − a·c·cos·L_t` in a front bin. Not on a closed solid's surface
//! ([`crate::solids`]): light inside a solid was already cancelled by its near face.

use super::{CpuSolver, LocalMode, Table};
use crate::brdf::{lobe_shape, mirror, DiscreteLobe};
use crate::system::System;
use glam::DVec3;
use rayon::prelude::*;
use std::f64::consts::PI;

/// A leaf's reflection as the local pass samples it: its front-side incident bins with their
/// quadrature weight (−cos)·ω·c, and its discrete glossy lobe (effective exponent, per-bin
/// albedo factors, the incident bins' mirror directions).
struct Reflector<'a> {
    kd: DVec3,
    ks: DVec3,
    incoming: Vec<(usize, f64)>,
    lobe: Option<(&'a DiscreteLobe, &'a [f32], Vec<DVec3>)>,
}

impl<'a> Reflector<'a> {
    fn new(sys: &'a System, slot: usize) -> Self {
        let leaf = &sys.leaves[slot];
        let mat = &sys.materials[leaf.material as usize];
        let (n, w, c) = (leaf.normal, sys.bins.omega, leaf.cos_norm);
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
        let lobe = sys.lobes[leaf.material as usize]
            .as_ref()
            .zip(sys.lobe_factors(slot))
            .map(|(lobe, f)| {
                let mirrored = incoming
                    .iter()
                    .map(|&(l, _)| mirror(sys.bins.centers[l], n))
                    .collect();
                (lobe, f, mirrored)
            });
        Self {
            kd: mat.kd,
            ks: mat.ks,
            incoming,
            lobe,
        }
    }

    /// Irradiance of incident radiance `l(bin)`.
    fn irradiance(&self, l: impl Fn(usize) -> DVec3) -> DVec3 {
        self.incoming.iter().map(|&(b, wt)| l(b) * wt).sum()
    }

    /// Radiance reflected toward `dir` of incident radiance `l(bin)` whose irradiance is `e`.
    fn reflect(&self, e: DVec3, dir: DVec3, l: impl Fn(usize) -> DVec3) -> DVec3 {
        let mut r = self.kd / PI * e;
        if let Some((lobe, factors, mirrored)) = &self.lobe {
            for (&(b, wt), m) in self.incoming.iter().zip(mirrored) {
                // The truncated lobe (brdf::LOBE_CUTOFF), as the GPU sums it.
                let cos_alpha = m.dot(dir);
                if !lobe.keeps(cos_alpha) {
                    continue;
                }
                let shape = lobe_shape(lobe.exponent, cos_alpha);
                r += self.ks * (shape * factors[b] as f64 * wt) * l(b);
            }
        }
        r
    }
}

/// The leaves' first bounce of direct light, per node and bin: `a·c·cos·(kd/π·E_d + Σ f·L_d)`
/// in front bins (eq. 18's reflection of the direct incident table `direct_in`), zero
/// elsewhere. It does not change between iterations, so both solvers compute it once per
/// direct-light table and the local pass adds it, instead of summing the direct light's lobe
/// every iteration.
pub fn direct_exitant(sys: &System, direct_in: &Table) -> Table {
    let m = sys.bins.count;
    let mut out = Table::zeros(sys.rows(), m);
    out.data
        .par_chunks_mut(m)
        .enumerate()
        .for_each(|(node, ex)| {
            let slot = sys.leaf_slot[node];
            if slot == u32::MAX {
                return;
            }
            let leaf = &sys.leaves[slot as usize];
            let r = Reflector::new(sys, slot as usize);
            let ld = |l: usize| direct_in.row(node)[l];
            let e_d = r.irradiance(ld);
            for (j, dir) in sys.bins.centers.iter().enumerate() {
                let cj = dir.dot(leaf.normal);
                if cj > 0.0 {
                    ex[j] = leaf.area * leaf.cos_norm * cj * r.reflect(e_d, *dir, ld);
                }
            }
        });
    out
}

/// Runs the local pass over all leaves, updating `i_ex` (per `mode`) and `i_total`.
pub fn local(s: &mut CpuSolver<'_>, mode: LocalMode) {
    let sys = s.sys;
    let s = &mut s.state;
    let m = sys.bins.count;
    let (l_push, direct) = (&s.l_push, s.direct_ex.as_ref());
    let env = s.environment_ex.as_ref();
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
            let dx = direct.map(|d| d.row(node));
            let ev = env.map(|d| d.row(node));
            let r = Reflector::new(sys, slot as usize);
            let lt = |l: usize| lp[l];
            let e_t = r.irradiance(lt);
            for (j, dir) in sys.bins.centers.iter().enumerate() {
                let cj = dir.dot(n);
                if cj > 0.0 {
                    if mode == LocalMode::Antiradiance {
                        continue;
                    }
                    let base = a * c * cj;
                    let r_t = r.reflect(e_t, *dir, lt);
                    // The shadowed environment's first bounce, reflected once: shown and sent.
                    let sky = ev.map_or(DVec3::ZERO, |d| d[j]);
                    tot[j] = base * r_t + sky;
                    // Light arriving at the back in bin j is blocked: antiradiance out the front.
                    let blocked = if antiradiance && leaf.blocks_back {
                        lt(j)
                    } else {
                        DVec3::ZERO
                    };
                    // The first bounce of direct light ([`direct_exitant`]) adds to I_ex only.
                    let first = dx.map_or(DVec3::ZERO, |d| d[j]);
                    ex[j] = base * (r_t + ke - blocked) + first + sky;
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::CpuSolver;

    fn plane(ks: f64) -> System {
        System::build(&crate::scene::test_plane(ks)).unwrap()
    }

    /// Direct light of one radiance in every bin: a Lambertian leaf's first bounce is
    /// `a·c·cos·kd/π·E` in its front bins, `E = Σ_front L·cos·ω·c`, and zero behind and on
    /// cluster rows.
    #[test]
    fn direct_exitant_of_a_lambertian_leaf() {
        let sys = plane(0.0);
        let l = DVec3::new(1.0, 2.0, 3.0);
        let mut direct = Table::zeros(sys.rows(), sys.bins.count);
        for leaf in &sys.leaves {
            direct.row_mut(leaf.node as usize).fill(l);
        }
        let d = direct_exitant(&sys, &direct);
        for leaf in &sys.leaves {
            let n = leaf.normal;
            let e: DVec3 = sys
                .bins
                .centers
                .iter()
                .filter(|b| b.dot(n) < 0.0)
                .map(|b| l * (-b.dot(n) * sys.bins.omega * leaf.cos_norm))
                .sum();
            for (j, dir) in sys.bins.centers.iter().enumerate() {
                let c = dir.dot(n);
                let want = if c > 0.0 {
                    leaf.area * leaf.cos_norm * c * 0.5 / PI * e
                } else {
                    DVec3::ZERO
                };
                let got = d.row(leaf.node as usize)[j];
                assert!((got - want).length() <= 1e-12 * want.length().max(1.0));
            }
        }
        for r in (0..sys.rows()).filter(|&r| sys.leaf_slot[r] == u32::MAX) {
            assert!(d.row(r).iter().all(|v| *v == DVec3::ZERO));
        }
    }

    /// With a glossy lobe, a local pass adds exactly the first bounce to I_ex and nothing to
    /// I_total (the first bounce of direct light is drawn per pixel).
    #[test]
    fn the_local_pass_adds_the_first_bounce_to_i_ex_only() {
        let sys = plane(0.3);
        assert!(sys.lobes.iter().any(|l| l.is_some()));
        let light = |_: usize, b: usize| DVec3::new(0.1, 0.2, 0.3) * (1.0 + b as f64 * 0.05);
        let mut lit = CpuSolver::new(&sys);
        lit.set_direct(light);
        lit.initialize();
        let mut dark = CpuSolver::new(&sys);
        dark.initialize();
        let first = lit.direct_exitant().unwrap().clone();
        assert!(first.data.iter().any(|v| v.length() > 0.0));
        for leaf in &sys.leaves {
            let r = leaf.node as usize;
            for j in 0..sys.bins.count {
                let added = lit.i_ex.row(r)[j] - dark.i_ex.row(r)[j];
                assert!((added - first.row(r)[j]).length() <= 1e-12);
                assert_eq!(lit.i_total.row(r)[j], dark.i_total.row(r)[j]);
            }
        }
    }
}

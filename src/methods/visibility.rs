//! Explicit visibility of the links (hierarchical radiosity's, §5 and Fig. 14f of the paper):
//! each link gets the fraction of its transport that is unoccluded, estimated by rays between
//! points on its two ends, cast in parallel with the project's ray caster.
//!
//! The rays of a link join point `k` on the sender to point `k` on the receiver (a 6-D Kronecker
//! sequence with a per-link random offset: stratified, unbiased). A leaf is sampled uniformly by
//! area; a receiving cluster picks one of its leaves by area, then a point on it. A sending
//! cluster picks its leaves by their expected radiosity × area ([`sender_weights`]): its exitant
//! intensity is what its leaves send, and a cluster holding an emitter and the ceiling behind it
//! sends the emitter's light, not the hidden ceiling's (by area alone, the Cornell box's lamp
//! cluster came out half occluded by the lamp itself and the image 22% too dark). Each pair is weighted by
//! the point-to-point kernel `cos_s·cos_r / r²` (r² bounded below by the sender's disc radius², as
//! the form factor is), so the fraction is the form-factor-weighted visibility
//! `∫∫ G·V / ∫∫ G`; pairs where either leaf faces away carry no transport and cast no ray.

use super::Sequence;
use crate::raycast::RayCaster;
use crate::system::System;
use glam::DVec3;
use rayon::prelude::*;
use std::f64::consts::PI;
use std::time::Instant;

/// What computing the visibility cost and found.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct VisibilityStats {
    /// Rays cast.
    pub rays: u64,
    /// Wall time (ms).
    pub ms: f64,
    /// Links none of whose rays got through.
    pub occluded: usize,
    /// Links some of whose rays were blocked and some not.
    pub partial: usize,
}

/// How much each leaf is expected to send per unit area, for picking a sending cluster's
/// leaves: its emitted exitance π·Ke plus its albedo times the mean radiosity the emitters would
/// sustain in a closed room of the scene's mean albedo (luminance-like means of RGB). Without
/// emitters every leaf weighs its albedo (analytic lights' light is then all reflected light).
pub fn sender_weights(sys: &System) -> Vec<f64> {
    let mean = |v: DVec3| v.element_sum() / 3.0;
    let mat = |l: &crate::system::LeafAttributes| &sys.materials[l.material as usize];
    let area: f64 = sys.leaves.iter().map(|l| l.area).sum();
    let emitted: f64 = sys
        .leaves
        .iter()
        .map(|l| l.area * PI * mean(mat(l).ke))
        .sum();
    let rho = sys
        .leaves
        .iter()
        .map(|l| l.area * mean(mat(l).kd + mat(l).ks))
        .sum::<f64>()
        / area.max(1e-300);
    let rho = rho.min(0.95);
    let reflected = if emitted > 0.0 {
        emitted * rho / (area * (1.0 - rho))
    } else {
        1.0
    };
    sys.leaves
        .iter()
        .map(|l| PI * mean(mat(l).ke) + mean(mat(l).kd + mat(l).ks) * reflected)
        .collect()
}

/// Where a node's leaves lie among the leaf slots, and the prefix sums to pick them by.
struct Sampler<'a> {
    sys: &'a System,
    /// Per node: its leaves are slots `range[n].0 .. range[n].1`.
    range: Vec<(u32, u32)>,
    /// `area[i]` = area of leaf slots `0..i` (receivers pick by it).
    area: Vec<f64>,
    /// `send[i]` = [`sender_weights`] × area of leaf slots `0..i` (senders pick by it).
    send: Vec<f64>,
}

impl<'a> Sampler<'a> {
    fn new(sys: &'a System) -> Self {
        let leaves = &sys.hierarchy.leaves;
        let range = sys
            .hierarchy
            .nodes
            .iter()
            .enumerate()
            .map(|(i, n)| {
                // Depth-first order: a subtree's rows are [i, end) and its leaves contiguous.
                let lo = leaves.partition_point(|&l| l < i as u32) as u32;
                let hi = leaves.partition_point(|&l| l < n.end) as u32;
                (lo, hi)
            })
            .collect();
        let prefix = |w: &mut dyn FnMut(usize) -> f64| {
            let mut cdf = Vec::with_capacity(sys.leaves.len() + 1);
            cdf.push(0.0);
            for i in 0..sys.leaves.len() {
                cdf.push(cdf[i] + w(i));
            }
            cdf
        };
        let weights = sender_weights(sys);
        Self {
            sys,
            range,
            area: prefix(&mut |i| sys.leaves[i].area),
            send: prefix(&mut |i| sys.leaves[i].area * weights[i]),
        }
    }

    /// A point on node `n` and its normal, from three uniform numbers; `sending` picks a
    /// cluster's leaves by what they send, else by area.
    fn point(&self, n: u32, u: [f64; 3], sending: bool) -> (DVec3, DVec3) {
        let (lo, hi) = self.range[n as usize];
        let by_weight = sending && self.send[hi as usize] > self.send[lo as usize];
        let cdf = if by_weight { &self.send } else { &self.area };
        let slot = if hi - lo <= 1 {
            lo as usize
        } else {
            let (a, b) = (cdf[lo as usize], cdf[hi as usize]);
            let t = a + u[0] * (b - a);
            (cdf.partition_point(|&c| c <= t) - 1).clamp(lo as usize, hi as usize - 1)
        };
        let leaf = &self.sys.leaves[slot];
        let e = self.sys.hierarchy.element(leaf.node).expect("leaf slot") as usize;
        let p = self.sys.elements[e].point(u[1], u[2]);
        (p, leaf.normal)
    }
}

/// The visibility fraction of every link of `sys` (in link order) from `rays` rays each.
pub fn link_visibility(sys: &System, caster: &RayCaster, rays: u32) -> (Vec<f64>, VisibilityStats) {
    let t = Instant::now();
    let sampler = Sampler::new(sys);
    let root = &sys.hierarchy.nodes[0];
    // Rays leave and reach the surfaces this far off them (far below any element, far above
    // float rounding of the coordinates).
    let eps = 1e-6 * (root.radius + root.center.abs().max_element()).max(1e-300);
    let per_link: Vec<(f64, u64, u8)> = sys
        .links
        .links
        .par_iter()
        .map(|l| {
            let s = &sys.hierarchy.nodes[l.sender as usize];
            let rho2 = (s.area / PI).min(s.radius * s.radius);
            let seq = Sequence::<6>::new((l.receiver as u64) << 32 | l.sender as u64);
            let (mut sum_w, mut sum_v, mut cast, mut blocked) = (0.0, 0.0, 0u64, 0u64);
            for k in 0..rays as usize {
                let u = seq.point(k);
                let (xs, ns) = sampler.point(l.sender, [u[0], u[1], u[2]], true);
                let (xr, nr) = sampler.point(l.receiver, [u[3], u[4], u[5]], false);
                let d = xr - xs;
                let r2 = d.length_squared();
                if r2 <= 0.0 {
                    continue;
                }
                let dir = d / r2.sqrt();
                let (cs, cr) = (ns.dot(dir), -nr.dot(dir));
                if cs <= 0.0 || cr <= 0.0 {
                    continue;
                }
                let w = cs * cr / r2.max(rho2);
                let (o, target) = (xs + ns * eps, xr + nr * eps);
                let seg = target - o;
                let len = seg.length();
                cast += 1;
                sum_w += w;
                if caster.occluded(o, seg / len, 0.0, len) {
                    blocked += 1;
                } else {
                    sum_v += w;
                }
            }
            // A link whose samples all face away carries (almost) nothing: leave it as it is.
            let v = if sum_w > 0.0 { sum_v / sum_w } else { 1.0 };
            let kind = match (blocked, cast) {
                (0, _) => 0,
                (b, c) if b == c => 2,
                _ => 1,
            };
            (v, cast, kind)
        })
        .collect();
    let stats = VisibilityStats {
        rays: per_link.iter().map(|p| p.1).sum(),
        ms: t.elapsed().as_secs_f64() * 1e3,
        occluded: per_link.iter().filter(|p| p.2 == 2).count(),
        partial: per_link.iter().filter(|p| p.2 == 1).count(),
    };
    (per_link.into_iter().map(|p| p.0).collect(), stats)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Material, Scene};

    fn quad(s: &mut Scene, name: &str, p: [DVec3; 4], mat: u32) {
        s.add_mesh(name, p.to_vec(), vec![[0, 1, 2], [0, 2, 3]], mat);
    }

    /// Two facing squares with a screen covering half of the gap between them (as seen along
    /// the axis): the mean visibility of the links is about one half, and without the screen
    /// every link is fully visible.
    #[test]
    fn a_screen_blocks_about_what_it_covers() {
        let v = DVec3::new;
        for screen in [false, true] {
            let mut s = Scene::empty();
            let m = s.add_material(Material::diffuse("grey", 0.5));
            quad(
                &mut s,
                "bottom",
                [v(0., 0., 0.), v(0., 0., 1.), v(1., 0., 1.), v(1., 0., 0.)],
                m,
            );
            quad(
                &mut s,
                "top",
                [v(0., 1., 0.), v(1., 1., 0.), v(1., 1., 1.), v(0., 1., 1.)],
                m,
            );
            if screen {
                // A large plate at mid-height over x < 0.5.
                quad(
                    &mut s,
                    "screen",
                    [
                        v(-5., 0.5, -5.),
                        v(-5., 0.5, 5.),
                        v(0.5, 0.5, 5.),
                        v(0.5, 0.5, -5.),
                    ],
                    m,
                );
            }
            s.solver.element_size = 0.25;
            s.solver.bins = 32;
            let sys = System::build(&s).unwrap();
            let caster = RayCaster::new(&sys);
            let (vis, stats) = link_visibility(&sys, &caster, 64);
            // Links between the two squares, weighted by the transport they carry (∝ the two
            // areas over the squared distance): by symmetry half of it crosses x < 0.5.
            let node = |n: u32| &sys.hierarchy.nodes[n as usize];
            let (mut sum, mut weight, mut count) = (0.0, 0.0, 0);
            for (l, v) in sys.links.links.iter().zip(&vis) {
                let (r, s) = (node(l.receiver), node(l.sender));
                if (r.center.y - s.center.y).abs() < 0.9 {
                    continue;
                }
                let w = r.area * s.area / (r.center - s.center).length_squared();
                sum += w * v;
                weight += w;
                count += 1;
                // Leaves both left of the screen's edge see each other through it; both right,
                // past it.
                let side = |n: u32| {
                    let e = sys.hierarchy.element(n)?;
                    let xs: Vec<f64> = sys.elements[e as usize]
                        .corner_points()
                        .map(|c| c.x)
                        .collect();
                    let (lo, hi) = (
                        xs.iter().cloned().fold(9.0, f64::min),
                        xs.iter().cloned().fold(-9.0, f64::max),
                    );
                    (hi <= 0.5).then_some(-1).or((lo >= 0.5).then_some(1))
                };
                match (side(l.receiver), side(l.sender)) {
                    (Some(-1), Some(-1)) if screen => assert_eq!(*v, 0.0),
                    (Some(1), Some(1)) => assert_eq!(*v, 1.0),
                    _ => {}
                }
            }
            let mean = sum / weight;
            println!(
                "screen {screen}: {count} links between the squares, transport-weighted visibility {mean:.3}, {stats:?}"
            );
            if screen {
                assert!((mean - 0.5).abs() < 0.1, "{mean}");
                assert!(stats.occluded > 0 && stats.partial > 0);
            } else {
                assert!(vis.iter().all(|&x| x == 1.0));
                assert_eq!(stats.occluded + stats.partial, 0);
            }
        }
    }
}

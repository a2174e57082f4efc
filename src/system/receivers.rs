//! Receiver calibration of the push (issue 36): a cluster receives one incident radiance per bin
//! and the push hands it to all its leaves, but the leaves see the cluster's senders under
//! different projected solid angles (nearer or farther, more or less tilted). Per leaf, the
//! ratio of what its ancestors' links should deliver from a uniform unit radiance field (the
//! exact unoccluded projected solid angle, at the leaf, of the leaves below those links'
//! senders) to what they do deliver scales the pushed radiance at that leaf. Measured in
//! docs/measurements.md (issue 36).

use super::System;
use crate::linker::projected_solid_angle;
use crate::scene::{Scene, SolverSettings};
use rayon::prelude::*;

/// Limits of a leaf's factor: where the links are too coarse for a ratio to repair (a leaf
/// whose ancestors deliver almost nothing), the push is left nearly as it was.
const MIN_SCALE: f64 = 0.5;
const MAX_SCALE: f64 = 2.0;

/// An element farther than this many times the sum of the two radii is taken as a point
/// (its area, normal and center): the projected solid angle's relative error is then about
/// the square of the inverse, under 1%.
const FAR: f64 = 10.0;

/// Most leaves calibrated: the terms grow with leaves² and with the faces of near face
/// clusters (`info`, Intel Xeon, 2 cores: the dragon room's 7,786 leaves 4.1 → 11.4 s, the
/// breakfast room's 20,523 leaves 8.5 → 54 s); past this a scene keeps the paper's push, and its
/// plan says so.
pub const MAX_LEAVES: usize = 10_000;

/// Whether an object of `scene` may move (keyframes, `moving = true`, a host's choice): its
/// links follow it, these factors would not, and a still render of a pose must draw what the
/// animation draws there.
fn moves(scene: &Scene) -> bool {
    scene.objects.iter().any(|o| o.moving)
}

/// Whether `sys` (linked) gets push factors for `scene` under `settings`.
pub fn applies(sys: &System, scene: &Scene, settings: &SolverSettings) -> bool {
    settings.receiver_calibration
        && !moves(scene)
        && !sys.links.links.is_empty()
        && sys.leaves.len() <= MAX_LEAVES
}

/// The plan's line on the receiver calibration (`None` for a system without links).
pub fn decision(sys: &System, scene: &Scene, settings: &SolverSettings) -> Option<String> {
    if sys.links.links.is_empty() {
        return None;
    }
    Some(if !sys.push_scale.is_empty() {
        let mut v = sys.push_scale.clone();
        v.sort_by(f64::total_cmp);
        format!(
            "receiver calibration: each leaf scales the radiance its clusters push to it by its own view of their senders (factors {:.2}–{:.2}, median {:.3})",
            v[0],
            v[v.len() - 1],
            v[v.len() / 2]
        )
    } else if !settings.receiver_calibration {
        "receiver calibration off (solver.receiver_calibration = false): every leaf takes its clusters' radiance as pushed".to_string()
    } else if moves(scene) {
        "receiver calibration off: moving objects change every leaf's view of its clusters' senders, and only their links are recomputed per frame; the paper's push".to_string()
    } else {
        format!(
            "receiver calibration off: {} leaves, more than {MAX_LEAVES} (its cost grows with leaves²); the paper's push",
            sys.leaves.len()
        )
    })
}

/// `l_in ← U(i_ex)` on one-channel tables (`rows × bins`), as the global pass gathers.
pub(super) fn gather(sys: &System, i_ex: &[f64], l_in: &mut [f64]) {
    let m = sys.bins.count;
    let links = &sys.links;
    l_in.par_chunks_mut(m).enumerate().for_each(|(r, row)| {
        row.fill(0.0);
        for l in &links.links[links.offsets[r] as usize..links.offsets[r + 1] as usize] {
            let v = i_ex[l.sender as usize * m + l.sender_bin as usize] * l.form_factor;
            if let Some(spread) = sys.filters.row(l.cone, l.receiver_bin as u32) {
                for &(j, w) in spread {
                    if sys.reads(l, j as usize) {
                        row[j as usize] += v * w as f64;
                    }
                }
            }
        }
    });
}

/// `l_push ← push(l_in)` on one-channel tables, each leaf's share scaled by its
/// [`System::push_factor`], as [`crate::solver::push::push`] does.
pub(super) fn push_down(sys: &System, l_in: &[f64], l_push: &mut [f64]) {
    let m = sys.bins.count;
    for (i, node) in sys.hierarchy.nodes.iter().enumerate() {
        let (head, tail) = l_push.split_at_mut(i * m);
        let dst = &mut tail[..m];
        dst.copy_from_slice(&l_in[i * m..(i + 1) * m]);
        if node.parent != u32::MAX {
            let k = sys.push_factor(i as u32);
            let p = node.parent as usize;
            for (j, (d, s)) in dst.iter_mut().zip(&head[p * m..(p + 1) * m]).enumerate() {
                if sys.pushes(i as u32, j) {
                    *d += s * k;
                }
            }
        }
    }
}

/// The exitant intensity of a uniform unit radiance field: `a·c·cos` in every leaf's front
/// bins, pulled into the clusters.
pub(super) fn unit_field(sys: &System) -> Vec<f64> {
    let m = sys.bins.count;
    let mut i_ex = vec![0.0; sys.rows() * m];
    for l in &sys.leaves {
        let row = &mut i_ex[l.node as usize * m..(l.node as usize + 1) * m];
        for (v, c) in row.iter_mut().zip(&sys.bins.centers) {
            let cos = c.dot(l.normal);
            if cos > 0.0 {
                *v = l.area * l.cos_norm * cos;
            }
        }
    }
    pull_sums(sys, &mut i_ex);
    i_ex
}

/// Clusters' rows as the sums of their children's (children follow their parent in
/// pre-order, so a backward sweep sees them first).
pub(super) fn pull_sums(sys: &System, i_ex: &mut [f64]) {
    let m = sys.bins.count;
    let h = &sys.hierarchy;
    for i in (0..h.len()).rev() {
        if let crate::hierarchy::NodeKind::Cluster([a, b]) = h.nodes[i].kind {
            for j in 0..m {
                i_ex[i * m + j] = i_ex[a as usize * m + j] + i_ex[b as usize * m + j];
            }
        }
    }
}

/// Irradiance at leaf `li`'s front from an incident row (per bin), as the local pass sums it.
fn front_irradiance(sys: &System, row: &[f64], li: usize) -> f64 {
    let leaf = &sys.leaves[li];
    let e: f64 = row
        .iter()
        .zip(&sys.bins.centers)
        .map(|(v, c)| v * (-c.dot(leaf.normal)).max(0.0))
        .sum();
    e * sys.bins.omega * leaf.cos_norm
}

/// Unoccluded projected solid angle `∫ cos dω` at leaf `li`'s center, clipped to its front
/// half-space, of leaf `k`'s faces that turn their front to it: Lambert's polygon formula when
/// the two are near, the element as a point (area, normal) when far.
fn element_psa(sys: &System, li: usize, k: usize) -> f64 {
    let h = &sys.hierarchy;
    let leaf = &sys.leaves[li];
    let p = sys.leaf_element(li).center;
    let e = sys.leaf_element(k);
    let v = p - e.center;
    let d2 = v.length_squared();
    let reach =
        FAR * (h.nodes[leaf.node as usize].radius + h.nodes[sys.leaves[k].node as usize].radius);
    if d2 > reach * reach {
        let d = d2.sqrt();
        let (cs, cr) = (e.normal.dot(v) / d, -leaf.normal.dot(v) / d);
        return if cs > 0.0 && cr > 0.0 {
            e.area * cs * cr / d2
        } else {
            0.0
        };
    }
    let mut sum = 0.0;
    for f in &e.faces {
        let [a, b, c] = f.corners;
        let n = (b - a).cross(c - a);
        // Only faces whose front sees the point; a face in its plane exchanges nothing.
        if n.dot(p - a) > 1e-9 * n.length() * (p - a).length() {
            sum += projected_solid_angle(p, leaf.normal, &f.corners);
        }
    }
    sum
}

/// What leaf `li`'s ancestors' links should deliver to it from a unit radiance field: the
/// projected solid angle of every leaf below their senders. Each pair of leaves lies under one
/// link at most, so over all leaves this is `O(leaves²)` at worst.
fn exact_pushed(sys: &System, li: usize) -> f64 {
    let h = &sys.hierarchy;
    let links = &sys.links;
    let mut sum = 0.0;
    let mut a = h.nodes[sys.leaves[li].node as usize].parent;
    while a != u32::MAX {
        let r = a as usize;
        for l in &links.links[links.offsets[r] as usize..links.offsets[r + 1] as usize] {
            let s = l.sender as usize;
            for k in s..h.nodes[s].end as usize {
                let slot = sys.leaf_slot[k];
                if slot != u32::MAX && slot as usize != li {
                    sum += element_psa(sys, li, slot as usize);
                }
            }
        }
        a = h.nodes[r].parent;
    }
    sum
}

/// Every leaf's factor on its ancestors' pushed radiance, normalized so that the area-weighted
/// flux pushed from a unit field is unchanged (in the order of [`System::leaves`]),
/// for a system whose [`System::push_scale`] is still empty.
/// `O(leaves²)` point tests plus exact polygons for near neighbours, and one unscaled
/// propagation of a unit field.
pub fn push_scales(sys: &System) -> Vec<f64> {
    let m = sys.bins.count;
    let i_ex = unit_field(sys);
    let mut l_in = vec![0.0; sys.rows() * m];
    let mut l_push = vec![0.0; sys.rows() * m];
    gather(sys, &i_ex, &mut l_in);
    push_down(sys, &l_in, &mut l_push);
    let raw: Vec<(f64, f64)> = (0..sys.leaves.len())
        .into_par_iter()
        .map(|li| {
            let r = sys.leaves[li].node as usize;
            let own = front_irradiance(sys, &l_in[r * m..(r + 1) * m], li);
            let pushed = front_irradiance(sys, &l_push[r * m..(r + 1) * m], li) - own;
            let exact = exact_pushed(sys, li);
            // A leaf its ancestors reach with (almost) nothing: no ratio to take.
            if pushed <= 1e-9 || exact <= 1e-9 {
                return (1.0, pushed.max(0.0));
            }
            ((exact / pushed).clamp(MIN_SCALE, MAX_SCALE), pushed)
        })
        .collect();
    // Redistribute, do not add: the flux the push delivers from a unit field stays what the
    // calibrated cluster links make it. Unnormalized, the factors' median was 1.04 (the links'
    // spread loses some light below a leaf's horizon) and Veach's room went from 1.19× to
    // 1.22× Mitsuba's mean; normalized, 1.19×.
    let (mut before, mut after) = (0.0, 0.0);
    for (li, &(s, p)) in raw.iter().enumerate() {
        let w = sys.leaves[li].area * p;
        before += w;
        after += w * s;
    }
    let k = if after > 0.0 { before / after } else { 1.0 };
    raw.into_iter().map(|(s, _)| s * k).collect()
}

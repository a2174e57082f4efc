//! The bounded link mesh (§3.3, "Moving Objects and Lights"): links made once, valid for every
//! time of a scene's keyframed motion, so that an animated frame never relinks.
//!
//! At preparation every keyframed object is its own subtree of the hierarchy
//! ([`Hierarchy::build_grouped`]) and the oracle refines a pair if it would refine it at *any*
//! of the motion's sampled poses ([`sample_times`]: the current pose, every key's time and
//! [`SAMPLES_PER_SEGMENT`] steps between consecutive keys; a pair with a moving node is judged
//! at its distance less half the largest distance a point of each moving end travels between
//! two samples, so that the motion between samples is covered too). Pairs of static nodes are refined once, as for a
//! still scene. Per frame `System::follow` moves the elements and the moving nodes and
//! recomputes, for the links with a moving node at either end only, the sides, bins, cone class
//! and calibrated form factor, exactly as preparing the same link at that pose would; the
//! closed scene's energy normalization λ measured at preparation is kept.

use crate::bins::Bins;
use crate::elements::Element;
use crate::filter::FilterTables;
use crate::hierarchy::{Hierarchy, NodeKind};
use crate::linker::{self, Ctx, Link, Links, Step};
use crate::scene::Scene;
use glam::{DMat4, DVec3};
use rayon::prelude::*;
use std::time::Instant;

/// Poses sampled between two consecutive keys (plus the keys themselves). Fewer samples mean
/// a larger travel margin and so more links; measured on the moving Cornell box (README,
/// "Moving lights and objects"), 1 / 4 / 8 / 16 steps: 751 601 / 713 150 / 706 756 / 703 511
/// links, linking 0.65 / 0.7 / 1.05 / 1.5 s.
pub const SAMPLES_PER_SEGMENT: usize = 8;

/// [`Bound::node_group`] of a cluster over more than one group (a top cluster).
pub use crate::meshed::MIXED;
/// [`Bound::node_group`] of a static node.
pub use crate::meshed::STATIC;

/// What moves in a system linked for its whole motion, and how.
#[derive(Debug, Clone)]
pub struct Bound {
    /// The keyframed objects (indices into [`Scene::objects`]); object `objects[g]` is group
    /// `g + 1`, group 0 is everything static.
    pub objects: Vec<usize>,
    /// The object-to-world transform each moving object's elements stand at now.
    pub transforms: Vec<DMat4>,
    /// Group of every node: [`STATIC`], `g + 1` (wholly in `objects[g]`) or [`MIXED`].
    pub node_group: Vec<u32>,
    /// Scene times the motion was sampled at (the pose at preparation comes first).
    pub times: Vec<f64>,
    /// Per moving object, the largest distance a corner travels between consecutive samples.
    pub travel: Vec<f64>,
    /// Links with a moving or mixed node at either end (indices into the link set): the ones a
    /// frame recomputes.
    pub moving_links: Vec<u32>,
}

pub use crate::meshed::mesh_groups;

/// The times the motion of `objects` is sampled at: 0, every key's time, and
/// [`SAMPLES_PER_SEGMENT`] evenly spaced steps between consecutive ones (the values hold
/// outside the keys, so nothing later or earlier needs a sample).
pub fn sample_times(scene: &Scene, objects: &[usize]) -> Vec<f64> {
    let mut keys: Vec<f64> = vec![0.0];
    for &o in objects {
        if let Some(m) = &scene.objects[o].motion {
            keys.extend(m.keys.iter().map(|k| k.time));
        }
    }
    keys.sort_by(f64::total_cmp);
    keys.dedup();
    let mut times = vec![keys[0]];
    for w in keys.windows(2) {
        for k in 1..=SAMPLES_PER_SEGMENT {
            times.push(w[0] + (w[1] - w[0]) * k as f64 / SAMPLES_PER_SEGMENT as f64);
        }
    }
    times
}

/// `e` moved by the rigid transform `m` (area kept: a rigid motion does not change it).
fn moved(e: &Element, m: &DMat4) -> Element {
    let mut out = e.clone();
    for f in &mut out.faces {
        f.corners = f.corners.map(|c| m.transform_point3(c));
    }
    out.update_geometry();
    out.area = e.area;
    out
}

/// The group of every node (see [`Bound::node_group`]), from the groups of the elements.
fn node_groups(h: &Hierarchy, element_group: &[u32]) -> Vec<u32> {
    let mut g = vec![STATIC; h.len()];
    for i in (0..h.len()).rev() {
        g[i] = match h.nodes[i].kind {
            NodeKind::Leaf(e) => element_group[e as usize],
            NodeKind::Cluster([a, b]) if g[a as usize] == g[b as usize] => g[a as usize],
            NodeKind::Cluster(_) => MIXED,
        };
    }
    g
}

/// Recomputes the center and radius of every node that is not static, as
/// [`Hierarchy::build`] does, from the leaves below it in `els`.
pub(crate) fn place_nodes(h: &mut Hierarchy, els: &[Element], node_group: &[u32]) {
    for (i, &g) in node_group.iter().enumerate() {
        if g == STATIC {
            continue;
        }
        let below: Vec<&Element> = (i as u32..h.nodes[i].end)
            .filter_map(|k| h.element(k))
            .map(|e| &els[e as usize])
            .collect();
        let area: f64 = below.iter().map(|e| e.area).sum();
        let center = if area > 0.0 {
            below.iter().map(|e| e.center * e.area).sum::<DVec3>() / area
        } else {
            below.iter().map(|e| e.center).sum::<DVec3>() / below.len() as f64
        };
        let radius = below
            .iter()
            .flat_map(|e| e.corner_points())
            .map(|c| (c - center).length())
            .fold(0.0, f64::max);
        let n = &mut h.nodes[i];
        n.center = center;
        n.radius = radius;
    }
}

/// The elements with every moving object placed at time `t` (`transforms`: where they stand).
fn elements_at(
    scene: &Scene,
    els: &[Element],
    mesh_group: &[u32],
    objects: &[usize],
    transforms: &[DMat4],
    t: f64,
) -> Vec<Element> {
    let steps: Vec<DMat4> = objects
        .iter()
        .zip(transforms)
        .map(|(&o, now)| {
            let m = scene.objects[o].motion.as_ref().expect("keyframed object");
            m.transform_at(t) * now.inverse()
        })
        .collect();
    els.iter()
        .map(|e| match mesh_group[e.mesh as usize] {
            STATIC => e.clone(),
            g => moved(e, &steps[g as usize - 1]),
        })
        .collect()
}

/// Links `h` over `els` for the whole motion of `scene`'s keyframed objects (`objects`, mesh
/// groups `mesh_group`): a pair is refined if the oracle refines it at any sampled pose; links
/// get the values of the pose the elements stand at now. Returns the links (sorted, with
/// offsets and the cone classes any pose uses) and the bound.
#[allow(clippy::too_many_arguments)]
pub fn build_bounded_links(
    scene: &Scene,
    h: &Hierarchy,
    els: &[Element],
    bins: &Bins,
    oracle: f64,
    max_links: u64,
    objects: Vec<usize>,
    mesh_group: &[u32],
) -> crate::Result<(Links, Bound)> {
    let t0 = Instant::now();
    let element_group: Vec<u32> = els.iter().map(|e| mesh_group[e.mesh as usize]).collect();
    let node_group = node_groups(h, &element_group);
    let transforms: Vec<DMat4> = objects
        .iter()
        .map(|&o| scene.objects[o].transform)
        .collect();
    let times = sample_times(scene, &objects);
    let poses: Vec<Vec<Element>> = times
        .iter()
        .map(|&t| elements_at(scene, els, mesh_group, &objects, &transforms, t))
        .collect();
    // How far a corner of each object travels between consecutive samples.
    let mut travel = vec![0.0f64; objects.len()];
    for w in poses.windows(2) {
        for (i, (a, b)) in w[0].iter().zip(&w[1]).enumerate() {
            let g = element_group[i];
            if g != STATIC {
                let d = a
                    .corner_points()
                    .zip(b.corner_points())
                    .map(|(p, q)| (p - q).length())
                    .fold(0.0, f64::max);
                travel[g as usize - 1] = travel[g as usize - 1].max(d);
            }
        }
    }
    // Between two samples a point is within half the travel of one of them.
    let margin: Vec<f64> = node_group
        .iter()
        .map(|&g| match g {
            STATIC => 0.0,
            MIXED => travel.iter().copied().fold(0.0, f64::max) / 2.0,
            g => travel[g as usize - 1] / 2.0,
        })
        .collect();
    let trees: Vec<Hierarchy> = poses
        .iter()
        .map(|p| {
            let mut t = h.clone();
            place_nodes(&mut t, p, &node_group);
            t
        })
        .collect();
    // The pose the elements stand at now: the links' values.
    let now = Ctx::new(h, els, bins, oracle);
    let sampled: Vec<Ctx> = trees
        .iter()
        .zip(&poses)
        .map(|(t, p)| Ctx {
            margin: &margin,
            group: &node_group,
            ..Ctx::new(t, p, bins, oracle)
        })
        .collect();
    let moving = |n: u32| node_group[n as usize] != STATIC;
    // One decision for the whole motion: split if any pose splits, link if any pose links.
    let step = |r: u32, s: u32| -> Step {
        if r == s || !(moving(r) || moving(s)) {
            return now.step(r, s);
        }
        let mut any_link = false;
        for c in &sampled {
            match c.step(r, s) {
                Step::Split(p) => return Step::Split(p),
                Step::Done(l) => any_link |= l.is_some(),
            }
        }
        if !any_link {
            return Step::Done(None);
        }
        let d = (h.nodes[r as usize].center - h.nodes[s as usize].center).length();
        // A pair that exchanges nothing now keeps the sides of some pose (it gets a zero form
        // factor until the motion brings it in view, `System::follow`).
        let sides = match now.sides(r, s) {
            0 => sampled.iter().map(|c| c.sides(r, s)).fold(0, |a, b| a | b),
            x => x,
        };
        Step::Done(Some(now.link(r, s, d.max(f64::MIN_POSITIVE), sides)))
    };
    let links = crate::linker::refine_all(&step, max_links);
    if links.len() as u64 > max_links {
        return Err(crate::Error::LinkBudget {
            budget: max_links,
            elements: els.len(),
            oracle,
            estimate: links.len() as f64,
        });
    }
    let (links, offsets) = crate::linker::by_receiver(links, h.len());
    let moving_links: Vec<u32> = (0..links.len() as u32)
        .filter(|&i| {
            let l = &links[i as usize];
            moving(l.receiver) || moving(l.sender)
        })
        .collect();
    // Every cone class a moving link takes at some pose, and those between (the class varies
    // continuously with the distance), so that a frame always finds its spreading table.
    let classes = crate::filter::class_count(bins);
    let mut used = vec![false; classes];
    for l in &links {
        used[l.cone as usize] = true;
    }
    for (t, p) in trees.iter().zip(&poses) {
        let c = Ctx::new(t, p, bins, oracle);
        let range = moving_links
            .par_iter()
            .map(|&i| {
                let l = &links[i as usize];
                let d = (t.nodes[l.receiver as usize].center - t.nodes[l.sender as usize].center)
                    .length();
                let k = c
                    .link(l.receiver, l.sender, d.max(f64::MIN_POSITIVE), l.sides)
                    .cone;
                (k, k)
            })
            .reduce(|| (u8::MAX, 0), |a, b| (a.0.min(b.0), a.1.max(b.1)));
        if range.0 <= range.1 {
            let lo = range.0.saturating_sub(1) as usize;
            let hi = (range.1 as usize + 1).min(classes - 1);
            used[lo..=hi].iter_mut().for_each(|u| *u = true);
        }
    }
    let bound = Bound {
        objects,
        transforms,
        node_group,
        times,
        travel,
        moving_links,
    };
    Ok((
        Links {
            links,
            offsets,
            linking_ms: t0.elapsed().as_secs_f64() * 1e3,
            used_classes: used,
        },
        bound,
    ))
}

impl Bound {
    /// Sets the sides, bins, cone class and calibrated form factor of every moving link in
    /// `all` from the current geometry (`h` and `els` where they stand), as linking that pair
    /// there would; pairs that exchange nothing at this pose get a zero form factor. `lambda`
    /// is the energy normalization the form factors are divided by.
    pub fn refresh_links(
        &self,
        all: &mut Links,
        h: &Hierarchy,
        els: &[Element],
        bins: &Bins,
        filters: &FilterTables,
        lambda: Option<f64>,
    ) {
        let ctx = Ctx::new(h, els, bins, 1.0);
        let used = &all.used_classes;
        let links = &all.links;
        let (mut fresh, silent): (Vec<Link>, Vec<bool>) = self
            .moving_links
            .par_iter()
            .map(|&i| {
                let l = links[i as usize];
                let (nr, ns) = (&h.nodes[l.receiver as usize], &h.nodes[l.sender as usize]);
                let d = (nr.center - ns.center).length().max(f64::MIN_POSITIVE);
                let sides = ctx.sides(l.receiver, l.sender);
                let kept = if sides == 0 { l.sides } else { sides };
                let mut n = ctx.link(l.receiver, l.sender, d, kept);
                n.cone = nearest_used(used, n.cone);
                (n, sides == 0)
            })
            .unzip();
        linker::calibrate_links(&mut fresh, h, els, bins, filters);
        let links = &mut all.links;
        for ((&i, mut l), quiet) in self.moving_links.iter().zip(fresh).zip(silent) {
            if quiet {
                l.form_factor = 0.0;
            }
            if let Some(lambda) = lambda {
                l.form_factor /= lambda;
            }
            links[i as usize] = l;
        }
    }
}

/// The used cone class nearest to `c` (a frame's link may fall in a class no sampled pose
/// gave, between two that did; the ones next to the sampled range are marked used too).
fn nearest_used(used: &[bool], c: u8) -> u8 {
    let c = c as usize;
    (0..used.len())
        .filter(|&k| used[k])
        .min_by_key(|&k| k.abs_diff(c))
        .unwrap_or(c) as u8
}

#[cfg(test)]
mod tests;

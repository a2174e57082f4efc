//! Link construction (§3.2): hierarchical refinement from the root self-link, with the
//! solid-angle oracle, the hemisphere rules (a leaf receives from both sides: it reflects what
//! reaches its front and blocks what reaches either), and the form factor of eq. 17,
//! then calibrated so that every link carries the energy it should
//! ([`calibrate_form_factors`]). No visibility is computed: links are unoccluded transport U.

use crate::bins::Bins;
use crate::elements::Element;
use crate::filter;
use crate::hierarchy::Hierarchy;
use glam::DVec3;
use rayon::prelude::*;
use std::f64::consts::PI;
use std::time::Instant;

mod calibrate;
pub use calibrate::{calibrate_form_factors, calibrate_links, projected_solid_angle};

/// One link: the sender's exitant intensity in `sender_bin` arrives at the receiver, spread
/// around `receiver_bin` by the table of cone class `cone`, scaled by `form_factor`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Link {
    /// Receiving node (row).
    pub receiver: u32,
    /// Sending node (row).
    pub sender: u32,
    /// Bin of the travel direction sender→receiver at the sender.
    pub sender_bin: u16,
    /// Central bin of the arriving light at the receiver. Bins are indexed by travel direction
    /// for both exitant and incident quantities (the Arvo convention of §2), so it equals
    /// `sender_bin`; it is stored separately because the GPU reads them from different tables.
    pub receiver_bin: u16,
    /// `1 / (max(r², ρ²) ω_bin)` as built: eq. 17, bounded as r → 0 by the sender's disc radius
    /// ρ (a disc of radius ρ cannot deliver more than πL of irradiance); then calibrated by
    /// [`calibrate_form_factors`] (zero for ends that exchange nothing) and, in closed scenes,
    /// divided by the transport's spectral radius ([`crate::System::conserve_energy`]).
    pub form_factor: f64,
    /// Cone class of the sender's solid angle (0: within one bin, no spreading).
    pub cone: u8,
    /// Which sides of a leaf receiver the link's light arrives at ([`FRONT`], [`BACK`] or both;
    /// clusters receive both): the global pass spreads it only into those bins, so the blur of a
    /// link from the front does not leak into back bins, where it would be blocked.
    pub sides: u8,
}

/// [`Link::sides`]: light arrives at the receiver's front (reflected and blocked).
pub const FRONT: u8 = 1;
/// [`Link::sides`]: light arrives at the receiver's back (blocked only: opaque from both sides).
pub const BACK: u8 = 2;

/// The link set, sorted by receiver, with a per-receiver index for gathering.
#[derive(Debug, Clone, Default)]
pub struct Links {
    /// Links sorted by (receiver, sender).
    pub links: Vec<Link>,
    /// `links[offsets[r]..offsets[r+1]]` are the links into node `r`.
    pub offsets: Vec<u32>,
    /// Wall time of linking in milliseconds.
    pub linking_ms: f64,
    /// Cone classes used by at least one link.
    pub used_classes: Vec<bool>,
}

impl Links {
    /// Number of links.
    pub fn len(&self) -> usize {
        self.links.len()
    }

    /// True when there are no links.
    pub fn is_empty(&self) -> bool {
        self.links.is_empty()
    }

    /// Links per second achieved while linking.
    pub fn links_per_second(&self) -> f64 {
        self.links.len() as f64 / (self.linking_ms / 1e3).max(1e-9)
    }
}

/// True when `sender` lies strictly in front of the plane of the leaf `receiver`
/// (light from it arrives at the receiver's front side).
pub fn in_front(receiver: &Element, sender: DVec3) -> bool {
    let d = sender - receiver.center;
    receiver.normal.dot(d) > 1e-7 * d.length()
}

/// True when some part of the element `sender` (some corner of its faces) lies strictly in front
/// of the plane of the leaf `receiver` (as [`in_front`] judges a point). A sender that straddles
/// the receiver's plane sends light from its front part: judged by its center alone, that part
/// was lost (a block's face cutting through floor elements lost 1.4% of the closed-hemisphere
/// irradiance).
pub fn partly_in_front(receiver: &Element, sender: &Element) -> bool {
    sender.corner_points().any(|c| in_front(receiver, c))
}

/// True when some part of the element `sender` lies strictly behind the plane of the leaf
/// `receiver` (its light arrives at the receiver's back, to be blocked).
pub fn partly_behind(receiver: &Element, sender: &Element) -> bool {
    sender.corner_points().any(|c| {
        let d = c - receiver.center;
        receiver.normal.dot(d) < -1e-7 * d.length()
    })
}

/// [`partly_in_front`] and [`partly_behind`] in one pass over the corners, stopping once both
/// are found; the corner's distance (a square root) is taken only where the signed height
/// alone does not decide the tolerance (|d| ≤ |d|₁, so `h > 1e-7 |d|₁` implies `h > 1e-7 |d|`).
fn sides_by_corners(receiver: &Element, sender: &Element) -> (bool, bool) {
    let (mut front, mut behind) = (false, false);
    for c in sender.corner_points() {
        let d = c - receiver.center;
        let h = receiver.normal.dot(d);
        let l1 = d.abs().element_sum();
        if h > 0.0 && !front {
            front = h > 1e-7 * l1 || h > 1e-7 * d.length();
        } else if h < 0.0 && !behind {
            behind = -h > 1e-7 * l1 || h < -1e-7 * d.length();
        }
        if front && behind {
            break;
        }
    }
    (front, behind)
}

/// Relative width of a tie in the refinement tests: far above f64 rounding, far below any real
/// difference between two configurations.
const TIE: f64 = 1e-9;

/// The refinement's view of one configuration of the scene (the bounded link mesh of
/// [`crate::bound`] asks one per sampled pose).
pub(crate) struct Ctx<'a> {
    pub(crate) h: &'a Hierarchy,
    pub(crate) els: &'a [Element],
    pub(crate) bins: &'a Bins,
    pub(crate) limit: f64,
    /// Per node, how far it may move between two sampled poses of a motion (empty: a still
    /// scene), and its group ([`crate::bound::Bound::node_group`]): the oracle judges a pair
    /// at its distance less both margins, unless the two move together.
    pub(crate) margin: &'a [f64],
    pub(crate) group: &'a [u32],
}

/// One refinement decision: a link (or none), or the pairs to refine into.
pub(crate) enum Step {
    Done(Option<Link>),
    Split(Vec<(u32, u32)>),
}

impl<'a> Ctx<'a> {
    /// The refinement over `h` and `els` with oracle τ = `oracle`.
    pub(crate) fn new(h: &'a Hierarchy, els: &'a [Element], bins: &'a Bins, oracle: f64) -> Self {
        Ctx {
            h,
            els,
            bins,
            limit: oracle * bins.omega,
            margin: &[],
            group: &[],
        }
    }

    /// The distance the oracle may lose between the pair's centers as they move.
    fn slack(&self, r: u32, s: u32) -> f64 {
        if self.margin.is_empty() {
            return 0.0;
        }
        let (gr, gs) = (self.group[r as usize], self.group[s as usize]);
        if gr == gs && gr != crate::meshed::MIXED {
            return 0.0;
        }
        self.margin[r as usize] + self.margin[s as usize]
    }

    fn leaf(&self, n: u32) -> Option<&Element> {
        self.h.element(n).map(|e| &self.els[e as usize])
    }

    /// Whether some triangle below the cluster `s` lies partly in front of the leaf `re`'s
    /// plane, and whether some lies partly behind it (stops once both are found).
    fn sides_of_cluster(&self, re: &Element, s: u32) -> (bool, bool) {
        let (mut front, mut back) = (false, false);
        for k in s..self.h.nodes[s as usize].end {
            if let Some(e) = self.h.element(k) {
                let (f, b) = self.sides_of_leaf(re, k, &self.els[e as usize]);
                front |= f;
                back |= b;
                if front && back {
                    break;
                }
            }
        }
        (front, back)
    }

    /// [`partly_in_front`] and [`partly_behind`] of the leaf `se` (node `k`) against the leaf
    /// `re`, answered by `k`'s bounding sphere where it lies wholly on one side by more than
    /// both tests' tolerance (every corner is then judged the same way), else by the corners.
    fn sides_of_leaf(&self, re: &Element, k: u32, se: &Element) -> (bool, bool) {
        let n = &self.h.nodes[k as usize];
        let v = n.center - re.center;
        let h = re.normal.dot(v);
        // A corner c is within the sphere: |c − re.center| ≤ |v| + radius, and the corner
        // tests' tolerance is 1e-7 of that distance.
        let margin = 1e-6 * (v.length() + n.radius);
        if h - n.radius > margin {
            (true, false)
        } else if h + n.radius < -margin {
            (false, true)
        } else {
            sides_by_corners(re, se)
        }
    }

    /// The sides of the receiver `r` light from `s` arrives at ([`FRONT`], [`BACK`], both, or
    /// 0: none, the pair exchanges nothing). Clusters receive at both.
    pub(crate) fn sides(&self, r: u32, s: u32) -> u8 {
        // A leaf reflects what arrives at its front and blocks what arrives at either side
        // (opaque from both sides); a sender in its plane exchanges nothing with it.
        let ns = &self.h.nodes[s as usize];
        let Some(re) = self.leaf(r) else {
            return FRONT | BACK;
        };
        let (front, back) = match self.leaf(s) {
            Some(se) => self.sides_of_leaf(re, s, se),
            None => {
                let h = re.normal.dot(ns.center - re.center);
                let tie = TIE * (h.abs() + ns.radius);
                let (front, back) = (h + ns.radius > tie, h - ns.radius < -tie);
                if front && back {
                    // The bounding sphere straddles the plane: ask the cluster's triangles
                    // (an adjacent wall's cluster touches the plane but has nothing behind).
                    self.sides_of_cluster(re, s)
                } else {
                    (front, back)
                }
            }
        };
        // A closed solid's face does not block from behind: it needs no light from there.
        let back = back && re.blocks_back;
        (front as u8 * FRONT) | (back as u8 * BACK)
    }

    /// One refinement decision for the pair (receiver `r`, sender `s`).
    pub(crate) fn step(&self, r: u32, s: u32) -> Step {
        let (nr, ns) = (&self.h.nodes[r as usize], &self.h.nodes[s as usize]);
        if r == s {
            // Self-links are always subdivided; a leaf does not light itself.
            return match self.h.children(r) {
                None => Step::Done(None),
                Some([a, b]) => Step::Split(vec![(a, a), (a, b), (b, a), (b, b)]),
            };
        }
        let sides = self.sides(r, s);
        if sides == 0 {
            return Step::Done(None);
        }
        let d = (nr.center - ns.center).length();
        let big = nr.radius.max(ns.radius);
        let dm = (d - self.slack(r, s)).max(0.0);
        // Regular meshes put many pairs exactly on these thresholds; a tie within TIE decides
        // the same way in any unit (rounding would otherwise flip it with the scene's scale).
        let coarse = dm <= (nr.radius + ns.radius) * (1.0 + TIE)
            || PI * big * big > self.limit * dm * dm * (1.0 + TIE);
        let (rc, sc) = (self.h.children(r), self.h.children(s));
        if coarse && (rc.is_some() || sc.is_some()) {
            let split_receiver = match (rc, sc) {
                (Some(_), Some(_)) => nr.radius >= ns.radius * (1.0 - TIE),
                (Some(_), None) => true,
                _ => false,
            };
            return Step::Split(if split_receiver {
                rc.unwrap().iter().map(|&c| (c, s)).collect()
            } else {
                sc.unwrap().iter().map(|&c| (r, c)).collect()
            });
        }
        Step::Done(Some(self.link(r, s, d, sides)))
    }

    /// The link of the pair at distance `d` between the centers, reaching `sides`.
    pub(crate) fn link(&self, r: u32, s: u32, d: f64, sides: u8) -> Link {
        let (nr, ns) = (&self.h.nodes[r as usize], &self.h.nodes[s as usize]);
        let rho2 = (ns.area / PI).min(ns.radius * ns.radius);
        let dir = (nr.center - ns.center) / d;
        let bin = self.bins.bin_of(dir) as u16;
        let cone_solid_angle = 2.0 * PI * (1.0 - d / (d * d + rho2).sqrt());
        Link {
            receiver: r,
            sender: s,
            sender_bin: bin,
            receiver_bin: bin,
            form_factor: 1.0 / ((d * d).max(rho2) * self.bins.omega),
            cone: filter::cone_class(self.bins, cone_solid_angle),
            sides,
        }
    }
}

/// Refines the root pair (0, 0) by `step` into links, in parallel over all cores: breadth-first
/// until there is enough independent work for every core, then depth-first per pair (recursion
/// depth ≤ twice the hierarchy's, which median splits keep logarithmic). Stops early once more
/// than `max_links` exist (the caller refuses).
pub(crate) fn refine_all(step: &(dyn Fn(u32, u32) -> Step + Sync), max_links: u64) -> Vec<Link> {
    use std::sync::atomic::{AtomicU64, Ordering::Relaxed};
    fn refine(
        step: &(dyn Fn(u32, u32) -> Step + Sync),
        made: &AtomicU64,
        max: u64,
        r: u32,
        s: u32,
        out: &mut Vec<Link>,
    ) {
        if made.load(Relaxed) > max {
            return;
        }
        match step(r, s) {
            Step::Done(l) => {
                made.fetch_add(l.is_some() as u64, Relaxed);
                out.extend(l)
            }
            Step::Split(p) => p
                .into_iter()
                .for_each(|(a, b)| refine(step, made, max, a, b, out)),
        }
    }
    let made = AtomicU64::new(0);
    let mut tasks = vec![(0u32, 0u32)];
    let mut links = Vec::new();
    let want = 64 * rayon::current_num_threads();
    while !tasks.is_empty() && tasks.len() < want {
        let mut next = Vec::with_capacity(tasks.len() * 4);
        for (r, s) in tasks {
            match step(r, s) {
                Step::Done(l) => links.extend(l),
                Step::Split(p) => next.extend(p),
            }
        }
        tasks = next;
    }
    let rest: Vec<Vec<Link>> = tasks
        .par_iter()
        .map(|&(r, s)| {
            let mut out = Vec::new();
            refine(step, &made, max_links, r, s, &mut out);
            out
        })
        .collect();
    links.extend(rest.into_iter().flatten());
    links
}

/// The links `step` would make, estimated from about one in `stride` of the independent pairs
/// the refinement starts from (the same breadth-first split as [`refine_all`], picked by a
/// hash), counting at most `cap` links in the sample before it stops. Costs
/// about `1/stride` of linking: the budget fitting asks it before each try.
pub(crate) fn sample_links(
    step: &(dyn Fn(u32, u32) -> Step + Sync),
    stride: usize,
    cap: u64,
) -> f64 {
    use std::sync::atomic::{AtomicU64, Ordering::Relaxed};
    fn count(step: &(dyn Fn(u32, u32) -> Step + Sync), made: &AtomicU64, cap: u64, r: u32, s: u32) {
        if made.load(Relaxed) > cap {
            return;
        }
        match step(r, s) {
            Step::Done(l) => {
                made.fetch_add(l.is_some() as u64, Relaxed);
            }
            Step::Split(p) => p
                .into_iter()
                .for_each(|(a, b)| count(step, made, cap, a, b)),
        }
    }
    let mut tasks = vec![(0u32, 0u32)];
    let mut direct = 0u64;
    let want = 64 * rayon::current_num_threads() * stride;
    while !tasks.is_empty() && tasks.len() < want {
        let mut next = Vec::with_capacity(tasks.len() * 4);
        for (r, s) in tasks {
            match step(r, s) {
                Step::Done(l) => direct += l.is_some() as u64,
                Step::Split(p) => next.extend(p),
            }
        }
        tasks = next;
    }
    let made = AtomicU64::new(0);
    // A hashed pick, not every stride-th: the breadth-first split puts self pairs (which make
    // the most links) at every fourth place, and a regular stride picked them alone (+53%).
    let pick = |i: usize| {
        let mut z = (i as u64).wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        (z ^ (z >> 31)) % stride.max(1) as u64 == 0
    };
    let sample: Vec<(u32, u32)> = tasks
        .iter()
        .enumerate()
        .filter(|&(i, _)| pick(i))
        .map(|(_, t)| *t)
        .collect();
    sample
        .par_iter()
        .for_each(|&(r, s)| count(step, &made, cap, r, s));
    let share = sample.len() as f64 / tasks.len().max(1) as f64;
    direct as f64 + made.load(Relaxed) as f64 / share.max(f64::MIN_POSITIVE)
}

/// `links` sorted by (receiver, sender), and the index of each of `nodes` receivers' first link
/// (`nodes + 1` entries).
pub(crate) fn by_receiver(mut links: Vec<Link>, nodes: usize) -> (Vec<Link>, Vec<u32>) {
    links.par_sort_unstable_by_key(|l| (l.receiver, l.sender));
    let mut offsets = vec![0u32; nodes + 1];
    for l in &links {
        offsets[l.receiver as usize + 1] += 1;
    }
    for i in 0..nodes {
        offsets[i + 1] += offsets[i];
    }
    (links, offsets)
}

/// Links the oracle makes, estimated before linking: every receiver gathers from senders of at
/// most τ·ω_bin each over its sphere, about 2·m/τ of them (measured 2.1 per leaf and m/τ on the
/// Cornell box), and never more than one per ordered pair of elements.
pub fn estimate_links(elements: usize, bins: usize, oracle: f64) -> f64 {
    let n = elements as f64;
    (2.0 * n * bins as f64 / oracle).min(n * n)
}

/// [`build_links`] under a budget first counts the links of one in this many of the starting
/// pairs ([`sample_links`]).
pub const PROBE_STRIDE: usize = 8;
/// ... and refuses without linking when that estimate passes the budget by this factor (the
/// sample's spread: on the Cornell box at element sizes 0.25 and 0.1 it was −0.6% and +18%).
pub const PROBE_MARGIN: f64 = 1.3;

/// Builds all links of the scene, in parallel over all cores.
/// `oracle` is τ: a link is refined while a node subtends more than τ·ω_bin. Refuses (stops
/// early) when more than `max_links` links would be made.
pub fn build_links(
    h: &Hierarchy,
    els: &[Element],
    bins: &Bins,
    oracle: f64,
    max_links: u64,
) -> crate::Result<Links> {
    let t0 = Instant::now();
    let ctx = Ctx::new(h, els, bins, oracle);
    // Under a budget that the rough estimate comes near, a sample of an eighth first: far past
    // the budget, refuse without linking.
    let rough = estimate_links(els.len(), bins.count, oracle);
    if max_links < u64::MAX / 2 && rough > max_links as f64 / 4.0 {
        let cap = max_links / PROBE_STRIDE as u64 * 2;
        let estimate = sample_links(&|r, s| ctx.step(r, s), PROBE_STRIDE, cap);
        if estimate > PROBE_MARGIN * max_links as f64 {
            return Err(crate::Error::LinkBudget {
                budget: max_links,
                elements: els.len(),
                oracle,
                estimate,
            });
        }
    }
    let links = refine_all(&|r, s| ctx.step(r, s), max_links);
    if links.len() as u64 > max_links {
        return Err(crate::Error::LinkBudget {
            budget: max_links,
            elements: els.len(),
            oracle,
            estimate: links.len() as f64,
        });
    }
    let (links, offsets) = by_receiver(links, h.len());
    let mut used_classes = vec![false; filter::class_count(bins)];
    for l in &links {
        used_classes[l.cone as usize] = true;
    }
    Ok(Links {
        links,
        offsets,
        linking_ms: t0.elapsed().as_secs_f64() * 1e3,
        used_classes,
    })
}

#[cfg(test)]
mod sample_tests {
    use super::*;

    /// The sampled count is near the count (the budget's probe refuses only past 1.3× it).
    #[test]
    fn a_sample_of_an_eighth_estimates_the_links() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell-box.toml");
        let s = crate::scene::load_scene(&path).unwrap();
        for size in [0.25, 0.1] {
            let els = crate::elements::build_elements(
                &s,
                &crate::scene::SolverSettings {
                    element_size: size,
                    ..s.solver.clone()
                },
            )
            .unwrap();
            let h = Hierarchy::build(&els);
            let bins = Bins::new(128).unwrap();
            let ctx = Ctx::new(&h, &els, &bins, 1.0);
            let n = refine_all(&|r, s| ctx.step(r, s), u64::MAX).len() as f64;
            let e = sample_links(&|r, s| ctx.step(r, s), PROBE_STRIDE, u64::MAX);
            println!(
                "element size {size}: {n} links, sampled {e:.0} ({:+.1}%)",
                100.0 * (e / n - 1.0)
            );
            assert!((e / n - 1.0).abs() < 0.2, "{e} against {n}");
        }
    }
}

//! Link construction (§3.2): hierarchical refinement from the root self-link, with the
//! solid-angle oracle, the hemisphere rules (a leaf receives from both sides: it reflects what
//! reaches its front and blocks what reaches either), and the form factor of eq. 17,
//! then calibrated so that every link carries the energy it should
//! ([`calibrate_form_factors`]). No visibility is computed: links are unoccluded transport U.

use crate::bins::Bins;
use crate::elements::Element;
use crate::filter;
use crate::hierarchy::{Hierarchy, NodeKind};
use glam::DVec3;
use rayon::prelude::*;
use std::f64::consts::PI;
use std::time::Instant;

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
            (partly_in_front(re, se), partly_behind(re, se))
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

/// Smallest |cosine| between a leaf link's bin center and either plane (see [`calibrate_form_factors`]).
const MIN_BIN_COS: f64 = 0.02;

/// Projected solid angle `∫ cos θ dω` of triangle `tri` seen from point `p` with normal `n`,
/// after clipping it to the half-space in front of `p` (Lambert's polygon formula).
pub fn projected_solid_angle(p: DVec3, n: DVec3, tri: &[DVec3; 3]) -> f64 {
    // Clip against the plane n·(x - p) >= 0 (Sutherland–Hodgman on a triangle), on the stack:
    // the calibration calls this for every face of every leaf link's sender.
    let mut poly = [DVec3::ZERO; 4];
    let mut len = 0;
    for i in 0..3 {
        let (a, b) = (tri[i] - p, tri[(i + 1) % 3] - p);
        let (da, db) = (n.dot(a), n.dot(b));
        if da >= 0.0 {
            poly[len] = a;
            len += 1;
        }
        if (da >= 0.0) != (db >= 0.0) {
            poly[len] = a + (b - a) * (da / (da - db));
            len += 1;
        }
    }
    if len < 3 {
        return 0.0;
    }
    let mut sum = 0.0;
    for i in 0..len {
        let (a, b) = (poly[i], poly[(i + 1) % len]);
        let c = a.cross(b);
        let cl = c.length();
        if cl < 1e-300 {
            continue;
        }
        let theta = cl.atan2(a.dot(b));
        sum += theta * n.dot(c / cl);
    }
    (0.5 * sum).abs()
}

/// Per node, the receiving profile `G(j) = Σ a_r c_r max(0, −n_r·ω_j)` over the leaves `r` below
/// it (`c_r` the cosine normalization): what a unit radiance arriving in bin `j` delivers, as
/// irradiance × area, to the node's leaves in the local pass. Sums of children, so built bottom-up.
fn receiving_profiles(h: &Hierarchy, els: &[Element], bins: &Bins, cos_norm: &[f64]) -> Vec<f64> {
    let m = bins.count;
    let mut g = vec![0.0; h.len() * m];
    g.par_chunks_mut(m).enumerate().for_each(|(i, row)| {
        if let Some(e) = h.element(i as u32) {
            let el = &els[e as usize];
            let k = el.area * cos_norm[e as usize];
            for (x, c) in row.iter_mut().zip(&bins.centers) {
                *x = k * (-el.normal.dot(*c)).max(0.0);
            }
        }
    });
    for i in (0..h.len()).rev() {
        if let NodeKind::Cluster([a, b]) = h.nodes[i].kind {
            for j in 0..m {
                g[i * m + j] = g[a as usize * m + j] + g[b as usize * m + j];
            }
        }
    }
    g
}

/// Sets every link's form factor so that the discrete transport delivers the right energy.
///
/// **Leaf→leaf links** deliver the exact irradiance at the receiver's center for a Lambertian
/// sender: the sender triangle's projected solid angle over what the discrete path (sender bin
/// cosine, spreading, receiver bin cosines) would deliver per unit radiance. Far links change
/// little; near links (corners, contact) lose the point-collocation error. Where the bin of the
/// center direction has its center on the wrong side of either plane (near-grazing pairs), the
/// nearest usable bin is used.
///
/// **Links with a cluster at either end** deliver the right flux from a sender whose every leaf
/// has unit radiance (or antiradiance) toward the receiver, summed over the receiver's leaves:
///
/// `F = T / (ω_bin · Σ_s a_s c_s |n_s·ω_b| · Σ_j w_j G_R(j))`
///
/// The denominator is what the discrete path delivers per unit F: the sender's intensity in the
/// link's bin `b` (its leaves' areas × bin-center cosines × cosine normalizations), spread by the
/// link's table `w` and received by the receiver's leaves ([`receiving_profiles`]: their front
/// bins' cosines × normalizations). The target `T = Σ_r Σ_s a_r a_s cos⁺_r |cos_s| d² /
/// (|x_r − c_S|² |c_R − x_s|²)` is the point-to-point exchange with each end's leaves seen from
/// the other end's center (a separable approximation: exact when either end is a leaf but for
/// the point kernel, within 0.3% of the exact pair sum at τ = 1). eq. 17's `1/(d² ω_bin)` alone
/// evaluates the leaves' cosines at the bin center instead of the true direction, counts
/// `c_s` and `c_r` (±5%), loses the receiver cosine to the Gaussian blur, and takes `1/d²` at the
/// centers; in a closed box at τ = 1 that lost 4–9% of the energy of these links (1.6% of all
/// irradiance per bounce). The factor is unsigned (senders mix radiance and antiradiance), so
/// it is the same for any uniform field. Coplanar ends (which exchange nothing) get `F = 0`
/// where eq. 17 leaked through the blur. Cost: `O(|R| + |S| + spread)` per link.
pub fn calibrate_form_factors(
    links: &mut Links,
    h: &Hierarchy,
    els: &[Element],
    bins: &Bins,
    filters: &crate::filter::FilterTables,
) {
    calibrate_links(&mut links.links, h, els, bins, filters);
}

/// [`calibrate_form_factors`] of some links only (the bounded link mesh recalibrates the links
/// touching moving elements every frame, [`crate::bound`]).
pub fn calibrate_links(
    links: &mut [Link],
    h: &Hierarchy,
    els: &[Element],
    bins: &Bins,
    filters: &crate::filter::FilterTables,
) {
    let m = bins.count;
    let cos_norm: Vec<f64> = els
        .par_iter()
        .map(|e| bins.cosine_normalization(e.normal))
        .collect();
    let profiles = receiving_profiles(h, els, bins, &cos_norm);
    // Element indices of the leaves below node `n` (a contiguous pre-order range).
    let leaves_below = |n: u32| (n..h.nodes[n as usize].end).filter_map(|k| h.element(k));
    links.par_iter_mut().for_each(|l| {
        let (Some(re), Some(se)) = (h.element(l.receiver), h.element(l.sender)) else {
            let (nr, ns) = (&h.nodes[l.receiver as usize], &h.nodes[l.sender as usize]);
            let wb = bins.centers[l.sender_bin as usize];
            let (mut sent, mut true_sent) = (0.0, 0.0);
            for s in leaves_below(l.sender) {
                let e = &els[s as usize];
                sent += e.area * cos_norm[s as usize] * e.normal.dot(wb).abs();
                let v = nr.center - e.center;
                let d2 = v.length_squared();
                if d2 > 0.0 {
                    true_sent += e.area * e.normal.dot(v).abs() / (d2 * d2.sqrt());
                }
            }
            // A leaf receiver linked only to its back is calibrated for its back, as a front.
            let flip = if l.sides == BACK { -1.0 } else { 1.0 };
            let mut true_received = 0.0;
            for e in leaves_below(l.receiver).map(|k| &els[k as usize]) {
                let v = e.center - ns.center;
                let d2 = v.length_squared();
                if d2 > 0.0 {
                    true_received += e.area * (-flip * e.normal.dot(v)).max(0.0) / (d2 * d2.sqrt());
                }
            }
            let g = &profiles[l.receiver as usize * m..(l.receiver as usize + 1) * m];
            let g_at = |j: usize| match h.element(l.receiver) {
                Some(e) if flip < 0.0 => {
                    let e = e as usize;
                    els[e].area * cos_norm[e] * els[e].normal.dot(bins.centers[j]).max(0.0)
                }
                _ => g[j],
            };
            let received: f64 = filters
                .row(l.cone, l.receiver_bin as u32)
                .map_or(0.0, |row| {
                    row.iter().map(|&(j, w)| w as f64 * g_at(j as usize)).sum()
                });
            if sent > 0.0 && received > 0.0 {
                let d2 = (nr.center - ns.center).length_squared();
                l.form_factor = true_sent * true_received * d2 / (bins.omega * sent * received);
            }
            return;
        };
        let (r, s) = (&els[re as usize], &els[se as usize]);
        // A sender wholly behind the receiver delivers to its back: calibrated as to a front.
        let rn = if l.sides & FRONT == 0 {
            -r.normal
        } else {
            r.normal
        };
        let cr = |w: DVec3| (-rn.dot(w)).max(0.0);
        let dir = (r.center - s.center).normalize();
        let side = s.normal.dot(dir).signum();
        // A bin is usable when its center leaves the sender on the same side as the true
        // direction and arrives at the receiver's side; near-grazing pairs may need a neighbour.
        let usable = |b: usize| {
            let w = bins.centers[b];
            s.normal.dot(w) * side >= MIN_BIN_COS && -rn.dot(w) >= MIN_BIN_COS
        };
        let mut b = l.sender_bin as usize;
        if !usable(b) {
            match (0..bins.count).filter(|&k| usable(k)).max_by(|&x, &y| {
                bins.centers[x]
                    .dot(dir)
                    .total_cmp(&bins.centers[y].dot(dir))
            }) {
                Some(k) => b = k,
                None => return,
            }
        }
        let wb = bins.centers[b];
        let spread = filters.row(l.cone, b as u32).map_or(0.0, |row| {
            row.iter()
                .map(|&(j, w)| w as f64 * cr(bins.centers[j as usize]))
                .sum()
        });
        if spread <= 0.0 {
            return;
        }
        let phi: f64 = s
            .faces
            .iter()
            .map(|f| projected_solid_angle(r.center, rn, &f.corners))
            .sum();
        let delivered = bins.omega
            * cos_norm[re as usize]
            * s.area
            * cos_norm[se as usize]
            * s.normal.dot(wb).abs()
            * spread;
        l.sender_bin = b as u16;
        l.receiver_bin = b as u16;
        l.form_factor = phi / delivered;
    });
}

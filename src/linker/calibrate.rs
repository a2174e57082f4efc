//! Calibration of the links' form factors (§3.2, eq. 17 made exact where it matters): leaf
//! links by the projected solid angle of the sender's faces, cluster links by the flux their
//! leaves would exchange, so that every link carries the energy it should.

use super::{Link, Links, BACK, FRONT};
use crate::bins::Bins;
use crate::elements::Element;
use crate::hierarchy::{Hierarchy, NodeKind};
use glam::DVec3;
use rayon::prelude::*;

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

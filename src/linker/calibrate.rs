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

/// Per face of `faces` and per edge (corner i → i+1), the face that shares the edge in reverse
/// (`u32::MAX`: none). Two faces sharing an edge traverse it in opposite directions, and
/// Lambert's formula gives the two traversals exactly opposite terms (the same angle, negated
/// cross products), so over a set of faces whose terms share a sign only the edges whose
/// partner lies outside the set need evaluating: a face cluster of 20 triangles has about 20
/// such edges of 60.
fn partners(faces: &[crate::elements::Face]) -> Vec<[u32; 3]> {
    let key = |v: DVec3| [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()];
    let mut by_edge: std::collections::HashMap<([u64; 3], [u64; 3]), Vec<u32>> = Default::default();
    for (k, f) in faces.iter().enumerate() {
        for i in 0..3 {
            let e = (key(f.corners[i]), key(f.corners[(i + 1) % 3]));
            by_edge.entry(e).or_default().push(k as u32);
        }
    }
    let mut out = vec![[u32::MAX; 3]; faces.len()];
    for (k, f) in faces.iter().enumerate() {
        for i in 0..3 {
            if out[k][i] != u32::MAX {
                continue;
            }
            let reverse = (key(f.corners[(i + 1) % 3]), key(f.corners[i]));
            // Pair with the first reverse traversal not yet paired (a manifold edge has one).
            let Some(others) = by_edge.get(&reverse) else {
                continue;
            };
            for &o in others {
                let oi = (0..3)
                    .find(|&j| {
                        (
                            key(faces[o as usize].corners[j]),
                            key(faces[o as usize].corners[(j + 1) % 3]),
                        ) == reverse
                    })
                    .unwrap();
                if o as usize != k && out[o as usize][oi] == u32::MAX {
                    out[k][i] = o;
                    out[o as usize][oi] = k as u32;
                    break;
                }
            }
        }
    }
    out
}

/// Lambert's term of the edge `a → b` (corners relative to the point) for the normal `n`.
fn edge_term(n: DVec3, a: DVec3, b: DVec3) -> f64 {
    let c = a.cross(b);
    let cl = c.length();
    if cl < 1e-300 {
        return 0.0;
    }
    cl.atan2(a.dot(b)) * n.dot(c / cl)
}

/// Projected solid angle of the element `s`'s faces from `p` with normal `n`, the sum of
/// [`projected_solid_angle`] over its faces computed with fewer edges: faces wholly in front of
/// `p`'s plane are grouped by the side they turn toward `p` (within a group every face's term
/// has one sign), and each group's sum is taken over the edges it does not share with itself
/// ([`partners`]); faces that the plane clips are taken one by one.
fn sender_projected_solid_angle(
    p: DVec3,
    n: DVec3,
    s: &Element,
    partners: Option<&[[u32; 3]]>,
) -> f64 {
    let Some(partners) = partners else {
        return s
            .faces
            .iter()
            .map(|f| projected_solid_angle(p, n, &f.corners))
            .sum();
    };
    // Group of each face: 0 clipped, 1 and 2 the two orientations toward p.
    const STACK: usize = 64;
    let mut small = [0u8; STACK];
    let mut large = Vec::new();
    let group: &mut [u8] = if s.faces.len() <= STACK {
        &mut small[..s.faces.len()]
    } else {
        large.resize(s.faces.len(), 0);
        &mut large
    };
    let mut clipped = 0.0;
    for (g, f) in group.iter_mut().zip(&s.faces) {
        let [a, b, c] = f.corners.map(|v| v - p);
        *g = if n.dot(a) < 0.0 || n.dot(b) < 0.0 || n.dot(c) < 0.0 {
            clipped += projected_solid_angle(p, n, &f.corners);
            0
        } else if a.dot(b.cross(c)) >= 0.0 {
            1
        } else {
            2
        };
    }
    let mut sums = [0.0f64; 3];
    for (k, f) in s.faces.iter().enumerate() {
        let g = group[k];
        if g == 0 {
            continue;
        }
        for (i, &o) in partners[k].iter().enumerate() {
            if o != u32::MAX && group[o as usize] == g {
                continue;
            }
            sums[g as usize] += edge_term(n, f.corners[i] - p, f.corners[(i + 1) % 3] - p);
        }
    }
    clipped + 0.5 * (sums[1].abs() + sums[2].abs())
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
    // The shared edges of the leaf senders with several faces (only those these links use: the
    // bounded link mesh recalibrates a few links per frame).
    let mut multi = vec![false; els.len()];
    for l in links.iter() {
        if let (Some(_), Some(s)) = (h.element(l.receiver), h.element(l.sender)) {
            multi[s as usize] = els[s as usize].faces.len() > 1;
        }
    }
    let partners: Vec<Option<Vec<[u32; 3]>>> = els
        .par_iter()
        .zip(&multi)
        .map(|(e, &m)| m.then(|| partners(&e.faces)))
        .collect();
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
        let phi = sender_projected_solid_angle(r.center, rn, s, partners[se as usize].as_deref());
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::elements::Face;

    /// A 4 × 4 grid of quads (32 triangles, consistently wound) on a gently curved sheet.
    fn sheet() -> Element {
        let z = |x: f64, y: f64| 0.1 * (x * 1.3).sin() * (y * 0.7).cos();
        let v = |i: usize, j: usize| {
            let (x, y) = (i as f64 * 0.25, j as f64 * 0.25);
            DVec3::new(x, y, z(x, y))
        };
        let mut faces = Vec::new();
        for i in 0..4 {
            for j in 0..4 {
                let (a, b, c, d) = (v(i, j), v(i + 1, j), v(i + 1, j + 1), v(i, j + 1));
                faces.push(Face {
                    corners: [a, b, c],
                    triangle: 0,
                });
                faces.push(Face {
                    corners: [a, c, d],
                    triangle: 0,
                });
            }
        }
        Element::from_faces(faces, 0, 0)
    }

    /// On a connected sheet only the boundary's 16 edges of 96 have no partner, and the
    /// projected solid angle by partner-less edges per orientation group equals the face-by-face
    /// sum, from points that see it whole, clipped, and from its other side.
    #[test]
    fn shared_edges_give_the_face_by_face_projected_solid_angle() {
        let s = sheet();
        let pairs = partners(&s.faces);
        let unpaired = pairs.iter().flatten().filter(|&&o| o == u32::MAX).count();
        assert_eq!(unpaired, 16);
        let (mut whole, mut clipped) = (0, 0);
        for k in 0..400 {
            let t = k as f64 * 0.37;
            let p = DVec3::new(
                0.5 + 1.5 * t.sin(),
                0.5 + 1.2 * (1.7 * t).cos(),
                0.05 + 0.8 * (0.3 * t).sin(),
            );
            let n =
                (DVec3::new(0.3 * (2.3 * t).sin(), 0.2 * t.cos(), -1.0) * p.z.signum()).normalize();
            let face_by_face: f64 = s
                .faces
                .iter()
                .map(|f| projected_solid_angle(p, n, &f.corners))
                .sum();
            let got = sender_projected_solid_angle(p, n, &s, Some(&pairs));
            assert!(
                (got - face_by_face).abs() <= 1e-12 * face_by_face.max(1e-3),
                "{p}: {got} against {face_by_face}"
            );
            if s.faces
                .iter()
                .any(|f| f.corners.iter().any(|&c| n.dot(c - p) < 0.0))
            {
                clipped += 1;
            } else {
                whole += 1;
            }
        }
        assert!(
            whole > 50 && clipped > 50,
            "{whole} whole, {clipped} clipped"
        );
    }
}

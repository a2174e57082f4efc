//! The global pass's footprint rectangles: a filter row's bins on the `nu × nv` grid cut into
//! line-sized rectangles, nearby pieces joined.

use super::super::layout::{BinRect, MAX_RECT_BINS};

/// The rectangles of the bins' `nu × nv` grid that the global pass draws for one filter row
/// (`(bin, weight)`), keeping the weighted bins `keep` accepts: one per 4-connected component
/// of them (a footprint the octahedral map's seam splits has several), cut into bands of at
/// most `max_height` rows and [`MAX_RECT_BINS`] bins, then pieces close together joined
/// ([`MERGE_SLACK`]). Every kept bin is in exactly one mask.
pub fn bin_rects(
    nu: u32,
    nv: u32,
    row: &[(u32, f32)],
    keep: impl Fn(u32) -> bool,
    max_height: u32,
) -> Vec<BinRect> {
    // A one-row band must fit the 64-bit mask: grids have nu ≤ 64 (bins::MAX_BINS).
    debug_assert!(nu <= MAX_RECT_BINS, "{nu} grid columns");
    let m = (nu * nv) as usize;
    let mut on = vec![false; m];
    for &(j, w) in row {
        if w != 0.0 && keep(j) {
            on[j as usize] = true;
        }
    }
    let mut seen = vec![false; m];
    let (mut rects, mut stack, mut comp) = (Vec::new(), Vec::new(), Vec::new());
    for start in 0..m {
        if !on[start] || seen[start] {
            continue;
        }
        comp.clear();
        seen[start] = true;
        stack.push(start as u32);
        while let Some(b) = stack.pop() {
            comp.push(b);
            let (u, v) = (b % nu, b / nu);
            let near = [
                (u > 0).then(|| b - 1),
                (u + 1 < nu).then(|| b + 1),
                (v > 0).then(|| b - nu),
                (v + 1 < nv).then(|| b + nu),
            ];
            for n in near.into_iter().flatten() {
                if on[n as usize] && !seen[n as usize] {
                    seen[n as usize] = true;
                    stack.push(n);
                }
            }
        }
        // Column range of the component in each of its grid rows (connected: none is empty).
        let vmin = comp.iter().map(|b| b / nu).min().unwrap_or(0);
        let vmax = comp.iter().map(|b| b / nu).max().unwrap_or(0);
        let mut span = vec![(u32::MAX, 0u32); (vmax - vmin + 1) as usize];
        for b in &comp {
            let s = &mut span[(b / nu - vmin) as usize];
            *s = (s.0.min(b % nu), s.1.max(b % nu + 1));
        }
        let mut v = vmin;
        while v <= vmax {
            // Grow the band row by row while it stays within the line width and the mask.
            let (mut lo, mut hi) = span[(v - vmin) as usize];
            let mut end = v + 1;
            while end <= vmax {
                let (a, z) = span[(end - vmin) as usize];
                let (l, h) = (lo.min(a), hi.max(z));
                if end + 1 - v > max_height.max(1) || (h - l) * (end + 1 - v) > MAX_RECT_BINS {
                    break;
                }
                (lo, hi) = (l, h);
                end += 1;
            }
            let mut r = BinRect {
                u0: lo,
                v0: v,
                width: hi - lo,
                height: end - v,
                mask: 0,
            };
            for b in &comp {
                let (u, w) = (b % nu, b / nu);
                if (v..end).contains(&w) {
                    r.mask |= 1u64 << ((w - v) * r.width + (u - lo));
                }
            }
            rects.push(r);
            v = end;
        }
    }
    merge_rects(&mut rects, max_height.max(1));
    rects
}

/// Texels a merge may add to the rectangles it joins: on lavapipe a line costs about 165 ns of
/// front end (vertex shading, setup, binning) and a rasterized fragment about 8 ns (Cornell box,
/// README's profile section), so two pieces of a footprint close together (across the
/// octahedral seam) are cheaper drawn as one line. 24 against 16 and 40: the global pass gained
/// most of what 40 did, and Veach stays under 34M fragments per iteration.
pub const MERGE_SLACK: i64 = 24;

/// Joins pairs of `rects` whose bounding rectangle stays within `max_height` rows and
/// [`MAX_RECT_BINS`] bins and adds at most [`MERGE_SLACK`] texels, the cheapest first.
fn merge_rects(rects: &mut Vec<BinRect>, max_height: u32) {
    let area = |r: &BinRect| (r.width * r.height) as i64;
    loop {
        let mut best: Option<(i64, usize, usize, BinRect)> = None;
        for i in 0..rects.len() {
            for j in i + 1..rects.len() {
                let (a, b) = (rects[i], rects[j]);
                let (u0, v0) = (a.u0.min(b.u0), a.v0.min(b.v0));
                let u1 = (a.u0 + a.width).max(b.u0 + b.width);
                let v1 = (a.v0 + a.height).max(b.v0 + b.height);
                let u = BinRect {
                    u0,
                    v0,
                    width: u1 - u0,
                    height: v1 - v0,
                    mask: 0,
                };
                let added = area(&u) - area(&a) - area(&b);
                if u.height > max_height
                    || u.width * u.height > MAX_RECT_BINS
                    || added > MERGE_SLACK
                    || best.is_some_and(|b| b.0 <= added)
                {
                    continue;
                }
                best = Some((added, i, j, u));
            }
        }
        let Some((_, i, j, mut u)) = best else {
            return;
        };
        for r in [rects[i], rects[j]] {
            for bit in 0..r.width * r.height {
                if r.mask >> bit & 1 == 1 {
                    let (du, dv) = (r.u0 + bit % r.width - u.u0, r.v0 + bit / r.width - u.v0);
                    u.mask |= 1u64 << (dv * u.width + du);
                }
            }
        }
        rects[i] = u;
        rects.swap_remove(j);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearby_pieces_share_a_line_and_distant_ones_do_not() {
        // Two 2×2 pieces one column apart: one 5×2 line (2 texels added).
        let square = |u0: u32, v0: u32, n: u32| {
            (0..n * n).map(move |k| ((v0 + k / n) * 8 + u0 + k % n, 1.0f32))
        };
        let row: Vec<_> = square(0, 0, 2).chain(square(3, 0, 2)).collect();
        let r = bin_rects(8, 16, &row, |_| true, 16);
        assert_eq!(r.len(), 1, "{r:?}");
        assert_eq!((r[0].u0, r[0].v0, r[0].width, r[0].height), (0, 0, 5, 2));
        assert_eq!(r[0].mask, 0b11011_11011);
        // Two 3×3 pieces twelve rows apart: joined they would add 27 > MERGE_SLACK texels.
        let row: Vec<_> = square(0, 0, 3).chain(square(0, 12, 3)).collect();
        assert_eq!(bin_rects(8, 16, &row, |_| true, 16).len(), 2);
        // Nor beyond the widest line.
        let row: Vec<_> = square(0, 0, 2).chain(square(0, 3, 2)).collect();
        assert_eq!(bin_rects(8, 16, &row, |_| true, 4).len(), 2);
        assert_eq!(bin_rects(8, 16, &row, |_| true, 5).len(), 1);
    }

    #[test]
    fn rectangles_cover_each_kept_bin_exactly_once() {
        let (nu, nv) = (8u32, 16u32);
        for center in [0u32, 7, 45, 64, 100, 127] {
            let (cu, cv) = ((center % nu) as i32, (center / nu) as i32);
            // A round footprint, with its far side across the seam (the opposite edge).
            let row: Vec<(u32, f32)> = (0..nu * nv)
                .filter(|b| {
                    let (u, v) = ((b % nu) as i32, (b / nu) as i32);
                    (u - cu).pow(2) + (v - cv).pow(2) <= 6 || (v == nv as i32 - 1 - cv && u == cu)
                })
                .map(|b| (b, if b == center + 1 { 0.0 } else { 0.5 }))
                .collect();
            for keep_all in [true, false] {
                let keep = |j: u32| keep_all || j % 3 != 0;
                for max_height in [1, 3, 16] {
                    let rects = bin_rects(nu, nv, &row, keep, max_height);
                    let mut count = vec![0; (nu * nv) as usize];
                    for r in &rects {
                        assert!(r.height <= max_height && r.width * r.height <= MAX_RECT_BINS);
                        assert!(r.u0 + r.width <= nu && r.v0 + r.height <= nv);
                        assert!(r.mask < 1u64 << (r.width * r.height) || r.width * r.height == 64);
                        for bit in 0..r.width * r.height {
                            if r.mask >> bit & 1 == 1 {
                                let (du, dv) = (bit % r.width, bit / r.width);
                                count[((r.v0 + dv) * nu + r.u0 + du) as usize] += 1;
                            }
                        }
                    }
                    for b in 0..nu * nv {
                        let want = row.iter().any(|e| e.0 == b && e.1 != 0.0) && keep(b);
                        assert_eq!(count[b as usize], want as i32, "bin {b} of {center}");
                    }
                    if max_height == 16 && keep_all {
                        // The footprint and its piece across the seam.
                        assert!(rects.len() <= 2, "{rects:?}");
                    }
                }
            }
        }
    }
}

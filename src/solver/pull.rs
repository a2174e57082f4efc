//! Pull: an interior node's exitant intensity is the sum of its leaves' (intensities are already
//! weighted by area, §4.2, so no scaling). The GPU draws one textured line per (leaf, ancestor).

use super::Table;
use crate::hierarchy::{Hierarchy, NodeKind};

/// Overwrites every cluster row of `i_ex` with the sum of its children's rows.
pub fn pull(h: &Hierarchy, i_ex: &mut Table) {
    let m = i_ex.bins;
    // Children follow their parent in pre-order, so a backward sweep sees children first.
    for i in (0..h.len()).rev() {
        if let NodeKind::Cluster([a, b]) = h.nodes[i].kind {
            let (head, tail) = i_ex.data.split_at_mut((i + 1) * m);
            let dst = &mut head[i * m..];
            let off = (i + 1) * m;
            let (ra, rb) = (a as usize * m - off, b as usize * m - off);
            for k in 0..m {
                dst[k] = tail[ra + k] + tail[rb + k];
            }
        }
    }
}

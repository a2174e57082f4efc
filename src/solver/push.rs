//! Push: the radiance gathered at interior nodes is added to every node below them. Pre-order
//! storage makes each subtree a contiguous range, which the GPU covers with one quad per node.

use super::Table;
use crate::hierarchy::Hierarchy;

/// `l_push[i] = Σ l_in[a]` over `i` and all its ancestors `a`.
pub fn push(h: &Hierarchy, l_in: &Table, l_push: &mut Table) {
    let m = l_in.bins;
    // Parents precede children in pre-order, so one forward sweep suffices.
    for (i, node) in h.nodes.iter().enumerate() {
        let (head, tail) = l_push.data.split_at_mut(i * m);
        let dst = &mut tail[..m];
        dst.copy_from_slice(l_in.row(i));
        if node.parent != u32::MAX {
            let p = node.parent as usize;
            for (d, s) in dst.iter_mut().zip(&head[p * m..(p + 1) * m]) {
                *d += *s;
            }
        }
    }
}

//! Push: the radiance gathered at interior nodes is added to every node below them (at a leaf,
//! only on its front: [`System::pushes`]). Pre-order storage makes each subtree a contiguous
//! range, which the GPU covers with one quad per node.

use super::Table;
use crate::system::System;

/// `l_push[i] = Σ l_in[a]` over `i` and all its ancestors `a` (a leaf's back: its own `l_in`).
pub fn push(sys: &System, l_in: &Table, l_push: &mut Table) {
    let h = &sys.hierarchy;
    let m = l_in.bins;
    // Parents precede children in pre-order, so one forward sweep suffices.
    for (i, node) in h.nodes.iter().enumerate() {
        let (head, tail) = l_push.data.split_at_mut(i * m);
        let dst = &mut tail[..m];
        dst.copy_from_slice(l_in.row(i));
        if node.parent != u32::MAX {
            let p = node.parent as usize;
            for (j, (d, s)) in dst.iter_mut().zip(&head[p * m..(p + 1) * m]).enumerate() {
                if sys.pushes(i as u32, j) {
                    *d += *s;
                }
            }
        }
    }
}

//! Push: the radiance gathered at interior nodes is added to every node below them (at a leaf,
//! only on its front: [`System::pushes`]). Pre-order storage makes each subtree a contiguous
//! range, which the GPU covers with one quad per node. A leaf scales what its ancestors push by
//! its [`System::push_factor`] (the receiver calibration, [`crate::system::receivers`]).

use super::Table;
use crate::system::System;

/// `l_push[i] = l_in[i] + k_i Σ l_in[a]` over `i`'s ancestors `a`, `k_i` its push factor (a
/// leaf's back: its own `l_in`).
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
            let k = sys.push_factor(i as u32);
            for (j, (d, s)) in dst.iter_mut().zip(&head[p * m..(p + 1) * m]).enumerate() {
                if sys.pushes(i as u32, j) {
                    *d += *s * k;
                }
            }
        }
    }
}

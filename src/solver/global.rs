//! Global pass (eq. 16): every link adds `F · I_ex(sender, sender_bin)` to the receiver's
//! incident radiance, spread over bins by its cone class's table (every link is filtered), in
//! the bins the receiver reads ([`System::reads`]: a leaf only on the sides the link reaches). Parallel
//! over receivers. The GPU blends exactly these bins (wide lines over rectangles of the bins' grid, the
//! rest of each rectangle discarded).

use super::Table;
use crate::system::System;
use glam::DVec3;
use rayon::prelude::*;

/// `l_in ← U(i_ex)`: gathers over all links (overwrites `l_in`).
pub fn global(sys: &System, i_ex: &Table, l_in: &mut Table) {
    let m = sys.bins.count;
    let links = &sys.links;
    l_in.data
        .par_chunks_mut(m)
        .enumerate()
        .for_each(|(r, row)| {
            row.fill(DVec3::ZERO);
            let range = links.offsets[r] as usize..links.offsets[r + 1] as usize;
            for l in &links.links[range] {
                let v = i_ex.data[l.sender as usize * m + l.sender_bin as usize] * l.form_factor;
                let spread = sys
                    .filters
                    .row(l.cone, l.receiver_bin as u32)
                    .expect("table of a used cone class");
                for &(j, w) in spread {
                    if sys.reads(l, j as usize) {
                        row[j as usize] += v * w as f64;
                    }
                }
            }
        });
}

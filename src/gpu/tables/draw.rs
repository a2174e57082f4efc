//! What the passes draw, built once from the system: the global pass's lines (bucketed by
//! sender image), push and pull row pairs, and the local pass's quads.

use super::super::layout::{
    BinRect, GpuCombo, GpuLink, QuadInstance, RowPair, LINK_MAX_COMBOS, LINK_MAX_ROWS,
};
use super::{bin_rects, TableLayout};
use crate::error::{Error, Result};
use crate::system::System;

/// Everything the passes draw, built once from the [`System`].
#[derive(Debug, Clone, Default)]
pub struct DrawData {
    /// One record per line of the global pass (a link has one per rectangle of receiver bins
    /// it covers, [`bin_rects`]), ordered by the sender's image ([`sender_image`]), then by the
    /// rectangle's height (the draw's line width).
    pub links: Vec<GpuLink>,
    /// `(sender image, line width, first record, record count)` of each draw of the global pass.
    pub link_buckets: Vec<(u32, u32, u32, u32)>,
    /// Links drawn (each has one record per rectangle).
    pub link_count: usize,
    /// The widest line (tallest rectangle) the records were made for.
    pub max_line_width: u32,
    /// What lines with the same central bin, filter layer and receiver rectangle share.
    pub combos: Vec<GpuCombo>,
    /// Fragments the global pass rasterizes (Σ rectangle areas over lines).
    pub global_fragments: u64,
    /// Fragments it blends: bins with filter weight that the receiver reads (the rest of a
    /// rectangle is discarded).
    pub global_blended: u64,
    /// Lines the global pass draws.
    pub global_lines: u64,
    /// Filter-table layer of each cone class (`u16::MAX` when unused).
    pub class_layer: Vec<u16>,
    /// Push, top-down: every node with its parent (`u32::MAX` for the root), by depth.
    pub push: Vec<RowPair>,
    /// `push[push_levels[d]]` are the nodes at depth `d`.
    pub push_levels: Vec<std::ops::Range<u32>>,
    /// Pull, bottom-up: every cluster with its right child (the left one is the next row),
    /// deepest clusters first.
    pub pull: Vec<RowPair>,
    /// `(range of pull, depth)` per level, deepest first.
    pub pull_levels: Vec<(std::ops::Range<u32>, u32)>,
    /// Runs of Lambertian leaf rows (local pass, diffuse fast path).
    pub diffuse_quads: Vec<QuadInstance>,
    /// Runs of glossy leaf rows (local pass, Phong sum).
    pub glossy_quads: Vec<QuadInstance>,
    /// Runs of all leaf rows (irradiance step).
    pub leaf_quads: Vec<QuadInstance>,
}

/// The multiply-rotate hash of rustc (`FxHasher`): the link packing looks up a small key per
/// link, where the standard library's SipHash took most of the time.
#[derive(Default)]
struct FxHasher(u64);

impl std::hash::Hasher for FxHasher {
    fn write(&mut self, bytes: &[u8]) {
        for c in bytes.chunks(8) {
            let mut w = [0u8; 8];
            w[..c.len()].copy_from_slice(c);
            self.write_u64(u64::from_le_bytes(w));
        }
    }
    fn write_u64(&mut self, v: u64) {
        self.0 = (self.0.rotate_left(5) ^ v).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
    fn write_u32(&mut self, v: u32) {
        self.write_u64(v as u64);
    }
    fn write_u16(&mut self, v: u16) {
        self.write_u64(v as u64);
    }
    fn write_u8(&mut self, v: u8) {
        self.write_u64(v as u64);
    }
    fn write_usize(&mut self, v: usize) {
        self.write_u64(v as u64);
    }
    fn finish(&self) -> u64 {
        self.0
    }
}

/// Which I_ex image holds row `row` of `sys`: [`SENDER_LEAF`] (the leaves' ping-pong pair),
/// [`SENDER_EVEN`] or [`SENDER_ODD`] (clusters by depth parity, as pull writes them).
pub fn sender_image(sys: &System, row: u32) -> u32 {
    if sys.leaf_slot[row as usize] != u32::MAX {
        SENDER_LEAF
    } else if sys.hierarchy.nodes[row as usize].depth % 2 == 1 {
        SENDER_ODD
    } else {
        SENDER_EVEN
    }
}

/// [`sender_image`]: a leaf's I_ex (`AR_SENDER_LEAF` in `glsl/common.glsl`).
pub const SENDER_LEAF: u32 = 0;
/// [`sender_image`]: a cluster at even depth (`AR_SENDER_EVEN`).
pub const SENDER_EVEN: u32 = 1;
/// [`sender_image`]: a cluster at odd depth (`AR_SENDER_ODD`).
pub const SENDER_ODD: u32 = 2;

impl DrawData {
    /// Builds the draw data of `sys` in `layout`.
    /// `glossy_everywhere` sends every leaf through the general BRDF pass (`--all-passes`);
    /// `max_line_width` is the widest line the device draws (1 without wide lines): the global
    /// pass's rectangles are at most that many bin rows tall.
    pub fn new(
        sys: &System,
        layout: &TableLayout,
        glossy_everywhere: bool,
        max_line_width: u32,
    ) -> Result<Self> {
        if sys.rows() as u64 > LINK_MAX_ROWS as u64 {
            return Err(Error::TooLarge {
                what: format!(
                    "GPU link records for {} nodes (they address at most {LINK_MAX_ROWS} rows; solver.element_size)",
                    sys.rows()
                ),
                needed_bytes: sys.rows() as u64 * 12,
                limit_bytes: LINK_MAX_ROWS as u64 * 12,
            });
        }
        let classes = sys.filters.rows.len();
        let mut class_layer = vec![u16::MAX; classes];
        for (layer, c) in sys.filters.used_classes().into_iter().enumerate() {
            class_layer[c] = layer as u16;
        }
        let lines = Self::links(sys, layout, &class_layer, max_line_width)?;
        let h = &sys.hierarchy;
        let depth = h.max_depth() as usize;
        let mut push_by_depth: Vec<Vec<RowPair>> = vec![Vec::new(); depth + 1];
        let mut pull_by_depth: Vec<Vec<RowPair>> = vec![Vec::new(); depth + 1];
        for (r, node) in h.nodes.iter().enumerate() {
            let r = r as u32;
            push_by_depth[node.depth as usize].push(RowPair {
                row: r,
                other: node.parent,
            });
            if let Some([_, right]) = h.children(r) {
                pull_by_depth[node.depth as usize].push(RowPair {
                    row: r,
                    other: right,
                });
            }
        }
        let (mut push, mut push_levels) = (Vec::new(), Vec::new());
        for level in push_by_depth {
            let start = push.len() as u32;
            push.extend(level);
            push_levels.push(start..push.len() as u32);
        }
        let (mut pull, mut pull_levels) = (Vec::new(), Vec::new());
        for (d, level) in pull_by_depth.into_iter().enumerate().rev() {
            if level.is_empty() {
                continue;
            }
            let start = pull.len() as u32;
            pull.extend(level);
            pull_levels.push((start..pull.len() as u32, d as u32));
        }
        let runs_of = |pred: &dyn Fn(u32) -> bool| {
            let mut out = Vec::new();
            let mut start = None;
            for r in 0..=sys.rows() as u32 {
                let inside = (r as usize) < sys.rows() && pred(r);
                match (inside, start) {
                    (true, None) => start = Some(r),
                    (false, Some(s)) => {
                        for (a, b) in layout.split(s, r) {
                            out.push(QuadInstance {
                                source: 0,
                                first: a,
                                end: b,
                            });
                        }
                        start = None;
                    }
                    _ => {}
                }
            }
            out
        };
        let glossy_leaf = |r: u32| {
            let slot = sys.leaf_slot[r as usize];
            slot != u32::MAX
                && (glossy_everywhere
                    || sys.materials[sys.leaves[slot as usize].material as usize].is_glossy())
        };
        let diffuse_quads = runs_of(&|r| sys.leaf_slot[r as usize] != u32::MAX && !glossy_leaf(r));
        let glossy_quads = runs_of(&glossy_leaf);
        let leaf_quads = runs_of(&|r| sys.leaf_slot[r as usize] != u32::MAX);
        Ok(Self {
            links: lines.records,
            link_count: sys.links.links.len(),
            max_line_width,
            link_buckets: lines.buckets,
            combos: lines.combos,
            global_fragments: lines.fragments,
            global_blended: lines.blended,
            global_lines: lines.lines,
            class_layer,
            push,
            push_levels,
            pull,
            pull_levels,
            diffuse_quads,
            glossy_quads,
            leaf_quads,
        })
    }

    /// The global pass's line records, their draw buckets and combos, and its counts.
    fn links(
        sys: &System,
        layout: &TableLayout,
        class_layer: &[u16],
        max_line_width: u32,
    ) -> Result<GlobalLines> {
        use std::collections::HashMap;
        type Fast<K, V> = HashMap<K, V, std::hash::BuildHasherDefault<FxHasher>>;
        let (nu, nv) = (layout.grid_columns(), layout.grid_rows);
        let max_height = max_line_width.clamp(1, nv);
        let mut combo_of: Fast<(u32, BinRect), u32> = Fast::default();
        let mut combos: Vec<GpuCombo> = Vec::new();
        // Each link's shape: the combos of its rectangles, shared by links alike in the
        // central bin, the cone class and which bins the receiver reads: all of them for a
        // cluster, those facing the sides the link reaches for a leaf (`System::reads`: its
        // normal and the sides). So shapes are cached per (normal, bin, class, sides) over the
        // whole scene (coplanar leaves share).
        let mut shapes: Vec<Vec<u32>> = Vec::new();
        let mut per_link: Vec<u32> = Vec::with_capacity(sys.links.links.len());
        let mut cache: Fast<([u64; 3], u16, u8, u8), u32> = Fast::default();
        let mut out = GlobalLines::default();
        for l in &sys.links.links {
            let reader = match sys.leaf_slot[l.receiver as usize] {
                u32::MAX => ([u64::MAX; 3], 0),
                slot => {
                    let n = sys.leaves[slot as usize].normal;
                    ([n.x, n.y, n.z].map(|c| (c + 0.0).to_bits()), l.sides)
                }
            };
            let key = (reader.0, l.receiver_bin, l.cone, reader.1);
            let shape = if let Some(&e) = cache.get(&key) {
                e
            } else {
                let row = sys
                    .filters
                    .row(l.cone, l.receiver_bin as u32)
                    .expect("table of a used cone class");
                let rects = bin_rects(nu, nv, row, |j| sys.reads(l, j as usize), max_height);
                let bin_layer = l.receiver_bin as u32 | (class_layer[l.cone as usize] as u32) << 16;
                let ids = rects
                    .iter()
                    .map(|r| {
                        let next = combos.len() as u32;
                        *combo_of.entry((bin_layer, *r)).or_insert_with(|| {
                            combos.push(GpuCombo {
                                bin_layer,
                                rect: r.packed(),
                                mask: [r.mask as u32, (r.mask >> 32) as u32],
                            });
                            next
                        })
                    })
                    .collect();
                shapes.push(ids);
                cache.insert(key, shapes.len() as u32 - 1);
                shapes.len() as u32 - 1
            };
            per_link.push(shape);
        }
        if combos.len() as u64 > LINK_MAX_COMBOS as u64 {
            return Err(Error::Invalid(format!(
                "{} link combos exceed what a link record addresses ({LINK_MAX_COMBOS})",
                combos.len(),
            )));
        }
        // One record per (link, rectangle), ordered by the sender's image, then the
        // rectangle's height: one draw per (image, height) with that line width, and the
        // vertex shader fetches I_ex from that image only. A counting sort (stable).
        let height = |c: u32| combos[c as usize].rect >> 24;
        let keys = (max_height + 1) as usize;
        let mut start = vec![0u32; 3 * keys + 1];
        for (l, &shape) in sys.links.links.iter().zip(&per_link) {
            for &c in &shapes[shape as usize] {
                start[sender_image(sys, l.sender) as usize * keys + height(c) as usize + 1] += 1;
            }
        }
        for i in 1..start.len() {
            start[i] += start[i - 1];
        }
        let total = start[start.len() - 1] as usize;
        out.records = vec![GpuLink::default(); total];
        for (l, &shape) in sys.links.links.iter().zip(&per_link) {
            let image = sender_image(sys, l.sender) as usize;
            for &c in &shapes[shape as usize] {
                let k = image * keys + height(c) as usize;
                out.records[start[k] as usize] =
                    GpuLink::new(l.receiver, l.sender, c, l.form_factor as f32);
                start[k] += 1;
                let r = combos[c as usize];
                out.fragments += ((r.rect >> 16 & 0xff) * (r.rect >> 24)) as u64;
                out.blended += (r.mask[0].count_ones() + r.mask[1].count_ones()) as u64;
            }
        }
        // After the fill, start[k] is the end of bucket k.
        let mut first = 0u32;
        for (k, &end) in start[..3 * keys].iter().enumerate() {
            if end > first {
                out.buckets
                    .push(((k / keys) as u32, (k % keys) as u32, first, end - first));
            }
            first = first.max(end);
        }
        out.lines = total as u64;
        out.combos = combos;
        Ok(out)
    }
}

/// What [`DrawData::links`] builds.
#[derive(Default)]
struct GlobalLines {
    records: Vec<GpuLink>,
    buckets: Vec<(u32, u32, u32, u32)>,
    combos: Vec<GpuCombo>,
    fragments: u64,
    blended: u64,
    lines: u64,
}

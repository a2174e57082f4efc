//! The table layout of §4.1 and the per-instance data the passes draw: one row per hierarchy
//! node, one texel per bin, rows split into column blocks to respect maxImageDimension2D.

use super::layout::{
    pack_run, GpuCombo, GpuLink, QuadInstance, RowPair, LINK_MAX_COMBOS, LINK_MAX_ROWS, MAX_RUNS,
};
use crate::error::{Error, Result};
use crate::solver::Table;
use crate::system::System;
use glam::DVec3;

/// Where rows and bins live in the table images. Within a row, bins are stored column by column
/// of their `nu × nv` grid (position `iu·nv + iv` for bin `iv·nu + iu`): the grid's cells are up
/// to twice as tall as wide on the octahedral square, so a filter's round footprint covers
/// about half as many grid columns as grid rows, and the global pass draws one line per
/// consecutive run of positions.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TableLayout {
    /// Rows (hierarchy nodes).
    pub rows: u32,
    /// Bins per row.
    pub bins: u32,
    /// Rows per column block (image height).
    pub rows_per_column: u32,
    /// Column blocks.
    pub columns: u32,
    /// Rows `nv` of the bins' grid (1: positions are bin indices).
    pub grid_rows: u32,
}

impl TableLayout {
    /// Fits `rows × bins` into images no larger than `max_dim` on a side.
    pub fn new(rows: u32, bins: u32, max_dim: u32) -> Result<Self> {
        Self::with_column_height(rows, bins, max_dim, max_dim)
    }

    /// As [`TableLayout::new`] with column blocks of at most `column_height` rows (tests use a
    /// small height to exercise the split on small scenes).
    pub fn with_column_height(
        rows: u32,
        bins: u32,
        max_dim: u32,
        column_height: u32,
    ) -> Result<Self> {
        let rows_per_column = rows.clamp(1, column_height.min(max_dim));
        let columns = rows.div_ceil(rows_per_column).max(1);
        if columns as u64 * bins as u64 > max_dim as u64 || bins > u16::MAX as u32 {
            return Err(Error::TooLarge {
                what: format!(
                    "table images for {rows} nodes × {bins} bins (maxImageDimension2D {max_dim})"
                ),
                needed_bytes: rows as u64 * bins as u64 * 8,
                limit_bytes: max_dim as u64 * max_dim as u64 * 8,
            });
        }
        Ok(Self {
            rows,
            bins,
            rows_per_column,
            columns,
            grid_rows: 1,
        })
    }

    /// The same layout with bins stored column by column of a grid of `nv` rows.
    pub fn with_grid(self, nv: u32) -> Self {
        debug_assert!(nv >= 1 && self.bins % nv == 0);
        Self {
            grid_rows: nv,
            ..self
        }
    }

    /// Position of `bin` within its row (`ar_position` in common.glsl).
    pub fn position(&self, bin: u32) -> u32 {
        let (nv, nu) = (self.grid_rows, self.bins / self.grid_rows);
        (bin % nu) * nv + bin / nu
    }

    /// The bin stored at `position` of a row (`ar_bin_at` in common.glsl).
    pub fn bin_at(&self, position: u32) -> u32 {
        let (nv, nu) = (self.grid_rows, self.bins / self.grid_rows);
        (position % nv) * nu + position / nv
    }

    /// Texel of `(row, position within the row)`.
    pub fn position_texel(&self, row: u32, position: u32) -> (u32, u32) {
        (
            (row / self.rows_per_column) * self.bins + position,
            row % self.rows_per_column,
        )
    }

    /// Table image width, texels.
    pub fn width(&self) -> u32 {
        self.columns * self.bins
    }

    /// Texel of `(row, bin)`.
    pub fn texel(&self, row: u32, bin: u32) -> (u32, u32) {
        self.position_texel(row, self.position(bin))
    }

    /// Texel of a row in the per-row images (attributes, irradiance).
    pub fn row_texel(&self, row: u32) -> (u32, u32) {
        (row / self.rows_per_column, row % self.rows_per_column)
    }

    /// Splits the row range `[first, end)` at column-block boundaries.
    pub fn split(&self, first: u32, end: u32) -> impl Iterator<Item = (u32, u32)> + '_ {
        let h = self.rows_per_column;
        let mut a = first;
        std::iter::from_fn(move || {
            (a < end).then(|| {
                let b = end.min((a / h + 1) * h);
                let r = (a, b);
                a = b;
                r
            })
        })
    }

    /// Converts texels read back (`rgba` per texel, row-major over the image) into a [`Table`].
    pub fn to_table(&self, rgba: &[[f32; 4]]) -> Table {
        let mut t = Table::zeros(self.rows as usize, self.bins as usize);
        let w = self.width() as usize;
        for r in 0..self.rows {
            for j in 0..self.bins {
                let (x, y) = self.texel(r, j);
                let v = rgba[y as usize * w + x as usize];
                t.data[(r * self.bins + j) as usize] =
                    DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64);
            }
        }
        t
    }

    /// Lays a [`Table`] out as RGBA texels.
    pub fn from_table(&self, t: &Table) -> Vec<[f32; 4]> {
        self.from_table_scaled(t, 1.0)
    }

    /// As [`TableLayout::from_table`], every value multiplied by `scale` (the solver's source
    /// scale) on the way, without a scaled copy of the table.
    pub fn from_table_scaled(&self, t: &Table, scale: f64) -> Vec<[f32; 4]> {
        let w = self.width() as usize;
        let mut out = vec![[0.0f32; 4]; w * self.rows_per_column as usize];
        for r in 0..self.rows {
            for j in 0..self.bins {
                let (x, y) = self.texel(r, j);
                let v = t.data[(r * self.bins + j) as usize] * scale;
                out[y as usize * w + x as usize] = [v.x as f32, v.y as f32, v.z as f32, 0.0];
            }
        }
        out
    }
}

/// Everything the passes draw, built once from the [`System`].
#[derive(Debug, Clone, Default)]
pub struct DrawData {
    /// One per link (global), ordered by the sender's image ([`sender_image`]), then by run
    /// count: the links of a bucket with `k` runs are drawn with `2k` vertices each.
    pub links: Vec<GpuLink>,
    /// `(sender image, runs, first link, link count)` of each draw of the global pass.
    pub link_buckets: Vec<(u32, u32, u32, u32)>,
    /// What links with the same central bin, filter layer and receiver runs share.
    pub combos: Vec<GpuCombo>,
    /// Receiver bin runs of the combos ([`pack_run`]).
    pub runs: Vec<u32>,
    /// Fragments the global pass draws (Σ run lengths over links), all of them blended.
    pub global_fragments: u64,
    /// Lines the global pass draws (Σ runs over links).
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

/// Maximal runs `[first, end)` of consecutive positions (in `layout`) of the bins of a filter
/// row (`(bin, weight)`) that `keep` accepts.
pub fn bin_runs(
    layout: &TableLayout,
    row: &[(u32, f32)],
    keep: impl Fn(u32) -> bool,
) -> Vec<(u32, u32)> {
    let mut positions: Vec<u32> = row
        .iter()
        .filter(|e| keep(e.0))
        .map(|e| layout.position(e.0))
        .collect();
    positions.sort_unstable();
    let mut runs: Vec<(u32, u32)> = Vec::new();
    for p in positions {
        match runs.last_mut() {
            Some(r) if r.1 == p => r.1 = p + 1,
            _ => runs.push((p, p + 1)),
        }
    }
    runs
}

impl DrawData {
    /// Builds the draw data of `sys` in `layout`.
    /// `glossy_everywhere` sends every leaf through the general BRDF pass (`--all-passes`).
    pub fn new(sys: &System, layout: &TableLayout, glossy_everywhere: bool) -> Result<Self> {
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
        let (links, link_buckets, combos, runs, global_fragments, global_lines) =
            Self::links(sys, layout, &class_layer)?;
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
            links,
            link_buckets,
            combos,
            runs,
            global_fragments,
            global_lines,
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

    /// Link records, their draw buckets, combos and runs, and the fragment and line counts.
    #[allow(clippy::type_complexity)]
    fn links(
        sys: &System,
        layout: &TableLayout,
        class_layer: &[u16],
    ) -> Result<(
        Vec<GpuLink>,
        Vec<(u32, u32, u32, u32)>,
        Vec<GpuCombo>,
        Vec<u32>,
        u64,
        u64,
    )> {
        use std::collections::HashMap;
        type Fast<K, V> = HashMap<K, V, std::hash::BuildHasherDefault<FxHasher>>;
        let mut combo_of: Fast<(u16, u16, Vec<(u32, u32)>), u32> = Fast::default();
        let (mut combos, mut runs) = (Vec::new(), Vec::new());
        let (mut fragments, mut lines) = (0u64, 0u64);
        // Every link's combo and run count. The runs depend on the central bin, the cone class
        // and which bins the receiver reads: all of them for a cluster, those facing the sides
        // the link reaches for a leaf (`System::reads`: its normal and the sides). So they are
        // cached per (normal, bin, class, sides) over the whole scene (coplanar leaves share).
        let mut per_link: Vec<(u32, u32)> = Vec::with_capacity(sys.links.links.len());
        let mut cache: Fast<([u64; 3], u16, u8, u8), (u32, u32)> = Fast::default();
        for l in &sys.links.links {
            let reader = match sys.leaf_slot[l.receiver as usize] {
                u32::MAX => ([u64::MAX; 3], 0),
                slot => {
                    let n = sys.leaves[slot as usize].normal;
                    ([n.x, n.y, n.z].map(|c| (c + 0.0).to_bits()), l.sides)
                }
            };
            let key = (reader.0, l.receiver_bin, l.cone, reader.1);
            let entry = if let Some(e) = cache.get(&key) {
                *e
            } else {
                let row = sys
                    .filters
                    .row(l.cone, l.receiver_bin as u32)
                    .expect("table of a used cone class");
                let r = bin_runs(layout, row, |j| sys.reads(l, j as usize));
                let layer = class_layer[l.cone as usize];
                let count = r.len() as u32;
                if count > MAX_RUNS {
                    return Err(Error::Invalid(format!(
                        "a link covers {count} runs of receiver bins, more than {MAX_RUNS}"
                    )));
                }
                let len: u32 = r.iter().map(|(a, b)| b - a).sum();
                let next = combos.len() as u32;
                let id = *combo_of
                    .entry((l.receiver_bin, layer, r.clone()))
                    .or_insert_with(|| {
                        combos.push(GpuCombo {
                            bin_layer: l.receiver_bin as u32 | (layer as u32) << 16,
                            runs: runs.len() as u32 | count << 24,
                        });
                        runs.extend(r.iter().map(|&(a, b)| pack_run(a, b)));
                        next
                    });
                let e = (id, count | len << 8);
                cache.insert(key, e);
                e
            };
            fragments += (entry.1 >> 8) as u64;
            lines += (entry.1 & 0xff) as u64;
            per_link.push(entry);
        }
        if combos.len() as u64 > LINK_MAX_COMBOS as u64 || runs.len() >= 1 << 24 {
            return Err(Error::Invalid(format!(
                "{} link combos and {} runs exceed what a link record addresses ({LINK_MAX_COMBOS} combos, 2^24 runs)",
                combos.len(),
                runs.len()
            )));
        }
        // Order the records by the sender's image, then run count: one draw per (image, count),
        // `2·runs` vertices per link, and the vertex shader fetches I_ex from that image only.
        // A counting sort (stable): at most 3 × 256 keys.
        let key: Vec<u32> = sys
            .links
            .links
            .iter()
            .zip(&per_link)
            .map(|(l, e)| sender_image(sys, l.sender) << 8 | (e.1 & 0xff))
            .collect();
        let mut start = vec![0u32; 3 << 8 | 1];
        for &k in &key {
            start[k as usize + 1] += 1;
        }
        for i in 1..start.len() {
            start[i] += start[i - 1];
        }
        let mut order = vec![0u32; key.len()];
        for (i, &k) in key.iter().enumerate() {
            order[start[k as usize] as usize] = i as u32;
            start[k as usize] += 1;
        }
        let mut buckets: Vec<(u32, u32, u32, u32)> = Vec::new();
        let links: Vec<GpuLink> = order
            .iter()
            .enumerate()
            .map(|(k, &i)| {
                let l = &sys.links.links[i as usize];
                let (combo, count) = (per_link[i as usize].0, per_link[i as usize].1 & 0xff);
                let source = key[i as usize] >> 8;
                match buckets.last_mut() {
                    Some(b) if b.0 == source && b.1 == count => b.3 += 1,
                    _ => buckets.push((source, count, k as u32, 1)),
                }
                GpuLink::new(l.receiver, l.sender, combo, l.form_factor as f32)
            })
            .collect();
        buckets.retain(|b| b.1 > 0);
        // The global pass pulls link `k` of a bucket by vertex index `2·runs·k + …`.
        if let Some(b) = buckets
            .iter()
            .find(|b| 2 * b.1 as u64 * (b.2 as u64 + b.3 as u64) > u32::MAX as u64)
        {
            return Err(Error::Invalid(format!(
                "{} links of {} receiver-bin runs each exceed the global pass's 32-bit vertex index",
                b.2 + b.3,
                b.1
            )));
        }
        Ok((links, buckets, combos, runs, fragments, lines))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn columns_respect_the_limit_and_round_trip() {
        let l = TableLayout::new(10, 4, 3).unwrap_err();
        assert!(l.to_string().contains("maxImageDimension2D"));
        let l = TableLayout::new(10, 4, 16).unwrap();
        assert_eq!((l.rows_per_column, l.columns, l.width()), (10, 1, 4));
        let l = TableLayout::with_column_height(10, 3, 16, 9).unwrap();
        assert_eq!((l.rows_per_column, l.columns, l.width()), (9, 2, 6));
        assert_eq!(l.texel(9, 2), (5, 0));
        assert_eq!(l.split(7, 10).collect::<Vec<_>>(), [(7, 9), (9, 10)]);
        let mut t = Table::zeros(10, 3);
        for (i, v) in t.data.iter_mut().enumerate() {
            *v = DVec3::splat(i as f64);
        }
        assert_eq!(l.to_table(&l.from_table(&t)), t);
    }
}

//! The table layout of §4.1 and the per-instance data the passes draw: one row per hierarchy
//! node, one texel per bin, rows split into column blocks to respect maxImageDimension2D. The
//! incident tables (L_in, L_push) keep each node's bins as a tile of the bins' `nu × nv` grid
//! instead, so that the global pass draws a filter's round footprint as one wide line.

use super::layout::{
    BinRect, GpuCombo, GpuLink, QuadInstance, RowPair, LINK_MAX_COMBOS, LINK_MAX_ROWS,
    MAX_RECT_BINS,
};
use crate::error::{Error, Result};
use crate::solver::Table;
use crate::system::System;
use glam::DVec3;

/// Where rows and bins live in the table images: bin `j` of row `r` at texel `(column block ·
/// m + j, r mod rows_per_column)`, except in the incident tables (L_in, L_push), which keep a
/// node's bins as a tile of the bins' `nu × nv` grid ([`TableLayout::tile_texel`]).
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
    /// Rows `nv` of the bins' grid (the incident tables' tile height; 1 until
    /// [`TableLayout::with_grid`]).
    pub grid_rows: u32,
    /// Incident tables: nodes per column block of tiles (each tile `nu` wide, `nv` tall).
    pub tile_nodes: u32,
    /// Incident tables: column blocks of tiles.
    pub tile_columns: u32,
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
            tile_nodes: rows_per_column,
            tile_columns: columns,
        })
    }

    /// The same layout with the incident tables' tiles `nu × nv` (the bins' grid):
    /// `rows_per_column / nv` nodes per column block, so the tiled images are about as large as
    /// the others.
    pub fn with_grid(self, nv: u32, max_dim: u32) -> Result<Self> {
        debug_assert!(nv >= 1 && self.bins % nv == 0);
        let tile_nodes = (self.rows_per_column / nv).max(1);
        let tile_columns = self.rows.div_ceil(tile_nodes).max(1);
        let nu = self.bins / nv;
        if tile_columns as u64 * nu as u64 > max_dim as u64 || tile_nodes * nv > max_dim.max(nv) {
            return Err(Error::TooLarge {
                what: format!(
                    "incident tables for {} nodes in tiles of {nu}×{nv} bins (maxImageDimension2D {max_dim})",
                    self.rows
                ),
                needed_bytes: self.rows as u64 * self.bins as u64 * 8,
                limit_bytes: max_dim as u64 * max_dim as u64 * 8,
            });
        }
        Ok(Self {
            grid_rows: nv,
            tile_nodes,
            tile_columns,
            ..self
        })
    }

    /// Columns `nu` of the bins' grid.
    pub fn grid_columns(&self) -> u32 {
        self.bins / self.grid_rows
    }

    /// Incident tables' image size, texels.
    pub fn tile_extent(&self) -> (u32, u32) {
        (
            self.tile_columns * self.grid_columns(),
            self.tile_nodes * self.grid_rows,
        )
    }

    /// Incident tables: texel of bin 0 of `row`'s tile (`ar_in_origin` in common.glsl).
    pub fn tile_origin(&self, row: u32) -> (u32, u32) {
        (
            (row / self.tile_nodes) * self.grid_columns(),
            (row % self.tile_nodes) * self.grid_rows,
        )
    }

    /// Incident tables: texel of `(row, bin)`, bin `iv·nu + iu` at `(iu, iv)` of the row's tile.
    pub fn tile_texel(&self, row: u32, bin: u32) -> (u32, u32) {
        let (x, y) = self.tile_origin(row);
        let nu = self.grid_columns();
        (x + bin % nu, y + bin / nu)
    }

    /// Converts texels of an incident table read back (row-major over [`Self::tile_extent`])
    /// into a [`Table`].
    pub fn tiles_to_table(&self, rgba: &[[f32; 4]]) -> Table {
        self.gather(rgba, self.tile_extent().0, |r, j| self.tile_texel(r, j))
    }

    /// The [`Table`] of texels `rgba` (row-major, `width` per image row) where `(row, bin)`
    /// lives at `texel(row, bin)`.
    fn gather(
        &self,
        rgba: &[[f32; 4]],
        width: u32,
        texel: impl Fn(u32, u32) -> (u32, u32),
    ) -> Table {
        let mut t = Table::zeros(self.rows as usize, self.bins as usize);
        for r in 0..self.rows {
            for j in 0..self.bins {
                let (x, y) = texel(r, j);
                let v = rgba[(y * width + x) as usize];
                t.data[(r * self.bins + j) as usize] =
                    DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64);
            }
        }
        t
    }

    /// Table image width, texels.
    pub fn width(&self) -> u32 {
        self.columns * self.bins
    }

    /// Texel of `(row, bin)` (`ar_texel` in common.glsl).
    pub fn texel(&self, row: u32, bin: u32) -> (u32, u32) {
        (
            (row / self.rows_per_column) * self.bins + bin,
            row % self.rows_per_column,
        )
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
        self.gather(rgba, self.width(), |r, j| self.texel(r, j))
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

    #[test]
    fn tiles_hold_every_bin_once_and_round_trip() {
        let l = TableLayout::with_column_height(10, 32, 4096, 9)
            .unwrap()
            .with_grid(4, 4096)
            .unwrap();
        // 9 rows per column block hold two 4-row tiles; 10 nodes need 5 columns of 8 bins.
        assert_eq!(
            (l.tile_nodes, l.tile_columns, l.tile_extent()),
            (2, 5, (40, 8))
        );
        assert_eq!(l.tile_texel(3, 9), (8 + 1, 4 + 1));
        let (w, h) = l.tile_extent();
        let mut seen = vec![false; (w * h) as usize];
        let mut t = Table::zeros(10, 32);
        let mut rgba = vec![[0.0f32; 4]; (w * h) as usize];
        for r in 0..10 {
            for j in 0..32 {
                let (x, y) = l.tile_texel(r, j);
                assert!(x < w && y < h);
                let i = (y * w + x) as usize;
                assert!(!seen[i], "texel ({x}, {y}) holds two bins");
                seen[i] = true;
                let v = (r * 32 + j) as f32;
                rgba[i] = [v, v, v, 0.0];
                t.data[(r * 32 + j) as usize] = DVec3::splat(v as f64);
            }
        }
        assert_eq!(l.tiles_to_table(&rgba), t);
        // Blocks of 7 rows hold one 4-row tile: 28 tiles of 8 columns pass 128 texels.
        assert!(TableLayout::with_column_height(28, 32, 128, 7)
            .unwrap()
            .with_grid(4, 128)
            .is_err());
    }

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

//! The table layout of §4.1 and the per-instance data the passes draw: one row per hierarchy
//! node, one texel per bin, rows split into column blocks to respect maxImageDimension2D.

use super::layout::{GpuLink, PullLine, QuadInstance};
use crate::error::{Error, Result};
use crate::solver::Table;
use crate::system::System;
use glam::DVec3;

/// Where rows and bins live in the table images.
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
        })
    }

    /// Table image width, texels.
    pub fn width(&self) -> u32 {
        self.columns * self.bins
    }

    /// Texel of `(row, bin)`.
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
        let w = self.width() as usize;
        let mut out = vec![[0.0f32; 4]; w * self.rows_per_column as usize];
        for r in 0..self.rows {
            for j in 0..self.bins {
                let (x, y) = self.texel(r, j);
                let v = t.data[(r * self.bins + j) as usize];
                out[y as usize * w + x as usize] = [v.x as f32, v.y as f32, v.z as f32, 0.0];
            }
        }
        out
    }
}

/// Everything the passes draw, built once from the [`System`].
#[derive(Debug, Clone, Default)]
pub struct DrawData {
    /// One per link (global pass).
    pub links: Vec<GpuLink>,
    /// Fragments the global pass draws (sum of spans).
    pub global_fragments: u64,
    /// Filter-table layer of each cone class (`u16::MAX` when unused).
    pub class_layer: Vec<u16>,
    /// One quad per (receiving node, column block) of its subtree (push pass).
    pub push_quads: Vec<QuadInstance>,
    /// Runs of Lambertian leaf rows (local pass, diffuse fast path).
    pub diffuse_quads: Vec<QuadInstance>,
    /// Runs of glossy leaf rows (local pass, Phong sum).
    pub glossy_quads: Vec<QuadInstance>,
    /// Runs of all leaf rows (irradiance step).
    pub leaf_quads: Vec<QuadInstance>,
    /// One per (leaf, ancestor) pair (pull pass).
    pub pull_lines: Vec<PullLine>,
}

impl DrawData {
    /// Builds the draw data of `sys` in `layout`.
    /// `glossy_everywhere` sends every leaf through the general BRDF pass (`--all-passes`).
    pub fn new(sys: &System, layout: &TableLayout, glossy_everywhere: bool) -> Self {
        let classes = sys.filters.rows.len();
        let mut class_layer = vec![u16::MAX; classes];
        for (layer, c) in sys.filters.used_classes().into_iter().enumerate() {
            class_layer[c] = layer as u16;
        }
        // Bin span of every (class, central bin) filter row: the line covers only those texels.
        let spans: Vec<Vec<u32>> = sys
            .filters
            .rows
            .iter()
            .map(|rows| {
                rows.iter()
                    .map(|row| {
                        let lo = row.iter().map(|e| e.0).min().unwrap_or(0);
                        let hi = row.iter().map(|e| e.0 + 1).max().unwrap_or(0);
                        lo | (hi << 16)
                    })
                    .collect()
            })
            .collect();
        let mut global_fragments = 0u64;
        let links: Vec<GpuLink> = sys
            .links
            .links
            .iter()
            .map(|l| {
                let span = spans[l.cone as usize][l.receiver_bin as usize];
                global_fragments += ((span >> 16) - (span & 0xffff)) as u64;
                GpuLink {
                    receiver: l.receiver,
                    sender: l.sender,
                    bin_layer: l.sender_bin as u32 | ((class_layer[l.cone as usize] as u32) << 16),
                    span,
                    form_factor: l.form_factor as f32,
                }
            })
            .collect();
        let h = &sys.hierarchy;
        let mut push_quads = Vec::new();
        for r in 0..sys.rows() as u32 {
            if sys.links.offsets[r as usize + 1] > sys.links.offsets[r as usize] {
                for (a, b) in layout.split(r, h.nodes[r as usize].end) {
                    push_quads.push(QuadInstance {
                        source: r,
                        first: a,
                        end: b,
                    });
                }
            }
        }
        let runs = |pred: &dyn Fn(u32) -> bool| {
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
        let diffuse_quads = runs(&|r| sys.leaf_slot[r as usize] != u32::MAX && !glossy_leaf(r));
        let glossy_quads = runs(&glossy_leaf);
        let leaf_quads = runs(&|r| sys.leaf_slot[r as usize] != u32::MAX);
        let mut pull_lines = Vec::new();
        for &leaf in &h.leaves {
            let mut a = h.nodes[leaf as usize].parent;
            while a != u32::MAX {
                pull_lines.push(PullLine { leaf, ancestor: a });
                a = h.nodes[a as usize].parent;
            }
        }
        Self {
            links,
            global_fragments,
            class_layer,
            push_quads,
            diffuse_quads,
            glossy_quads,
            leaf_quads,
            pull_lines,
        }
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

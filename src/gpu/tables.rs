//! The table layout of §4.1 and the per-instance data the passes draw: one row per hierarchy
//! node, one texel per bin, rows split into column blocks to respect maxImageDimension2D. The
//! incident tables (L_in, L_push) keep each node's bins as a tile of the bins' `nu × nv` grid
//! instead, so that the global pass draws a filter's round footprint as one wide line.

use crate::error::{Error, Result};
use crate::solver::Table;
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

mod draw;
mod rects;

pub use draw::{sender_image, DrawData, SENDER_EVEN, SENDER_LEAF, SENDER_ODD};
pub use rects::{bin_rects, MERGE_SLACK};

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
}

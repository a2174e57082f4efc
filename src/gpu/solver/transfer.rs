//! Table transfers between the host and the GPU solver's images: read-backs the CPU asks for
//! (tests, `reference`, warm starts) and uploads of I_ex and I_total. The iterations never use
//! them (the convergence figures come from the GPU reduction).

use super::GpuSolver;
use crate::error::Result;
use crate::gpu::memory::Image;
use crate::gpu::pack::{decode, encode};
use crate::gpu::resources::SolverImages;
use crate::plan::range::Range;
use crate::solver::Table;
use crate::system::System;

impl GpuSolver {
    fn read_texels(
        &mut self,
        pick: impl FnOnce(&mut SolverImages<Image>) -> &mut Image,
    ) -> Result<Vec<[f32; 4]>> {
        let img = pick(&mut self.res.images);
        Ok(decode(img.format, &img.read()?))
    }

    /// Reads I_ex (leaves + clusters) back as a table.
    pub fn read_i_ex(&mut self) -> Result<Table> {
        let p = self.parity;
        let leaf = self.read_texels(|im| im.leaf_ex_mut(p))?;
        let even = self.read_texels(|im| &mut im.cluster_ex)?;
        let odd = self.read_texels(|im| &mut im.cluster_ex_odd)?;
        // Each row is valid in one of the three images and zero in the others.
        let sum: Vec<[f32; 4]> = leaf
            .iter()
            .zip(even.iter().zip(&odd))
            .map(|(a, (b, c))| {
                [
                    a[0] + b[0] + c[0],
                    a[1] + b[1] + c[1],
                    a[2] + b[2] + c[2],
                    0.0,
                ]
            })
            .collect();
        Ok(self.unscale(self.res.layout().to_table(&sum)))
    }

    /// Reads I_total back.
    pub fn read_i_total(&mut self) -> Result<Table> {
        let t = self.read_texels(|im| &mut im.i_total)?;
        Ok(self.unscale(self.res.layout().to_table(&t)))
    }

    /// Replaces I_total with `table` (unscaled): a method that computes its display table
    /// itself (progressive refinement) draws it with the same frame.
    pub fn upload_i_total(&mut self, table: &Table) -> Result<()> {
        let l = *self.res.layout();
        let mut scaled = table.clone();
        scaled.data.iter_mut().for_each(|v| *v *= self.scale);
        let bytes = encode(self.res.plan.format, &l.from_table(&scaled));
        self.held.i_total = true;
        self.res.images.i_total.upload(&bytes)
    }

    /// Replaces I_ex with `table` (unscaled, one row per node of `sys`, clusters as pull makes
    /// them): a warm start from the previous frame's solution when objects moved (§3.3). Leaf
    /// rows go to the current leaf image, cluster rows to their depth parity's image.
    pub fn upload_i_ex(&mut self, sys: &System, table: &Table) -> Result<()> {
        debug_assert_eq!(sys.rows(), self.leaf_rows.len());
        self.put_i_ex(table)
    }

    /// [`GpuSolver::upload_i_ex`] for this solver's rows.
    fn put_i_ex(&mut self, table: &Table) -> Result<()> {
        self.held.i_ex = true;
        let l = *self.res.layout();
        let zero = || Table::zeros(table.rows(), table.bins);
        let (mut leaf, mut even, mut odd) = (zero(), zero(), zero());
        for r in 0..table.rows() {
            let dst = if self.leaf_rows[r] {
                &mut leaf
            } else if self.depth_parity[r] {
                &mut odd
            } else {
                &mut even
            };
            for (d, v) in dst.row_mut(r).iter_mut().zip(table.row(r)) {
                *d = *v * self.scale;
            }
        }
        let p = self.parity;
        let format = self.res.plan.format;
        let im = &mut self.res.images;
        im.leaf_ex_mut(p)
            .upload(&encode(format, &l.from_table(&leaf)))?;
        im.cluster_ex.upload(&encode(
            crate::gpu::resources::CLUSTER_FORMAT,
            &l.from_table(&even),
        ))?;
        im.cluster_ex_odd.upload(&encode(
            crate::gpu::resources::CLUSTER_FORMAT,
            &l.from_table(&odd),
        ))
    }

    /// Reads the pushed incident radiance back (push leaves odd depths' rows in the L_in image).
    pub fn read_l_push(&mut self) -> Result<Table> {
        let layout = *self.res.layout();
        let even = layout.tiles_to_table(&self.read_texels(|im| &mut im.l_push)?);
        let odd = layout.tiles_to_table(&self.read_texels(|im| &mut im.l_in)?);
        let mut t = even;
        for (r, node) in self.depth_parity.iter().enumerate() {
            if *node {
                t.row_mut(r).copy_from_slice(odd.row(r));
            }
        }
        Ok(self.unscale(t))
    }

    /// Uploads the first bounces of the direct light and of the environment at the current
    /// source scale (each a no-op without it).
    pub(super) fn upload_direct(&mut self) -> Result<()> {
        let l = *self.res.layout();
        let format = self.res.plan.format;
        let im = &mut self.res.images;
        for (table, image) in [
            (&self.direct, &mut im.direct),
            (&self.environment_ex, &mut im.environment),
        ] {
            if let Some(t) = table {
                image.upload(&encode(format, &l.from_table_scaled(t, self.scale)))?;
            }
        }
        Ok(())
    }

    /// Chooses the power-of-two source scale for the system's range, the environment and the
    /// direct light; where it changes, the direct light is uploaded again and a solution the
    /// images hold (a warm start across an update) is read back and uploaded at the new scale.
    pub(super) fn update_scale(&mut self) -> Result<()> {
        let direct_max = self.direct_max;
        let range = Range {
            brightest: self
                .sys_range
                .brightest
                .max(self.environment.max_element())
                .max(direct_max),
            dimmest: match (self.sys_range.dimmest, self.environment.max_element()) {
                (d, e) if e > 0.0 => Some(d.map_or(e, |d| d.min(e))),
                (d, _) => d,
            },
            ..self.sys_range
        };
        let s = range.scale();
        let e = self.environment * s;
        self.constants.environment = [e.x as f32, e.y as f32, e.z as f32, s as f32];
        if s != self.scale {
            let held = self.held;
            let i_ex = held.i_ex.then(|| self.read_i_ex()).transpose()?;
            let i_total = held.i_total.then(|| self.read_i_total()).transpose()?;
            self.scale = s;
            self.upload_direct()?;
            if let Some(t) = i_ex {
                self.put_i_ex(&t)?;
            }
            if let Some(t) = i_total {
                self.upload_i_total(&t)?;
            }
        }
        Ok(())
    }

    fn unscale(&self, mut t: Table) -> Table {
        let inv = 1.0 / self.scale;
        t.data.iter_mut().for_each(|v| *v *= inv);
        t
    }
}

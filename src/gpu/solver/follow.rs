//! The GPU solver following its system after objects moved along a bounded link mesh (§3.3,
//! [`crate::System::follow`]): the nodes, rows and link pairs stay, so the tables (and with
//! them the current solution) stay on the device; only the link records (form factors, bins,
//! cone classes of the links touching a moving node), the leaves' normals and the glossy lobe
//! factors are packed again and uploaded, recorded into a command buffer.

use super::GpuSolver;
use crate::error::{Error, Result};
use crate::gpu::layout::as_bytes;
use crate::gpu::memory::{Buffer, BufferDesc};
use crate::gpu::pack::{self, encode};
use crate::gpu::staged::Staged;
use crate::gpu::tables::DrawData;
use crate::plan::range::Range;
use crate::system::System;
use ash::vk;
use glam::DVec3;
use gpu_allocator::MemoryLocation;

/// What one follow uploaded.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct FollowUploads {
    /// Bytes staged and copied (link records, combos, attributes, lobe factors).
    pub bytes: u64,
    /// Buffers made anew because the moved system's records no longer fit.
    pub grown: usize,
}

/// Writes `bytes` into `buf` through `staged`, making the buffer anew (and `desc` with it)
/// where it is too small; returns whether it did. A storage buffer other than the link
/// records (read in chunks) may not outgrow `maxStorageBufferRange` (the shaders read it
/// whole), as [`GpuSolver::new`] checks.
fn rewrite(
    staged: &mut Staged,
    cmd: vk::CommandBuffer,
    ctx: &std::sync::Arc<crate::gpu::Context>,
    buf: &mut Buffer,
    desc: &mut BufferDesc,
    bytes: &[u8],
) -> Result<bool> {
    let grow = bytes.len() as u64 > buf.size;
    let range = ctx.info.max_storage_buffer_range as u64;
    if desc.usage.contains(vk::BufferUsageFlags::STORAGE_BUFFER)
        && bytes.len() as u64 > range
        && desc.name != "links"
    {
        return Err(Error::TooLarge {
            what: format!(
                "GPU buffer '{}' after a move (maxStorageBufferRange; solver.element_size, solver.oracle)",
                desc.name
            ),
            needed_bytes: bytes.len() as u64,
            limit_bytes: range,
        });
    }
    if grow {
        desc.size = bytes.len() as u64;
        *buf = Buffer::new(
            ctx,
            &desc.name,
            desc.size,
            desc.usage | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuOnly,
        )?;
    }
    staged.buffer(cmd, buf, bytes)?;
    Ok(grow)
}

impl GpuSolver {
    /// Takes `sys`, this solver's system after its objects moved along its bound, keeping the
    /// tables and the current solution: records the uploads of the new link records, the
    /// leaves' normals and lobe factors into `cmd` (their staging buffers live until the next
    /// follow: `cmd` must have completed by then, as must every command buffer that used this
    /// solver, and the uploads must come before any other of its commands in `cmd`). Returns
    /// `None`, recording nothing, where `sys` does not have this solver's rows, hierarchy and
    /// cone classes (the solver must be made anew). The direct light's first bounce belongs to
    /// the old system (it holds the leaves' normals and lobes): with lights, call
    /// [`GpuSolver::set_direct`] with the moved system's table before iterating; it, or
    /// [`GpuSolver::set_environment`] without lights, also chooses the source scale again (the
    /// engine makes both right after).
    pub fn record_follow(
        &mut self,
        cmd: vk::CommandBuffer,
        sys: &System,
    ) -> Result<Option<FollowUploads>> {
        self.record_uploads(cmd, sys)
    }

    /// [`GpuSolver::record_follow`] submitted on the solver's queue, waiting for it.
    pub fn follow(&mut self, sys: &System) -> Result<Option<FollowUploads>> {
        let ctx = self.ctx.clone();
        let mut out = Ok(None);
        ctx.submit_and_wait(|cmd| out = self.record_uploads(cmd, sys))?;
        self.staged.release();
        out
    }

    /// The uploads of [`GpuSolver::record_follow`], recorded (nothing submitted).
    fn record_uploads(
        &mut self,
        cmd: vk::CommandBuffer,
        sys: &System,
    ) -> Result<Option<FollowUploads>> {
        let layout = *self.res.layout();
        if sys.rows() as u32 != layout.rows || sys.bins.count as u32 != layout.bins {
            return Ok(None);
        }
        let old = self.res.draw();
        let draw = DrawData::new(
            sys,
            &layout,
            self.features.glossy_everywhere,
            old.max_line_width,
        )?;
        let same_shape = draw.class_layer == old.class_layer
            && draw.link_count == old.link_count
            && draw.push == old.push
            && draw.pull == old.pull
            && draw.diffuse_quads == old.diffuse_quads
            && draw.glossy_quads == old.glossy_quads
            && draw.leaf_quads == old.leaf_quads;
        if !same_shape {
            return Ok(None);
        }
        self.staged.release();
        let ctx = self.ctx.clone();
        let res = &mut self.res;
        let staged = &mut self.staged;
        let (b, d) = (&mut res.buffers, &mut res.plan.buffers);
        let mut grown = 0;
        staged.start(cmd);
        grown += rewrite(
            staged,
            cmd,
            &ctx,
            &mut b.links,
            &mut d.links,
            as_bytes(&draw.links),
        )? as usize;
        let combos = pack::padded(draw.combos.clone());
        grown += rewrite(
            staged,
            cmd,
            &ctx,
            &mut b.combos,
            &mut d.combos,
            as_bytes(&combos),
        )? as usize;
        staged.finish(cmd);
        let (na, lf) = pack::attributes(sys, &layout);
        let f32x4 = vk::Format::R32G32B32A32_SFLOAT;
        let im = &mut res.images;
        staged.image(cmd, &mut im.attr_normal_area, &encode(f32x4, &na))?;
        staged.image(cmd, &mut im.attr_leaf, &encode(f32x4, &lf))?;
        let (w, h) = (im.lobe_norm.extent.width, im.lobe_norm.extent.height);
        if w * h > 1 {
            let lobe = pack::lobe_factors(sys, &layout, w, h);
            staged.image(cmd, &mut im.lobe_norm, as_bytes(&lobe))?;
        }
        res.plan.draw = draw;
        if grown > 0 || res.link_chunks.records != (res.plan.draw.links.len() as u64).max(1) {
            res.rewrite_sets(&ctx)?;
        }
        self.work = crate::gpu::work::Work::of(sys, &self.res.plan);
        // The moved system's source range; its scale is chosen with the new direct light, so
        // that a held solution is rescaled at most once per update.
        self.sys_range = Range::of(sys, DVec3::ZERO, 0.0);
        Ok(Some(FollowUploads {
            bytes: self.staged.bytes(),
            grown,
        }))
    }
}

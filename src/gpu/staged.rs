//! Uploads into resources that already exist, recorded into a command buffer (the engine's own
//! submission or a host's): the bytes are staged at once, the copies run when the command
//! buffer does. An update after objects moved (§3.3) writes its changed link records and
//! attributes this way, so a host records it with the frame's iterations.

use super::barrier::{after_uploads, before_uploads, transition, Access};
use super::context::Context;
use super::memory::{copy_region, Buffer, Image};
use crate::error::Result;
use ash::vk;
use std::sync::Arc;

/// Staging buffers of recorded uploads, kept until their command buffer has completed.
pub struct Staged {
    ctx: Arc<Context>,
    staging: Vec<Buffer>,
    bytes: u64,
}

impl Staged {
    /// No uploads yet.
    pub fn new(ctx: &Arc<Context>) -> Self {
        Self {
            ctx: ctx.clone(),
            staging: Vec::new(),
            bytes: 0,
        }
    }

    /// Frees the staging buffers of earlier uploads: the command buffers that copied from them
    /// must have completed (the engine waits for its own; a host waits for its frame).
    pub fn release(&mut self) {
        self.staging.clear();
        self.bytes = 0;
    }

    /// Bytes staged since the last [`Staged::release`].
    pub fn bytes(&self) -> u64 {
        self.bytes
    }

    /// Orders the copies recorded next after the vertex input and shader reads recorded before
    /// them in `cmd`; call before the first [`Staged::buffer`].
    pub fn start(&self, cmd: vk::CommandBuffer) {
        before_uploads(&self.ctx, cmd);
    }

    /// Records a copy of `bytes` over the start of `dst` (made with transfer-destination use,
    /// as every uploaded buffer is). Call [`Staged::start`] before the first buffer copy and
    /// [`Staged::finish`] after the last.
    pub fn buffer(&mut self, cmd: vk::CommandBuffer, dst: &Buffer, bytes: &[u8]) -> Result<()> {
        if bytes.is_empty() {
            return Ok(());
        }
        debug_assert!(bytes.len() as u64 <= dst.size);
        let s = Buffer::staging(&self.ctx, "update", bytes)?;
        unsafe {
            self.ctx.device.cmd_copy_buffer(
                cmd,
                s.raw,
                dst.raw,
                &[vk::BufferCopy::default().size(bytes.len() as u64)],
            )
        };
        self.keep(s, bytes.len());
        Ok(())
    }

    /// Records a copy of `bytes` (every texel, tightly packed) into `dst`, which is left ready
    /// for sampling.
    pub fn image(&mut self, cmd: vk::CommandBuffer, dst: &mut Image, bytes: &[u8]) -> Result<()> {
        debug_assert_eq!(bytes.len() as u64, dst.bytes(), "{}", dst.name());
        let s = Buffer::staging(&self.ctx, dst.name(), bytes)?;
        transition(&self.ctx, cmd, &mut [(&mut *dst, Access::TransferDst)]);
        unsafe {
            self.ctx.device.cmd_copy_buffer_to_image(
                cmd,
                s.raw,
                dst.raw,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &[copy_region(dst.extent)],
            )
        };
        transition(&self.ctx, cmd, &mut [(&mut *dst, Access::Sampled)]);
        self.keep(s, bytes.len());
        Ok(())
    }

    /// Makes the recorded buffer copies visible to the vertex input and shader reads that follow.
    pub fn finish(&self, cmd: vk::CommandBuffer) {
        after_uploads(&self.ctx, cmd);
    }

    fn keep(&mut self, s: Buffer, n: usize) {
        self.staging.push(s);
        self.bytes += n as u64;
    }
}

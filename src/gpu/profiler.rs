//! Named, timed scopes: each pass is wrapped in a debug-utils label (seen by RenderDoc and
//! validation messages) and a pair of timestamp queries (read by `profile`), with the same name.

use super::context::Context;
use super::handle::Owned;
use crate::error::Result;
use crate::gpu::error::VkContext;
use ash::vk;
use std::ffi::CString;
use std::sync::Arc;

/// Timestamp queries of one recorded command buffer.
pub struct Profiler {
    pool: Option<Owned<vk::QueryPool>>,
    capacity: u32,
    next: u32,
    open: Vec<(String, Option<u32>)>,
    scopes: Vec<(String, u32)>,
}

impl Profiler {
    /// A profiler with room for `scopes` timed scopes per recording.
    pub fn new(ctx: &Arc<Context>, scopes: u32) -> Result<Self> {
        let capacity = if ctx.info.timestamps { scopes * 2 } else { 0 };
        let pool = if capacity > 0 {
            let p = unsafe {
                ctx.device.create_query_pool(
                    &vk::QueryPoolCreateInfo::default()
                        .query_type(vk::QueryType::TIMESTAMP)
                        .query_count(capacity),
                    None,
                )
            }
            .vk("creating the timestamp query pool")?;
            Some(Owned::new(ctx, p, "antiradiance pass timestamps"))
        } else {
            None
        };
        Ok(Self {
            pool,
            capacity,
            next: 0,
            open: Vec::new(),
            scopes: Vec::new(),
        })
    }

    /// Starts a new recording (resets the queries; must be outside rendering).
    pub fn reset(&mut self, ctx: &Context, cmd: vk::CommandBuffer) {
        self.next = 0;
        self.scopes.clear();
        self.open.clear();
        if let Some(pool) = &self.pool {
            unsafe {
                ctx.device
                    .cmd_reset_query_pool(cmd, pool.raw(), 0, self.capacity)
            };
        }
    }

    /// Opens a scope: debug label plus a timestamp (if room is left).
    pub fn begin(&mut self, ctx: &Context, cmd: vk::CommandBuffer, name: &str) {
        label_begin(ctx, cmd, name);
        let pool = self.pool.as_ref().map(|p| p.raw());
        let q = pool.filter(|_| self.next + 2 <= self.capacity).map(|pool| {
            let q = self.next;
            self.next += 2;
            unsafe {
                ctx.device
                    .cmd_write_timestamp2(cmd, vk::PipelineStageFlags2::ALL_COMMANDS, pool, q)
            };
            q
        });
        self.open.push((name.to_string(), q));
    }

    /// Closes the innermost scope.
    pub fn end(&mut self, ctx: &Context, cmd: vk::CommandBuffer) {
        if let Some((name, q)) = self.open.pop() {
            if let (Some(q), Some(pool)) = (q, &self.pool) {
                unsafe {
                    ctx.device.cmd_write_timestamp2(
                        cmd,
                        vk::PipelineStageFlags2::ALL_COMMANDS,
                        pool.raw(),
                        q + 1,
                    )
                };
                self.scopes.push((name, q));
            }
            label_end(ctx, cmd);
        }
    }

    /// Records `f` inside a named, timed scope: the debug label and the timestamp pair open
    /// before it and close after it, together.
    pub fn scope<T>(
        &mut self,
        ctx: &Context,
        cmd: vk::CommandBuffer,
        name: &str,
        f: impl FnOnce() -> T,
    ) -> T {
        self.begin(ctx, cmd, name);
        let r = f();
        self.end(ctx, cmd);
        r
    }

    /// Durations (ms) of the scopes of the last recording, in the order they closed. Call after
    /// the command buffer has completed.
    pub fn results(&self, ctx: &Context) -> Result<Vec<(String, f64)>> {
        let Some(pool) = self.pool.as_ref().filter(|_| self.next > 0) else {
            return Ok(Vec::new());
        };
        let mut ticks = vec![0u64; self.next as usize];
        unsafe {
            ctx.device.get_query_pool_results(
                pool.raw(),
                0,
                &mut ticks,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }
        .vk("reading timestamps")?;
        let period = ctx.info.timestamp_period as f64;
        Ok(self
            .scopes
            .iter()
            .map(|(name, q)| {
                let dt = ticks[*q as usize + 1].wrapping_sub(ticks[*q as usize]);
                (name.clone(), dt as f64 * period * 1e-6)
            })
            .collect())
    }
}

/// Opens a debug label (no-op without debug utils).
pub fn label_begin(ctx: &Context, cmd: vk::CommandBuffer, name: &str) {
    if let Some(d) = &ctx.debug {
        let n = CString::new(name).unwrap_or_default();
        unsafe {
            d.cmd_begin_debug_utils_label(cmd, &vk::DebugUtilsLabelEXT::default().label_name(&n))
        };
    }
}

/// Closes a debug label.
pub fn label_end(ctx: &Context, cmd: vk::CommandBuffer) {
    if let Some(d) = &ctx.debug {
        unsafe { d.cmd_end_debug_utils_label(cmd) };
    }
}

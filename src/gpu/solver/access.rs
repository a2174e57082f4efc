//! What a [`GpuSolver`] reports and hands a host: timings, images, memory, work.

use super::{GpuSolver, HostImages};
use crate::error::Result;
use crate::gpu::memory::MemoryReport;
use ash::vk;

impl GpuSolver {
    /// Pass timings (ms, in recording order) of the last submission made by this solver, or of
    /// the host's last command buffer via [`GpuSolver::read_timings`].
    pub fn timings(&self) -> &[(String, f64)] {
        &self.timings
    }

    /// Reads the timestamps of a host-submitted command buffer (after it completed).
    pub fn read_timings(&mut self) -> Result<&[(String, f64)]> {
        self.timings = self.profiler.results(&self.ctx)?;
        Ok(&self.timings)
    }

    /// Makes I_total readable by shaders (a frame's passes, or the host's own) in `cmd`.
    pub fn prepare_display(&mut self, cmd: vk::CommandBuffer) {
        crate::gpu::barrier::transition(
            &self.ctx,
            cmd,
            &mut [(
                &mut self.res.images.i_total,
                crate::gpu::barrier::Access::Sampled,
            )],
        );
    }

    /// The images a host application reads.
    pub fn images(&self) -> HostImages {
        let im = &self.res.images;
        let leaf = im.leaf_ex(self.parity);
        HostImages {
            leaf_ex: (leaf.raw, leaf.view),
            cluster_ex: (im.cluster_ex.raw, im.cluster_ex.view),
            i_total: (im.i_total.raw, im.i_total.view),
            layout: *self.res.layout(),
        }
    }

    /// GPU memory by purpose.
    pub fn memory(&self) -> MemoryReport {
        self.res.memory()
    }

    /// The raster work of one propagation ([`crate::gpu::work::Work`]).
    pub fn work(&self) -> crate::gpu::work::Work {
        self.work
    }

    /// Links drawn by the global pass (each as one or more line records).
    pub fn link_count(&self) -> usize {
        self.res.draw().link_count
    }
}

//! What a host that records the engine's GPU work into its own command buffers sees of it: the
//! output image and the state it is left in, the exposure, the timestamps of the last recorded
//! work, and what the last update did. Nothing here hands out the backend itself.
//!
//! A frame recorded by a host is: [`Engine::record_update`] (where something moved; first in
//! the command buffer), [`Engine::begin_recording`], [`Engine::record_initialize`] (the first
//! frame) or nothing, [`Engine::record_iterations`], [`Engine::record_draw`]; then the host's
//! own use of [`Engine::output_image`], submission and wait. `examples/embed.rs` does this.

use super::gpu::FollowReport;
use super::Engine;
use crate::error::{Error, Result};
use ash::vk;

/// The frame's output image as [`Engine::record_draw`] leaves it.
#[derive(Debug, Clone, Copy)]
pub struct OutputImage {
    /// The image (linear RGB radiance times the exposure, one texel per pixel).
    pub image: vk::Image,
    /// A colour view over all of it.
    pub view: vk::ImageView,
    /// Its format (`R32G32B32A32_SFLOAT`).
    pub format: vk::Format,
    /// Its size: the camera's width × height.
    pub extent: vk::Extent2D,
    /// The layout `record_draw` leaves it in (`SHADER_READ_ONLY_OPTIMAL`).
    pub layout: vk::ImageLayout,
    /// The stages and accesses of that state: the source scope of the host's next barrier
    /// on it (to copy, blit or sample it).
    pub stages: vk::PipelineStageFlags2,
    /// See `stages`.
    pub access: vk::AccessFlags2,
}

impl Engine {
    fn gpu_backend(&mut self, what: &str) -> Result<&mut super::gpu::GpuBackend> {
        super::gpu_of(&mut self.backend)
            .ok_or_else(|| Error::Invalid(format!("{what} needs the GPU backend")))
    }

    /// The output image the last [`Engine::record_draw`] writes (valid until an update makes
    /// the backend anew: read it again after every [`Engine::record_update`]). It is the frame
    /// before reduction: `camera.supersample` × the image's size (a host samples or blits it),
    /// one unshifted pass of `camera.passes` (only [`Engine::draw`] averages the passes).
    pub fn output_image(&mut self) -> Result<OutputImage> {
        let out = if self.backend.host_frame().is_some() {
            let h = self.backend.host_frame().expect("checked");
            h.output().ok_or_else(|| {
                Error::Invalid("the output image exists after the first record_draw".into())
            })?
        } else {
            &self
                .gpu_backend("the output image")?
                .frame()
                .images()
                .output
        };
        let (stages, access) = out.access.stage_access();
        Ok(OutputImage {
            image: out.raw,
            view: out.view,
            format: out.format,
            extent: out.extent,
            layout: out.access.layout(),
            stages,
            access,
        })
    }

    /// Multiplies the output radiance by `factor` from the next draw on (a viewer's exposure;
    /// 1 by default). An update that makes the backend anew starts again at 1.
    pub fn set_exposure(&mut self, factor: f32) -> Result<()> {
        if let Some(h) = self.backend.host_frame() {
            h.set_exposure(factor);
            return Ok(());
        }
        self.gpu_backend("an exposure")?
            .frame()
            .set_exposure(factor);
        Ok(())
    }

    /// Starts the timestamps of a host's command buffer: once per command buffer, after
    /// [`Engine::record_update`] and before the other `record_*` calls. It resets the
    /// engine's query pools in `cmd`.
    pub fn begin_recording(&mut self, cmd: vk::CommandBuffer) -> Result<()> {
        if self.backend.host_frame().is_some() {
            return Ok(()); // nothing timed on the device
        }
        self.gpu_backend("recording into a command buffer")?
            .begin(cmd);
        Ok(())
    }

    /// The timed scopes (pass → GPU ms, in order: the solver's, then the frame's) of the
    /// command buffer last begun with [`Engine::begin_recording`], which must have completed.
    pub fn recorded_timings(&mut self) -> Result<Vec<(String, f64)>> {
        if self.backend.host_frame().is_some() {
            // The frame was drawn on the host: its wall-clock passes.
            return Ok(self.backend.take_timings());
        }
        let g = self.gpu_backend("timestamps")?;
        let mut t = g.solver().read_timings()?.to_vec();
        t.extend_from_slice(g.frame().read_timings()?);
        Ok(t)
    }

    /// What the last update did on the GPU backend (kept in place, bytes uploaded, shadow
    /// views drawn again); `None` on the CPU backend. A backend made anew reports
    /// `in_place: false`.
    pub fn last_update(&mut self) -> Option<FollowReport> {
        super::gpu_of(&mut self.backend).map(|g| g.last_follow())
    }
}

//! The frame following a moved scene (§3.3): its buffers written again in place (the moved
//! corners, elements, lights and shadow views) and, of the shadow maps, only the views that
//! can have changed marked for the next shadow render: a light's view that moved, or one that
//! may see a moved object before or after its move.

use super::{constants, FrameData, FrameScene, GpuFrame};
use crate::error::Result;
use crate::gpu::memory::Buffer;
use crate::gpu::pack;
use ash::vk;
use glam::DVec3;
use gpu_allocator::MemoryLocation;

impl GpuFrame {
    /// Takes the moved scene `f` (its system, surfaces, lights and shadow views), keeping
    /// the images, pipelines and the shadow maps of views that cannot have changed: views equal
    /// to the last ones that meet none of the `moved` spheres (around each moved object before
    /// and after its move). Returns false, changing nothing, where the images or the views'
    /// squares in the atlas would differ (a new camera size, features, atlas or view count):
    /// the frame must be made anew.
    pub fn follow(&mut self, f: &FrameScene<'_>, moved: &[(DVec3, f64)]) -> Result<bool> {
        let (maps, features) = (f.maps, f.features);
        let shared = f.shared_lights.0..f.shared_lights.1;
        let size = (f.camera.width, f.camera.height);
        let block = crate::frame::direct::block_for(f.surf.direct_block, &shared, size);
        let same_images = *features == self.features
            && block == self.direct_block
            && Self::describe(f.camera, features, maps, f.surf, block)
                .iter()
                .zip(self.images.iter())
                .all(|(d, im)| *d == im.desc);
        let rects: Vec<[u32; 3]> = maps
            .views
            .iter()
            .map(|v| [v.atlas.0, v.atlas.1, v.size])
            .collect();
        if !same_images || rects != self.shadow_rects {
            return Ok(false);
        }
        let data = FrameData::new(f);
        let ctx = self.ctx.clone();
        self.staged.release();
        let mut grown = false;
        let mut result: Result<()> = Ok(());
        let (buffers, staged) = (&mut self.buffers, &mut self.staged);
        ctx.submit_and_wait(|cmd| {
            result = (|| {
                staged.start(cmd);
                for (buf, &(name, bytes, usage)) in buffers.iter_mut().zip(data.contents().iter()) {
                    if bytes.len() as u64 > buf.size {
                        grown = true;
                        *buf = Buffer::new(
                            &ctx,
                            name,
                            bytes.len() as u64,
                            usage | vk::BufferUsageFlags::TRANSFER_DST,
                            MemoryLocation::GpuOnly,
                        )?;
                    }
                    staged.buffer(cmd, buf, bytes)?;
                }
                staged.finish(cmd);
                Ok(())
            })();
        })?;
        result?;
        self.staged.release();
        self.corner_count = data.corners.len() as u32;
        self.splat_count = pack::splat_instances(f.surf, features.splat).len() as u32;
        let shared = (f.shared_lights, self.direct_block);
        self.constants = constants(f.scene, f.lights.len(), shared, f.camera, f.sys);
        // Views marked by an earlier follow and not drawn since stay marked.
        let pending = self.only.take();
        let only: Vec<bool> = maps
            .views
            .iter()
            .enumerate()
            .map(|(i, v)| {
                self.views.get(i) != Some(v)
                    || moved.iter().any(|&(c, r)| v.may_see(c, r))
                    || pending.as_ref().is_some_and(|p| p[i])
            })
            .collect();
        self.views = maps.views.clone();
        self.only = Some(only);
        if grown {
            // The set points at the storage buffers; keep the I_total binding.
            self.write_set(self.i_total);
        }
        Ok(true)
    }

    /// Views the next shadow render draws.
    pub fn shadow_views_to_render(&self) -> usize {
        match &self.only {
            Some(o) if self.rendered => o.iter().filter(|&&b| b).count(),
            _ => self.shadow_rects.len(),
        }
    }
}

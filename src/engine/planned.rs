//! What a prepared scene would take on a device with given limits, without opening one: the GPU
//! solver's memory by resource, the frame's images and shadow maps, and the raster work per
//! propagation. `info` reports it for lavapipe's limits and a discrete GPU's; `profile` reads
//! the same figures from the device it runs on ([`super::Engine::memory`]).

use super::Prepared;
use crate::error::Result;
use crate::gpu::frame::GpuFrame;
use crate::gpu::links::LinkChunks;
use crate::gpu::memory::Purpose;
use crate::gpu::resources::{table_format, ResourcePlan};
use crate::gpu::Context;
use serde::Serialize;
use std::collections::BTreeMap;

pub use crate::gpu::memory::MemoryReport;
pub use crate::gpu::work::{PassWork, Work};

/// Bytes the solver reads back per iteration (the convergence figures reduced on the device).
pub const READBACK_BYTES_PER_ITERATION: usize = crate::gpu::reduce::Reducer::BYTES_PER_ITERATION;

/// The device limits the GPU resources are sized by.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct DeviceLimits {
    /// What these limits are.
    pub name: String,
    /// `maxImageDimension2D`: the tables' column blocks fit in it.
    pub max_image_dimension: u32,
    /// Widest line drawn (1 without wide lines): the global pass's rectangles are at most this
    /// many bin rows tall.
    pub max_line_width: u32,
    /// `maxStorageBufferRange`: the link records are read in ranges of at most this.
    pub max_storage_buffer_range: u64,
}

impl DeviceLimits {
    /// lavapipe's (Mesa 22–24): what CI runs on.
    pub fn lavapipe() -> Self {
        Self {
            name: "lavapipe".into(),
            max_image_dimension: 16384,
            max_line_width: 255,
            max_storage_buffer_range: 128 << 20,
        }
    }

    /// A discrete GPU's, as current NVIDIA drivers report them (maxImageDimension2D 32768,
    /// lineWidthRange up to 64, maxStorageBufferRange 2³² − 1); AMD's differ (16384 texels).
    pub fn discrete() -> Self {
        Self {
            name: "discrete GPU".into(),
            max_image_dimension: 32768,
            max_line_width: 64,
            max_storage_buffer_range: u32::MAX as u64,
        }
    }

    /// The limits of `ctx`'s device.
    pub fn of(ctx: &Context) -> Self {
        Self {
            name: ctx.info.name.clone(),
            max_image_dimension: ctx.info.max_image_dimension,
            max_line_width: ctx.info.max_line_width,
            max_storage_buffer_range: ctx.info.max_storage_buffer_range as u64,
        }
    }
}

/// What a prepared scene takes on a device with [`DeviceLimits`].
#[derive(Debug, Clone, Serialize)]
pub struct Planned {
    /// The limits planned against.
    pub limits: DeviceLimits,
    /// Bytes by resource: the solver's images and buffers, `frame_images`, `shadow_maps`.
    pub memory_bytes: BTreeMap<String, u64>,
    /// The GPU passes' raster work per propagation.
    pub work: Work,
    /// Descriptor ranges the link records are read through.
    pub link_chunks: u32,
}

impl Prepared {
    /// The GPU resources of this scene's plan on a device with `limits`, described, not made:
    /// L_in and L_push in the table format (a device that rounds float16 blending; one that
    /// truncates, as lavapipe does, accumulates them in float32 and `profile` reports that).
    pub fn planned(&self, limits: &DeviceLimits) -> Result<Planned> {
        let (sys, plan) = (&self.system, &self.plan);
        let resources = ResourcePlan::new(
            sys,
            &plan.features,
            plan.precision,
            table_format(plan.precision),
            u32::MAX,
            limits.max_image_dimension,
            limits.max_line_width.max(1),
        )?;
        let work = Work::of(sys, &resources);
        let mut memory_bytes = resources.memory().by_name();
        memory_bytes.remove("total");
        let frame = GpuFrame::planned_memory(
            &self.camera,
            &plan.features,
            &self.maps,
            &self.surfaces,
            crate::frame::direct::block_for(
                self.surfaces.direct_block,
                &self.shared_lights,
                (self.camera.width, self.camera.height),
            ),
        );
        memory_bytes.insert("frame_images".into(), frame.get(Purpose::FrameImages));
        memory_bytes.insert("shadow_maps".into(), frame.get(Purpose::ShadowMaps));
        let link_chunks =
            LinkChunks::new(work.global.primitives, limits.max_storage_buffer_range).chunks;
        Ok(Planned {
            limits: limits.clone(),
            memory_bytes,
            work,
            link_chunks,
        })
    }
}

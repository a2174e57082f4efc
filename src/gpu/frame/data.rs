//! The frame's buffer records: packed on the CPU from the scene, its lights and surfaces (pure
//! functions of `crate::gpu::pack`), uploaded as one storage or vertex buffer each.

use super::FrameScene;
use crate::error::Result;
use crate::frame::edges::EmitterTriangles;
use crate::gpu::context::Context;
use crate::gpu::layout::{as_bytes, bin_centers, CornerVertex, GpuMaterial};
use crate::gpu::memory::{Buffer, BufferDesc, Purpose};
use crate::gpu::pack;
use crate::gpu::passes::targets::FrameBuffers;
use ash::vk;
use std::sync::Arc;

/// The frame's buffer records, packed on the CPU ([`crate::gpu::pack`]).
pub(super) struct FrameData {
    pub(super) corners: Vec<CornerVertex>,
    splats: Vec<u32>,
    materials: Vec<GpuMaterial>,
    bin_centers: Vec<[f32; 4]>,
    elements: Vec<crate::gpu::layout::GpuFrameElement>,
    adj_offsets: Vec<u32>,
    adj_list: Vec<crate::gpu::layout::GpuAdjEntry>,
    lights: Vec<crate::gpu::layout::GpuLight>,
    shadow_views: Vec<crate::gpu::layout::GpuShadowView>,
    emitters: Vec<crate::gpu::layout::GpuEmitterTriangle>,
    vertex_positions: Vec<[f32; 4]>,
}

impl FrameData {
    pub(super) fn new(f: &FrameScene<'_>) -> Self {
        let FrameScene {
            scene,
            lights,
            sys,
            surf,
            maps,
            features: f,
            ..
        } = *f;
        // Shared-vertex adjacency only where smooth meshes are interpolated.
        let (adj_offsets, adj_list, vertex_positions) = if f.vertex {
            (
                surf.adjacency_offsets.clone(),
                pack::adjacency(surf),
                pack::vertex_positions(surf),
            )
        } else {
            (Vec::new(), Vec::new(), Vec::new())
        };
        // Storage buffers may not be empty: pad with one unused record.
        Self {
            corners: pack::corners(scene, sys, surf),
            splats: pack::padded(pack::splat_instances(surf, f.splat)),
            materials: pack::padded(sys.materials.iter().map(GpuMaterial::new).collect()),
            bin_centers: bin_centers(&sys.bins),
            elements: pack::padded(pack::frame_elements(sys, surf)),
            adj_offsets: pack::padded(adj_offsets),
            adj_list: pack::padded(adj_list),
            lights: pack::padded(pack::lights(lights, maps)),
            shadow_views: pack::padded(pack::shadow_views(maps)),
            emitters: pack::padded(pack::emitter_triangles(&EmitterTriangles::new(scene))),
            vertex_positions: pack::padded(vertex_positions),
        }
    }

    /// Each buffer's name, bytes and use.
    pub(super) fn contents(&self) -> FrameBuffers<(&'static str, &[u8], vk::BufferUsageFlags)> {
        let vb = vk::BufferUsageFlags::VERTEX_BUFFER;
        let sb = vk::BufferUsageFlags::STORAGE_BUFFER;
        FrameBuffers {
            corners: ("element corners", as_bytes(&self.corners), vb),
            splats: ("splat instances", as_bytes(&self.splats), vb),
            materials: ("frame materials", as_bytes(&self.materials), sb),
            bin_centers: ("frame bin centers", as_bytes(&self.bin_centers), sb),
            elements: ("frame elements", as_bytes(&self.elements), sb),
            adj_offsets: ("shared-vertex offsets", as_bytes(&self.adj_offsets), sb),
            adj_list: ("shared-vertex elements", as_bytes(&self.adj_list), sb),
            lights: ("lights", as_bytes(&self.lights), sb),
            shadow_views: ("shadow views", as_bytes(&self.shadow_views), sb),
            emitters: ("emitting triangles", as_bytes(&self.emitters), sb),
            vertex_positions: (
                "shared-vertex positions",
                as_bytes(&self.vertex_positions),
                sb,
            ),
        }
    }

    pub(super) fn upload(&self, ctx: &Arc<Context>) -> Result<FrameBuffers<Buffer>> {
        self.contents().try_map(|&(name, bytes, usage)| {
            BufferDesc {
                name: name.into(),
                size: bytes.len() as u64,
                usage,
                purpose: Purpose::FrameBuffers,
            }
            .upload(ctx, bytes)
        })
    }
}

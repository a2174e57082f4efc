//! The frame's image set (shared by the frame passes and [`crate::gpu::frame::GpuFrame`], which
//! both import it from here), described as data from the camera size and the plan.

use crate::frame::camera::SUPERSAMPLE;
use crate::gpu::memory::{resource_set, ImageDesc, Purpose, DEPTH_FORMAT};
use crate::plan::Features;
use ash::vk;

/// Format of the frame's float targets.
pub const RGBA32F: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

resource_set! {
    /// Images of the frame passes.
    pub struct FrameImages {
        /// Shadow maps, every view's in its place of one atlas (R32F linear distances).
        pub shadow_map,
        /// Depth for the shadow-map views.
        pub shadow_depth,
        /// G-buffer position + leaf (2W × 2H).
        pub gbuf_position,
        /// G-buffer vertex-interpolated radiance (1×1 placeholder without smooth meshes or
        /// shading normals: the normal target comes after it).
        pub gbuf_vertex,
        /// G-buffer interpolated shading normal (1×1 placeholder without OBJ `vn`).
        pub gbuf_normal,
        /// G-buffer depth.
        pub gbuf_depth,
        /// Splat sums (Σ w·L, Σ w) (1×1 placeholder without flat surfaces).
        pub splat,
        /// The display bin toward the eye at each splat texel's sample (R32F, −1 where none),
        /// so the splat's fragments read it (1×1 placeholder without flat surfaces).
        pub splat_bins,
        /// The area emitters' shared direct light at each block's corner pixel (`frame::direct`;
        /// 1×1 placeholder where no block is shared).
        pub direct_blocks,
        /// The shared vertices' display radiance toward the eye, computed once per vertex
        /// (`passes::vertex_values`; 1×1 placeholder without smooth meshes).
        pub vertex_values,
        /// Final linear radiance (W × H).
        pub output,
    }
}

impl FrameImages<ImageDesc> {
    /// The images of a `width × height` frame with a shadow-map atlas of `atlas` texels
    /// (width, height); the vertex-radiance and splat targets only where `features` draw them,
    /// the splat sums per pixel, or per 2×2 sample where `splat_per_sample` (`frame::splat`); the
    /// direct light's blocks where `direct_block` (pixels per side) is above 1 (`frame::direct`);
    /// the values of `vertices` shared vertices where `features` interpolate smooth meshes.
    pub fn describe(
        width: u32,
        height: u32,
        features: &Features,
        atlas: (u32, u32),
        splat_per_sample: bool,
        direct_block: u32,
        vertices: usize,
    ) -> Self {
        let (sw, sh) = (width * SUPERSAMPLE, height * SUPERSAMPLE);
        let splat = match (features.splat, splat_per_sample) {
            (false, _) => (1, 1),
            (true, true) => (sw, sh),
            (true, false) => (width, height),
        };
        let (sums, bins) = if features.splat {
            ("splat sums", "splat bins")
        } else {
            ("splat sums (none)", "splat bins (none)")
        };
        let frame = |name: &str, w, h, f| ImageDesc::new(name, w, h, f, Purpose::FrameImages);
        let shadow = |name: &str, f| {
            let (w, h) = (atlas.0.max(1), atlas.1.max(1));
            ImageDesc::new(name, w, h, f, Purpose::ShadowMaps)
        };
        Self {
            shadow_map: shadow("shadow maps", vk::Format::R32G32_SFLOAT),
            shadow_depth: shadow("shadow depth", DEPTH_FORMAT),
            gbuf_position: frame("G-buffer position", sw, sh, RGBA32F),
            // Attachments are positional: the normal target (location 2) needs the vertex
            // target (location 1) at full size before it.
            gbuf_vertex: if features.vertex || features.normals {
                frame("G-buffer vertex radiance", sw, sh, RGBA32F)
            } else {
                frame("G-buffer vertex radiance (none)", 1, 1, RGBA32F)
            },
            gbuf_normal: if features.normals {
                frame("G-buffer shading normal", sw, sh, RGBA32F)
            } else {
                frame("G-buffer shading normal (none)", 1, 1, RGBA32F)
            },
            gbuf_depth: frame("G-buffer depth", sw, sh, DEPTH_FORMAT),
            splat: frame(sums, splat.0, splat.1, RGBA32F),
            splat_bins: frame(bins, splat.0, splat.1, vk::Format::R32_SFLOAT),
            direct_blocks: if direct_block > 1 {
                let b = direct_block as usize;
                let (gw, gh) = crate::frame::direct::grid(width as usize, height as usize, b);
                frame("direct light blocks", gw as u32, gh as u32, RGBA32F)
            } else {
                frame("direct light blocks (none)", 1, 1, RGBA32F)
            },
            vertex_values: if features.vertex && vertices > 0 {
                let (w, h) = super::vertex_values::extent(vertices);
                frame("shared-vertex values", w, h, RGBA32F)
            } else {
                frame("shared-vertex values (none)", 1, 1, RGBA32F)
            },
            output: frame("frame", width, height, RGBA32F),
        }
    }
}

resource_set! {
    /// Buffers of the frame passes: vertex input, then the storage buffers of the frame set.
    pub struct FrameBuffers {
        /// Element corners and crack-filling input triangles (shadow, G-buffer).
        pub corners,
        /// Leaf slots to splat (one instance per fan).
        pub splats,
        /// Materials (the frame's BRDF uses each material's own exponent).
        pub materials,
        /// Bin centers.
        pub bin_centers,
        /// Per-leaf records.
        pub elements,
        /// Shared-vertex CSR offsets.
        pub adj_offsets,
        /// Shared-vertex leaf lists.
        pub adj_list,
        /// Lights.
        pub lights,
        /// Shadow views.
        pub shadow_views,
        /// Emitting triangles (emitter edges, `frame/edges.rs`).
        pub emitters,
        /// Shared-vertex positions.
        pub vertex_positions,
    }
}

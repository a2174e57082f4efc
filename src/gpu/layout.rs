//! Host mirrors of everything the shaders read: push constants, per-instance vertex data,
//! storage-buffer records and descriptor bindings. `glsl/common.glsl` is the GLSL side; the tests
//! below check sizes, offsets and that both files name the same fields and bindings in order.

/// Push constants shared by every pass (`PassConstants` in common.glsl).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PassConstants {
    /// Width of the bound render target, texels.
    pub target_width: u32,
    /// Height of the bound render target, texels.
    pub target_height: u32,
    /// Width of one row in the target: `m` for tables, 1 for per-row images.
    pub quad_width: u32,
    /// Line endpoint offset for the line rasterization mode in use.
    pub line_offset: f32,
    /// Bin solid angle `4π/m`.
    pub omega: f32,
    /// Bit 1: tables are float16 (bit 0 is unused: direct light is a specialization constant).
    pub flags: u32,
    /// Global pass: the I_ex image the draw's senders live in
    /// ([`super::tables::sender_image`]); zero elsewhere.
    pub sender: u32,
    /// Local pass: weight of the last iterate in the new one (`1 − ω` of a damped symmetric
    /// iteration, [`crate::solver::CpuState::damping`]); 0 undamped.
    pub keep: f32,
    /// Constant environment radiance times the source scale (rgb); the source scale (a), a
    /// power of two that every emitted radiance is multiplied by to centre values in float16's range.
    pub environment: [f32; 4],
}

/// `PassConstants::flags` bit: tables are float16; shaders round stores to nearest.
pub const FLAG_HALF: u32 = 2;

/// Bits of a row index in a [`GpuLink`] (the rest of each word carries half the combo index).
pub const LINK_ROW_BITS: u32 = 22;
/// Rows a [`GpuLink`] can address.
pub const LINK_MAX_ROWS: u32 = 1 << LINK_ROW_BITS;
/// Combos a [`GpuLink`] can address (two halves of 10 bits).
pub const LINK_MAX_COMBOS: u32 = 1 << (2 * (32 - LINK_ROW_BITS));

/// One line of a link as the global pass pulls it from a storage buffer by vertex index (12
/// bytes): the receiver and sender rows, each with half of the line's combo index (central bin,
/// filter layer and the receiver bin rectangle it covers, shared by all lines alike in those),
/// and the form factor. A link whose footprint splits into several rectangles has one record
/// per rectangle.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct GpuLink {
    /// Receiver row (low 22 bits), combo index bits 10..20 (high 10 bits).
    pub receiver_combo: u32,
    /// Sender row (low 22 bits), combo index bits 0..10 (high 10 bits).
    pub sender_combo: u32,
    /// Form factor (eq. 17 with the exact-leaf calibration).
    pub form_factor: f32,
}

impl GpuLink {
    /// Packs a link; rows below [`LINK_MAX_ROWS`], combo below [`LINK_MAX_COMBOS`].
    pub fn new(receiver: u32, sender: u32, combo: u32, form_factor: f32) -> Self {
        debug_assert!(receiver < LINK_MAX_ROWS && sender < LINK_MAX_ROWS);
        debug_assert!(combo < LINK_MAX_COMBOS);
        let half = 32 - LINK_ROW_BITS;
        Self {
            receiver_combo: receiver | (combo >> half) << LINK_ROW_BITS,
            sender_combo: sender | (combo & ((1 << half) - 1)) << LINK_ROW_BITS,
            form_factor,
        }
    }

    /// (receiver, sender, combo), as the vertex shader unpacks them.
    pub fn unpack(&self) -> (u32, u32, u32) {
        let mask = LINK_MAX_ROWS - 1;
        let half = 32 - LINK_ROW_BITS;
        (
            self.receiver_combo & mask,
            self.sender_combo & mask,
            (self.receiver_combo >> LINK_ROW_BITS) << half | self.sender_combo >> LINK_ROW_BITS,
        )
    }
}

/// What the lines of links with the same central bin, filter layer and receiver rectangle
/// share (16 bytes, a storage-buffer record, `uvec4` in the shaders).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub struct GpuCombo {
    /// Central bin (low 16 bits) and filter-table layer (high 16 bits).
    pub bin_layer: u32,
    /// The rectangle of the receiver's bin grid the line covers ([`BinRect::packed`]):
    /// first column, first row, width, height, 8 bits each.
    pub rect: u32,
    /// Which of the rectangle's bins blend (bit `dv·width + du`), low and high words.
    pub mask: [u32; 2],
}

/// Bins one line of the global pass may cover: the width of its rectangle times its height
/// (the fragment shader's mask is 64 bits).
pub const MAX_RECT_BINS: u32 = 64;

/// A rectangle of the bins' `nu × nv` grid drawn by one line of the global pass, and which of
/// its bins carry filter weight for a bin the receiver reads (the rest are discarded).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub struct BinRect {
    /// First grid column.
    pub u0: u32,
    /// First grid row.
    pub v0: u32,
    /// Columns.
    pub width: u32,
    /// Rows (the line's width in texels).
    pub height: u32,
    /// Bit `dv·width + du`: bin `(u0 + du, v0 + dv)` is drawn.
    pub mask: u64,
}

impl BinRect {
    /// `u0 | v0 << 8 | width << 16 | height << 24` (grids up to 64 × 64 bins).
    pub fn packed(&self) -> u32 {
        self.u0 | self.v0 << 8 | self.width << 16 | self.height << 24
    }

    /// Bins drawn (blended).
    pub fn drawn(&self) -> u32 {
        self.mask.count_ones()
    }
}

/// A row and a second row the pass reads (push: the parent, drawn as a quad over the row's
/// tile; pull: the right child, the left being the next row, drawn as one line across the row).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct RowPair {
    /// Row written.
    pub row: u32,
    /// Row read besides it (`u32::MAX`: none).
    pub other: u32,
}

/// A quad covering whole rows `[first, end)` of one column block (the local pass); `source` is
/// unused.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct QuadInstance {
    /// Unused (zero).
    pub source: u32,
    /// First covered row.
    pub first: u32,
    /// One past the last covered row (same column block as `first`).
    pub end: u32,
}

/// A material in the storage buffer (std430, `Material` in common.glsl).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct GpuMaterial {
    /// Diffuse albedo (rgb); the solver's record: the lobe's index in the lobe-bins buffer (a,
    /// −1 without a lobe).
    pub kd: [f32; 4],
    /// Specular albedo (rgb) and Phong exponent (a).
    pub ks_ns: [f32; 4],
    /// Emitted radiance (rgb); the solver's record: the lobe's truncation cosine (a).
    pub ke: [f32; 4],
}

impl GpuMaterial {
    /// The shader record of `m` (the frame's per-pixel BRDF uses the material's own exponent).
    pub fn new(m: &crate::scene::Material) -> Self {
        Self::with_exponent(m, m.ns)
    }

    /// The record with the Phong exponent replaced (the solver's lobe as the bins sample it).
    pub fn with_exponent(m: &crate::scene::Material, ns: f64) -> Self {
        let v = |v: glam::DVec3, w: f64| [v.x as f32, v.y as f32, v.z as f32, w as f32];
        Self {
            kd: v(m.kd, 0.0),
            ks_ns: v(m.ks, ns),
            ke: v(m.ke, 0.0),
        }
    }
}

/// Bin center directions as the `vec4` records of the bin-centers storage buffer.
pub fn bin_centers(bins: &crate::bins::Bins) -> Vec<[f32; 4]> {
    bins.centers
        .iter()
        .map(|c| [c.x as f32, c.y as f32, c.z as f32, 0.0])
        .collect()
}

/// Descriptor bindings of the solver's one set layout (`AR_BINDING_*` in common.glsl).
pub mod binding {
    /// Leaves' I_ex, current (read by global and local).
    pub const LEAF_EX: u32 = 0;
    /// Clusters' I_ex (written by pull, read by global).
    pub const CLUSTER_EX: u32 = 1;
    /// Cone-filter tables, one m×m layer per used class.
    pub const FILTER: u32 = 2;
    /// Gathered incident radiance L_in.
    pub const L_IN: u32 = 3;
    /// Pushed incident radiance.
    pub const L_PUSH: u32 = 4;
    /// Irradiance from links, one texel per row.
    pub const IRRADIANCE_T: u32 = 5;
    /// Attributes: normal (rgb), area (a).
    pub const ATTR_NORMAL_AREA: u32 = 6;
    /// Attributes: cosine normalization, material index, leaf flag.
    pub const ATTR_LEAF: u32 = 7;
    /// The leaves' first bounce of direct light per bin ([`crate::solver::local::direct_exitant`]).
    pub const DIRECT: u32 = 8;
    /// Leaves' I_ex just written by the local pass (read by pull).
    pub const LEAF_EX_NEXT: u32 = 9;
    /// Materials storage buffer.
    pub const MATERIALS: u32 = 10;
    /// Bin center directions storage buffer (vec4 per bin).
    pub const BIN_CENTERS: u32 = 11;
    /// Glossy leaves' lobe factor per incident bin (R32, table layout; 1×1 without glossy leaves).
    pub const LOBE_NORM: u32 = 12;
    /// Clusters' I_ex at odd depths (`CLUSTER_EX` holds the even depths): pull writes one
    /// parity per level while reading the other.
    pub const CLUSTER_EX_ODD: u32 = 13;
    /// Link combos (storage: [`super::GpuCombo`]).
    pub const COMBOS: u32 = 14;
    /// Incident bins each glossy lobe's truncated cone can reach, per mirror bin (storage:
    /// [`crate::gpu::pack::lobe_bins`]).
    pub const LOBE_BINS: u32 = 15;
    /// Link records (storage: [`super::GpuLink`]), pulled by the global pass's vertex index.
    pub const LINKS: u32 = 16;
    /// The leaves' first bounce of the shadowed environment per bin
    /// ([`crate::frame::environment`]; 1×1 without an environment).
    pub const ENVIRONMENT: u32 = 17;
    /// Float16 blending rounded to nearest, emulated ([`crate::gpu::blend16`]): the incident
    /// tables' sums as float32 bits, four words per texel (one word where not emulated).
    pub const ROUNDED: u32 = 18;
    /// Number of bindings.
    pub const COUNT: u32 = 19;
    /// Storage-buffer bindings (the rest are combined image samplers).
    pub const BUFFERS: [u32; 6] = [MATERIALS, BIN_CENTERS, COMBOS, LOBE_BINS, LINKS, ROUNDED];
}

/// Push constants of the frame passes (`FrameConstants` in common.glsl, 128 bytes: the
/// guaranteed minimum of `maxPushConstantsSize`).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FrameConstants {
    /// World → clip of the camera, or of the shadow view being drawn (column-major).
    pub view_proj: [[f32; 4]; 4],
    /// Eye position (xyz); 1 / source scale (w), to undo the solver's scale on I_total.
    pub eye: [f32; 4],
    /// Environment radiance seen where camera rays escape (rgb); the factor on the output (w:
    /// a viewer's exposure, 1 otherwise).
    pub environment: [f32; 4],
    /// Target width, target height, bins `m`, rows per column block of I_total.
    pub sizes: [u32; 4],
    /// Light count, shadow view being drawn, shadow map side, supersampling per axis.
    pub misc: [u32; 4],
}

/// One shadow-map view (`ShadowView` in common.glsl; mirrors [`crate::frame::shadow::ShadowView`]).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct GpuShadowView {
    /// World → clip (column-major).
    pub view_proj: [[f32; 4]; 4],
    /// Origin (xyz); 1 for orthographic, 0 for perspective (w).
    pub origin: [f32; 4],
    /// Unit axis (xyz); half side or tan(fov/2) (w).
    pub forward: [f32; 4],
    /// Its map in the atlas: first texel x, y, side, unused.
    pub atlas: [u32; 4],
    /// Unit image right (xyz; w unused): with `up`, the rays through the texel centers that
    /// the receiver-plane lookup intersects with the receiver.
    pub right: [f32; 4],
    /// Unit image up (xyz; w unused).
    pub up: [f32; 4],
}

/// One analytic light (`Light` in common.glsl).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct GpuLight {
    /// Kind (0 directional, 1 point, 2 spot, 3 emitter sample), first shadow view, view count,
    /// 1 where an emitter sample has a cell.
    pub kind_views: [u32; 4],
    /// Position (xyz).
    pub position: [f32; 4],
    /// Travel direction (directional), spot axis or emitter normal (xyz).
    pub direction: [f32; 4],
    /// Irradiance (directional), intensity or emitted radiance (rgb); spot cut-off in radians
    /// (w).
    pub power: [f32; 4],
    /// Spot beam width in radians or emitter sample area (x).
    pub params: [f32; 4],
    /// An emitter sample's cell: its corners (xyz), where `kind_views.w` is 1.
    pub cell: [[f32; 4]; 3],
}

/// An emitting triangle for the emitter edges of the compose pass (`EmitterTriangle` in
/// common.glsl; [`crate::frame::edges::EmitterTriangles`]).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct GpuEmitterTriangle {
    /// Corners (xyz), counter-clockwise from the emitting side.
    pub c0: [f32; 4],
    /// Second corner.
    pub c1: [f32; 4],
    /// Third corner.
    pub c2: [f32; 4],
    /// Emitted radiance (rgb).
    pub ke: [f32; 4],
}

/// Per-face data of the frame passes (`FrameElement` in common.glsl), in face-slot order
/// ([`crate::frame::surfaces::Surfaces`]): the leaf's display data and the face's normal.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct GpuFrameElement {
    /// The leaf's center (xyz), splat radius (w).
    pub center_radius: [f32; 4],
    /// The leaf's unit normal (xyz), area (w).
    pub normal_area: [f32; 4],
    /// Table row, flat-surface id, shading mode, material index.
    pub ids: [u32; 4],
    /// Cosine normalization (x); 1 where the face has shading normals, else 0 (y).
    pub cos_norm: [f32; 4],
    /// The face's unit normal (xyz).
    pub face_normal: [f32; 4],
}

/// One entry of the shared-vertex lists (`AdjEntry` in common.glsl, 20 bytes): a slot whose
/// leaf blends at the vertex, its shading normal there and its weight
/// ([`crate::frame::surfaces::Surfaces`] `adjacency`, `adjacency_normal`, `adjacency_weight`).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct GpuAdjEntry {
    /// Face slot.
    pub leaf: u32,
    /// Its interpolated vertex normal at the shared vertex (not normalized).
    pub normal: [f32; 3],
    /// Its weight.
    pub weight: f32,
}

/// One element corner as vertex input of the shadow and G-buffer passes (32 bytes).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct CornerVertex {
    /// World position.
    pub position: [f32; 3],
    /// Leaf slot of the element.
    pub leaf: u32,
    /// Shared vertex (vertex-interpolated elements) or `u32::MAX`.
    pub vertex: u32,
    /// Shading normal at the corner (interpolated vertex normals, not normalized; the face
    /// normal without `vn`), interpolated by the rasterizer into the G-buffer.
    pub normal: [f32; 3],
}

/// Descriptor bindings of the frame passes (`AR_FRAME_*` in common.glsl).
pub mod frame_binding {
    /// I_total table (sampled).
    pub const I_TOTAL: u32 = 0;
    /// Materials (storage).
    pub const MATERIALS: u32 = 1;
    /// Bin centers (storage).
    pub const BIN_CENTERS: u32 = 2;
    /// Frame elements (storage).
    pub const ELEMENTS: u32 = 3;
    /// Shared-vertex CSR offsets (storage).
    pub const ADJ_OFFSETS: u32 = 4;
    /// Shared-vertex leaf lists (storage).
    pub const ADJ_LIST: u32 = 5;
    /// Lights (storage).
    pub const LIGHTS: u32 = 6;
    /// Shadow views (storage).
    pub const SHADOW_VIEWS: u32 = 7;
    /// Shadow maps, views stacked vertically (sampled R32F).
    pub const SHADOW_MAP: u32 = 8;
    /// G-buffer: position (xyz), leaf slot + 1 (w, negative on an emitting leaf); 0 = background.
    pub const GBUF_POSITION: u32 = 9;
    /// G-buffer: vertex-interpolated indirect radiance.
    pub const GBUF_VERTEX: u32 = 10;
    /// Splat accumulation: Σ w·L (rgb), Σ w (a).
    pub const SPLAT: u32 = 11;
    /// Emitting triangles (storage).
    pub const EMITTERS: u32 = 12;
    /// G-buffer: interpolated shading normal (xyz) where the scene has `vn` (sampled).
    pub const GBUF_NORMAL: u32 = 13;
    /// The splat texels' display bins toward the eye (R32F; −1 where none; sampled).
    pub const SPLAT_BINS: u32 = 14;
    /// The area emitters' shared direct light at each block's corner pixel (RGBA32F; a: the
    /// inverse depth of its samples' mean where that pixel shares it, else 0; sampled;
    /// `frame::direct`).
    pub const DIRECT_BLOCKS: u32 = 15;
    /// Shared vertices' positions (storage, xyz).
    pub const VERTEX_POSITIONS: u32 = 16;
    /// Shared vertices' display radiance toward the eye (RGBA32F, vertex `v` at texel
    /// `(v mod W, v / W)`, `W` = [`crate::gpu::passes::vertex_values::WIDTH`]; sampled).
    pub const VERTEX_VALUES: u32 = 17;
    /// Number of bindings.
    pub const COUNT: u32 = 18;
    /// Storage-buffer bindings (the rest are combined image samplers).
    pub const BUFFERS: [u32; 9] = [
        VERTEX_POSITIONS,
        EMITTERS,
        MATERIALS,
        BIN_CENTERS,
        ELEMENTS,
        ADJ_OFFSETS,
        ADJ_LIST,
        LIGHTS,
        SHADOW_VIEWS,
    ];
}

/// Local-pass mode specialization constant (`AR_MODE` in common.glsl, constant_id 0).
pub mod mode {
    /// Reflection and antiradiance (symmetric scheme).
    pub const BOTH: u32 = 0;
    /// Reflection only (asymmetric step, eq. 13).
    pub const REFLECT: u32 = 1;
    /// Antiradiance only (asymmetric step, eq. 14).
    pub const ANTIRADIANCE: u32 = 2;
}

/// Specialization constant ids (`AR_SPEC_*` in common.glsl): a pipeline's values come from the
/// scene's [`crate::plan::Features`], so a pass a scene does not need compiles away.
pub mod spec {
    /// Local-pass mode ([`super::mode`]).
    pub const MODE: u32 = 0;
    /// The local pass runs the general BRDF (Phong) sum.
    pub const GLOSSY: u32 = 1;
    /// The local pass writes antiradiance into the back bins.
    pub const ANTIRADIANCE: u32 = 2;
    /// Direct light from the direct-light table is reflected.
    pub const DIRECT: u32 = 3;
    /// The environment is added to the incident light.
    pub const ENVIRONMENT: u32 = 4;
    /// Emission is added in the local pass.
    pub const EMISSION: u32 = 5;
    /// The frame splats flat-surface elements.
    pub const SPLAT: u32 = 6;
    /// The frame interpolates smooth meshes per vertex.
    pub const VERTEX: u32 = 7;
    /// Number of feature constants ([`values`]).
    pub const COUNT: usize = 8;
    /// Bins per table row `m` ([`crate::gpu::tables::TableLayout`]; solver passes only).
    pub const BINS: u32 = 8;
    /// Rows `nv` of the bins' grid: the incident tables' tile height.
    pub const GRID_ROWS: u32 = 9;
    /// Rows stored per column block of a table image.
    pub const ROWS_PER_COLUMN: u32 = 10;
    /// Incident tables' nodes per column block of tiles (`AR_TILE_NODES`).
    pub const TILE_NODES: u32 = 11;
    /// The incident tables' width where float16 blending is emulated ([`crate::gpu::blend16`]),
    /// 0 where the passes blend.
    pub const ROUND_WIDTH: u32 = 12;
    /// Number of a solver pipeline's constants ([`solver_values`]).
    pub const SOLVER_COUNT: usize = 13;

    /// The values of every constant for `features` and local-pass mode `mode`.
    pub fn values(f: &crate::plan::Features, mode: u32, glossy: bool) -> [u32; COUNT] {
        [
            mode,
            glossy as u32,
            f.antiradiance as u32,
            f.direct as u32,
            f.environment as u32,
            f.emission as u32,
            f.splat as u32,
            f.vertex as u32,
        ]
    }

    /// A solver pipeline's constants: [`values`], then the table layout, which the shaders'
    /// texel addressing divides by (constants let the compiler turn those divisions into
    /// multiplies; on lavapipe a division by a push constant is a scalar loop per lane), then
    /// the incident tables' width where float16 blending is emulated (`round`).
    pub fn solver_values(
        f: &crate::plan::Features,
        mode: u32,
        glossy: bool,
        table: &crate::gpu::tables::TableLayout,
        round: bool,
    ) -> [u32; SOLVER_COUNT] {
        let mut v = [0; SOLVER_COUNT];
        v[..COUNT].copy_from_slice(&values(f, mode, glossy));
        v[BINS as usize] = table.bins;
        v[GRID_ROWS as usize] = table.grid_rows;
        v[ROWS_PER_COLUMN as usize] = table.rows_per_column;
        v[TILE_NODES as usize] = table.tile_nodes;
        v[ROUND_WIDTH as usize] = if round { table.tile_extent().0 } else { 0 };
        v
    }
}

/// Views a slice of plain `#[repr(C)]` records as bytes for upload.
pub fn as_bytes<T: Copy>(v: &[T]) -> &[u8] {
    // SAFETY: the layout types are repr(C) with only u32/f32 fields and no padding.
    unsafe { std::slice::from_raw_parts(v.as_ptr() as *const u8, std::mem::size_of_val(v)) }
}

#[cfg(test)]
mod tests;

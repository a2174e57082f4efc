//! The solver's images, buffers and descriptor sets (§4.1). [`ResourcePlan`] describes them as
//! data from a [`System`] and its [`Features`] (what `info` reports, without a device);
//! [`Resources`] creates exactly those and fills them from the pure packing functions of
//! [`super::pack`]. Only what the scene needs is created: no glossy or direct-light tables for
//! scenes without them.

use super::context::Context;
use super::handle::Owned;
use super::layout::{as_bytes, binding, GpuCombo, GpuLink, GpuMaterial, QuadInstance, RowPair};
use super::links::LinkChunks;
use super::memory::{resource_set, Buffer, BufferDesc, Image, ImageDesc, MemoryReport, Purpose};
use super::pack;
use super::tables::{DrawData, TableLayout};
use crate::error::Result;
use crate::gpu::error::VkContext;
use crate::plan::Features;
use crate::scene::Precision;
use crate::system::System;
use ash::vk;
use std::sync::Arc;

resource_set! {
    /// Images of the solver. `leaf_ex0`/`leaf_ex1` are the ping-pong pair the local pass
    /// alternates between.
    pub struct SolverImages {
        /// Leaves' I_ex (cluster rows zero), parity 0.
        pub leaf_ex0,
        /// Leaves' I_ex, parity 1.
        pub leaf_ex1,
        /// Clusters' I_ex at even depths (leaf and odd rows zero), rebuilt by every pull.
        pub cluster_ex,
        /// Clusters' I_ex at odd depths (pull writes one parity per level, reading the other).
        pub cluster_ex_odd,
        /// Gathered incident radiance.
        pub l_in,
        /// Pushed incident radiance.
        pub l_push,
        /// Display intensity.
        pub i_total,
        /// Irradiance from links (one texel per row).
        pub irradiance_t,
        /// Normal and area per row.
        pub attr_normal_area,
        /// Cosine normalization, material, leaf flag per row.
        pub attr_leaf,
        /// Cone-filter tables (R32, one m×m layer per used class).
        pub filter,
        /// The leaves' first bounce of direct light (zero until set; 1×1 placeholder for scenes
        /// without lights).
        pub direct,
        /// Lobe factors per glossy leaf and incident bin (1×1 placeholder without glossy leaves).
        pub lobe_norm,
        /// The leaves' first bounce of the shadowed environment (zero until set; 1×1
        /// placeholder for scenes without an environment).
        pub environment,
    }
}

impl<T> SolverImages<T> {
    /// The leaves' I_ex of parity `p`.
    pub fn leaf_ex(&self, p: usize) -> &T {
        if p == 0 {
            &self.leaf_ex0
        } else {
            &self.leaf_ex1
        }
    }

    /// The leaves' I_ex of parity `p`, writable.
    pub fn leaf_ex_mut(&mut self, p: usize) -> &mut T {
        if p == 0 {
            &mut self.leaf_ex0
        } else {
            &mut self.leaf_ex1
        }
    }
}

resource_set! {
    /// Vertex and storage buffers of the solver.
    pub struct SolverBuffers {
        /// Links (global).
        pub links,
        /// What lines share: central bin, filter layer, receiver bin rectangle (global).
        pub combos,
        /// Push quads (one per node tile), by depth.
        pub push,
        /// Diffuse leaf runs.
        pub diffuse_quads,
        /// Glossy leaf runs.
        pub glossy_quads,
        /// All leaf runs (irradiance).
        pub leaf_quads,
        /// Pull lines, by depth.
        pub pull,
        /// Materials.
        pub materials,
        /// Bin centers.
        pub bin_centers,
        /// Incident bins of each glossy lobe's truncated cone, per mirror bin.
        pub lobe_bins,
        /// The incident tables' sums where float16 blending is emulated ([`super::blend16`]).
        pub rounded,
    }
}

/// Format of the cluster I_ex image: float32 at every precision. Pull sums up to thousands of
/// signed leaf intensities per cluster (radiance and antiradiance cancel); float16 blending
/// loses up to an ulp per addition, which put Cornell-box clusters 4% off.
pub const CLUSTER_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
const F32X4: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

/// Texel format for a precision (f64 is the CPU's; a GPU asked for it uses float32).
pub fn table_format(p: Precision) -> vk::Format {
    match p {
        Precision::F16 => vk::Format::R16G16B16A16_SFLOAT,
        Precision::F32 | Precision::F64 => vk::Format::R32G32B32A32_SFLOAT,
    }
}

impl SolverImages<ImageDesc> {
    /// The images of a solve in `layout` with `format` tables and `accum_format` L_in/L_push;
    /// the direct-light and lobe tables are full-size only when `features` use them
    /// (`glossy_tables`: some leaf reads lobe factors).
    pub fn describe(
        layout: &TableLayout,
        format: vk::Format,
        accum_format: vk::Format,
        features: &Features,
        glossy_tables: bool,
        filter_layers: u32,
    ) -> Self {
        let (tw, th) = (layout.width(), layout.rows_per_column);
        let (rw, rh) = (layout.columns, layout.rows_per_column);
        // The incident tables hold each node's bins as a tile of the bins' grid.
        let (iw, ih) = layout.tile_extent();
        let m = layout.bins;
        let img = |name: &str, w, h, f, p| ImageDesc::new(name, w, h, f, p);
        let table = |name: &str| img(name, tw, th, format, Purpose::Tables);
        let row = |name: &str, f| img(name, rw, rh, f, Purpose::ElementAttributes);
        Self {
            leaf_ex0: table("I_ex leaves (ping)"),
            leaf_ex1: table("I_ex leaves (pong)"),
            cluster_ex: img(
                "I_ex clusters (even)",
                tw,
                th,
                CLUSTER_FORMAT,
                Purpose::Tables,
            ),
            cluster_ex_odd: img(
                "I_ex clusters (odd)",
                tw,
                th,
                CLUSTER_FORMAT,
                Purpose::Tables,
            ),
            l_in: img("L_in", iw, ih, accum_format, Purpose::Tables),
            l_push: img("L_in pushed", iw, ih, accum_format, Purpose::Tables),
            i_total: table("I_total"),
            irradiance_t: row("irradiance (links)", format),
            attr_normal_area: row("attributes: normal, area", F32X4),
            attr_leaf: row("attributes: cos norm, material", F32X4),
            filter: img(
                "cone filter tables",
                m,
                m * filter_layers.max(1),
                vk::Format::R32_SFLOAT,
                Purpose::FilterTables,
            ),
            // Without lights the shaders never read it (specialized away): a 1×1 placeholder.
            direct: if features.direct {
                table("direct light")
            } else {
                img("direct light (none)", 1, 1, format, Purpose::Tables)
            },
            environment: if features.environment {
                table("environment light")
            } else {
                img("environment light (none)", 1, 1, format, Purpose::Tables)
            },
            lobe_norm: if glossy_tables {
                img(
                    "lobe factors",
                    tw,
                    th,
                    vk::Format::R32_SFLOAT,
                    Purpose::Tables,
                )
            } else {
                let f = vk::Format::R32_SFLOAT;
                img("lobe factors (none)", 1, 1, f, Purpose::Tables)
            },
        }
    }
}

impl SolverBuffers<BufferDesc> {
    /// The buffers holding `draw`, `materials` material records, `bins` bin centers and
    /// `lobe_bins` words of lobe neighbourhoods.
    pub fn describe(draw: &DrawData, materials: usize, bins: usize, lobe_bins: usize) -> Self {
        let vb = vk::BufferUsageFlags::VERTEX_BUFFER;
        let sb = vk::BufferUsageFlags::STORAGE_BUFFER;
        let prim = Purpose::PushPullPrimitives;
        let quads = |name: &str, q: &[QuadInstance]| {
            BufferDesc::of::<QuadInstance>(name, q.len(), vb, prim)
        };
        let rows = |name: &str, r: &[RowPair]| BufferDesc::of::<RowPair>(name, r.len(), vb, prim);
        Self {
            links: BufferDesc::of::<GpuLink>("links", draw.links.len().max(1), sb, Purpose::Links),
            combos: BufferDesc::of::<GpuCombo>(
                "link combos",
                draw.combos.len().max(1),
                sb,
                Purpose::Links,
            ),
            push: rows("push quads", &draw.push),
            diffuse_quads: quads("local quads (diffuse)", &draw.diffuse_quads),
            glossy_quads: quads("local quads (glossy)", &draw.glossy_quads),
            leaf_quads: quads("local quads (irradiance)", &draw.leaf_quads),
            pull: rows("pull lines", &draw.pull),
            materials: BufferDesc::of::<GpuMaterial>(
                "materials",
                materials,
                sb,
                Purpose::ElementAttributes,
            ),
            bin_centers: BufferDesc::of::<[f32; 4]>(
                "bin centers",
                bins,
                sb,
                Purpose::ElementAttributes,
            ),
            lobe_bins: BufferDesc::of::<u32>(
                "lobe bins",
                lobe_bins.max(1),
                sb,
                Purpose::ElementAttributes,
            ),
            rounded: rounded_desc(1),
        }
    }
}

/// The emulated float16 blending's buffer of `words` float32 words ([`super::blend16`]).
fn rounded_desc(words: usize) -> BufferDesc {
    let usage = vk::BufferUsageFlags::STORAGE_BUFFER
        | vk::BufferUsageFlags::TRANSFER_SRC
        | vk::BufferUsageFlags::TRANSFER_DST;
    BufferDesc::of::<u32>("float16 rounding sums", words, usage, Purpose::Tables)
}

/// Everything the solver will create for one scene, as data: the table layout, the draw
/// records, and the descriptions of every image and buffer.
pub struct ResourcePlan {
    /// Table layout.
    pub layout: TableLayout,
    /// Table texel format.
    pub format: vk::Format,
    /// Format of the additive targets L_in and L_push (the table format unless the device
    /// truncates float16 blending).
    pub accum_format: vk::Format,
    /// Draw records (counts are needed when recording).
    pub draw: DrawData,
    /// Incident bins of the glossy lobes' cones ([`super::pack::lobe_bins`]).
    pub lobe_bins: Vec<u32>,
    /// Image descriptions.
    pub images: SolverImages<ImageDesc>,
    /// Buffer descriptions.
    pub buffers: SolverBuffers<BufferDesc>,
    /// Float16 blending rounded to nearest is emulated in the global and push passes
    /// ([`super::blend16`]; test-only, for devices that truncate).
    pub round_f16: bool,
}

impl ResourcePlan {
    /// Describes the resources of `sys` with `features` at `precision`; L_in and L_push in
    /// `accum_format`; column blocks of at most `column_height` rows in images no larger than
    /// `max_image_dimension`; the global pass's lines at most `max_line_width` texels wide
    /// ([`super::context::DeviceInfo::max_line_width`]).
    pub fn new(
        sys: &System,
        features: &Features,
        precision: Precision,
        accum_format: vk::Format,
        column_height: u32,
        max_image_dimension: u32,
        max_line_width: u32,
    ) -> Result<Self> {
        let layout = TableLayout::with_column_height(
            sys.rows() as u32,
            sys.bins.count as u32,
            max_image_dimension,
            column_height,
        )?
        .with_grid(sys.bins.nv as u32, max_image_dimension)?;
        let format = table_format(precision);
        let draw = DrawData::new(sys, &layout, features.glossy_everywhere, max_line_width)?;
        let glossy_tables =
            features.glossy && (!sys.lobe_norm.is_empty() || features.glossy_everywhere);
        let layers = sys.filters.used_classes().len() as u32;
        let lobe_bins = if features.glossy {
            super::pack::lobe_bins(sys)
        } else {
            Vec::new()
        };
        Ok(Self {
            images: SolverImages::describe(
                &layout,
                format,
                accum_format,
                features,
                glossy_tables,
                layers,
            ),
            buffers: SolverBuffers::describe(
                &draw,
                sys.materials.len(),
                sys.bins.count,
                lobe_bins.len(),
            ),
            lobe_bins,
            layout,
            format,
            accum_format,
            draw,
            round_f16: false,
        })
    }

    /// The same plan with float16 blending rounded to nearest emulated ([`super::blend16`]):
    /// the incident tables' sums kept in a buffer of four words per texel.
    pub fn with_round_f16(mut self) -> Self {
        let (w, h) = self.layout.tile_extent();
        self.buffers.rounded = rounded_desc(4 * (w as usize) * (h as usize));
        self.round_f16 = true;
        self
    }

    /// The memory these resources take, by purpose.
    pub fn memory(&self) -> MemoryReport {
        MemoryReport::default()
            .images(self.images.iter())
            .buffers(self.buffers.iter())
    }

    /// Table memory of `rows × bins` at `precision` in the worst case (every table, L_in and
    /// L_push in float32 as on a device that truncates float16 blending): the bound checked
    /// before linking, when only the element count is known. (The column split changes only
    /// the padding of the last block, so one column stands for any split.)
    pub fn worst_table_bytes(rows: u32, bins: u32, precision: Precision) -> Result<u64> {
        let layout = TableLayout::new(rows, bins, u32::MAX)?;
        let images = SolverImages::describe(
            &layout,
            table_format(precision),
            F32X4,
            &Features::ALL,
            true,
            1,
        );
        Ok(MemoryReport::default()
            .images(images.iter())
            .get(Purpose::Tables))
    }
}

/// All GPU resources of one solver, created from a [`ResourcePlan`]; they free themselves.
pub struct Resources {
    /// What was created, and the layout and draw records.
    pub plan: ResourcePlan,
    /// Images.
    pub images: SolverImages<Image>,
    /// Buffers.
    pub buffers: SolverBuffers<Buffer>,
    /// `sets[p]` binds `leaf_ex(p)` as current and `leaf_ex(1-p)` as next, and the first chunk
    /// of link records.
    pub sets: [vk::DescriptorSet; 2],
    /// `link_sets[c - 1][p]`: as `sets[p]` with chunk `c ≥ 1` of the link records bound.
    pub link_sets: Vec<[vk::DescriptorSet; 2]>,
    /// How the link records are split into descriptor ranges.
    pub link_chunks: LinkChunks,
    /// Largest descriptor range the link records are read through (`maxStorageBufferRange`).
    link_range: u64,
    set_layout: vk::DescriptorSetLayout,
    sampler: Owned<vk::Sampler>,
    _pool: Owned<vk::DescriptorPool>,
}

impl Resources {
    /// Creates and fills everything `plan` describes for `sys`, with descriptor sets of
    /// `set_layout` that read the link records in ranges of at most `link_range` bytes.
    pub fn new(
        ctx: &Arc<Context>,
        plan: ResourcePlan,
        sys: &System,
        set_layout: vk::DescriptorSetLayout,
        link_range: u64,
    ) -> Result<Self> {
        let mut images = plan.images.try_map(|d| d.create(ctx))?;
        let layout = &plan.layout;
        let lobe = &mut images.lobe_norm;
        let (w, h) = (lobe.extent.width, lobe.extent.height);
        lobe.upload(as_bytes(&pack::lobe_factors(sys, layout, w, h)))?;
        let (na, lf) = pack::attributes(sys, layout);
        let f32x4 = F32X4;
        images.attr_normal_area.upload(&pack::encode(f32x4, &na))?;
        images.attr_leaf.upload(&pack::encode(f32x4, &lf))?;
        images.filter.upload(as_bytes(&pack::filter_tables(sys)))?;
        for im in [&mut images.direct, &mut images.environment] {
            let d = &im.desc;
            let zero = vec![[0.0; 4]; (d.width * d.height) as usize];
            im.upload(&pack::encode(plan.format, &zero))?;
        }
        let draw = &plan.draw;
        let b = &plan.buffers;
        let materials = pack::solver_materials(sys);
        let centers = super::layout::bin_centers(&sys.bins);
        // Storage buffers may not be empty.
        let combos = super::pack::padded(draw.combos.clone());
        let buffers = SolverBuffers {
            links: b
                .links
                .upload(ctx, as_bytes(&super::pack::padded(draw.links.clone())))?,
            combos: b.combos.upload(ctx, as_bytes(&combos))?,
            push: b.push.upload(ctx, as_bytes(&draw.push))?,
            diffuse_quads: b.diffuse_quads.upload(ctx, as_bytes(&draw.diffuse_quads))?,
            glossy_quads: b.glossy_quads.upload(ctx, as_bytes(&draw.glossy_quads))?,
            leaf_quads: b.leaf_quads.upload(ctx, as_bytes(&draw.leaf_quads))?,
            pull: b.pull.upload(ctx, as_bytes(&draw.pull))?,
            materials: b.materials.upload(ctx, as_bytes(&materials))?,
            bin_centers: b.bin_centers.upload(ctx, as_bytes(&centers))?,
            lobe_bins: b
                .lobe_bins
                .upload(ctx, as_bytes(&super::pack::padded(plan.lobe_bins.clone())))?,
            rounded: b.rounded.upload(ctx, &vec![0; b.rounded.size as usize])?,
        };
        let sampler = super::pipelines::texel_sampler(ctx, "texelFetch sampler")?;
        let link_chunks = LinkChunks::new(plan.draw.links.len() as u64, link_range);
        let (pool, sets, link_sets) = allocate_sets(ctx, set_layout, link_chunks.chunks)?;
        let mut res = Self {
            plan,
            images,
            buffers,
            sets,
            link_sets,
            link_chunks,
            link_range,
            set_layout,
            sampler,
            _pool: pool,
        };
        res.rewrite_sets(ctx)?;
        Ok(res)
    }

    /// Points every descriptor set at the buffers again (after one was made anew), making the
    /// sets anew where the link records now need another number of chunks (no command buffer
    /// that used the old sets may be pending).
    pub fn rewrite_sets(&mut self, ctx: &Arc<Context>) -> Result<()> {
        let chunks = LinkChunks::new(self.plan.draw.links.len() as u64, self.link_range);
        if chunks.chunks != self.link_chunks.chunks {
            let (pool, sets, link_sets) = allocate_sets(ctx, self.set_layout, chunks.chunks)?;
            (self._pool, self.sets, self.link_sets) = (pool, sets, link_sets);
        }
        self.link_chunks = chunks;
        for p in 0..2 {
            ctx.name(
                self.sets[p],
                &format!("antiradiance set (current = I_ex {p})"),
            );
            self.write_set(ctx, self.sets[p], p, 0);
            for (c, s) in self.link_sets.iter().enumerate() {
                self.write_set(ctx, s[p], p, c as u32 + 1);
            }
        }
        Ok(())
    }

    /// The set of parity `p` with chunk `chunk` of the link records bound.
    pub fn set_for_chunk(&self, p: usize, chunk: u32) -> vk::DescriptorSet {
        match chunk {
            0 => self.sets[p],
            c => self.link_sets[c as usize - 1][p],
        }
    }

    /// Writes `set` of parity `p`: every image binding and the storage buffers, the link
    /// records' chunk `chunk`.
    fn write_set(&self, ctx: &Context, set: vk::DescriptorSet, p: usize, chunk: u32) {
        let im = &self.images;
        let image_of = |b: u32| -> &Image {
            match b {
                binding::LEAF_EX => im.leaf_ex(p),
                binding::CLUSTER_EX => &im.cluster_ex,
                binding::CLUSTER_EX_ODD => &im.cluster_ex_odd,
                binding::FILTER => &im.filter,
                binding::L_IN => &im.l_in,
                binding::L_PUSH => &im.l_push,
                binding::IRRADIANCE_T => &im.irradiance_t,
                binding::ATTR_NORMAL_AREA => &im.attr_normal_area,
                binding::ATTR_LEAF => &im.attr_leaf,
                binding::DIRECT => &im.direct,
                binding::ENVIRONMENT => &im.environment,
                binding::LOBE_NORM => &im.lobe_norm,
                _ => im.leaf_ex(1 - p),
            }
        };
        let images: Vec<(u32, vk::ImageView)> = (0..binding::COUNT)
            .filter(|b| !binding::BUFFERS.contains(b))
            .map(|b| (b, image_of(b).view))
            .collect();
        let b = &self.buffers;
        let whole = (0, vk::WHOLE_SIZE);
        let buffers = [
            (binding::MATERIALS, b.materials.raw, whole),
            (binding::BIN_CENTERS, b.bin_centers.raw, whole),
            (binding::COMBOS, b.combos.raw, whole),
            (binding::LOBE_BINS, b.lobe_bins.raw, whole),
            (binding::LINKS, b.links.raw, self.link_chunks.range(chunk)),
            (binding::ROUNDED, b.rounded.raw, whole),
        ];
        super::pipelines::write_set_ranges(ctx, set, self.sampler.raw(), &images, &buffers);
    }

    /// GPU memory by purpose (the descriptions the resources were created from).
    pub fn memory(&self) -> MemoryReport {
        self.plan.memory()
    }

    /// Table layout.
    pub fn layout(&self) -> &TableLayout {
        &self.plan.layout
    }

    /// Draw records.
    pub fn draw(&self) -> &DrawData {
        &self.plan.draw
    }
}

/// A pool with the two parities' sets of `set_layout` for each of `chunks` link chunks.
#[allow(clippy::type_complexity)]
fn allocate_sets(
    ctx: &Arc<Context>,
    set_layout: vk::DescriptorSetLayout,
    chunks: u32,
) -> Result<(
    Owned<vk::DescriptorPool>,
    [vk::DescriptorSet; 2],
    Vec<[vk::DescriptorSet; 2]>,
)> {
    let kinds = super::pipelines::descriptor_kinds(binding::COUNT, &binding::BUFFERS);
    let n = 2 * chunks.max(1);
    let pool = super::pipelines::descriptor_pool(ctx, &kinds, n, "antiradiance descriptor pool")?;
    let layouts = vec![set_layout; n as usize];
    let sets = unsafe {
        ctx.device.allocate_descriptor_sets(
            &vk::DescriptorSetAllocateInfo::default()
                .descriptor_pool(pool.raw())
                .set_layouts(&layouts),
        )
    }
    .vk("allocating descriptor sets")?;
    let pairs: Vec<[vk::DescriptorSet; 2]> = sets.chunks(2).map(|s| [s[0], s[1]]).collect();
    Ok((pool, pairs[0], pairs[1..].to_vec()))
}

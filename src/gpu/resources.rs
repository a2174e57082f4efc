//! The solver's images, buffers and descriptor sets (§4.1), created from a [`System`]. Only what
//! the scene needs is created: no glossy or direct-light data for scenes without them.

use super::context::Context;
use super::layout::{as_bytes, binding, GpuMaterial};
use super::memory::{Buffer, Image};
use super::tables::{DrawData, TableLayout};
use crate::error::{Result, VkContext};
use crate::scene::Precision;
use crate::system::System;
use ash::vk;
use half::f16;

/// Images of the solver. `leaf_ex` is the ping-pong pair the local pass alternates between.
pub struct Images {
    /// Leaves' I_ex (cluster rows zero): `[0]`/`[1]` swapped every propagation.
    pub leaf_ex: [Image; 2],
    /// Clusters' I_ex (leaf rows zero), rebuilt by every pull.
    pub cluster_ex: Image,
    /// Gathered incident radiance.
    pub l_in: Image,
    /// Pushed incident radiance.
    pub l_push: Image,
    /// Display intensity.
    pub i_total: Image,
    /// Irradiance from links + environment (one texel per row).
    pub irradiance_t: Image,
    /// Irradiance from direct light (one texel per row).
    pub irradiance_d: Image,
    /// Normal and area per row.
    pub attr_normal_area: Image,
    /// Cosine normalization, material, leaf flag per row.
    pub attr_leaf: Image,
    /// Cone-filter tables (R32, one m×m layer per used class).
    pub filter: Image,
    /// Direct incident radiance (zero until set; 1×1 placeholder for scenes without lights).
    pub direct: Image,
    /// Lobe factors per glossy leaf and incident bin (1×1 placeholder without glossy leaves).
    pub lobe_norm: Image,
}

impl Images {
    fn all_mut(&mut self) -> [&mut Image; 13] {
        let [a, b] = &mut self.leaf_ex;
        [
            a,
            b,
            &mut self.cluster_ex,
            &mut self.l_in,
            &mut self.l_push,
            &mut self.i_total,
            &mut self.irradiance_t,
            &mut self.irradiance_d,
            &mut self.attr_normal_area,
            &mut self.attr_leaf,
            &mut self.filter,
            &mut self.direct,
            &mut self.lobe_norm,
        ]
    }
}

/// Vertex and storage buffers.
pub struct Buffers {
    /// Links (global).
    pub links: Buffer,
    /// Push quads.
    pub push_quads: Buffer,
    /// Diffuse leaf runs.
    pub diffuse_quads: Buffer,
    /// Glossy leaf runs.
    pub glossy_quads: Buffer,
    /// All leaf runs (irradiance).
    pub leaf_quads: Buffer,
    /// Pull lines.
    pub pull_lines: Buffer,
    /// Materials.
    pub materials: Buffer,
    /// Bin centers.
    pub bin_centers: Buffer,
}

/// Bytes of GPU memory by purpose (the `memory_bytes` of `profile`).
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct MemoryReport {
    /// I_ex (3 images), L_in, L_push, I_total, direct.
    pub tables: u64,
    /// Link vertex buffer.
    pub links: u64,
    /// Cone-filter tables.
    pub filter_tables: u64,
    /// Attribute and irradiance images.
    pub element_attributes: u64,
    /// Push quads, local runs, pull lines.
    pub push_pull_primitives: u64,
    /// Sum.
    pub total: u64,
}

impl MemoryReport {
    /// A report of these parts and their total.
    pub fn sum(
        tables: u64,
        links: u64,
        filter_tables: u64,
        element_attributes: u64,
        push_pull_primitives: u64,
    ) -> Self {
        Self {
            tables,
            links,
            filter_tables,
            element_attributes,
            push_pull_primitives,
            total: tables + links + filter_tables + element_attributes + push_pull_primitives,
        }
    }

    /// The parts by name (the `memory_bytes` of `info` and `profile`).
    pub fn by_name(&self) -> std::collections::BTreeMap<String, u64> {
        [
            ("tables", self.tables),
            ("links", self.links),
            ("filter_tables", self.filter_tables),
            ("element_attributes", self.element_attributes),
            ("push_pull_primitives", self.push_pull_primitives),
            ("total", self.total),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect()
    }
}

/// All GPU resources of one solver.
pub struct Resources {
    /// Table layout.
    pub layout: TableLayout,
    /// Table texel format.
    pub format: vk::Format,
    /// Format of the additive targets L_in and L_push (the table format unless the device
    /// truncates float16 blending).
    pub accum_format: vk::Format,
    /// Draw data (counts are needed when recording).
    pub draw: DrawData,
    /// Images.
    pub images: Images,
    /// Buffers.
    pub buffers: Buffers,
    /// Nearest sampler for `texelFetch` bindings.
    pub sampler: vk::Sampler,
    /// Descriptor pool.
    pub pool: vk::DescriptorPool,
    /// `sets[p]` binds `leaf_ex[p]` as current and `leaf_ex[1-p]` as next.
    pub sets: [vk::DescriptorSet; 2],
}

/// Format of the cluster I_ex image (float32 at every precision, see [`Resources::new`]).
pub const CLUSTER_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

/// Texel format for a precision.
pub fn table_format(p: Precision) -> vk::Format {
    match p {
        Precision::F16 => vk::Format::R16G16B16A16_SFLOAT,
        Precision::F32 => vk::Format::R32G32B32A32_SFLOAT,
    }
}

/// Encodes RGBA f32 texels in `format`.
pub fn encode(format: vk::Format, texels: &[[f32; 4]]) -> Vec<u8> {
    if format == vk::Format::R16G16B16A16_SFLOAT {
        texels
            .iter()
            .flat_map(|t| {
                t.iter()
                    .flat_map(|&x| f16::from_f32(x).to_bits().to_le_bytes())
            })
            .collect()
    } else {
        texels
            .iter()
            .flat_map(|t| t.iter().flat_map(|x| x.to_le_bytes()))
            .collect()
    }
}

/// Decodes RGBA texels of `format` to f32.
pub fn decode(format: vk::Format, bytes: &[u8]) -> Vec<[f32; 4]> {
    if format == vk::Format::R16G16B16A16_SFLOAT {
        bytes
            .chunks_exact(8)
            .map(|c| {
                let h = |i: usize| {
                    f16::from_bits(u16::from_le_bytes([c[2 * i], c[2 * i + 1]])).to_f32()
                };
                [h(0), h(1), h(2), h(3)]
            })
            .collect()
    } else {
        bytes
            .chunks_exact(16)
            .map(|c| {
                let f = |i: usize| {
                    f32::from_le_bytes([c[4 * i], c[4 * i + 1], c[4 * i + 2], c[4 * i + 3]])
                };
                [f(0), f(1), f(2), f(3)]
            })
            .collect()
    }
}

impl Resources {
    /// Creates and fills everything for `sys`; `column_height` caps the rows per column block.
    pub fn new(
        ctx: &Context,
        sys: &System,
        precision: Precision,
        accum_format: vk::Format,
        column_height: u32,
        features: &crate::plan::Features,
    ) -> Result<Self> {
        let m = sys.bins.count as u32;
        let layout = TableLayout::with_column_height(
            sys.rows() as u32,
            m,
            ctx.info.max_image_dimension,
            column_height,
        )?;
        let format = table_format(precision);
        let draw = DrawData::new(sys, &layout, features.glossy_everywhere);
        let (tw, th) = (layout.width(), layout.rows_per_column);
        let (rw, rh) = (layout.columns, layout.rows_per_column);
        let f32x4 = vk::Format::R32G32B32A32_SFLOAT;
        let table = |name: &str| ctx.create_image(name, tw, th, format);
        let layers = sys.filters.used_classes().len().max(1) as u32;
        let mut images = Images {
            leaf_ex: [table("I_ex leaves (ping)")?, table("I_ex leaves (pong)")?],
            // Pull sums up to thousands of signed leaf intensities per cluster (radiance and
            // antiradiance cancel); float16 blending loses up to an ulp per addition, which put
            // Cornell-box clusters 4% off, so cluster sums are float32 at any precision.
            cluster_ex: ctx.create_image("I_ex clusters", tw, th, CLUSTER_FORMAT)?,
            l_in: ctx.create_image("L_in", tw, th, accum_format)?,
            l_push: ctx.create_image("L_in pushed", tw, th, accum_format)?,
            i_total: table("I_total")?,
            irradiance_t: ctx.create_image("irradiance (links+environment)", rw, rh, format)?,
            irradiance_d: ctx.create_image("irradiance (direct)", rw, rh, format)?,
            attr_normal_area: ctx.create_image("attributes: normal, area", rw, rh, f32x4)?,
            attr_leaf: ctx.create_image("attributes: cos norm, material", rw, rh, f32x4)?,
            filter: ctx.create_image(
                "cone filter tables",
                m,
                m * layers,
                vk::Format::R32_SFLOAT,
            )?,
            // Without lights the shaders never read it (specialized away): a 1×1 placeholder.
            direct: if features.direct {
                table("direct light")?
            } else {
                ctx.create_image("direct light (none)", 1, 1, format)?
            },
            lobe_norm: if !features.glossy
                || (sys.lobe_norm.is_empty() && !features.glossy_everywhere)
            {
                ctx.create_image("lobe factors (none)", 1, 1, vk::Format::R32_SFLOAT)?
            } else {
                ctx.create_image("lobe factors", tw, th, vk::Format::R32_SFLOAT)?
            },
        };
        // Lobe factors in table layout (leaf rows of glossy leaves; zero elsewhere).
        let mut lobe =
            vec![0.0f32; (images.lobe_norm.extent.width * images.lobe_norm.extent.height) as usize];
        for (li, leaf) in sys.leaves.iter().enumerate() {
            if let Some(f) = sys.lobe_factors(li) {
                for (j, &v) in f.iter().enumerate() {
                    let (x, y) = layout.texel(leaf.node, j as u32);
                    lobe[(y * tw + x) as usize] = v;
                }
            }
        }
        ctx.upload_image(&mut images.lobe_norm, as_bytes(&lobe))?;
        // Attributes.
        let mut na = vec![[0.0f32; 4]; (rw * rh) as usize];
        let mut lf = vec![[0.0f32; 4]; (rw * rh) as usize];
        for leaf in &sys.leaves {
            let (x, y) = layout.row_texel(leaf.node);
            let i = (y * rw + x) as usize;
            let n = leaf.normal;
            na[i] = [n.x as f32, n.y as f32, n.z as f32, leaf.area as f32];
            lf[i] = [leaf.cos_norm as f32, leaf.material as f32, 1.0, 0.0];
        }
        ctx.upload_image(&mut images.attr_normal_area, &encode(f32x4, &na))?;
        ctx.upload_image(&mut images.attr_leaf, &encode(f32x4, &lf))?;
        // Dense filter tables, one layer per used class.
        let mut ft = vec![0.0f32; (m * m * layers) as usize];
        for (layer, c) in sys.filters.used_classes().into_iter().enumerate() {
            for (l, row) in sys.filters.rows[c].iter().enumerate() {
                for &(j, w) in row {
                    ft[((layer as u32 * m + l as u32) * m + j) as usize] = w;
                }
            }
        }
        ctx.upload_image(&mut images.filter, as_bytes(&ft))?;
        let d = &images.direct;
        let zero = encode(
            format,
            &vec![[0.0; 4]; (d.extent.width * d.extent.height) as usize],
        );
        ctx.upload_image(&mut images.direct, &zero)?;
        let vb = vk::BufferUsageFlags::VERTEX_BUFFER;
        let sb = vk::BufferUsageFlags::STORAGE_BUFFER;
        let materials: Vec<GpuMaterial> = sys
            .materials
            .iter()
            .zip(&sys.lobes)
            .map(|(m, lobe)| GpuMaterial::with_exponent(m, lobe.map_or(m.ns, |l| l.exponent)))
            .collect();
        let centers = super::layout::bin_centers(&sys.bins);
        let buffers = Buffers {
            links: ctx.upload_buffer("links", as_bytes(&draw.links), vb)?,
            push_quads: ctx.upload_buffer("push quads", as_bytes(&draw.push_quads), vb)?,
            diffuse_quads: ctx.upload_buffer(
                "local quads (diffuse)",
                as_bytes(&draw.diffuse_quads),
                vb,
            )?,
            glossy_quads: ctx.upload_buffer(
                "local quads (glossy)",
                as_bytes(&draw.glossy_quads),
                vb,
            )?,
            leaf_quads: ctx.upload_buffer(
                "local quads (irradiance)",
                as_bytes(&draw.leaf_quads),
                vb,
            )?,
            pull_lines: ctx.upload_buffer("pull lines", as_bytes(&draw.pull_lines), vb)?,
            materials: ctx.upload_buffer("materials", as_bytes(&materials), sb)?,
            bin_centers: ctx.upload_buffer("bin centers", as_bytes(&centers), sb)?,
        };
        let sampler = super::pipelines::texel_sampler(ctx, "texelFetch sampler")?;
        let kinds = super::pipelines::descriptor_kinds(binding::COUNT, &binding::BUFFERS);
        let pool =
            super::pipelines::descriptor_pool(ctx, &kinds, 2, "antiradiance descriptor pool")?;
        Ok(Self {
            layout,
            format,
            accum_format,
            draw,
            images,
            buffers,
            sampler,
            pool,
            sets: [vk::DescriptorSet::null(); 2],
        })
    }

    /// Allocates and writes the two descriptor sets (after the set layout exists).
    pub fn write_sets(&mut self, ctx: &Context, set_layout: vk::DescriptorSetLayout) -> Result<()> {
        let layouts = [set_layout, set_layout];
        let sets = unsafe {
            ctx.device.allocate_descriptor_sets(
                &vk::DescriptorSetAllocateInfo::default()
                    .descriptor_pool(self.pool)
                    .set_layouts(&layouts),
            )
        }
        .vk("allocating descriptor sets")?;
        self.sets = [sets[0], sets[1]];
        for p in 0..2 {
            ctx.name(
                self.sets[p],
                &format!("antiradiance set (current = I_ex {p})"),
            );
            self.update_set(ctx, p);
        }
        Ok(())
    }

    /// (Re)writes set `p` (also after the direct image is replaced).
    pub fn update_set(&self, ctx: &Context, p: usize) {
        let im = &self.images;
        let image_of = |b: u32| -> &Image {
            match b {
                binding::LEAF_EX => &im.leaf_ex[p],
                binding::CLUSTER_EX => &im.cluster_ex,
                binding::FILTER => &im.filter,
                binding::L_IN => &im.l_in,
                binding::L_PUSH => &im.l_push,
                binding::IRRADIANCE_T => &im.irradiance_t,
                binding::IRRADIANCE_D => &im.irradiance_d,
                binding::ATTR_NORMAL_AREA => &im.attr_normal_area,
                binding::ATTR_LEAF => &im.attr_leaf,
                binding::DIRECT => &im.direct,
                binding::LOBE_NORM => &im.lobe_norm,
                _ => &im.leaf_ex[1 - p],
            }
        };
        let image_infos: Vec<(u32, [vk::DescriptorImageInfo; 1])> = (0..binding::COUNT)
            .filter(|b| !binding::BUFFERS.contains(b))
            .map(|b| {
                (
                    b,
                    [vk::DescriptorImageInfo::default()
                        .sampler(self.sampler)
                        .image_view(image_of(b).view)
                        .image_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)],
                )
            })
            .collect();
        let buf_infos = [
            (
                binding::MATERIALS,
                [vk::DescriptorBufferInfo::default()
                    .buffer(self.buffers.materials.raw)
                    .range(vk::WHOLE_SIZE)],
            ),
            (
                binding::BIN_CENTERS,
                [vk::DescriptorBufferInfo::default()
                    .buffer(self.buffers.bin_centers.raw)
                    .range(vk::WHOLE_SIZE)],
            ),
        ];
        let mut writes: Vec<vk::WriteDescriptorSet> = image_infos
            .iter()
            .map(|(b, info)| {
                vk::WriteDescriptorSet::default()
                    .dst_set(self.sets[p])
                    .dst_binding(*b)
                    .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
                    .image_info(info)
            })
            .collect();
        writes.extend(buf_infos.iter().map(|(b, info)| {
            vk::WriteDescriptorSet::default()
                .dst_set(self.sets[p])
                .dst_binding(*b)
                .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                .buffer_info(info)
        }));
        unsafe { ctx.device.update_descriptor_sets(&writes, &[]) };
    }

    /// The memory [`Resources::new`] would allocate for `sys` with `features` at `precision`,
    /// without a device (for `info`), assuming L_in/L_push in the table format and images up to
    /// `max_image_dimension` texels.
    pub fn planned_memory(
        sys: &System,
        features: &crate::plan::Features,
        precision: Precision,
        max_image_dimension: u32,
    ) -> Result<MemoryReport> {
        let m = sys.bins.count as u32;
        let layout =
            TableLayout::with_column_height(sys.rows() as u32, m, max_image_dimension, u32::MAX)?;
        let draw = DrawData::new(sys, &layout, features.glossy_everywhere);
        let texel = Image::texel_bytes(table_format(precision));
        let table = layout.width() as u64 * layout.rows_per_column as u64;
        let rows = layout.columns as u64 * layout.rows_per_column as u64;
        let glossy_tables =
            features.glossy && (!sys.lobe_norm.is_empty() || features.glossy_everywhere);
        let tables = table * (5 * texel + 16)
            + if features.direct {
                table * texel
            } else {
                texel
            }
            + if glossy_tables { table * 4 } else { 4 };
        let layers = sys.filters.used_classes().len().max(1) as u64;
        let size = |n: usize, t: usize| (n * t) as u64;
        let quad = std::mem::size_of::<super::layout::QuadInstance>();
        Ok(MemoryReport::sum(
            tables,
            size(
                draw.links.len(),
                std::mem::size_of::<super::layout::GpuLink>(),
            ),
            m as u64 * m as u64 * layers * 4,
            rows * (2 * texel + 32)
                + size(sys.materials.len(), std::mem::size_of::<GpuMaterial>())
                + m as u64 * 16,
            size(draw.push_quads.len(), quad)
                + size(draw.diffuse_quads.len(), quad)
                + size(draw.glossy_quads.len(), quad)
                + size(draw.leaf_quads.len(), quad)
                + size(
                    draw.pull_lines.len(),
                    std::mem::size_of::<super::layout::PullLine>(),
                ),
        ))
    }

    /// GPU memory by purpose.
    pub fn memory(&self) -> MemoryReport {
        let im = &self.images;
        let b = &self.buffers;
        let tables = im.leaf_ex[0].bytes()
            + im.leaf_ex[1].bytes()
            + im.cluster_ex.bytes()
            + im.l_in.bytes()
            + im.l_push.bytes()
            + im.i_total.bytes()
            + im.direct.bytes()
            + im.lobe_norm.bytes();
        let attrs = im.irradiance_t.bytes()
            + im.irradiance_d.bytes()
            + im.attr_normal_area.bytes()
            + im.attr_leaf.bytes()
            + b.materials.size
            + b.bin_centers.size;
        let prims = b.push_quads.size
            + b.diffuse_quads.size
            + b.glossy_quads.size
            + b.leaf_quads.size
            + b.pull_lines.size;
        MemoryReport::sum(tables, b.links.size, im.filter.bytes(), attrs, prims)
    }

    /// Frees everything.
    pub fn destroy(&mut self, ctx: &Context) {
        unsafe {
            ctx.device.destroy_descriptor_pool(self.pool, None);
            ctx.device.destroy_sampler(self.sampler, None);
        }
        for i in self.images.all_mut() {
            ctx.destroy_image(i);
        }
        let b = &mut self.buffers;
        for buf in [
            &mut b.links,
            &mut b.push_quads,
            &mut b.diffuse_quads,
            &mut b.glossy_quads,
            &mut b.leaf_quads,
            &mut b.pull_lines,
            &mut b.materials,
            &mut b.bin_centers,
        ] {
            ctx.destroy_buffer(buf);
        }
    }
}

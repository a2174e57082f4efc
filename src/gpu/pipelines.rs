//! Graphics pipelines of the passes (dynamic rendering, dynamic viewport/scissor), the solver's
//! one descriptor-set layout and pipeline layout. Additive blending is a per-target option of a
//! pipeline, so accumulation is explicit where a pipeline is made.

use super::context::Context;
use super::handle::Owned;
use super::layout::{binding, PassConstants};
use super::shaders::spirv;
use crate::error::Result;
use crate::gpu::error::VkContext;
use ash::vk;
use std::ffi::CStr;
use std::sync::Arc;

/// One color target of a pipeline.
#[derive(Debug, Clone, Copy)]
pub struct Target {
    /// Attachment format.
    pub format: vk::Format,
    /// Add to what is there (ONE, ONE) instead of overwriting.
    pub additive: bool,
    /// Whether the pipeline writes the target at all (else the write mask is empty).
    pub write: bool,
}

/// What a pipeline draws.
pub struct PipelineDesc<'a> {
    /// Debug name (also the pass name).
    pub name: &'a str,
    /// Vertex shader file under `glsl/`.
    pub vert: &'a str,
    /// Fragment shader file under `glsl/`.
    pub frag: &'a str,
    /// Line list or triangle strip.
    pub topology: vk::PrimitiveTopology,
    /// Per-instance record size (bytes); 0 for no vertex input.
    pub stride: u32,
    /// Per-instance attributes: (format, offset), location = index.
    pub attributes: &'a [(vk::Format, u32)],
    /// Color targets.
    pub targets: &'a [Target],
    /// Specialization constants of both stages, constant_id = index
    /// ([`super::layout::spec::values`]); empty: the shaders' defaults (everything on).
    pub specialization: &'a [u32],
    /// Vertex records advance per vertex (true) or per instance (false, the solver's passes).
    pub per_vertex: bool,
    /// Reversed depth test (greater: depth 1 is near) and write against a [`super::memory::DEPTH_FORMAT`] attachment.
    pub depth: bool,
    /// The line width is dynamic state, set per draw (`vkCmdSetLineWidth`; lines only).
    pub wide_lines: bool,
}

/// A descriptor-set layout and the pipeline layout made of it plus push constants.
pub struct Layouts {
    /// Set layout.
    pub set: Owned<vk::DescriptorSetLayout>,
    /// Pipeline layout: that set plus the push constants.
    pub pipeline: Owned<vk::PipelineLayout>,
}

impl Layouts {
    /// Creates the solver's layouts.
    pub fn new(ctx: &Arc<Context>) -> Result<Self> {
        let kinds = descriptor_kinds(binding::COUNT, &binding::BUFFERS);
        Self::with(
            ctx,
            "antiradiance",
            &kinds,
            std::mem::size_of::<PassConstants>() as u32,
        )
    }

    /// A set layout with binding `i` of type `kinds[i]` and a pipeline layout with that set and
    /// `push_bytes` of push constants (vertex + fragment stages).
    pub fn with(
        ctx: &Arc<Context>,
        name: &str,
        kinds: &[vk::DescriptorType],
        push_bytes: u32,
    ) -> Result<Self> {
        let stages = vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT;
        Self::with_stages(ctx, name, kinds, push_bytes, stages)
    }

    /// [`Layouts::with`] for the shader `stages` given (e.g. compute).
    pub fn with_stages(
        ctx: &Arc<Context>,
        name: &str,
        kinds: &[vk::DescriptorType],
        push_bytes: u32,
        stages: vk::ShaderStageFlags,
    ) -> Result<Self> {
        let bindings: Vec<_> = kinds
            .iter()
            .enumerate()
            .map(|(b, &kind)| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(b as u32)
                    .descriptor_type(kind)
                    .descriptor_count(1)
                    .stage_flags(stages)
            })
            .collect();
        let set = unsafe {
            ctx.device.create_descriptor_set_layout(
                &vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings),
                None,
            )
        }
        .vk("creating the descriptor set layout")?;
        let set = Owned::new(ctx, set, &format!("{name} set layout"));
        let ranges = [vk::PushConstantRange::default()
            .stage_flags(stages)
            .size(push_bytes)];
        let sets = [set.raw()];
        let pipeline = unsafe {
            ctx.device.create_pipeline_layout(
                &vk::PipelineLayoutCreateInfo::default()
                    .set_layouts(&sets)
                    .push_constant_ranges(&ranges),
                None,
            )
        }
        .vk("creating the pipeline layout")?;
        let pipeline = Owned::new(ctx, pipeline, &format!("{name} pipeline layout"));
        Ok(Self { set, pipeline })
    }
}

/// Descriptor types of bindings `0..count`: storage buffers where listed in `buffers`, combined
/// image samplers elsewhere (every image is read with `texelFetch`).
pub fn descriptor_kinds(count: u32, buffers: &[u32]) -> Vec<vk::DescriptorType> {
    (0..count)
        .map(|b| {
            if buffers.contains(&b) {
                vk::DescriptorType::STORAGE_BUFFER
            } else {
                vk::DescriptorType::COMBINED_IMAGE_SAMPLER
            }
        })
        .collect()
}

/// A nearest, clamp-to-edge sampler for the combined image samplers (reads are `texelFetch`).
pub fn texel_sampler(ctx: &Arc<Context>, name: &str) -> Result<Owned<vk::Sampler>> {
    let sampler = unsafe {
        ctx.device.create_sampler(
            &vk::SamplerCreateInfo::default()
                .mag_filter(vk::Filter::NEAREST)
                .min_filter(vk::Filter::NEAREST)
                .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_EDGE)
                .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE),
            None,
        )
    }
    .vk(name)?;
    Ok(Owned::new(ctx, sampler, name))
}

/// A descriptor pool for `sets` sets whose bindings are `kinds`.
pub fn descriptor_pool(
    ctx: &Arc<Context>,
    kinds: &[vk::DescriptorType],
    sets: u32,
    name: &str,
) -> Result<Owned<vk::DescriptorPool>> {
    let count = |t| kinds.iter().filter(|&&k| k == t).count() as u32 * sets;
    let sizes: Vec<_> = [
        vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
        vk::DescriptorType::STORAGE_BUFFER,
    ]
    .into_iter()
    .filter(|&t| count(t) > 0)
    .map(|ty| vk::DescriptorPoolSize {
        ty,
        descriptor_count: count(ty),
    })
    .collect();
    let pool = unsafe {
        ctx.device.create_descriptor_pool(
            &vk::DescriptorPoolCreateInfo::default()
                .max_sets(sets)
                .pool_sizes(&sizes),
            None,
        )
    }
    .vk(name)?;
    Ok(Owned::new(ctx, pool, name))
}

/// Allocates one descriptor set of `layout` from `pool`.
pub fn allocate_set(
    ctx: &Context,
    pool: &Owned<vk::DescriptorPool>,
    layout: &Owned<vk::DescriptorSetLayout>,
    name: &str,
) -> Result<vk::DescriptorSet> {
    let set = unsafe {
        ctx.device.allocate_descriptor_sets(
            &vk::DescriptorSetAllocateInfo::default()
                .descriptor_pool(pool.raw())
                .set_layouts(&[layout.raw()]),
        )
    }
    .vk(name)?[0];
    ctx.name(set, name);
    Ok(set)
}

/// Writes `set`: each `(binding, view)` as a combined image sampler in shader-read layout with
/// `sampler`, each `(binding, buffer)` as a whole storage buffer.
pub fn write_set(
    ctx: &Context,
    set: vk::DescriptorSet,
    sampler: vk::Sampler,
    images: &[(u32, vk::ImageView)],
    buffers: &[(u32, vk::Buffer)],
) {
    let whole: Vec<_> = buffers
        .iter()
        .map(|&(b, buf)| (b, buf, (0, vk::WHOLE_SIZE)))
        .collect();
    write_set_ranges(ctx, set, sampler, images, &whole);
}

/// As [`write_set`] with each buffer's (offset, range) given.
pub fn write_set_ranges(
    ctx: &Context,
    set: vk::DescriptorSet,
    sampler: vk::Sampler,
    images: &[(u32, vk::ImageView)],
    buffers: &[(u32, vk::Buffer, (u64, u64))],
) {
    let image_infos: Vec<[vk::DescriptorImageInfo; 1]> = images
        .iter()
        .map(|(_, view)| {
            [vk::DescriptorImageInfo::default()
                .sampler(sampler)
                .image_view(*view)
                .image_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)]
        })
        .collect();
    let buffer_infos: Vec<[vk::DescriptorBufferInfo; 1]> = buffers
        .iter()
        .map(|&(_, b, (offset, range))| {
            [vk::DescriptorBufferInfo::default()
                .buffer(b)
                .offset(offset)
                .range(range)]
        })
        .collect();
    let mut writes: Vec<vk::WriteDescriptorSet> = images
        .iter()
        .zip(&image_infos)
        .map(|((b, _), info)| {
            vk::WriteDescriptorSet::default()
                .dst_set(set)
                .dst_binding(*b)
                .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
                .image_info(info)
        })
        .collect();
    writes.extend(buffers.iter().zip(&buffer_infos).map(|((b, _, _), info)| {
        vk::WriteDescriptorSet::default()
            .dst_set(set)
            .dst_binding(*b)
            .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
            .buffer_info(info)
    }));
    unsafe { ctx.device.update_descriptor_sets(&writes, &[]) };
}

const MAIN: &CStr = c"main";

/// Builds a compute pipeline from the compute shader `file` under `glsl/`.
pub fn create_compute(
    ctx: &Arc<Context>,
    layout: &Owned<vk::PipelineLayout>,
    file: &str,
) -> Result<Owned<vk::Pipeline>> {
    let d = &ctx.device;
    let code = spirv(file);
    let module =
        unsafe { d.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&code), None) }
            .vk(file)?;
    let module = Owned::new(ctx, module, file);
    let stage = vk::PipelineShaderStageCreateInfo::default()
        .stage(vk::ShaderStageFlags::COMPUTE)
        .module(module.raw())
        .name(MAIN);
    let info = vk::ComputePipelineCreateInfo::default()
        .stage(stage)
        .layout(layout.raw());
    let p = unsafe { d.create_compute_pipelines(ctx.pipeline_cache(), &[info], None) }
        .map_err(|(_, e)| e)
        .vk(file)?[0];
    Ok(Owned::new(ctx, p, file))
}

/// Builds a graphics pipeline from `desc`.
pub fn create(
    ctx: &Arc<Context>,
    layout: &Owned<vk::PipelineLayout>,
    desc: &PipelineDesc<'_>,
) -> Result<Owned<vk::Pipeline>> {
    let d = &ctx.device;
    // SPIR-V compiled by build.rs; modules live only as long as pipeline creation.
    let module = |file: &str| -> Result<Owned<vk::ShaderModule>> {
        let code = spirv(file);
        let m = unsafe {
            d.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&code), None)
        }
        .vk(file)?;
        Ok(Owned::new(ctx, m, file))
    };
    let vs = module(desc.vert)?;
    let fs = module(desc.frag)?;
    let spec_data: Vec<u8> = desc
        .specialization
        .iter()
        .flat_map(|v| v.to_ne_bytes())
        .collect();
    let spec_entries: Vec<_> = (0..desc.specialization.len() as u32)
        .map(|i| {
            vk::SpecializationMapEntry::default()
                .constant_id(i)
                .offset(4 * i)
                .size(4)
        })
        .collect();
    let spec = vk::SpecializationInfo::default()
        .map_entries(&spec_entries)
        .data(&spec_data);
    let stage = |flags, module| {
        vk::PipelineShaderStageCreateInfo::default()
            .stage(flags)
            .module(module)
            .name(MAIN)
            .specialization_info(&spec)
    };
    let stages = [
        stage(vk::ShaderStageFlags::VERTEX, vs.raw()),
        stage(vk::ShaderStageFlags::FRAGMENT, fs.raw()),
    ];
    let vb = [vk::VertexInputBindingDescription::default()
        .binding(0)
        .stride(desc.stride)
        .input_rate(if desc.per_vertex {
            vk::VertexInputRate::VERTEX
        } else {
            vk::VertexInputRate::INSTANCE
        })];
    let attrs: Vec<_> = desc
        .attributes
        .iter()
        .enumerate()
        .map(|(i, &(format, offset))| {
            vk::VertexInputAttributeDescription::default()
                .location(i as u32)
                .binding(0)
                .format(format)
                .offset(offset)
        })
        .collect();
    let vertex_input = if desc.stride > 0 {
        vk::PipelineVertexInputStateCreateInfo::default()
            .vertex_binding_descriptions(&vb)
            .vertex_attribute_descriptions(&attrs)
    } else {
        vk::PipelineVertexInputStateCreateInfo::default()
    };
    let assembly = vk::PipelineInputAssemblyStateCreateInfo::default().topology(desc.topology);
    let viewport = vk::PipelineViewportStateCreateInfo::default()
        .viewport_count(1)
        .scissor_count(1);
    let is_line = desc.topology == vk::PrimitiveTopology::LINE_LIST;
    let mut line_state = vk::PipelineRasterizationLineStateCreateInfoEXT::default()
        .line_rasterization_mode(match ctx.info.line_mode {
            super::context::LineMode::Rectangular => vk::LineRasterizationModeEXT::RECTANGULAR,
            super::context::LineMode::Bresenham => vk::LineRasterizationModeEXT::BRESENHAM,
        });
    let mut raster = vk::PipelineRasterizationStateCreateInfo::default()
        .polygon_mode(vk::PolygonMode::FILL)
        .cull_mode(vk::CullModeFlags::NONE)
        .line_width(1.0);
    if is_line && ctx.line_rasterization_ext() {
        raster = raster.push_next(&mut line_state);
    }
    let ms = vk::PipelineMultisampleStateCreateInfo::default()
        .rasterization_samples(vk::SampleCountFlags::TYPE_1);
    let blends: Vec<_> = desc
        .targets
        .iter()
        .map(|t| {
            vk::PipelineColorBlendAttachmentState::default()
                .blend_enable(t.additive)
                .src_color_blend_factor(vk::BlendFactor::ONE)
                .dst_color_blend_factor(vk::BlendFactor::ONE)
                .color_blend_op(vk::BlendOp::ADD)
                .src_alpha_blend_factor(vk::BlendFactor::ONE)
                .dst_alpha_blend_factor(vk::BlendFactor::ONE)
                .alpha_blend_op(vk::BlendOp::ADD)
                .color_write_mask(if t.write {
                    vk::ColorComponentFlags::RGBA
                } else {
                    vk::ColorComponentFlags::empty()
                })
        })
        .collect();
    let blend = vk::PipelineColorBlendStateCreateInfo::default().attachments(&blends);
    let dynamic = [
        vk::DynamicState::VIEWPORT,
        vk::DynamicState::SCISSOR,
        vk::DynamicState::LINE_WIDTH,
    ];
    let dyn_state = vk::PipelineDynamicStateCreateInfo::default()
        .dynamic_states(&dynamic[..if desc.wide_lines { 3 } else { 2 }]);
    let formats: Vec<_> = desc.targets.iter().map(|t| t.format).collect();
    let mut rendering =
        vk::PipelineRenderingCreateInfo::default().color_attachment_formats(&formats);
    let depth_state = vk::PipelineDepthStencilStateCreateInfo::default()
        .depth_test_enable(desc.depth)
        .depth_write_enable(desc.depth)
        .depth_compare_op(vk::CompareOp::GREATER);
    if desc.depth {
        rendering = rendering.depth_attachment_format(super::memory::DEPTH_FORMAT);
    }
    let info = vk::GraphicsPipelineCreateInfo::default()
        .stages(&stages)
        .vertex_input_state(&vertex_input)
        .input_assembly_state(&assembly)
        .viewport_state(&viewport)
        .rasterization_state(&raster)
        .multisample_state(&ms)
        .color_blend_state(&blend)
        .depth_stencil_state(&depth_state)
        .dynamic_state(&dyn_state)
        .layout(layout.raw())
        .push_next(&mut rendering);
    let result = unsafe { d.create_graphics_pipelines(ctx.pipeline_cache(), &[info], None) };
    let p = result.map_err(|(_, e)| e).vk(desc.name)?[0];
    Ok(Owned::new(ctx, p, desc.name))
}

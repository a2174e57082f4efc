//! Graphics pipelines of the passes (dynamic rendering, dynamic viewport/scissor), the solver's
//! one descriptor-set layout and pipeline layout. Additive blending is a per-target option of a
//! pipeline, so accumulation is explicit where a pipeline is made.

use super::context::Context;
use super::layout::{binding, PassConstants};
use super::shaders::compile;
use crate::error::{Result, VkContext};
use ash::vk;
use std::ffi::CStr;

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
}

/// The shared layouts.
pub struct Layouts {
    /// Set layout with every binding of [`binding`].
    pub set: vk::DescriptorSetLayout,
    /// Pipeline layout: that set plus [`PassConstants`] push constants.
    pub pipeline: vk::PipelineLayout,
}

impl Layouts {
    /// Creates the solver's layouts.
    pub fn new(ctx: &Context) -> Result<Self> {
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
        ctx: &Context,
        name: &str,
        kinds: &[vk::DescriptorType],
        push_bytes: u32,
    ) -> Result<Self> {
        let bindings: Vec<_> = kinds
            .iter()
            .enumerate()
            .map(|(b, &kind)| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(b as u32)
                    .descriptor_type(kind)
                    .descriptor_count(1)
                    .stage_flags(vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT)
            })
            .collect();
        let set = unsafe {
            ctx.device.create_descriptor_set_layout(
                &vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings),
                None,
            )
        }
        .vk("creating the descriptor set layout")?;
        ctx.name(set, &format!("{name} set layout"));
        let ranges = [vk::PushConstantRange::default()
            .stage_flags(vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT)
            .size(push_bytes)];
        let sets = [set];
        let pipeline = unsafe {
            ctx.device.create_pipeline_layout(
                &vk::PipelineLayoutCreateInfo::default()
                    .set_layouts(&sets)
                    .push_constant_ranges(&ranges),
                None,
            )
        }
        .vk("creating the pipeline layout")?;
        ctx.name(pipeline, &format!("{name} pipeline layout"));
        Ok(Self { set, pipeline })
    }

    /// Frees the layouts.
    pub fn destroy(&self, ctx: &Context) {
        unsafe {
            ctx.device.destroy_pipeline_layout(self.pipeline, None);
            ctx.device.destroy_descriptor_set_layout(self.set, None);
        }
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
pub fn texel_sampler(ctx: &Context, name: &str) -> Result<vk::Sampler> {
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
    ctx.name(sampler, name);
    Ok(sampler)
}

/// A descriptor pool for `sets` sets whose bindings are `kinds`.
pub fn descriptor_pool(
    ctx: &Context,
    kinds: &[vk::DescriptorType],
    sets: u32,
    name: &str,
) -> Result<vk::DescriptorPool> {
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
    ctx.name(pool, name);
    Ok(pool)
}

const MAIN: &CStr = c"main";

/// Builds a graphics pipeline from `desc`.
pub fn create(
    ctx: &Context,
    layout: vk::PipelineLayout,
    desc: &PipelineDesc<'_>,
) -> Result<vk::Pipeline> {
    let d = &ctx.device;
    let module = |file: &str| -> Result<vk::ShaderModule> {
        let code = compile(file)?;
        let m = unsafe {
            d.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&code), None)
        }
        .vk(file)?;
        ctx.name(m, file);
        Ok(m)
    };
    let vs = module(desc.vert)?;
    let fs = module(desc.frag).inspect_err(|_| unsafe { d.destroy_shader_module(vs, None) })?;
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
        stage(vk::ShaderStageFlags::VERTEX, vs),
        stage(vk::ShaderStageFlags::FRAGMENT, fs),
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
    let dynamic = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
    let dyn_state = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic);
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
        .layout(layout)
        .push_next(&mut rendering);
    let result = unsafe { d.create_graphics_pipelines(vk::PipelineCache::null(), &[info], None) };
    unsafe {
        d.destroy_shader_module(vs, None);
        d.destroy_shader_module(fs, None);
    }
    let p = result.map_err(|(_, e)| e).vk(desc.name)?[0];
    ctx.name(p, desc.name);
    Ok(p)
}

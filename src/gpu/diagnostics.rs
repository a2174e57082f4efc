//! Checks of the raster mapping itself: which texels a set of link lines covers. Vulkan's line
//! rules differ from OpenGL's; the global and pull passes rely on every line hitting each texel
//! of its span exactly once.

use super::barrier::{transition, Access};
use super::context::Context;
use super::layout::{as_bytes, GpuLink, PassConstants};
use super::memory::{Buffer, ImageDesc, Purpose};
use super::pack::decode;
use super::passes::{begin_rendering, end_rendering, global, Load};
use super::pipelines::{create, Layouts, Target};
use super::tables::TableLayout;
use crate::error::Result;
use ash::vk;
use std::sync::Arc;

/// Draws `links` (only receiver and span matter) with the global pass's vertex shader and a
/// fragment shader that adds 1, and returns the hit count of every texel (row-major over the
/// `layout.width() × layout.rows_per_column` image).
pub fn line_coverage(
    ctx: &Arc<Context>,
    layout: &TableLayout,
    links: &[GpuLink],
) -> Result<Vec<f32>> {
    draw_lines(
        ctx,
        layout,
        links,
        "coverage.frag",
        vk::Format::R32G32B32A32_SFLOAT,
    )
}

/// How a device rounds additive blending into float16 targets.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum BlendRounding {
    /// Round to nearest (what GPUs do; errors grow as √N over N additions).
    Nearest,
    /// Truncation toward zero (lavapipe): every addition loses half an ulp on average, a bias
    /// that grows as N.
    TowardZero,
}

/// Adds 0.7 a hundred times into one float16 texel: 69.44 with round-to-nearest, 68.94 with
/// truncation (exact: 70).
pub fn f16_blend_rounding(ctx: &Arc<Context>) -> Result<BlendRounding> {
    let layout = TableLayout::new(1, 1, ctx.info.max_image_dimension)?;
    let links = vec![
        GpuLink {
            span: 1 << 16,
            ..Default::default()
        };
        100
    ];
    let sum = draw_lines(
        ctx,
        &layout,
        &links,
        "probe.frag",
        vk::Format::R16G16B16A16_SFLOAT,
    )?[0];
    Ok(if sum > 69.2 {
        BlendRounding::Nearest
    } else {
        BlendRounding::TowardZero
    })
}

fn draw_lines(
    ctx: &Arc<Context>,
    layout: &TableLayout,
    links: &[GpuLink],
    frag: &str,
    format: vk::Format,
) -> Result<Vec<f32>> {
    let layouts = Layouts::new(ctx)?;
    let targets = [Target {
        format,
        additive: true,
        write: true,
    }];
    let pipeline = create(ctx, &layouts.pipeline, &global::desc(frag, &targets))?;
    let buf = Buffer::upload(
        ctx,
        "coverage lines",
        as_bytes(links),
        vk::BufferUsageFlags::VERTEX_BUFFER,
    )?;
    let mut img = ImageDesc::new(
        "coverage target",
        layout.width(),
        layout.rows_per_column,
        format,
        Purpose::Scratch,
    )
    .create(ctx)?;
    let c = PassConstants {
        bins: layout.bins,
        rows_per_column: layout.rows_per_column,
        target_width: layout.width(),
        target_height: layout.rows_per_column,
        quad_width: layout.bins,
        line_offset: ctx.info.line_mode.endpoint_offset(),
        ..Default::default()
    };
    ctx.submit_and_wait(|cmd| unsafe {
        transition(ctx, cmd, &mut [(&mut img, Access::Attachment)]);
        begin_rendering(ctx, cmd, &[(&img, Load::Clear)]);
        ctx.device
            .cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, pipeline.raw());
        ctx.device.cmd_push_constants(
            cmd,
            layouts.pipeline.raw(),
            vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT,
            0,
            as_bytes(std::slice::from_ref(&c)),
        );
        ctx.device.cmd_bind_vertex_buffers(cmd, 0, &[buf.raw], &[0]);
        ctx.device.cmd_draw(cmd, 2, links.len() as u32, 0, 0);
        end_rendering(ctx, cmd);
    })?;
    Ok(decode(format, &img.read()?).iter().map(|t| t[0]).collect())
}

//! Checks of the raster mapping itself: which texels a set of lines covers. Vulkan's line rules
//! differ from OpenGL's; the pull pass relies on every line hitting each texel of its span
//! exactly once, the global pass on every wide line hitting each texel of its rectangle once.

use super::barrier::{transition, Access};
use super::context::Context;
use super::layout::{as_bytes, PassConstants};
use super::memory::{Buffer, ImageDesc, Purpose};
use super::pack::decode;
use super::passes::{begin_rendering, end_rendering, Load};
use super::pipelines::{create, Layouts, PipelineDesc, Target};
use super::tables::TableLayout;
use crate::error::Result;
use ash::vk;
use std::sync::Arc;

/// Draws one line per `(row, lo, hi)` over bins `[lo, hi)` with the line endpoints the pull
/// pass uses (`ar_line_end`), a fragment shader that adds 1, and returns the hit count of every
/// texel (row-major over the `layout.width() × layout.rows_per_column` image).
pub fn line_coverage(
    ctx: &Arc<Context>,
    layout: &TableLayout,
    spans: &[(u32, u32, u32)],
) -> Result<Vec<f32>> {
    draw_lines(
        ctx,
        layout,
        spans,
        "coverage.frag",
        vk::Format::R32G32B32A32_SFLOAT,
    )
}

/// Draws one line per rectangle `(x0, y0, width, height)` of a `size` target with the
/// endpoints and line width the global pass uses (`ar_rect_line_end`: as wide as the rectangle
/// is tall), a fragment shader that adds 1, and returns the hit count of every texel
/// (row-major). Heights must not pass [`super::context::DeviceInfo::max_line_width`].
pub fn rect_coverage(ctx: &Arc<Context>, size: (u32, u32), rects: &[[u32; 4]]) -> Result<Vec<f32>> {
    let mut sorted = rects.to_vec();
    sorted.sort_by_key(|r| r[3]);
    let mut groups: Vec<(f32, u32, u32)> = Vec::new();
    for (i, r) in sorted.iter().enumerate() {
        match groups.last_mut() {
            Some(g) if g.0 == r[3] as f32 => g.2 += 1,
            _ => groups.push((r[3] as f32, i as u32, 1)),
        }
    }
    let format = vk::Format::R32G32B32A32_SFLOAT;
    let records = Records {
        vert: "rect.vert",
        attribute: vk::Format::R32G32B32A32_UINT,
        stride: 16,
        bytes: as_bytes(&sorted),
        groups: &groups,
    };
    let layout = TableLayout::new(1, 1, ctx.info.max_image_dimension)?;
    draw(ctx, &layout, size, "coverage.frag", format, &records)
}

pub use super::context::BlendRounding;

/// The probe's sum on a device that rounds float16 blending to nearest (69 + 7/16).
pub const PROBE_SUM_NEAREST: f32 = 69.4375;
/// The probe's sum on a device that truncates float16 blending toward zero (68 + 15/16).
pub const PROBE_SUM_TOWARD_ZERO: f32 = 68.9375;

/// What the probe's `sum` (0.7 added a hundred times into one float16 texel; exact: 70) says
/// about the device: [`PROBE_SUM_NEAREST`] or anything closer to 70 is [`BlendRounding::Nearest`];
/// [`PROBE_SUM_TOWARD_ZERO`], anything else below the midpoint, or a non-number is
/// [`BlendRounding::TowardZero`] (the safe answer: the solver then accumulates in float32).
pub fn classify_blend_sum(sum: f32) -> BlendRounding {
    if sum > 69.2 {
        BlendRounding::Nearest
    } else {
        BlendRounding::TowardZero
    }
}

/// How `ctx`'s device rounds additive float16 blending: 0.7 added a hundred times into one
/// float16 texel, the sum classified ([`classify_blend_sum`]); probed once per context, on
/// first use (never while the context is being made).
pub fn f16_blend_rounding(ctx: &Arc<Context>) -> Result<BlendRounding> {
    if let Some(r) = ctx.f16_rounding.get() {
        return Ok(*r);
    }
    let r = classify_blend_sum(f16_blend_sum(ctx)?);
    Ok(*ctx.f16_rounding.get_or_init(|| r))
}

/// The probe's sum: 0.7 added a hundred times into one float16 texel by additive blending.
pub fn f16_blend_sum(ctx: &Arc<Context>) -> Result<f32> {
    let layout = TableLayout::new(1, 1, ctx.info.max_image_dimension)?;
    let spans = vec![(0, 0, 1); 100];
    let sum = draw_lines(
        ctx,
        &layout,
        &spans,
        "probe.frag",
        vk::Format::R16G16B16A16_SFLOAT,
    )?[0];
    Ok(sum)
}

fn draw_lines(
    ctx: &Arc<Context>,
    layout: &TableLayout,
    spans: &[(u32, u32, u32)],
    frag: &str,
    format: vk::Format,
) -> Result<Vec<f32>> {
    let records: Vec<[u32; 2]> = spans
        .iter()
        .map(|&(r, lo, hi)| [r, lo | hi << 16])
        .collect();
    let records = Records {
        vert: "span.vert",
        attribute: vk::Format::R32G32_UINT,
        stride: 8,
        bytes: as_bytes(&records),
        groups: &[(1.0, 0, spans.len() as u32)],
    };
    let size = (layout.width(), layout.rows_per_column);
    draw(ctx, layout, size, frag, format, &records)
}

/// Per-instance line records and their draws `(line width, first, count)`.
struct Records<'a> {
    vert: &'a str,
    attribute: vk::Format,
    stride: u32,
    bytes: &'a [u8],
    groups: &'a [(f32, u32, u32)],
}

fn draw(
    ctx: &Arc<Context>,
    layout: &TableLayout,
    size: (u32, u32),
    frag: &str,
    format: vk::Format,
    records: &Records<'_>,
) -> Result<Vec<f32>> {
    let layouts = Layouts::new(ctx)?;
    let targets = [Target {
        format,
        additive: true,
        write: true,
    }];
    // Only the table layout matters to span.vert; the feature constants keep their values.
    let constants =
        super::layout::spec::solver_values(&crate::plan::Features::ALL, 0, false, layout, false);
    let desc = PipelineDesc {
        name: frag,
        vert: records.vert,
        frag,
        topology: vk::PrimitiveTopology::LINE_LIST,
        stride: records.stride,
        attributes: &[(records.attribute, 0)],
        targets: &targets,
        specialization: &constants,
        per_vertex: false,
        depth: false,
        wide_lines: true,
    };
    let pipeline = create(ctx, &layouts.pipeline, &desc)?;
    let buf = Buffer::upload(
        ctx,
        "coverage lines",
        records.bytes,
        vk::BufferUsageFlags::VERTEX_BUFFER,
    )?;
    let mut img =
        ImageDesc::new("coverage target", size.0, size.1, format, Purpose::Scratch).create(ctx)?;
    let c = PassConstants {
        target_width: size.0,
        target_height: size.1,
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
        for &(width, first, count) in records.groups {
            ctx.device.cmd_set_line_width(cmd, width);
            ctx.device.cmd_draw(cmd, 2, count, 0, first);
        }
        end_rendering(ctx, cmd);
    })?;
    Ok(decode(format, &img.read()?).iter().map(|t| t[0]).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use half::f16;

    /// Float16 addition of `a + b` rounded to nearest or truncated toward zero.
    fn add(a: f16, b: f16, truncate: bool) -> f16 {
        let exact = a.to_f64() + b.to_f64();
        let r = f16::from_f64(exact);
        if truncate && r.to_f64().abs() > exact.abs() {
            f16::from_bits(r.to_bits() - 1)
        } else {
            r
        }
    }

    /// The two sums the probe tells apart, from a software float16 accumulator with each
    /// rounding, and the decision on both (and on what a broken probe could return).
    #[test]
    fn probe_sums_classify_both_behaviours() {
        for (truncate, want_sum, want) in [
            (false, PROBE_SUM_NEAREST, BlendRounding::Nearest),
            (true, PROBE_SUM_TOWARD_ZERO, BlendRounding::TowardZero),
        ] {
            let mut s = f16::ZERO;
            for _ in 0..100 {
                s = add(s, f16::from_f32(0.7), truncate);
            }
            assert_eq!(s.to_f32(), want_sum, "truncate {truncate}");
            assert_eq!(classify_blend_sum(s.to_f32()), want);
        }
        assert_eq!(classify_blend_sum(69.44), BlendRounding::Nearest);
        assert_eq!(classify_blend_sum(68.94), BlendRounding::TowardZero);
        // Exact accumulation (a device blending at higher precision) is as good as nearest.
        assert_eq!(classify_blend_sum(70.0), BlendRounding::Nearest);
        for broken in [0.0, 0.7, 64.0, f32::NAN] {
            assert_eq!(classify_blend_sum(broken), BlendRounding::TowardZero);
        }
    }
}

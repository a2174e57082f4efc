//! Checks of the raster mapping itself: which texels a set of link lines covers. Vulkan's line
//! rules differ from OpenGL's; the global and pull passes rely on every line hitting each texel
//! of its span exactly once.

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

/// Draws one line per `(row, lo, hi)` over bins `[lo, hi)` with the line endpoints every line
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
    let spans = vec![(0, 0, 1); PROBE_ADDITIONS];
    let sum = draw_lines(
        ctx,
        &layout,
        &spans,
        "probe.frag",
        vk::Format::R16G16B16A16_SFLOAT,
    )?[0];
    Ok(classify_probe(sum))
}

/// Additions of 0.7 the probe makes into one float16 texel.
pub const PROBE_ADDITIONS: usize = 100;

/// What the probe's sum says: 69.44 after round-to-nearest additions, 68.94 after truncating
/// ones (exact: 70); the threshold lies between them.
pub fn classify_probe(sum: f32) -> BlendRounding {
    if sum > 69.2 {
        BlendRounding::Nearest
    } else {
        BlendRounding::TowardZero
    }
}

fn draw_lines(
    ctx: &Arc<Context>,
    layout: &TableLayout,
    spans: &[(u32, u32, u32)],
    frag: &str,
    format: vk::Format,
) -> Result<Vec<f32>> {
    let layouts = Layouts::new(ctx)?;
    let targets = [Target {
        format,
        additive: true,
        write: true,
    }];
    let desc = PipelineDesc {
        name: frag,
        vert: "span.vert",
        frag,
        topology: vk::PrimitiveTopology::LINE_LIST,
        stride: 8,
        attributes: &[(vk::Format::R32G32_UINT, 0)],
        targets: &targets,
        specialization: &[],
        per_vertex: false,
        depth: false,
    };
    let pipeline = create(ctx, &layouts.pipeline, &desc)?;
    let records: Vec<[u32; 2]> = spans
        .iter()
        .map(|&(r, lo, hi)| [r, lo | hi << 16])
        .collect();
    let buf = Buffer::upload(
        ctx,
        "coverage lines",
        as_bytes(&records),
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
        grid_rows: layout.grid_rows,
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
        ctx.device.cmd_draw(cmd, 2, spans.len() as u32, 0, 0);
        end_rendering(ctx, cmd);
    })?;
    Ok(decode(format, &img.read()?).iter().map(|t| t[0]).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The classifier on both behaviours, with the sums each rounding gives (computed here on
    /// the CPU with `half`, independently of any device).
    #[test]
    fn the_probe_tells_rounding_from_truncation() {
        use half::f16;
        let add = |truncate: bool| {
            let mut s = f16::from_f32(0.0);
            for _ in 0..PROBE_ADDITIONS {
                let exact = s.to_f64() + f16::from_f32(0.7).to_f64();
                s = if truncate {
                    // Toward zero: the largest float16 not above the exact (positive) sum.
                    let r = f16::from_f64(exact);
                    if r.to_f64() > exact {
                        f16::from_bits(r.to_bits() - 1)
                    } else {
                        r
                    }
                } else {
                    f16::from_f64(exact)
                };
            }
            s.to_f32()
        };
        let (nearest, truncated) = (add(false), add(true));
        assert!((nearest - 69.44).abs() < 0.01, "{nearest}");
        assert!((truncated - 68.94).abs() < 0.01, "{truncated}");
        assert_eq!(classify_probe(nearest), BlendRounding::Nearest);
        assert_eq!(classify_probe(truncated), BlendRounding::TowardZero);
    }
}

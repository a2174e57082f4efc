#version 450
// Diagnostics: one line per record over a rectangle of the target, with the endpoints the
// global pass uses (ar_rect_line_end), drawn as wide as the rectangle is tall, so the coverage
// check tests the global pass's rasterization.
#include "common.glsl"

layout(location = 0) in uvec4 rect;   // x0, y0, width, height (texels)

void main() {
    gl_Position = ar_rect_line_end(ivec2(rect.xy), rect.zw, (gl_VertexIndex & 1) != 0);
}

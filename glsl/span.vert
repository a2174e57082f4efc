#version 450
// Diagnostics: one line per record over bins [lo, hi) of a row, with the endpoints the pull pass
// uses (ar_line_end), so the coverage check tests its rasterization.
#include "common.glsl"

layout(location = 0) in uvec2 span;   // row, lo | hi << 16

void main() {
    uint bin_edge = (gl_VertexIndex & 1) == 0 ? span.y & 0xffffu : span.y >> 16;
    gl_Position = ar_line_end(span.x, bin_edge);
}

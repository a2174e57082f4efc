#version 450
// Quads over whole rows [first, end) of one column block (local pass), drawn as a
// 4-vertex triangle strip per instance.
#include "common.glsl"

layout(location = 0) in uvec3 quad;   // unused, first row, end row
layout(location = 0) flat out uint source_row;

void main() {
    uint block = quad.y / AR_ROWS_PER_COLUMN;
    float x0 = float(block * pc.quad_width);
    float y0 = float(quad.y % AR_ROWS_PER_COLUMN);
    float x = (gl_VertexIndex & 1) == 0 ? x0 : x0 + float(pc.quad_width);
    float y = (gl_VertexIndex & 2) == 0 ? y0 : y0 + float(quad.z - quad.y);
    gl_Position = ar_clip(vec2(x, y));
    source_row = quad.x;
}

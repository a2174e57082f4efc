#version 450
// Pull: one line per (leaf, ancestor) across the ancestor's row.
#include "common.glsl"

layout(location = 0) in uvec2 pair;   // leaf row, ancestor row
layout(location = 0) flat out uint leaf_row;

void main() {
    ivec2 t = ar_texel(pair.y, 0u);
    float x = float(t.x) + (gl_VertexIndex == 0 ? 0.0 : float(pc.bins)) + pc.line_offset;
    gl_Position = ar_clip(vec2(x, float(t.y) + 0.5));
    leaf_row = pair.x;
}

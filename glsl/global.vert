#version 450
// Global pass (eq. 16): one line per link across the receiver's row in L_in.
#include "common.glsl"

layout(location = 0) in uvec4 link;      // receiver, sender, bin | layer << 16, lo | hi << 16
layout(location = 1) in float form_factor;

layout(location = 0) flat out ivec2 sender_texel;
layout(location = 1) flat out int filter_row;
layout(location = 2) flat out float ff;

void main() {
    uint bin = link.z & 0xffffu;
    uint layer = link.z >> 16;
    uint lo = link.w & 0xffffu;
    uint hi = link.w >> 16;
    ivec2 t = ar_texel(link.x, 0u);
    float x = float(t.x) + float(gl_VertexIndex == 0 ? lo : hi) + pc.line_offset;
    gl_Position = ar_clip(vec2(x, float(t.y) + 0.5));
    sender_texel = ar_texel(link.y, bin);
    filter_row = int(layer * pc.bins + bin);
    ff = form_factor;
}

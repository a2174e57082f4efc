#version 450
// Global pass: the link's F · I_ex weighted by its cone-filter table at this bin, accumulated
// into L_in by additive blending; the rectangle's bins outside the mask (no filter weight, or
// a bin the leaf receiver never reads) are discarded.
#include "common.glsl"

layout(binding = AR_BINDING_FILTER) uniform sampler2D filter_table;

layout(location = 0) flat in vec3 sent;
layout(location = 1) flat in ivec2 corner;
layout(location = 2) flat in ivec2 filter_at;
layout(location = 3) flat in uint width;
layout(location = 4) flat in uvec2 mask;
layout(location = 0) out vec4 l_in;

void main() {
    ivec2 d = ivec2(gl_FragCoord.xy) - corner;
    uint bit = uint(d.y) * width + uint(d.x);
    uint word = bit < 32u ? mask.x : mask.y;
    if (((word >> (bit & 31u)) & 1u) == 0u) {
        discard;
    }
    // The table's columns are bins (iv·nu + iu), so the fragment's offset in the rectangle
    // finds its weight without a division.
    float w = texelFetch(filter_table, filter_at + ivec2(d.y * int(AR_GRID_COLUMNS) + d.x, 0), 0).r;
    l_in = vec4(sent * w, 0.0);
}

#version 450
// Global pass: the link's F · I_ex weighted by its cone-filter table at this bin, accumulated
// into L_in by additive blending; the rectangle's bins outside the mask (no filter weight, or
// a bin the leaf receiver never reads) are discarded.
#include "round16.glsl"

layout(binding = AR_BINDING_FILTER) uniform sampler2D filter_table;

layout(location = 0) flat in vec3 sent;
layout(location = 1) flat in uvec3 place;  // corner x | y << 16, column | width << 16, row
layout(location = 2) flat in uvec2 mask;
layout(location = 0) out vec4 l_in;

void main() {
    ivec2 d = ivec2(gl_FragCoord.xy) - ivec2(place.x & 0xffffu, place.x >> 16);
    uint bit = uint(d.y) * (place.y >> 16) + uint(d.x);
    uint word = bit < 32u ? mask.x : mask.y;
    if (((word >> (bit & 31u)) & 1u) == 0u) {
        discard;
    }
    // The table's columns are bins (iv·nu + iu), so the fragment's offset in the rectangle
    // finds its weight without a division.
    int column = int(place.y & 0xffffu) + d.y * int(AR_GRID_COLUMNS) + d.x;
    float w = texelFetch(filter_table, ivec2(column, place.z), 0).r;
    if (AR_ROUND_WIDTH != 0u) {
        ar_round_add(ivec2(gl_FragCoord.xy), sent * w);
        l_in = vec4(0.0);
        return;
    }
    l_in = vec4(sent * w, 0.0);
}

#version 450
// Global pass: the link's F · I_ex weighted by its cone-filter table at this bin, accumulated
// into L_in by additive blending.
#include "common.glsl"

layout(binding = AR_BINDING_FILTER) uniform sampler2D filter_table;

layout(location = 0) flat in vec3 sent;
layout(location = 1) flat in int filter_row;
layout(location = 2) flat in int row_start;
layout(location = 0) out vec4 l_in;

void main() {
    // The table's columns go by position in the row (src/gpu/pack.rs filter_tables), so no
    // division maps the fragment to its bin: integer division is scalar on a CPU rasterizer.
    float w = texelFetch(filter_table, ivec2(int(gl_FragCoord.x) - row_start, filter_row), 0).r;
    l_in = vec4(sent * w, 0.0);
}

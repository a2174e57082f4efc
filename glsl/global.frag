#version 450
// Global pass: the link's F · I_ex weighted by its cone-filter table at this bin, accumulated
// into L_in by additive blending.
#include "common.glsl"

layout(binding = AR_BINDING_FILTER) uniform sampler2D filter_table;

layout(location = 0) flat in vec3 sent;
layout(location = 1) flat in int filter_row;
layout(location = 0) out vec4 l_in;

void main() {
    uint j = ar_bin_at(ivec2(gl_FragCoord.xy));
    float w = texelFetch(filter_table, ivec2(int(j), filter_row), 0).r;
    l_in = vec4(sent * w, 0.0);
}

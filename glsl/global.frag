#version 450
// Global pass: F * I_ex(sender, bin) spread by the cone-filter table of the link's class,
// accumulated into L_in by additive blending.
#include "common.glsl"

layout(binding = AR_BINDING_LEAF_EX) uniform sampler2D leaf_ex;
layout(binding = AR_BINDING_CLUSTER_EX) uniform sampler2D cluster_ex;
layout(binding = AR_BINDING_FILTER) uniform sampler2D filter_table;

layout(location = 0) flat in ivec2 sender_texel;
layout(location = 1) flat in int filter_row;
layout(location = 2) flat in float ff;
layout(location = 0) out vec4 l_in;

void main() {
    uint j = ar_bin_at(ivec2(gl_FragCoord.xy));
    float w = texelFetch(filter_table, ivec2(int(j), filter_row), 0).r;
    // Leaves and clusters live in separate images (zero where the other is valid).
    vec3 i_ex = texelFetch(leaf_ex, sender_texel, 0).rgb + texelFetch(cluster_ex, sender_texel, 0).rgb;
    l_in = vec4(i_ex * (ff * w), 0.0);
}

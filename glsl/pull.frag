#version 450
// Pull: the leaf's new I_ex added into its ancestor's row (additive blending).
#include "common.glsl"

layout(binding = AR_BINDING_LEAF_EX_NEXT) uniform sampler2D leaf_ex_next;
layout(location = 0) flat in uint leaf_row;
layout(location = 0) out vec4 cluster_ex;

void main() {
    uint j = ar_bin_at(ivec2(gl_FragCoord.xy));
    cluster_ex = vec4(texelFetch(leaf_ex_next, ar_texel(leaf_row, j), 0).rgb, 0.0);
}

#version 450
// Push: a node's gathered L_in added to every row of its subtree (additive blending).
#include "common.glsl"

layout(binding = AR_BINDING_L_IN) uniform sampler2D l_in;
layout(location = 0) flat in uint source_row;
layout(location = 0) out vec4 l_push;

void main() {
    uint j = ar_bin_at(ivec2(gl_FragCoord.xy));
    l_push = vec4(texelFetch(l_in, ar_texel(source_row, j), 0).rgb, 0.0);
}

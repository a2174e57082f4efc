// Pull (bottom-up, one draw per depth): a cluster's I_ex is the sum of its two children's, each
// a leaf (the new leaf I_ex) or a cluster one level deeper (the other parity's image). The
// including shader defines AR_CHILDREN, the sampler of the children's parity.
#include "common.glsl"

layout(binding = AR_BINDING_LEAF_EX_NEXT) uniform sampler2D leaf_ex_next;
layout(location = 0) flat in uint row;
layout(location = 1) flat in uint other;
layout(location = 0) out vec4 cluster_ex;

vec3 ar_child(uint child, uint j) {
    ivec2 t = ar_texel(child, j);
    return texelFetch(leaf_ex_next, t, 0).rgb + texelFetch(AR_CHILDREN, t, 0).rgb;
}

void main() {
    uint j = ar_bin_at(ivec2(gl_FragCoord.xy));
    cluster_ex = vec4(ar_child(row + 1u, j) + ar_child(other, j), 0.0);
}

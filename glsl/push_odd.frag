#version 450
// Push at an odd depth: the parent's pushed value (even depth, in the L_push image) added to the
// node's own tile of the L_in image by additive blending, which then holds L_push(node). At a leaf
// only on its front, times the leaf's push factor (push.glsl).
#include "push.glsl"
#include "round16.glsl"

layout(binding = AR_BINDING_L_PUSH) uniform sampler2D l_push;
layout(location = 0) flat in uint row;
layout(location = 1) flat in uint other;
layout(location = 0) out vec4 pushed;

void main() {
    uint j = ar_in_bin_at(ivec2(gl_FragCoord.xy));
    bool add = ar_pushes(row, j);
    pushed = add ? vec4(ar_push_factor(row) * texelFetch(l_push, ar_in_texel(other, j), 0).rgb, 0.0) : vec4(0.0);
    if (AR_ROUND_WIDTH != 0u) {
        ar_round_add(ivec2(gl_FragCoord.xy), pushed.rgb);
        pushed = vec4(0.0);
    }
}

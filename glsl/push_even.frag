#version 450
// Push at an even depth (top-down, one draw per depth): L_push(node) = L_in(node) + the parent's
// pushed value, which odd depths keep in the L_in image (glsl/push_odd.frag). Written into the
// L_push image. At a leaf the parent's value is added on its front only, times the leaf's push
// factor (push.glsl).
#include "push.glsl"

layout(binding = AR_BINDING_L_IN) uniform sampler2D l_in;
layout(location = 0) flat in uint row;
layout(location = 1) flat in uint other;
layout(location = 0) out vec4 pushed;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    uint j = ar_in_bin_at(p);
    vec3 v = texelFetch(l_in, p, 0).rgb;
    if (other != 0xffffffffu && ar_pushes(row, j)) {
        v += ar_push_factor(row) * texelFetch(l_in, ar_in_texel(other, j), 0).rgb;
    }
    // A float16 target rounds what it stores (emulated: the target is float32).
    pushed = vec4(AR_ROUND_WIDTH != 0u ? vec3(ar_round_f16(v.r), ar_round_f16(v.g), ar_round_f16(v.b)) : v, 0.0);
}

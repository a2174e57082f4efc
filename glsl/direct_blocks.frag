#version 450
// The area emitters' shared direct light at each block's corner pixel (src/gpu/passes/
// direct_blocks.rs, frame/direct.rs): one full-screen triangle at the blocks' grid, evaluating
// it where the corner pixel's samples share it (a: the inverse of their mean's depth along the
// view axis, the perspective-correct weight; 0 where they share none) so that compose
// interpolates it for the other pixels of the block instead of evaluating it at each.
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"
#include "shared_direct.glsl"

layout(location = 0) out vec4 out_direct;

void main() {
    int ss = int(pc.misc.w & 0xFFu);
    int block = int(pc.misc.w >> 8u);
    ivec2 px = ivec2(gl_FragCoord.xy) * block;
    vec3 mid;
    vec3 normal_sum;
    uint slot0;
    uint a = pc.misc.y;
    uint b = pc.misc.z;
    if (a < b && ar_shares_direct(px, ss, mid, normal_sum, slot0)) {
        // Clip w is the depth along the view axis (the jitter moves x and y only).
        float depth = (pc.view_proj * vec4(mid, 1.0)).w;
        out_direct = vec4(ar_shared_direct(mid, normal_sum, slot0, a, b), 1.0 / depth);
    } else {
        out_direct = vec4(0.0);
    }
}

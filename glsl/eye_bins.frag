#version 450
// The splat texels' display bins toward the eye (src/gpu/passes/eye_bins.rs): one full-screen
// triangle at the splat target's size, at each texel's G-buffer sample (a pixel's first, or
// every sample), so the splat's fragments read the bin instead of finding it, and the G-buffer
// does not find it under overdraw at every sample.
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"

layout(location = 0) out float out_bin;

void main() {
    ivec2 t = ivec2(gl_FragCoord.xy) * (textureSize(gbuf_position, 0).x / int(pc.sizes.x));
    vec4 g = texelFetch(gbuf_position, t, 0);
    out_bin = ar_gbuf_background(g.w) ? -1.0 : ar_sample_bin(g.xyz, ar_gbuf_leaf(g.w), t);
}

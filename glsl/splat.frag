#version 450
// Adds w·L and w where the G-buffer shows the same flat surface (the normalization is in compose),
// once per pixel at its first sample, or per sample (src/frame/splat.rs).
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"

layout(location = 0) flat in vec4 center_radius;
layout(location = 1) flat in vec4 normal_ac;
layout(location = 2) flat in uvec2 row_surface;
layout(location = 0) out vec4 acc;

void main() {
    // Per pixel (its first sample) or per sample: the G-buffer's texels per splat texel.
    ivec2 t = ivec2(gl_FragCoord.xy) * (textureSize(gbuf_position, 0).x / int(pc.sizes.x));
    vec4 g = texelFetch(gbuf_position, t, 0);
    if (ar_gbuf_background(g.w)) {
        discard;
    }
    FrameElement h = elements[ar_gbuf_leaf(g.w)];
    if (h.ids.z == AR_MODE_VERTEX || h.ids.y != row_surface.y) {
        discard;
    }
    float w = ar_splat_weight(length(g.xyz - center_radius.xyz), center_radius.w);
    if (w <= 0.0) {
        discard;
    }
    // The bin toward the eye as the sample's shading normal sees it, found once per splat texel
    // (eye_bins.frag; surfaces.rs display_bin); the splatted leaf's own cosine normalizes it.
    float bin = texelFetch(splat_bins, ivec2(gl_FragCoord.xy), 0).x;
    vec3 l = vec3(0.0);
    if (bin >= 0.0) {
        l = ar_display_radiance_in(normal_ac.xyz, normal_ac.w, row_surface.x, uint(bin + 0.5));
    }
    acc = vec4(l * w, w);
}

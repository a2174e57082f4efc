#version 450
// Adds w·L and w where the G-buffer shows the same flat surface (the normalization is in compose).
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"

layout(location = 0) flat in vec4 center_radius;
layout(location = 1) flat in vec4 normal_ac;
layout(location = 2) flat in uvec2 row_surface;
layout(location = 0) out vec4 acc;

void main() {
    vec4 g = texelFetch(gbuf_position, ivec2(gl_FragCoord.xy), 0);
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
    // The bin toward the eye as the pixel's shading normal sees it (shading.rs eye_direction);
    // the splatted elements lie in the pixel's plane.
    vec3 wo = normalize(pc.eye.xyz - g.xyz);
    vec3 dir = wo;
    if (h.cos_norm.y > 0.5) {
        vec3 n = h.face_normal.xyz;
        vec3 ns = ar_shading_normal(texelFetch(gbuf_normal, ivec2(gl_FragCoord.xy), 0).xyz, n, wo);
        dir = ar_eye_direction(wo, ns, n);
    }
    acc = vec4(ar_display_radiance_of(normal_ac.xyz, normal_ac.w, row_surface.x, dir) * w, w);
}

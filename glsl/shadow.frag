#version 450
// Stores the linear distance the lookup compares against (ShadowView::distance in shadow.rs) and
// the surface's normal turned to the light, packed (shadow.rs render_cpu_reusing).
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"

layout(location = 0) in vec3 world;
layout(location = 0) out vec2 texel;

void main() {
    ShadowView v = shadow_views[pc.misc.y];
    bool ortho = v.origin.w > 0.5;
    vec3 toward = ortho ? -v.forward.xyz : v.origin.xyz - world;
    // The triangle's plane: its interpolated positions across the 2x2 quad all lie on it.
    vec3 c = cross(dFdx(world), dFdy(world));
    vec3 n = dot(c, c) > 0.0 ? normalize(c) : normalize(toward);
    n = dot(n, toward) < 0.0 ? -n : n;
    float dist = ortho ? dot(world - v.origin.xyz, v.forward.xyz) : length(world - v.origin.xyz);
    texel = vec2(dist, ar_pack_normal(n));
}

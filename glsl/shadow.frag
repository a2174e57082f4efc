#version 450
// Stores the linear distance the lookup compares against (ShadowView::distance in shadow.rs).
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"

layout(location = 0) in vec3 world;
layout(location = 0) out float dist;

void main() {
    ShadowView v = shadow_views[pc.misc.y];
    dist = v.origin.w > 0.5 ? dot(world - v.origin.xyz, v.forward.xyz) : length(world - v.origin.xyz);
}
